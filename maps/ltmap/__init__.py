"""The Landmark-Tree map (LT-map)."""

"""Maps: LT-map, roadmap, room estimate, coverage, exploration map, planning, and the file store."""

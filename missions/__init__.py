"""Missions: the YAML mission language, its loader and validator, the runner and the CLI."""

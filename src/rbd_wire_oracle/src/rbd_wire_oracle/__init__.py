"""Test oracles of the wire formats RoboDog speaks (vendor facts, not our code)."""

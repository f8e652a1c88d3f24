"""Baking a recording into keys, force arrows and a cut surface revealed over time."""

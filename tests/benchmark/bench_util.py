"""Helpers of the benchmark tests: a flat scene config with no craters and no rocks."""

FLAT_SCENE = """
[terrain]
source = "procedural"
size_m = [40.0, 40.0]
post_m = 0.25
rms_height_m = 0.05
[craters]
enabled = false
[rocks]
enabled = false
"""

"""The tetrahedral mesh type: checks, quality, orientation, reading and writing."""

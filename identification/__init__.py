"""Joint axes and DH parameters from tracked link trajectories (paper, Sect. "Kinematic
Parameters Identification"). Not implemented yet: see the project's issues."""

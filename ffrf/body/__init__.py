"""Rotations (Euler parameters), modal moments and the FFRF flexible body with its kernels."""

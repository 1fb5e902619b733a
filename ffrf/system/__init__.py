"""Markers, constraints, joints, drives, the multibody system, its packed kernels and reactions."""

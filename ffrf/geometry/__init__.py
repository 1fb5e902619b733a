"""Parametric link geometry and its gmsh meshing."""

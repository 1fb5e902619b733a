"""Scenes: the scene-file schema and builder, single-loop linkages and their runs."""

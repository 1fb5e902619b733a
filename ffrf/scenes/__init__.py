"""Scenes: the scene-file schema and builder, the paper's Bennett scenes and their runs."""

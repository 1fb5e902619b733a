"""The equivalent Exudyn model of a scene and the cross-validation reports.
Not implemented yet: see the project's issues."""

"""Cross-validation against Exudyn: the equivalent Exudyn model of our scenes, built from one set
of items (:mod:`validation.exudyn_items`, solver settings in :mod:`validation.exudyn_solvers`) for
the single-body scenes (:mod:`validation.reduced_body`, :mod:`validation.single_body_scenes`, their force
elements and loads in :mod:`validation.single_body_forces` and :mod:`validation.exudyn_force_conventions`, run
in :mod:`validation.exudyn_ffrf`), whole systems (:mod:`validation.exudyn_twin`,
:mod:`validation.twin_bases`), the Bennett linkage (:mod:`validation.exudyn_bennett`,
:mod:`validation.bennett_trajectory`, :mod:`validation.exudyn_conventions`) and scene files
(:mod:`validation.exudyn_scene`); mode-by-mode and trajectory-by-trajectory comparisons
(:mod:`validation.modes`, :mod:`validation.bennett_validation`, :mod:`validation.bennett_metrics`; our runs are
:class:`ffrf.output.result.Result` s, Exudyn's :class:`validation.twin_run.TwinRun` s)
and readable reports (:mod:`validation.report`, ``python -m validation``). Exudyn's own regression
models with modal flexible bodies, against the values Exudyn stores: :mod:`validation.testmodels`
(``python -m validation testmodels``). Exudyn is imported lazily; ``ffrf`` never imports it."""

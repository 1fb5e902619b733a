"""Cross-validation against Exudyn: the equivalent Exudyn model of our scenes (the FFRF
pendulum and free body, :mod:`validation.exudyn_ffrf`; the Bennett linkage,
:mod:`validation.exudyn_bennett`), mode-by-mode and trajectory-by-trajectory comparisons
(:mod:`validation.modes`, :mod:`validation.bennett_validation`) and readable reports
(:mod:`validation.report`, ``python -m validation``). Exudyn is imported lazily; ``ffrf``
never imports it."""

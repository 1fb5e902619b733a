"""Tolerance and design studies of many linkages: a study file, its variants, a Dask run and the analysis.

The layer sits above :mod:`ffrf.scenes`: a study names a base linkage (a linkage file or a named base an
application offers, :mod:`ffrf.studies.spec`), its sampled or gridded parameters (:mod:`ffrf.studies.sampling`),
and runs each variant as a whole linkage run (:mod:`ffrf.studies.variant`), on a Dask cluster
(:mod:`ffrf.studies.runner`), then analyses the rows (:mod:`ffrf.studies.sensitivity`,
:mod:`ffrf.studies.report`). Only the runner imports Dask, so ``ffrf`` itself imports without it.
"""

"""The paper's application: the flexible Bennett linkage of ``flexible_bennett_paper.tex``, built on the engine.

Its axes (:mod:`ffrf.paper.axes`), its four simulation variants (rigid, PLA, PLA with the base's twist alpha_3 =
91 or 92 deg) as scenes and as a study's named bases (:mod:`ffrf.paper.bennett_scene`) and the colours of its
figures (:mod:`ffrf.paper.figures`). The layer sits above :mod:`ffrf.studies` and below the command line; nothing
of the engine below it names the paper (``tests/test_architecture/test_engine_knows_no_paper.py``).
"""

from ffrf.paper.bennett_scene import VARIANTS, build_bennett

__all__ = ["VARIANTS", "build_bennett"]

"""Rational Linkages' two 6R models made collision-free with our links at half their unit size:
``collisions_free_6r`` (links 125 to 824 mm; ``collision_free = true`` designs the stacking from the nominal offsets
and from the model's own design, which it refines) and ``plane_fold_6r`` (every two neighbouring axes meet, the loop
folds flat at home; it ships no design: the search finds one whose housings sit far apart along the axes). The links
built on the stacking keep the 1 mm margin on their meshed solids along a revolution, between the checked poses too.
Designed links have the axial gap of ``designed_axial_gap`` (1.5 mm), so that what a joint keeps apart by
construction stays 0.5 mm above the margin, which the check on the solids can prove."""

import numpy as np
import pytest

from ffrf.scenes.collision_free import Stacking
from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.linkage_scene import build_linkage

GAP = 1.5e-3
#: What ``collision_free = true`` designed for each model at scale 0.5 (m; 2026-11-28 on a loaded 2-core Xeon:
#: 314 s and 437 s).
DESIGNED = {
    "collisions_free_6r": {
        "offsets": [-0.06661, 0.241956, -0.002855, -0.226089, -0.212788, 0.243988],
        "spacers": [0.0, 0.001929, 0.00342, 0.007334, 0.004016, 0.000787],
        "orders": [-1, -1, -1, -1, -1, -1],
    },
    "plane_fold_6r": {
        "offsets": [-0.001451, 0.000087, 0.005866, 0.012634, 0.011842, 0.001216],
        "spacers": [0.797513, 0.013029, 0.635336, 0.60999, 0.530736, 0.003448],
        "orders": [1, -1, -1, 1, 1, 1],
    },
}


def _document(model: str, **keys) -> dict:
    return {"linkage": {"model": model, "scale": 0.5, "modes": 1, **keys}}


@pytest.mark.parametrize(
    "model",
    # collisions_free_6r takes 84 s: plane_fold_6r keeps the check in the default suite
    [pytest.param(m, marks=pytest.mark.slow) if m == "collisions_free_6r" else m for m in sorted(DESIGNED)],
)
def test_the_designed_links_keep_the_margin_on_their_solids(model):
    """The stored stacking, checked as every run checks its links (Eqs. (CL1)-(CL4)): every pair keeps 1 mm along
    the whole revolution; the links at the joint points (no design) pass through each other."""
    loop, options, _ = linkage_options(_document(model, stacking=DESIGNED[model], link_design={"axial_gap": GAP}))
    clearance = build_linkage(loop, options).clearance(72, 1e-3)
    assert clearance.margin_met, clearance.summary()
    loop, options, _ = linkage_options(_document(model))
    assert build_linkage(loop, options).clearance(72, 1e-3).distance.min() < 0.0


@pytest.mark.slow
@pytest.mark.parametrize("model", sorted(DESIGNED))
def test_collision_free_designs_them(model):
    """``collision_free = true`` finds a stacking whose capsules keep the margin, and its links keep it on their
    solids."""
    loop, options, _ = linkage_options(_document(model, collision_free=True))
    assert options.design.axial_gap == GAP
    designed = Stacking.from_attach_points(loop, options.attach_points, options.design)
    assert np.all(np.asarray(designed.spacers) >= 0.0)
    clearance = build_linkage(loop, options).clearance(72, 1e-3)
    assert clearance.margin_met, clearance.summary()

"""Rational Linkages' ``collisions_free_6r`` made collision-free with our links at half its size (links 125 to 824 mm):
``collision_free = true`` designs the stacking (from the nominal offsets and from the model's own design, which it
refines), and the links built on it keep the 1 mm margin on their meshed solids along a revolution, between the
checked poses too. The axial gap is 1.5 mm, so that what a joint keeps apart by construction stays 0.5 mm above the
margin, which the check on the solids can prove."""

import numpy as np
import pytest

from ffrf.scenes.collision_free import Stacking
from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.linkage_scene import build_linkage

GAP = 1.5e-3
#: What ``collision_free = true`` designed for this linkage (m; 2026-11-28, 314 s on a loaded 2-core Xeon).
DESIGNED = {
    "offsets": [-0.06661, 0.241956, -0.002855, -0.226089, -0.212788, 0.243988],
    "spacers": [0.0, 0.001929, 0.00342, 0.007334, 0.004016, 0.000787],
    "orders": [-1, -1, -1, -1, -1, -1],
}


def _document(**keys) -> dict:
    return {"linkage": {"model": "collisions_free_6r", "scale": 0.5, "link_design": {"axial_gap": GAP}, **keys}}


def test_the_designed_links_keep_the_margin_on_their_solids():
    """The stored stacking, checked as every run checks its links (Eqs. (CL1)-(CL4)): every pair keeps 1 mm along
    the whole revolution."""
    loop, options, _ = linkage_options(_document(stacking=DESIGNED, modes=1))
    clearance = build_linkage(loop, options).clearance(72, 1e-3)
    assert clearance.margin_met, clearance.summary()


@pytest.mark.slow
def test_collision_free_designs_them():
    """``collision_free = true`` finds a stacking whose capsules keep the margin, and its links keep it on their
    solids."""
    loop, options, _ = linkage_options(_document(collision_free=True, modes=1))
    designed = Stacking.from_attach_points(loop, options.attach_points, options.design)
    assert np.all(np.asarray(designed.spacers) >= 0.0)
    clearance = build_linkage(loop, options).clearance(72, 1e-3)
    assert clearance.margin_met, clearance.summary()

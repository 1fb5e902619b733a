"""The Goldberg 5R that ships with the solver (``examples/goldberg_5r.toml``): Goldberg's DH table, and links that keep
the 1 mm margin along a revolution on their meshed solids."""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from ffrf.scenes.linkage_file import linkage_options
from ffrf.scenes.linkage_scene import build_linkage

EXAMPLE = Path(__file__).parents[2] / "examples" / "goldberg_5r.toml"


@pytest.fixture(scope="module")
def options():
    return linkage_options(tomllib.loads(EXAMPLE.read_text()))[:2]


def test_the_example_is_goldbergs_5r(options):
    """a = (a, b, c, a, b + c), alpha = (alpha, beta, gamma, alpha, beta + gamma), d = 0 with Bennett's condition
    a / sin(alpha) = b / sin(beta) = c / sin(gamma) (Goldberg 1943) for a = 150 mm and 75, 45, 100 deg; it closes
    and has one degree of freedom at home."""
    loop, _ = options
    a = 0.15
    alpha, beta, gamma = np.radians([75.0, 45.0, 100.0])
    b, c = a * np.sin(beta) / np.sin(alpha), a * np.sin(gamma) / np.sin(alpha)
    dh = loop.dh()
    np.testing.assert_allclose(dh.a, [a, b, c, a, b + c], atol=1e-12)
    np.testing.assert_allclose(dh.alpha, [alpha, beta, gamma, alpha, beta + gamma], atol=1e-12)
    np.testing.assert_allclose(dh.d, 0.0, atol=1e-12)
    assert loop.mobility() == 1  # a generic 5R (n - 6 = -1) would not move


def test_its_links_keep_the_margin_on_their_solids(options):
    """The shipped stacking, checked as every run checks its links (signed distance of the meshed solids, bounded
    between poses, Eqs. (CL1)-(CL4)): every pair keeps 1 mm along the whole revolution."""
    loop, linkage = options
    clearance = build_linkage(loop, linkage).clearance(72, 1e-3)
    assert clearance.margin_met, clearance.summary()
    assert min(clearance.distance) >= 1e-3


def test_its_run_verifies_itself(tmp_path):
    """``python -m ffrf run examples/goldberg_5r.toml`` exits 0: joint constraints, loop closure, the energy books
    and the distance to the ideal path within their tolerances, and the links' clearance margin met."""
    from ffrf.cli import main

    assert main(["run", str(EXAMPLE), "--out", str(tmp_path / "out")]) == 0

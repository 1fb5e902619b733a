"""Natural frequencies of a prism against Timoshenko / Euler-Bernoulli / Saint-Venant theory.

Prism 200 x 12 x 8 mm of printed PLA, clamped at x = 0 (all DOFs of that face)
or free-free. Measured (structured meshes, see docs/fe_models.md for the full study):
P2 at h = 4 mm is within 0.5 % (bending) and 1.5 % (torsion) of theory; P1 is
far too stiff in bending (+42 % at h = 4 mm, +14 % at h = 2 mm).
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
import pytest
from test_fe_models.ffrf_reference import (
    classify_mode,
    prism_mesh,
    rectangle_torsion_constant,
    timoshenko_bending_frequencies,
    torsion_frequencies,
)

from ffrf.fe.fe_model import FEModel
from ffrf.fe.materials import PLA
from ffrf.fe.modal import clamped_modes
from ffrf.reduction.free_free import free_free_basis

LENGTH, WIDTH, THICK = 0.2, 0.012, 0.008  # x, y, z
E, NU, RHO = PLA.E, PLA.nu, PLA.rho
AREA = WIDTH * THICK
I_Z_BENDING = WIDTH * THICK**3 / 12  # bending in z (thin direction)
I_Y_BENDING = THICK * WIDTH**3 / 12
G = E / (2 * (1 + NU))
J_TORSION = rectangle_torsion_constant(WIDTH, THICK)
I_POLAR = (WIDTH * THICK**3 + THICK * WIDTH**3) / 12


@functools.cache
def theory(bc):
    """First frequency (Hz) of each mode family from beam theory."""
    return {
        "bend_z": timoshenko_bending_frequencies(E, NU, RHO, AREA, I_Z_BENDING, LENGTH, bc, n=1)[0],
        "bend_y": timoshenko_bending_frequencies(E, NU, RHO, AREA, I_Y_BENDING, LENGTH, bc, n=1)[0],
        "torsion": torsion_frequencies(G, J_TORSION, RHO, I_POLAR, LENGTH, bc, n=1)[0],
    }


def fe_first_frequencies(h, order, bc, n_modes=8):
    points, tets = prism_mesh(LENGTH, WIDTH, THICK, h)
    model = FEModel.from_mesh(points, tets, E, NU, RHO, order=order)
    if bc == "clamped-free":
        clamped = clamped_modes(model, np.flatnonzero(np.repeat(model.nodes[:, 0] < 1e-12, 3)), n_modes)
        frequencies, shapes = clamped.frequencies, clamped.shapes
    else:
        free = free_free_basis(model, n_modes)  # checks that 6 rigid-body modes were left out
        frequencies, shapes = free.frequencies_hz, free.basis
    first = {}
    for i, f in enumerate(frequencies):
        kind = classify_mode(model.nodes, model.mass, shapes[:, i], LENGTH, (WIDTH / 2, THICK / 2))
        first.setdefault(kind, f)
    return first


# --- the reference formulas themselves, against tabulated values -------------------------


def test_reference_reduces_to_euler_bernoulli_tables():
    """Thomson, Theory of Vibration, App. D: beta L = 1.8751, 4.6941 (clamped-free), 4.7300, 7.8532 (free-free)."""
    for bc, beta_l in (("clamped-free", (1.8751, 4.6941)), ("free-free", (4.7300, 7.8532))):
        f = timoshenko_bending_frequencies(E, NU, RHO, AREA, I_Z_BENDING, LENGTH, bc, n=2, shear=False, rotary=False)
        eb = np.array(beta_l) ** 2 / (2 * np.pi * LENGTH**2) * np.sqrt(E * I_Z_BENDING / (RHO * AREA))
        np.testing.assert_allclose(f, eb, rtol=1e-4)


def test_reference_torsion_constants_match_roark():
    """Roark's Formulas for Stress and Strain, Table 10.7 case 4: J = k a b^3, k = 0.141 (a/b = 1), 0.229 (2)."""
    assert rectangle_torsion_constant(1.0, 1.0) == pytest.approx(0.1406, abs=1e-4)
    assert rectangle_torsion_constant(2.0, 1.0) / 2.0 == pytest.approx(0.2287, abs=1e-4)


def test_timoshenko_correction_is_below_euler_bernoulli():
    for bc in ("clamped-free", "free-free"):
        t = timoshenko_bending_frequencies(E, NU, RHO, AREA, I_Y_BENDING, LENGTH, bc, n=1)[0]
        eb = timoshenko_bending_frequencies(E, NU, RHO, AREA, I_Y_BENDING, LENGTH, bc, n=1, shear=False, rotary=False)[
            0
        ]
        assert 0.98 * eb < t < eb


# --- FE against theory ---------------------------------------------------------------------


@pytest.mark.parametrize("bc", ["clamped-free", "free-free"])
def test_p2_matches_beam_theory(bc):
    fe, ref = fe_first_frequencies(0.004, 2, bc), theory(bc)
    errors = {k: fe[k] / ref[k] - 1 for k in ref}
    print(f"P2 h=4mm {bc}: relative errors {errors}")
    assert abs(errors["bend_z"]) < 0.01
    assert abs(errors["bend_y"]) < 0.01
    # Saint-Venant theory ignores the warping restraint of the clamp: FE is slightly stiffer.
    assert 0.0 < errors["torsion"] < 0.025


def test_p1_is_stiff_in_bending_and_converges():
    ref = theory("clamped-free")
    coarse, fine = (fe_first_frequencies(h, 1, "clamped-free") for h in (0.004, 0.002))
    err_coarse = {k: coarse[k] / ref[k] - 1 for k in ref}
    err_fine = {k: fine[k] / ref[k] - 1 for k in ref}
    print(f"P1 clamped-free relative errors: h=4mm {err_coarse}, h=2mm {err_fine}")
    for kind in ("bend_z", "bend_y"):
        assert err_coarse[kind] > 0.2  # locking: P1 tets are much too stiff in bending
        assert 0.0 < err_fine[kind] < err_coarse[kind] / 2  # and converge from above
    assert 0.0 < err_fine["torsion"] < err_coarse["torsion"]


@pytest.mark.slow
@pytest.mark.parametrize("order, h_values", [(1, (0.004, 0.002, 0.001)), (2, (0.004, 0.002))])
def test_convergence_study(order, h_values):
    ref = theory("clamped-free")
    errors = []
    for h in h_values:
        fe = fe_first_frequencies(h, order, "clamped-free")
        errors.append(fe["bend_z"] / ref["bend_z"] - 1)
    print(f"P{order} clamped-free bend_z relative errors at h={h_values}: {errors}")
    assert all(abs(b) < abs(a) for a, b in itertools.pairwise(errors))

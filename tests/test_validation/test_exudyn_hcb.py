"""Exudyn's own Craig-Bampton reduction on our matrices (:func:`validation.modes.exudyn_hcb`), the twin's basis in
every cross-validation: the same on every call. Exudyn's ``ComputeHurtyCraigBamptonModes`` calls SciPy's ``eigsh``
without a start vector, and SciPy then draws one from the operating system's entropy; before
``validation.modes.deterministic_eigsh`` two calls on the same matrices differed in the basis' last digits, and so
every Exudyn number of ``python -m validation summary`` from run to run (1e-15 to 1e-13 relative)."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg
from validation_fixtures import bar

from validation.modes import deterministic_eigsh, exudyn_hcb


def hcb():
    body = bar()
    return exudyn_hcb(body, [body.frame_nodes, body.tip_nodes], [body.frame_weights, body.tip_weights], 4)


def test_exudyns_basis_is_the_same_on_every_call():
    (first, first_hz), (second, second_hz) = hcb(), hcb()
    assert np.array_equal(first, second) and np.array_equal(first_hz, second_hz)
    assert first_hz.size == 4 and np.all(first_hz > 0.0)


def test_scipys_own_eigsh_is_restored_and_a_given_start_is_kept():
    original = scipy.sparse.linalg.eigsh
    stiffness, mass = bar().stiffness[30:, 30:], bar().mass[30:, 30:]
    start = np.ones(stiffness.shape[0])
    with deterministic_eigsh():
        assert scipy.sparse.linalg.eigsh is not original
        ours = scipy.sparse.linalg.eigsh(A=stiffness, k=2, M=mass, sigma=0.0, v0=start)
    assert scipy.sparse.linalg.eigsh is original
    theirs = original(stiffness, k=2, M=mass, sigma=0.0, v0=start)
    assert np.array_equal(ours[0], theirs[0]) and np.array_equal(ours[1], theirs[1])

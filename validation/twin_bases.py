"""What the Exudyn twin needs of each of our bodies (:class:`TwinBody`) and its mode basis: Exudyn's own
Craig-Bampton modes on our nodes, M, K, interface node sets and weights (:func:`validation.modes.exudyn_hcb`), or
ours, and the maps between the two bases' modal coordinates (both span the same space, to 1e-13).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import SceneError
from ffrf.fe.fe_model import FEModel
from ffrf.reduction.craig_bampton import CraigBamptonBasis

__all__ = ["TwinBody", "TwinBasis", "twin_bases", "to_twin_layout"]


@dataclass(frozen=True, eq=False)
class TwinBody:
    """What the twin needs of one of our bodies. ``markers``: our interface markers by interface
    name (their points are the interfaces' weighted centres); ``reduction``: our
    :class:`ffrf.reduction.craig_bampton.CraigBamptonBasis`, interfaces in its order."""

    name: str
    fe: FEModel  # .nodes (N, 3), .mass, .stiffness
    interfaces: dict
    markers: dict
    reduction: CraigBamptonBasis


@dataclass(frozen=True)
class TwinBasis:
    """The mode basis of one body in the twin: Exudyn's own HCB (``source="exudyn"``) or ours."""

    matrix: NDArray[np.float64]  # (3N, m)
    fixed_interface_frequencies_hz: NDArray[np.float64]
    source: str
    setup_s: float
    to_ours: NDArray[np.float64]  # (m, m): our modal coordinates of the same displacement field
    from_ours: NDArray[np.float64]


def _modal_map(mass, source: NDArray, target: NDArray) -> NDArray[np.float64]:
    """Mass-orthogonal projection of span(source) onto target's coordinates, (target^T M target)^-1 target^T M
    source; exact when both span the same space (our and Exudyn's HCB bases do, to 1e-13)."""
    m_target = target.T @ (mass @ target)
    return np.linalg.solve(m_target, target.T @ (mass @ source))


def twin_bases(bodies: list[TwinBody], source: str = "exudyn") -> list[TwinBasis]:
    """Per body of the twin: Exudyn's own HCB modes on our nodes, M, K, interface node sets and weights
    (:func:`validation.modes.exudyn_hcb`), or ``source="ffrf"``: our basis as is."""
    from .modes import exudyn_hcb

    if source not in ("exudyn", "ffrf"):
        raise ValueError(f"basis source must be 'exudyn' or 'ffrf', got {source!r}")
    out = []
    for body in bodies:
        if not isinstance(body.reduction, CraigBamptonBasis):
            raise SceneError(
                f"body {body.name!r}: the Exudyn twin of a scene rebuilds Craig-Bampton bases; use reduction = "
                '"craig_bampton" here (free-free bodies are cross-validated by `python -m validation testmodels`)'
            )
        ours = np.asarray(body.reduction.basis)
        frequencies_ours = body.reduction.fixed_interface_frequencies_hz
        if source == "ffrf":
            eye = np.eye(ours.shape[1])
            out.append(TwinBasis(ours, frequencies_ours, "ffrf", 0.0, eye, eye))
            continue
        started = time.perf_counter()
        itfs = list(body.interfaces.values())
        basis, frequencies = exudyn_hcb(
            body.fe, [i.nodes for i in itfs], [i.weights for i in itfs], frequencies_ours.size
        )
        elapsed = time.perf_counter() - started
        out.append(
            TwinBasis(
                basis,
                np.sort(frequencies),
                "exudyn",
                elapsed,
                _modal_map(body.fe.mass, basis, ours),
                _modal_map(body.fe.mass, ours, basis),
            )
        )
    return out


def to_twin_layout(system, q: NDArray, bases: list[TwinBasis] | None) -> NDArray[np.float64]:
    """Our coordinates with each body's modal part in the twin's basis."""
    q = np.array(q, dtype=float)
    if bases is None:
        return q
    for k, basis in enumerate(bases):
        block = system.block(k)
        q[..., block.start + 7 : block.stop] = q[..., block.start + 7 : block.stop] @ basis.from_ours.T
    return q

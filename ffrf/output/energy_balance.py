"""The energy balance of a driven run: the drive's work against the changes of kinetic, gravity and
strain energy plus the damping dissipation. A residual that stays small is the check that the run
conserved what it should (``docs/formulation.md``: the work of the constraint forces of passive
joints vanishes, so only the drive does work).

Where a quasi-static path jumps between two equilibria with none between them (a contact letting go, a snap), the
books are kept on each stretch apart: the energy the jump releases (the work done across it less the rise of the
stored energy) is counted as dissipated, as damping takes it in the real linkage, and a jump must release energy,
not gain it (Eq. (C2))."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import cumulative_simpson

from ffrf.system.forces import assembled_forces
from ffrf.system.multibody import MultibodySystem

__all__ = [
    "cumulative_integral",
    "element_work",
    "stretch_integral",
    "energy_balance",
    "energy_scale",
    "relative_balance",
    "work_quadrature_error",
]


def cumulative_integral(values: NDArray, x: NDArray) -> NDArray[np.float64]:
    """Cumulative Simpson integral (fourth order for smooth samples; trapezoid below 3 samples)."""
    if len(x) < 3:
        return np.concatenate([[0.0], np.cumsum(0.5 * (values[1:] + values[:-1]) * np.diff(x))])
    return cumulative_simpson(values, x=x, initial=0.0)


def stretch_integral(values: NDArray, x: NDArray, jumps: Sequence[int] = ()) -> NDArray[np.float64]:
    """:func:`cumulative_integral` on each stretch between ``jumps`` (rows i where the samples jump from row i to
    i + 1) apart, a trapezoid across each jump: no polynomial through samples on both sides of a jump."""
    out = np.zeros(len(x))
    starts = [0, *(i + 1 for i in jumps)]
    ends = [*(i + 1 for i in jumps), len(x)]
    carried = 0.0
    for start, end in zip(starts, ends, strict=True):
        out[start:end] = carried + cumulative_integral(values[start:end], x[start:end])
        carried = float(out[end - 1])
        if end < len(x):
            carried += 0.5 * float(values[end - 1] + values[end]) * float(x[end] - x[end - 1])
    return out


def element_work(system: MultibodySystem, time: NDArray, q: NDArray, qd: NDArray | None) -> NDArray[np.float64]:
    """Work done on the bodies by the force elements (Eqs. (E1)-(E5), (P3)) since the first row: a conservative
    element's (a spring, a contact without damper) is the decrease of its stored energy, exactly; the others' the
    integral of ``Q_e . qd`` over time (dynamic runs), or of ``Q_e . dq`` along the path (quasi-static, ``qd`` None;
    trapezoids): dampers take, loads and motors add."""
    work = np.zeros(len(time))
    rates = np.zeros_like(q) if qd is None else qd
    integrated = [element for element in system.forces if not element.conservative]
    for element in system.forces:
        if element.conservative:
            stored = np.array(
                [
                    element.potential_energy([row[system.block(i)] for i in element.bodies], float(t))
                    for t, row in zip(time, q, strict=True)
                ]
            )
            work -= stored - stored[0]
    if not integrated:
        return work
    forces = np.array(
        [
            assembled_forces(tuple(integrated), system.offsets, row, rate, float(t))
            for t, row, rate in zip(time, q, rates, strict=True)
        ]
    )
    forces = np.real(forces)
    if qd is not None:
        return work + cumulative_integral(np.einsum("ij,ij->i", forces, qd), time)
    steps = np.einsum("ij,ij->i", 0.5 * (forces[1:] + forces[:-1]), np.diff(q, axis=0))
    return work + np.concatenate([[0.0], np.cumsum(steps)])


def energy_balance(
    system: MultibodySystem,
    time: NDArray,
    sensors: dict[str, NDArray],
    qd: NDArray | None,
    q: NDArray | None = None,
    jumps: Sequence[int] = (),
) -> dict[str, NDArray]:
    """Work of the drive (integral of ``driving_torque`` over ``drive_angle``), damping dissipation
    (integral of zetad^T D zetad over time; none for quasi-static runs, ``qd`` None) and the balance
    residual W - (dE_kin + dE_pot + dE_strain + D + R), from the rows of ``sensors`` (``energy_kinetic``,
    ``energy_potential``, ``energy_strain``); with force elements (and ``q``) W includes their work
    (:func:`element_work`, ``energy_elements_work``). ``jumps``: rows i of a quasi-static path that jumps from row i
    to i + 1; R (``energy_released_in_jumps``) sums what each released (module docstring). ``energy_work_error``:
    the drive's work by trapezoids less that by Simpson's rule, the estimate of its quadrature error."""
    torque, angle = sensors["driving_torque"], sensors["drive_angle"]
    work = stretch_integral(torque, angle, jumps)
    if qd is None:
        dissipated = np.zeros_like(work)
    else:
        blocks = [system.block(k) for k in range(len(system.bodies))]
        rate = np.array(
            [
                sum(float(v[b][7:] @ body.damping @ v[b][7:]) for b, body in zip(blocks, system.bodies, strict=True))
                for v in qd
            ]
        )
        dissipated = cumulative_integral(rate, time)
    stored = sum(
        sensors[f"energy_{kind}"] - sensors[f"energy_{kind}"][0] for kind in ("kinetic", "potential", "strain")
    )
    trapezoids = np.concatenate([[0.0], np.cumsum(0.5 * (torque[1:] + torque[:-1]) * np.diff(angle))])[: len(work)]
    out = {"energy_drive_work": work, "energy_dissipated": dissipated, "energy_work_error": np.abs(work - trapezoids)}
    if system.forces and q is not None:
        out["energy_elements_work"] = element_work(system, time, q, qd)
        work = work + out["energy_elements_work"]
    unreleased = work - stored - dissipated
    released = np.zeros_like(unreleased)
    for i in jumps:
        released[i + 1 :] += unreleased[i + 1] - unreleased[i]
    out["energy_released_in_jumps"] = released
    out["energy_balance_residual"] = unreleased - released
    return out


def energy_scale(sensors: dict[str, NDArray], floor: float = 0.0) -> float:
    r"""The energy a run moves (J), the scale its balance is judged against (Eq. (C2) of ``docs/formulation.md``):
    the largest of the drive's absolute work :math:`\int |\tau\, d\theta|` (trapezoids over the rows), the force
    elements' (the sum of the magnitudes of their work's increments), the dissipated energy (by damping, in jumps)
    and the ranges of the kinetic, potential and strain energies, and ``floor``. Unlike the drive's net work it is
    not zero where the drive does no net work, and it is zero only where nothing moves at all."""
    terms = [floor]
    if "driving_torque" in sensors and len(sensors["driving_torque"]) > 1:
        torque, angle = sensors["driving_torque"], sensors["drive_angle"]
        terms.append(float(np.sum(np.abs(0.5 * (torque[1:] + torque[:-1]) * np.diff(angle)))))
    if "energy_elements_work" in sensors:
        terms.append(float(np.sum(np.abs(np.diff(sensors["energy_elements_work"])))))
    for kind in ("dissipated", "released_in_jumps"):
        if f"energy_{kind}" in sensors:
            terms.append(float(np.max(np.abs(sensors[f"energy_{kind}"]))))
    for kind in ("kinetic", "potential", "strain"):
        if f"energy_{kind}" in sensors:
            terms.append(float(np.ptp(sensors[f"energy_{kind}"])))
    return max(terms)


def relative_balance(residual: NDArray, scale: float) -> float:
    """``max |residual| / scale``; where the scale is zero (nothing moved) 0 for a zero residual, else infinity:
    never the 0/0 of a residual relative to a drive that does no work."""
    largest = float(np.max(np.abs(residual))) if len(residual) else 0.0
    if scale > 0.0:
        return largest / scale
    return 0.0 if largest == 0.0 else float("inf")


def work_quadrature_error(sensors: dict[str, NDArray]) -> float:
    """An estimate (J) of the error of the drive's work integrated over the output rows: the largest difference,
    over the rows, between the cumulative Simpson integral the balance uses and trapezoids (which bounds the
    trapezoids' error, and Simpson's, fourth order, generously; ``energy_work_error`` where the balance kept it,
    on the stretches between jumps); 0 without a drive."""
    if "energy_work_error" in sensors:
        return float(np.max(sensors["energy_work_error"], initial=0.0))
    if "driving_torque" not in sensors or len(sensors["driving_torque"]) < 3:
        return 0.0
    torque, angle = sensors["driving_torque"], sensors["drive_angle"]
    trapezoids = np.concatenate([[0.0], np.cumsum(0.5 * (torque[1:] + torque[:-1]) * np.diff(angle))])
    return float(np.max(np.abs(cumulative_integral(torque, angle) - trapezoids)))

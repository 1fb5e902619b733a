r"""Static equilibrium: Newton on the constrained static equations, with load continuation.

With :math:`\dot q = \ddot q = 0` the quadratic velocity vector vanishes and the body
residual reduces to elastic and gravity forces (``docs/formulation.md``, Eq. (S1)):

.. math:: K_r\zeta - Q_g(q) + C_q^T\lambda = 0,\qquad g(q, t) = 0,

solved by Newton with the exact tangent :math:`[K_t + H,\ C_q^T;\ C_q,\ 0]`. Gravity can be
applied in ``load_steps`` increments (load continuation); each increment starts from the
previous equilibrium. A singular tangent means the system can still move freely (a
mechanism or an unconstrained body): the error says so and names the remedy.

Quasi-static sequences start each Newton solve from the polynomial through the last equilibria
(Eq. (S2)); Broyden's secant updates of the kept tangent between refactorisations (Eq. (S3)) are
an option, off by default (see :func:`quasi_static`). A step whose correction leaves the path (Eq. (S4)) is
halved and its rest predicted along the path's tangent. These change the iterates, not the equations solved.
"""

from __future__ import annotations

import itertools
import logging
import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import Interrupted, StaticDivergence
from ffrf.numerics.rank_revealing import FactoredMatrix, factor
from ffrf.solvers.common import PathJump, StaticSolution, extrapolation_weights
from ffrf.solvers.newton_kernels import CONVERGED, NOT_FINITE, REFACTOR, static_iterations, static_rhs, static_update
from ffrf.solvers.pseudo_transient import settle
from ffrf.system.multibody import MultibodySystem
from ffrf.system.packed_system import PackedSystem, contiguous, newton_model

__all__ = [
    "StaticDivergence",
    "StaticSolution",
    "path_rate",
    "path_times",
    "quasi_static",
    "refined_times",
    "residual_rate",
    "static_equilibrium",
    "tangent_at",
]

log = logging.getLogger(__name__)


def _factor_tangent(model: MultibodySystem | PackedSystem, q: NDArray, lam: NDArray, t: float) -> FactoredMatrix:
    """Eq. (S1)'s tangent [K_t + H, C_q^T; C_q, 0], factored by the rank rule of Eq. (R1).

    A singular tangent (free motions of a mechanism, redundant constraints, the folded poses of a
    near-rigid Bennett loop) is solved by its truncated pseudo-inverse: the minimum-norm Newton
    step still converges there."""
    zeros = np.zeros(model.n_coordinates)
    matrix = model.iteration_matrix(q, zeros, zeros, lam, t, 0.0, 1.0, 0.0)
    try:
        tangent = factor(matrix, what=f"static tangent at t = {t:g}")
    except FloatingPointError as error:
        raise StaticDivergence(f"{error}; check the model's stiffness and the start") from error
    if tangent.rank_deficiency:
        log.debug(
            "static tangent has %d free motion(s) at t = %g; using its pseudo-inverse", tangent.rank_deficiency, t
        )
    return tangent


def tangent_at(model: MultibodySystem | PackedSystem, q: NDArray, lam: NDArray, t: float) -> FactoredMatrix:
    """The static tangent of Eq. (S1) at ``(q, lam)`` and time ``t``, factored as Newton factors it (rank rule (R1)):
    what :mod:`ffrf.solvers.equilibrium_sensitivity` solves with."""
    return _factor_tangent(model, q, lam, t)


class _Secant:
    r"""Broyden's ("good") secant updates of a kept tangent, Eq. (S3), in the product form of
    Kelley (1995, Alg. 7.3.1 ``brsol``): the updated inverse is never formed, only the steps
    taken since the last refactorisation are stored. Inner products are taken in the
    equilibrated unknowns (``weights = 1 / cols^2``) so that lengths and forces mix sensibly."""

    _RESTART = 1e-2  # |1 - s_n.z / s_n.s_n| below this: the update is nearly singular, start over
    _MEMORY = 20  # steps kept before the memory restarts (each costs two dot products per iteration)

    def __init__(self, weights: NDArray):
        self.weights = weights
        self.steps: list[NDArray] = []

    def step(self, newton_step: NDArray) -> NDArray:
        """The Broyden step from the kept tangent's step ``-H_0 F(x)``; the result is remembered."""
        z = newton_step
        steps, w = self.steps, self.weights
        if steps:
            for s_j, s_next in itertools.pairwise(steps):
                z = z + s_next * ((w * s_j) @ z) / ((w * s_j) @ s_j)
            s_n = steps[-1]
            denominator = 1.0 - ((w * s_n) @ z) / ((w * s_n) @ s_n)
            if abs(denominator) < self._RESTART or len(steps) >= self._MEMORY:
                steps.clear()
                z = newton_step
            else:
                z = z / denominator
        steps.append(z)
        return z


def _not_converged(increments: list[float], gap: float, tolerance: float, advice: str) -> StaticDivergence:
    """The error for Newton out of iterations. Converging (the increments shrink, on average by
    0.7 or better per iteration): more iterations would do, and the message estimates how many at
    the mean rate. Otherwise the start or the load path must change (``advice``, the caller's remedy)."""
    first, last = increments[0], increments[-1]
    n = len(increments)
    rate = (last / first) ** (1.0 / (n - 1)) if n >= 2 and first > 0.0 else 1.0
    if rate < 0.7 and last < increments[-2]:
        more = int(np.ceil(np.log(tolerance / last) / np.log(rate))) if last > tolerance else 1
        return StaticDivergence(
            "static Newton was converging but ran out of iterations: "
            f"the increment fell from {first:.3e} to {last:.3e} "
            f"in {n} iterations (x{rate:.2f} per iteration; tolerance {tolerance:.1e}, constraint residual {gap:.3e}); "
            f"raise max_iterations (about {more} more at this rate), or loosen the tolerance if the increments stall "
            "at round-off"
        )
    return StaticDivergence(
        f"static Newton did not converge in {n} iterations: increments {first:.3e} first, {last:.3e} last, "
        f"constraint residual {gap:.3e}; {advice}"
    )


def _static_rhs(model: MultibodySystem | PackedSystem, q: NDArray, lam: NDArray, t: float, iteration: int):
    """Eq. (S1)'s right-hand side ``-[r; g]`` at ``(q, lam)`` and ``g``; a residual that is not finite stops
    Newton at ``iteration``."""
    zeros = np.zeros(model.n_coordinates)
    residual, gap = model.residual(q, zeros, zeros, lam, t)
    rhs, finite = static_rhs(residual, gap)
    if not finite:
        raise StaticDivergence(f"NaN in the static residual (iteration {iteration}); check the model and the start")
    return rhs, gap


#: Iterations without a new smallest increment after which Newton gives up in a system with contacts that separate:
#: where a contact with play switches within the step, the iterates cycle between contact states, and the step is
#: halved (Eq. (S4)) sooner than after every iteration allowed. (Without such contacts Newton may wander longer from
#: a far start and still converge: the two-bar chain from a stretched start, 7 iterations before its first new
#: smallest increment.)
STALLED_ITERATIONS = 6


def _separating_contacts(model: MultibodySystem | PackedSystem) -> bool:
    """Whether the model has force elements whose contacts separate (joints with play); a model that says nothing of
    its force elements (a packed system without its source, a stand-in of the tests) has none."""
    system = model.source() if isinstance(model, PackedSystem) else model
    return any(getattr(element, "separates", False) for element in getattr(system, "forces", ()))


def _newton(
    model: MultibodySystem | PackedSystem,
    q: NDArray,
    lam: NDArray,
    t: float,
    tolerance: float,
    max_iterations: int,
    tangent: FactoredMatrix | None = None,
    secant: bool = False,
    advice: str = "start closer to the equilibrium",
):
    """Newton from ``(q, lam)``; with a ``tangent`` from an earlier solve it starts as modified
    Newton and refactors whenever an iteration contracts the increment by less than a half.
    ``secant``: Broyden-update the kept tangent (Eq. (S3)) and refactor only when an increment
    grows (a secant step need not contract monotonically). ``advice`` ends the error message
    when Newton diverges or stalls (with contacts that separate, :data:`STALLED_ITERATIONS` without a new smallest
    increment). On the fast path
    (no force elements, hence no contacts) the iterations between factorisations of a regular tangent run in one
    kernel (:func:`ffrf.solvers.newton_kernels.static_iterations`, the same steps and tests)."""
    previous = np.inf
    smallest, stalled, may_stall = np.inf, 0, _separating_contacts(model)
    increments = np.empty(max_iterations)
    free_motions = 0
    updates = None
    refactor_above = 1.0 if secant else 0.5
    gap_max = np.inf
    iteration = 0
    while iteration < max_iterations:
        rhs = None
        if tangent is None:  # a tangent is factored only where the residual is finite
            rhs, gap = _static_rhs(model, q, lam, t, iteration + 1)
            tangent = _factor_tangent(model, q, lam, t)
            free_motions = max(free_motions, tangent.rank_deficiency)
            updates = None
        if isinstance(model, PackedSystem) and not model.forces and not secant and tangent.factors is not None:
            lu, pivots = tangent.factors
            status, used, q, lam, gap_max = static_iterations(
                model.bodies,
                model.joints,
                model.gravity,
                model.phi(t),
                tangent.rows,
                tangent.cols,
                lu,
                pivots,
                contiguous(q),
                contiguous(lam),
                float(tolerance),
                refactor_above,
                float(previous),
                increments,
                iteration,
            )
            iteration += used
            if status == NOT_FINITE:
                raise StaticDivergence(
                    f"NaN in the static residual (iteration {iteration}); check the model and the start"
                )
            if status == CONVERGED:
                return q, lam, iteration, tangent
            if status == REFACTOR:
                tangent = None
            previous = increments[iteration - 1]
            continue
        iteration += 1
        if rhs is None:
            rhs, gap = _static_rhs(model, q, lam, t, iteration)
        delta = tangent.solve(rhs)
        if secant and tangent.factors is not None:  # a pseudo-inverse (singular tangent) is used as is
            if updates is None:
                updates = _Secant(1.0 / tangent.cols**2)
            delta = updates.step(delta)
        # Multipliers of (nearly) redundant constraints, as in near-rigid closed loops, are fixed only to
        # round-off; once the positions stop changing at machine precision, further iterations cannot help.
        q, lam, increment, converged = static_update(q, lam, delta, gap, tolerance)
        increments[iteration - 1] = increment
        gap_max = float(np.abs(gap).max())
        if converged:
            return q, lam, iteration, tangent
        smallest, stalled = (increment, 0) if increment < smallest else (smallest, stalled + 1)
        if may_stall and stalled >= STALLED_ITERATIONS:
            break
        if increment > refactor_above * previous:
            tangent = None
        previous = increment
    if free_motions:
        raise StaticDivergence(
            f"the static tangent is singular ({free_motions} free motion(s)) and Newton found no equilibrium: the "
            "system is a mechanism or a body is not held; prescribe the drive or add the missing support"
        )
    raise _not_converged(list(increments[:iteration]), gap_max, tolerance, advice)


#: Halvings of one gravity increment of :func:`static_equilibrium` before the equilibrium is declared out of reach.
MAX_LOAD_HALVINGS = 6


def static_equilibrium(
    system: MultibodySystem,
    q0: NDArray,
    t: float = 0.0,
    load_steps: int = 1,
    tolerance: float = 1e-10,
    max_iterations: int = 25,
    *,
    fast_path: bool = True,
) -> StaticSolution:
    """Equilibrium near ``q0`` at time ``t`` (for prescribed motions), gravity in ``load_steps`` increments.
    An increment whose Newton solve fails is halved, from the last equilibrium, up to :data:`MAX_LOAD_HALVINGS`
    times (a structure that sags far under its weight: the undeformed pose is outside Newton's reach of the loaded
    equilibrium), and doubled again after each increment that converges, up to ``1/load_steps``; ``iterations``
    has one entry per converged increment.
    ``fast_path``: Newton with the whole-system kernels when the system is supported
    (:func:`ffrf.system.packed_system.newton_model`); the same solution to round-off."""
    if load_steps < 1:
        raise ValueError(f"load_steps must be >= 1, got {load_steps}")
    q = np.array(q0, dtype=float)
    lam = np.zeros(system.n_constraints)
    counts = []
    # The load in integer units (each step's fraction exact, as k / load_steps was before any halving)
    units = load_steps * 2**MAX_LOAD_HALVINGS
    done, halvings = 0, 0
    advice = f"apply gravity in more load_steps (now {load_steps}) or start closer to the equilibrium"
    while done < units:
        reached = min(units, done + 2 ** (MAX_LOAD_HALVINGS - halvings))
        target, loaded = reached / units, done / units
        scaled = replace(system, gravity=system.gravity * target)
        try:
            q_new, lam_new, iterations, _ = _newton(
                newton_model(scaled, fast_path), q, lam, t, tolerance, max_iterations, advice=advice
            )
        except StaticDivergence as error:
            if halvings == MAX_LOAD_HALVINGS:
                raise StaticDivergence(
                    f"{error} (gravity at {target:.4g} of its value, after {MAX_LOAD_HALVINGS} halvings of the load "
                    f"step from {loaded:.4g})"
                ) from error
            halvings += 1
            log.info("gravity step to %.4g of its value failed; halved (%d of %d)", target, halvings, MAX_LOAD_HALVINGS)
            continue
        q, lam, done = q_new, lam_new, reached
        counts.append(iterations)
        halvings = max(0, halvings - 1)
        log.debug("gravity at %.4g of its value: converged in %d iterations", target, iterations)
    return StaticSolution(q, lam, tuple(counts))


_PATH_ADVICE = (
    "the step was already halved 8 times, so the equilibrium path may end here (a limit point, or a "
    "drive that leaves the assembled branch): check the prescribed motion's range and the misfit"
)
_START_ADVICE = "the start is not near an equilibrium at this time: assemble it first"

#: Largest Newton correction of an accepted quasi-static step, as a fraction of the predicted step (Eq. (S4)).
#: A correction larger than the step itself means Newton left the path the predictor followed, typically for
#: another equilibrium branch through a nearby bifurcation (a flat-folded 6R's home pose).
MAX_CORRECTION = 0.5
#: Halvings of one quasi-static step before the path is declared ended.
MAX_HALVINGS = 8
#: Parts one quasi-static step may be done in (each a halved step that converged).
MAX_PARTS = 64
#: The same where contacts separate (joints with play): the path may crawl from contact switch to contact switch,
#: each part a few 1/256 of the step (the PLA Bennett's 1 deg print with 0.1 mm of play took more than 64 parts
#: for one path step at 98 deg of drive).
MAX_PARTS_WITH_PLAY = 1024
#: Jumps (Eq. (P6)) within one path step: one per shortest step at most.
MAX_JUMPS = 2**MAX_HALVINGS


class _Path:
    """The equilibria found so far, newest last, and the polynomial predictor through them (Eq. (S2))."""

    def __init__(self, t: float, q: NDArray, lam: NDArray, order: int):
        self.times, self.q, self.lam, self.order = [t], [q], [lam], order
        self.jumps: list[PathJump] = []

    def predict(self, t: float) -> tuple[NDArray, NDArray] | None:
        """Extrapolated ``(q, lam)`` at ``t`` from the last ``order + 1`` equilibria; ``None`` from one."""
        known = min(self.order + 1, len(self.times))
        if known < 2:
            return None
        weights = extrapolation_weights(np.array(self.times[-known:]), t)
        return weights @ np.asarray(self.q[-known:]), weights @ np.asarray(self.lam[-known:])

    def add(self, t: float, q: NDArray, lam: NDArray) -> None:
        self.times.append(t)
        self.q.append(q)
        self.lam.append(lam)
        del self.times[: -(self.order + 1)], self.q[: -(self.order + 1)], self.lam[: -(self.order + 1)]

    def restart(self, t: float, q: NDArray, lam: NDArray) -> None:
        """The path starts again at ``(t, q, lam)``: it jumped there, and no polynomial reaches across a jump."""
        self.jumps.append(PathJump(self.times[-1], self.q[-1], self.lam[-1], t, q, lam))
        self.times, self.q, self.lam = [t], [q], [lam]


def _path_departure(q: NDArray, predicted: NDArray, previous: NDArray, tolerance: float) -> tuple[float, float] | None:
    """Eq. (S4): ``(correction, predicted step)`` when Newton's correction from the prediction exceeds
    :data:`MAX_CORRECTION` of the predicted step (the step left the path), else ``None``."""
    correction, step = float(np.abs(q - predicted).max()), float(np.abs(predicted - previous).max())
    if correction <= MAX_CORRECTION * step + tolerance * max(1.0, float(np.abs(q).max())):
        return None
    return correction, step


def residual_rate(model: MultibodySystem | PackedSystem, q: NDArray, lam: NDArray, t: float) -> NDArray[np.float64]:
    """F_t of Eq. (S1)'s residual F = [r; g] at fixed ``(q, lam)``: a central difference in t (step
    ``1e-6 max(1, abs(t))``), as the time laws are user functions (Eqs. (S4), (S5))."""
    zeros = np.zeros(model.n_coordinates)
    h = 1e-6 * max(1.0, abs(t))
    ahead, behind = model.residual(q, zeros, zeros, lam, t + h), model.residual(q, zeros, zeros, lam, t - h)
    return (np.concatenate(ahead) - np.concatenate(behind)) / (2.0 * h)


def path_rate(model: MultibodySystem | PackedSystem, q: NDArray, lam: NDArray, t: float) -> tuple[NDArray, NDArray]:
    """The path's rate ``(dq/dt, dlambda/dt)`` at the equilibrium ``(q, lam, t)``: ``F_y y_t = -F_t`` with Eq. (S1)'s
    tangent F_y factored there (Eqs. (S4), (S5))."""
    rate = _factor_tangent(model, q, lam, t).solve(-residual_rate(model, q, lam, t))
    return rate[: model.n_coordinates], rate[model.n_coordinates :]


def _advance(model, path: _Path, t_to: float, tolerance: float, max_iterations: int, tangent, secant: bool):
    """Equilibrium at ``t_to`` from the path's newest one; a step that fails to converge or leaves the path
    (Eq. (S4)) is retried without secant updates, then halved, up to :data:`MAX_HALVINGS` times, each
    part predicted from the equilibria before it (Eq. (S2)); once a try left the path, the rest of the step is
    predicted along the path's tangent at its last equilibrium instead (Eq. (S4)). A step that still fails where a
    contact with play lets go jumps to the settled pose at the shortest step tried (:func:`_jump`) and goes on from
    there. Returns the Newton iterations spent and the kept tangent."""
    iterations, halvings, t_from, parts, jumps = 0, 0, path.times[-1], 0, 0
    max_parts = MAX_PARTS_WITH_PLAY if _separating_contacts(model) else MAX_PARTS
    failure: StaticDivergence | None = None
    # (t, dq/dt, dlambda/dt) at the path's last equilibrium, once a try left the path: a polynomial through
    # equilibria a whole step apart misses the path by a fixed fraction of any shorter step (Eq. (S4))
    along: tuple[float, NDArray, NDArray] | None = None
    left_path = False
    while True:
        t_try = t_from + (t_to - t_from) / 2.0**halvings
        if t_try == t_from or parts >= max_parts:
            # Halved steps that keep converging ever closer to t_to without reaching it: a limit point at t_to.
            raise StaticDivergence(
                f"the steps towards t = {t_to:.9g} s shrink without reaching it ({parts} parts, the last at "
                f"t = {t_from:.9g} s); {_PATH_ADVICE}"
            )
        q, lam = path.q[-1], path.lam[-1]
        predicted: tuple[NDArray, NDArray] | None
        if left_path:
            if along is None or along[0] != t_from:
                along = (t_from, *path_rate(model, q, lam, t_from))
            predicted = (q + (t_try - t_from) * along[1], lam + (t_try - t_from) * along[2])
        elif tangent is not None and tangent.rank_deficiency:
            # a free motion (a pin's rotation in its bore) is fixed by nothing but round-off: a polynomial through
            # equilibria would extrapolate its drift, so the step starts from the last equilibrium
            predicted = None
        else:
            predicted = path.predict(t_try)
        q_guess, lam_guess = (q, lam) if predicted is None else predicted
        attempts = [(tangent, secant)] + ([(None, False)] if secant else [])
        advice = _PATH_ADVICE if halvings >= MAX_HALVINGS else _START_ADVICE
        for kept, use_secant in attempts:
            try:
                q_new, lam_new, count, tangent = _newton(
                    model, q_guess, lam_guess, t_try, tolerance, max_iterations, kept, use_secant, advice
                )
            except StaticDivergence as error:
                failure = error
                continue
            iterations += count
            # A prediction through fewer than three equilibria is O(dt^2) off, as large as the step on a drive's
            # ramp from rest; Eq. (S4) judges only quadratic ones.
            departure = (
                None if predicted is None or len(path.times) < 3 else _path_departure(q_new, predicted[0], q, tolerance)
            )
            if departure is None:
                failure = None
                break
            left_path = True
            failure = StaticDivergence(
                f"Newton's correction {departure[0]:.3g} from the predicted state exceeds half the predicted step "
                f"{departure[1]:.3g} at t = {t_try:.6g} s (Eq. (S4)): the path turns sharper than the steps follow, "
                f"or another equilibrium branch crosses it; {advice}"
            )
        if failure is None:
            path.add(t_try, q_new, lam_new)
            if t_try == t_to:
                return iterations, tangent
            t_from, halvings, parts = t_try, 0, parts + 1  # the rest of the step, whole again
            continue
        if halvings >= MAX_HALVINGS or t_try == t_from:
            t_from, spent = _jump(model, path, t_to, tolerance, failure)
            iterations += spent
            # a jump is no part: a path that slides from contact switch to contact switch may need a jump per
            # shortest step (MAX_JUMPS), which the bound on parts would cut short
            jumps += 1
            if jumps > MAX_JUMPS:
                raise failure
            halvings, tangent, along, left_path = 0, None, None, False
            if t_from == t_to:
                return iterations, None
            continue
        halvings += 1
        tangent = None
        log.debug("quasi-static step %g -> %g halved", t_from, t_try)


#: Pseudo-transient iterations a jump's settling may take at one time before it tries a step twice as long: the
#: loose PLA Bennett with 0.2 mm of play, where a pin rolls round its bore as the load through it turns, settles in
#: 170 to 410 (measured at 11.05 s of its path, from 1/256 of a path step to the whole step).
JUMP_ITERATIONS = 600


def _jump(model, path: _Path, t_end: float, tolerance: float, failure: StaticDivergence) -> tuple[float, int]:
    """Where a contact with play lets go (a pin crossing its bore as the load through it reverses), the path has no
    equilibria between its last one and a pose on the far side: settle there (Eq. (P6)) at the shortest step tried,
    or, where the pins rest on the edge of a contact there, at a step twice as long, up to ``t_end``; the path
    starts again from the settled equilibrium. Returns the time it settled at and the iterations; raises
    ``failure`` for a system without such contacts, or when no settling succeeds."""
    system = model if isinstance(model, MultibodySystem) else model.source()
    if system is None or not _separating_contacts(system):
        raise failure
    t_from = path.times[-1]
    tries = [t_from + (t_end - t_from) / 2.0**k for k in range(MAX_HALVINGS, -1, -1)]
    for t_to in tries:
        try:
            settled = settle(system, path.q[-1], t_to, tolerance, max_iterations=JUMP_ITERATIONS)
        except StaticDivergence as error:
            last = error
            log.debug("settling at t = %.9g s failed: %s", t_to, error)
            continue
        log.info("the path jumps between t = %.9g s and %.9g s: a contact let go (Eq. (P6))", t_from, t_to)
        path.restart(t_to, settled.q, settled.multipliers)
        return t_to, settled.iterations[0]
    raise failure from last


def quasi_static(
    system: MultibodySystem,
    q0: NDArray,
    times: NDArray,
    tolerance: float = 1e-10,
    max_iterations: int = 25,
    progress=None,
    *,
    fast_path: bool = True,
    predictor_order: int = 4,
    secant: bool = False,
    max_step: float | None = None,
    path_step: Callable[[float], float] | None = None,
    path_breaks: tuple[float, ...] = (),
) -> StaticSolution:
    """A sequence of static equilibria at ``times`` (prescribed motions follow their time laws;
    no inertia). Returns ``q`` and ``multipliers`` with one row per time (``iterations`` per time).
    With ``max_step`` (s) the path is followed through intermediate equilibria at most that far apart
    (not returned): long steps can let Newton reach an equilibrium of another assembly branch.
    ``fast_path`` as in :func:`static_equilibrium`. Newton starts from the polynomial of degree
    ``predictor_order`` through the last equilibria (Eq. (S2); 0: the previous equilibrium), and a
    step whose correction leaves the predicted path (Eq. (S4)) is halved, its rest predicted along the path's
    tangent. With ``secant``, Newton
    Broyden-updates the kept tangent (Eq. (S3)). ``secant`` is off by default:
    on long steps (60 deg of drive between equilibria, coarse Bennett links) its updates led
    Newton to a wrong equilibrium (driving torque -16.5 N m instead of 0.018 N m) that plain
    modified Newton does not reach; on fine steps it saves about a fifth of the time. A failed step raises
    :class:`StaticDivergence` whose ``partial`` holds the equilibria at the ``times`` reached before it, and so does
    the :class:`Interrupted` a ``progress`` callback raises.

    With ``path_step`` (the longest path step from a time, s; e.g. Eq. (S10)) the path is followed on its own times
    (:func:`path_times`, ``max_step`` ignored) and each output is solved from the path's polynomial through the
    equilibria around it (Eq. (S2)), never becoming a path point: the equilibria and where the path stops do not
    depend on the outputs. A path that stops then ends the partial result with its last equilibrium (``times``).
    ``path_breaks``: times where the time laws have kinks (a load table's corners); each is a path point where the
    predictor starts again."""
    if predictor_order < 0:
        raise ValueError(f"predictor_order must be >= 0, got {predictor_order}")
    if path_step is not None:
        return _on_own_steps(
            newton_model(system, fast_path),
            np.array(q0, dtype=float),
            np.asarray(times, dtype=float),
            path_step,
            tolerance,
            max_iterations,
            progress,
            predictor_order,
            secant,
            tuple(path_breaks),
        )
    outputs = np.asarray(times, dtype=float)
    times, returned = refined_times(outputs, max_step)
    model = newton_model(system, fast_path)
    qs: list[NDArray] = []
    lams: list[NDArray] = []
    counts: list[int] = []
    tangent = None
    path = _Path(float(times[0]), np.array(q0, dtype=float), np.zeros(system.n_constraints), predictor_order)
    for k, t in enumerate(times):
        try:
            if k == 0:
                q, lam, iterations, tangent = _newton(
                    model, path.q[0], path.lam[0], float(t), tolerance, max_iterations, None, secant, _START_ADVICE
                )
                path = _Path(float(t), q, lam, predictor_order)
            else:
                iterations, tangent = _advance(model, path, float(t), tolerance, max_iterations, tangent, secant)
        except StaticDivergence as error:
            keep = np.flatnonzero(returned[:k])
            found = StaticSolution(
                np.array(qs)[keep], np.array(lams)[keep], tuple(counts[j] for j in keep), jumps=tuple(path.jumps)
            )
            raise StaticDivergence(f"quasi-static step {k} at t = {t:.6g} s: {error}", found) from error
        qs.append(path.q[-1].copy())
        lams.append(path.lam[-1].copy())
        counts.append(iterations)
        if progress is not None:
            try:
                progress(float(t), float(times[-1]))
            except Interrupted as error:  # asked to stop: leave with the equilibria at the times reached
                keep = np.flatnonzero(returned[: k + 1])
                error.partial = StaticSolution(
                    np.array(qs)[keep], np.array(lams)[keep], tuple(counts[j] for j in keep), jumps=tuple(path.jumps)
                )
                raise
    keep = np.flatnonzero(returned)
    return StaticSolution(
        np.array(qs)[keep], np.array(lams)[keep], tuple(counts[k] for k in keep), jumps=tuple(path.jumps)
    )


def refined_times(times: NDArray, max_step: float | None) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """``times`` with intermediate times so that no interval exceeds ``max_step`` (each interval cut into
    equal pieces, so equally spaced times stay equally spaced), and a mask of the given ones."""
    if max_step is None or times.size < 2:
        return times, np.ones(times.size, dtype=bool)
    if not max_step > 0.0:
        raise ValueError(f"max_step must be > 0 s, got {max_step}")
    refined, returned = [times[:1]], [np.array([True])]
    for start, end in itertools.pairwise(times):
        pieces = max(1, math.ceil(abs(end - start) / max_step - 1e-9))
        refined.append(np.append(start + (end - start) * np.arange(1, pieces) / pieces, end))
        returned.append(np.arange(1, pieces + 1) == pieces)
    return np.concatenate(refined), np.concatenate(returned)


def path_times(
    t_start: float, t_end: float, path_step: Callable[[float], float], breaks: tuple[float, ...] = ()
) -> NDArray[np.float64]:
    """The path's own times from ``t_start`` to ``t_end``: each the one before plus ``path_step`` of it (Eq. (S10)),
    the last step shortened to end at ``t_end`` (a last step under a quarter of the one before is merged into it);
    with ``breaks`` (kinks of the time laws, e.g. a load table's corners) the same on each piece between them."""
    inside = sorted(b for b in breaks if t_start < b < t_end)
    if inside:
        ends = [t_start, *inside, t_end]
        pieces = [path_times(a, b, path_step)[1:] for a, b in itertools.pairwise(ends)]
        return np.concatenate([[float(t_start)], *pieces])
    times = [float(t_start)]
    while times[-1] < t_end - 1e-12 * max(1.0, abs(t_end)):
        step = float(path_step(times[-1]))
        if not step > 0.0:
            raise ValueError(f"path_step({times[-1]:g}) must be > 0 s, got {step}")
        times.append(min(float(t_end), times[-1] + step))
    if len(times) > 2 and times[-1] - times[-2] < 0.25 * (times[-2] - times[-3]):
        del times[-2]
    return np.array(times)


class _History(_Path):
    """A :class:`_Path` that also keeps the last :data:`_KEPT` equilibria, and every one after the last solved output
    (a path step that crawls past contact switches may take hundreds of parts), to interpolate outputs among them."""

    _KEPT = 32

    def __init__(self, t: float, q: NDArray, lam: NDArray, order: int):
        super().__init__(t, q, lam, order)
        self.solved = -np.inf  # every output up to this t is solved
        self.kept: list[tuple[float, NDArray, NDArray]] = [(t, q, lam)]
        # the kept equilibria of the stretches between the last jumps, oldest first (``kept`` is the newest): an
        # output between a stretch's last equilibrium and the jump that ends it is solved on that stretch
        self.stretches: list[tuple[float, list[tuple[float, NDArray, NDArray]]]] = [(t, self.kept)]

    def add(self, t: float, q: NDArray, lam: NDArray) -> None:
        super().add(t, q, lam)
        self.kept.append((t, q, lam))
        self._trim()

    def _trim(self) -> None:
        """Keep the newest :data:`_KEPT` equilibria, or every one after the last solved output and ``order + 1``
        before it."""
        unsolved = sum(1 for point in self.kept if point[0] > self.solved)
        del self.kept[: -max(self._KEPT, unsolved + self.order + 1)]

    def restart(self, t: float, q: NDArray, lam: NDArray) -> None:
        super().restart(t, q, lam)
        self.kept = [(t, q, lam)]
        self.stretches.append((t, self.kept))

    def forget_before(self, t: float) -> None:
        """Every output up to ``t`` is solved: drop the stretches that end at or before it (a path step may jump many
        times, up to :data:`MAX_JUMPS`, and an output before the first jump still needs its stretch) and the
        equilibria no output needs any more."""
        while len(self.stretches) > 1 and self.stretches[1][0] <= t:
            del self.stretches[0]
        self.solved = t
        self._trim()

    def _stretch(self, t: float) -> tuple[float, float]:
        """Start and end of the stretch ``t`` lies on (between two jumps)."""
        starts = [start for start, _ in self.stretches]
        k = max((i for i, start in enumerate(starts) if start <= t), default=0)
        return starts[k], starts[k + 1] if k + 1 < len(starts) else np.inf

    def side(self, t: float) -> list[tuple[float, NDArray, NDArray]]:
        """The kept equilibria of the stretch ``t`` lies on (between two jumps)."""
        start, _ = self._stretch(t)
        return next(points for s, points in self.stretches if s == start)

    def interpolate(self, t: float, more: list[tuple[float, NDArray, NDArray]]) -> tuple[NDArray, NDArray]:
        """Eq. (S2) through the ``order + 1`` equilibria nearest ``t`` among the kept ones and ``more`` (outputs
        solved before): a start for Newton at ``t``."""
        start, end = self._stretch(t)
        points = list(self.side(t))
        # no polynomial across a jump; distinct times only: the Lagrange weights divide by their differences
        for point in (p for p in more if start <= p[0] < end):
            if all(abs(point[0] - other[0]) > 1e-9 * max(1.0, abs(t)) for other in points):
                points.append(point)
        nearest = sorted(points, key=lambda point: abs(point[0] - t))[: self.order + 1]
        if len(nearest) < 2:
            return nearest[0][1], nearest[0][2]
        weights = extrapolation_weights(np.array([point[0] for point in nearest]), t)
        return weights @ np.array([point[1] for point in nearest]), weights @ np.array([point[2] for point in nearest])


def _along_path(model, path: _History, t_out: float, tolerance: float, max_iterations: int):
    """The equilibrium at ``t_out`` followed from the path's last equilibrium before it, as a path step (halved
    where needed, Eq. (S4)) on a copy of the path: for an output that Newton from the interpolated start does not
    solve on the path. Returns ``(q, lambda, iterations)``."""
    before = [point for point in path.side(t_out) if point[0] < t_out]
    if not before:  # the stretch's equilibria before t_out are no longer kept (many jumps in a row)
        raise StaticDivergence(f"no equilibrium of the path is kept before the output at t = {t_out:.9g} s")
    start = before[-(path.order + 1) :]
    copy = _Path(start[0][0], start[0][1], start[0][2], path.order)
    for t, q, lam in start[1:]:
        copy.add(t, q, lam)
    iterations, _ = _advance(model, copy, t_out, tolerance, max_iterations, None, False)
    return copy.q[-1], copy.lam[-1], iterations


def _on_own_steps(
    model,
    q0: NDArray,
    outputs: NDArray,
    path_step,
    tolerance: float,
    max_iterations: int,
    progress,
    order,
    secant,
    breaks: tuple[float, ...] = (),
) -> StaticSolution:
    """:func:`quasi_static` with ``path_step``: the path on :func:`path_times`, the outputs solved from it. At a
    ``breaks`` time the predictor (S2), which assumes a smooth path, starts again from that equilibrium alone."""
    own = path_times(float(outputs[0]), float(outputs[-1]), path_step, breaks)
    restart = {float(b) for b in breaks}
    qs: list[NDArray] = []
    lams: list[NDArray] = []
    counts: list[int] = []
    done_times: list[float] = []
    path_tangent = None

    output_tangent = None

    def emit(upto: float, path: _History) -> None:
        """Solve every output not yet solved up to ``upto`` from the path around it, with a tangent of their own
        (the path's to begin with), so that the outputs do not change the path."""
        nonlocal output_tangent
        while len(qs) < outputs.size and outputs[len(qs)] <= upto + 1e-12 * max(1.0, abs(upto)):
            t_out = float(outputs[len(qs)])
            exact = [point for point in path.side(t_out) if abs(point[0] - t_out) <= 1e-12 * max(1.0, abs(t_out))]
            if exact:
                q, lam, count = exact[-1][1], exact[-1][2], 0
            else:
                # the outputs solved last are equilibria too: a start through them (closer than the path's points
                # when the outputs are denser) saves iterations, and the outputs still never enter the path
                recent = [(done_times[j], qs[j], lams[j]) for j in range(max(0, len(qs) - path.order - 1), len(qs))]
                q_guess, lam_guess = path.interpolate(t_out, recent)
                kept = path_tangent if output_tangent is None else output_tangent
                nearest = min(path.side(t_out), key=lambda point: abs(point[0] - t_out))[1]
                try:
                    q, lam, count, output_tangent = _newton(
                        model, q_guess, lam_guess, t_out, tolerance, max_iterations, kept, False, _PATH_ADVICE
                    )
                    # Eq. (S4) for an output: a correction larger than half the way from the nearest path point
                    # means Newton left the path (another branch near a bifurcation)
                    left = _path_departure(q, q_guess, nearest, tolerance) is not None
                except StaticDivergence:
                    left = True
                if left:
                    q, lam, count = _along_path(model, path, t_out, tolerance, max_iterations)
                    output_tangent = None
            qs.append(q.copy())
            lams.append(lam.copy())
            counts.append(count)
            done_times.append(t_out)
        if done_times:
            path.forget_before(done_times[-1])

    def partial(path: _History) -> StaticSolution:
        times = list(done_times)
        q_rows, lam_rows, count_rows = list(qs), list(lams), list(counts)
        last_t, last_q, last_lam = path.kept[-1]
        if not times or last_t > times[-1] + 1e-12 * max(1.0, abs(last_t)):
            times.append(last_t)
            q_rows.append(last_q.copy())
            lam_rows.append(last_lam.copy())
            count_rows.append(0)
        return StaticSolution(
            np.array(q_rows), np.array(lam_rows), tuple(count_rows), np.array(times), (*jumps, *path.jumps)
        )

    q, lam, _, path_tangent = _newton(
        model, q0, np.zeros(model.n_constraints), float(own[0]), tolerance, max_iterations, None, secant, _START_ADVICE
    )
    path = _History(float(own[0]), q, lam, order)
    jumps: list[PathJump] = []  # those of the paths before the last break
    emit(float(own[0]), path)
    for k, t in enumerate(own[1:], start=1):
        try:
            _, path_tangent = _advance(model, path, float(t), tolerance, max_iterations, path_tangent, secant)
            emit(float(t), path)
            if float(t) in restart:  # a kink of the path: the polynomial through points before it would miss after
                jumps += path.jumps
                path = _History(float(t), path.q[-1], path.lam[-1], order)
        except StaticDivergence as error:
            try:
                emit(path.times[-1], path)
            except StaticDivergence:
                pass  # the outputs before the stop that do not converge are left out; the path's own end is kept
            raise StaticDivergence(
                f"quasi-static path step {k} at t = {t:.6g} s (the last equilibrium at t = {path.times[-1]:.9g} s): "
                f"{error}",
                partial(path),
            ) from error
        if progress is not None:
            try:
                progress(float(t), float(own[-1]))
            except Interrupted as error:  # asked to stop: leave with the outputs solved so far
                error.partial = StaticSolution(
                    np.array(qs), np.array(lams), tuple(counts), np.array(done_times), (*jumps, *path.jumps)
                )
                raise
    emit(float(outputs[-1]), path)
    return StaticSolution(np.array(qs), np.array(lams), tuple(counts), np.array(done_times), (*jumps, *path.jumps))

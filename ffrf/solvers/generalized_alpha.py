r"""Generalized-alpha for index-3 constrained mechanical systems (Arnold and Bruels 2007).

Parameters from the spectral radius at infinity :math:`\rho_\infty` (Chung and Hulbert 1993):

.. math:: \alpha_m = \frac{2\rho_\infty - 1}{\rho_\infty + 1},\quad \alpha_f = \frac{\rho_\infty}{\rho_\infty + 1},\quad
          \gamma = \tfrac12 + \alpha_f - \alpha_m,\quad \beta = \tfrac14(\gamma + \tfrac12)^2.

Step ``n -> n+1`` with the algorithmic acceleration ``a`` (Arnold and Bruels, Alg. 1; ``docs/formulation.md`` Eq. (G2)):

.. math::
    q_{n+1} &= q_n + h\dot q_n + h^2(\tfrac12 - \beta)a_n + h^2\beta a_{n+1},\\
    \dot q_{n+1} &= \dot q_n + h(1-\gamma)a_n + h\gamma a_{n+1},\\
    (1-\alpha_m)a_{n+1} + \alpha_m a_n &= (1-\alpha_f)\ddot q_{n+1} + \alpha_f\ddot q_n,

and the equations of motion and position constraints hold at :math:`t_{n+1}`. Newton's
unknowns are :math:`\ddot q_{n+1}` and :math:`\lambda_{n+1}`; with
:math:`\beta' = h^2\beta(1-\alpha_f)/(1-\alpha_m)` and :math:`\gamma' = h\gamma(1-\alpha_f)/(1-\alpha_m)`
the iteration matrix is (Eq. (G3))

.. math:: \begin{bmatrix} M + \beta'(K_t + H) + \gamma' D_t & C_q^T\\ C_q & 0\end{bmatrix},

the constraint rows divided by :math:`\beta'` so that it stays well conditioned for small
steps and stiff bodies (Bottasso, Dopico and Trainelli 2008). :math:`K_t, D_t` are the exact
derivatives of :math:`M\ddot q - Q` (including :math:`\partial(M\ddot q)/\partial q`) and
:math:`H = \partial(C_q^T\lambda)/\partial q`, so full Newton converges quadratically.

One module of about 400 lines on purpose: the parameters, the step equations above and their
Newton iteration (with its factor reuse and singularity handling) are one algorithm read next to
these equations; what integrators share already lives in :mod:`ffrf.solvers.common`,
:mod:`ffrf.solvers.newton_kernels` and :mod:`ffrf.solvers.step_control`.
"""

from __future__ import annotations

import logging
import time as wallclock
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from numpy.typing import NDArray
from scipy.linalg.lapack import dgecon as gecon
from scipy.linalg.lapack import dgetrs as getrs

from ffrf.errors import Interrupted, NewtonDivergence, SingularIterationMatrix
from ffrf.numerics.rank_revealing import WELL_CONDITIONED, factor
from ffrf.solvers.common import IntegrationResult, consistent_accelerations, extrapolation_weights
from ffrf.solvers.newton_kernels import CONVERGED, EXHAUSTED, NOT_FINITE, REFACTOR, alpha_iterations, should_refactor
from ffrf.solvers.step_control import DisplacementScales, StepControl, displacement_error, local_error
from ffrf.system.multibody import MultibodySystem
from ffrf.system.packed_system import PackedSystem, contiguous, newton_model

__all__ = ["AlphaParameters", "generalized_alpha", "part_schedule", "precision_floor", "replayed_limit", "step_parts"]

log = logging.getLogger(__name__)

#: Degree of the polynomial that extrapolates Newton's start from the last accepted steps (Eq. (G6)). Measured on
#: the default Bennett scene's revolution at 10 ms steps: 4.22 iterations per step with the line (degree 1),
#: 3.78 with the parabola, and 124 against 71 factorisations.
PREDICTOR_DEGREE = 2
#: Most parts one step of a run with a ``step_limit`` is done in after Newton failures (Eq. (G7)).
MAX_PARTS = 64
#: A step whose Newton needed more iterations than this (retries included) makes the next step start in twice as
#: many parts (Eq. (G8)): twice the usual count. Measured on the default dynamic runs: the Bennett's 3.77 iterations
#: per step on average, at most 6; ``interp_4poses_6r`` rigid's 3.94, at most 7; a step whose first Newton failed
#: and was retried counts ``max_iterations`` (12) more.
SLOW_NEWTON = 8
#: A step whose largest error estimate (G8) is below the tolerance divided by this lets the next step have half as
#: many parts (not fewer than its ``step_limit`` asks): the estimate is O(h^3), so twice the part is 8 times the
#: estimate, and 16 leaves a margin of two.
GROW_MARGIN = 16.0


@dataclass(frozen=True)
class AlphaParameters:
    """Generalized-alpha coefficients from the spectral radius ``rho_inf`` in [0, 1]."""

    rho_inf: float
    alpha_m: float = field(init=False)
    alpha_f: float = field(init=False)
    gamma: float = field(init=False)
    beta: float = field(init=False)

    def __post_init__(self):
        if not 0.0 <= self.rho_inf <= 1.0:
            raise ValueError(f"rho_inf must lie in [0, 1], got {self.rho_inf}")
        am = (2.0 * self.rho_inf - 1.0) / (self.rho_inf + 1.0)
        af = self.rho_inf / (self.rho_inf + 1.0)
        gamma = 0.5 + af - am
        object.__setattr__(self, "alpha_m", am)
        object.__setattr__(self, "alpha_f", af)
        object.__setattr__(self, "gamma", gamma)
        object.__setattr__(self, "beta", 0.25 * (gamma + 0.5) ** 2)


def _factor_iteration_matrix(
    model: MultibodySystem | PackedSystem, q, qd, qdd, lam, t: float, beta_p: float, gamma_p: float
):
    """Eq. (G3), LU-factored. A poorly conditioned matrix (LAPACK's estimate) is judged by the rank
    rule (R1); a singular one stops the run, since LU's solve would only spread inf and NaN."""
    matrix = model.iteration_matrix(q, qd, qdd, lam, t, 1.0, beta_p, gamma_p)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)  # decided below, by the rank rule
        factors = scipy.linalg.lu_factor(matrix, check_finite=False)
    with np.errstate(divide="ignore", invalid="ignore"):
        rcond = gecon(factors[0], np.abs(matrix).sum(axis=0).max(), norm="1")[0]
    if not rcond > WELL_CONDITIONED:
        try:
            deficiency = factor(matrix, what=f"iteration matrix at t = {t:g}").rank_deficiency
        except FloatingPointError as error:
            raise _Singular(str(error)) from error
        if deficiency:
            raise _Singular(
                f"the iteration matrix at t = {t:.6g} s is singular ({deficiency} zero singular value(s)): "
                "the constraints are redundant at this state (a closed loop of links without modes, or Newton's "
                "iterate far from the motion, as after a step too long near a near-dead pose where one joint turns "
                "much faster than the driver) or a coordinate has no mass or stiffness; shorten the step where the "
                "motion is fast, give links without modes some, or remove redundant joint directions"
            )
    return factors


class _Singular(Exception):
    """Raised inside a step; :func:`generalized_alpha` turns it into :class:`SingularIterationMatrix`."""


@dataclass
class _State:
    q: NDArray
    qd: NDArray
    qdd: NDArray
    accel: NDArray  # algorithmic acceleration a
    lam: NDArray


@dataclass
class _Newton:
    """Newton settings and the factorised iteration matrix kept between steps (modified Newton)."""

    model: PackedSystem | MultibodySystem
    par: AlphaParameters
    tolerance: float
    max_iterations: int
    modified: bool
    factors: tuple | None = None
    factored_step: float = 0.0
    held_time: float | None = None  # the time the model is evaluated at, if not the step's own

    def model_time(self, t: float) -> float:
        return t if self.held_time is None else self.held_time


def _fast_iterations(
    newton: _Newton,
    model: PackedSystem,
    t: float,
    h: float,
    beta_p: float,
    gamma_p: float,
    bases: tuple,
    qdd: NDArray,
    lam: NDArray,
    refactor_each: bool,
) -> tuple[int, int, float, float]:
    """The Newton iterations of :func:`_step` on the fast path: jitted runs between factorisations
    (:func:`ffrf.solvers.newton_kernels.alpha_iterations`), same tests and order as the Python loop.
    Updates ``qdd`` and ``lam`` in place; returns ``(status, iterations, increment, gap)``."""
    q_base, qd_base, accel_base, to_accel = bases
    par = newton.par
    used, previous = 0, np.inf
    increment = gap_max = np.inf
    while used < newton.max_iterations:
        if newton.factors is None or refactor_each:
            accel = accel_base + to_accel * qdd
            newton.factors = _factor_iteration_matrix(
                model, q_base + h * h * par.beta * accel, qd_base + h * par.gamma * accel, qdd, lam, t, beta_p, gamma_p
            )
            newton.factored_step = h
        limit = 1 if refactor_each else newton.max_iterations - used
        lu, pivots = newton.factors
        outcome = alpha_iterations(
            model.bodies,
            model.joints,
            model.gravity,
            model.phi(t),
            lu,
            pivots,
            contiguous(q_base),
            contiguous(qd_base),
            contiguous(accel_base),
            float(to_accel),
            h * h * par.beta,
            h * par.gamma,
            float(beta_p),
            float(gamma_p),
            qdd,
            lam,
            float(newton.tolerance),
            int(limit),
            float(previous),
            int(used),
        )
        status, count = int(outcome[0]), int(outcome[1])
        increment, gap_max = float(outcome[2]), float(outcome[3])
        used += count
        if status in (CONVERGED, NOT_FINITE):
            return status, used, increment, gap_max
        if status == REFACTOR:
            newton.factors = None  # should_refactor asked for a new iteration matrix
        previous = increment
    return EXHAUSTED, used, increment, gap_max


def _predicted_unknowns(state: _State, h: float, before: tuple[tuple, ...]) -> tuple[NDArray, NDArray]:
    """Eq. (G6): Newton's start for ``(qdd, lambda)`` at the end of a step of length ``h``, extrapolated from the
    state and ``before``, the ``(qdd, lambda, h)`` of the accepted steps that led to it (most recent last): the
    parabola through the last three values, the line through two, or the state's own values without any. The
    extrapolation stops at a step more than twice shorter than the one after it (one cut to land on an output,
    whose difference quotients would amplify Newton's tolerance)."""
    times, values = [0.0], [(state.qdd, state.lam)]
    step = h
    for qdd_before, lam_before, h_before in reversed(before[-PREDICTOR_DEGREE:]):
        if not 0.0 < step / h_before <= 2.0:
            break
        times.append(times[-1] - h_before)
        values.append((qdd_before, lam_before))
        step = h_before
    if len(times) == 1:
        return state.qdd.copy(), state.lam.copy()
    weights = extrapolation_weights(np.array(times), h)
    qdd = sum(w * v[0] for w, v in zip(weights, values, strict=True))
    lam = sum(w * v[1] for w, v in zip(weights, values, strict=True))
    return qdd, lam


def _step(newton: _Newton, state: _State, t: float, h: float, before: tuple[tuple, ...] = ()):
    """One generalized-alpha step of length ``h`` to time ``t`` (Eqs. (G2), (G3)), Newton starting
    from the prediction (G6) with ``before`` (a retry starts from the state's own values). Returns
    the new state and the Newton iterations, or ``(None, iterations, diagnostics)`` if Newton failed."""
    par, model = newton.par, newton.model
    t = newton.model_time(t)  # from here on the time of the drives and loads, not of the step
    beta_p = h * h * par.beta * (1.0 - par.alpha_f) / (1.0 - par.alpha_m)
    gamma_p = h * par.gamma * (1.0 - par.alpha_f) / (1.0 - par.alpha_m)
    to_accel = (1.0 - par.alpha_f) / (1.0 - par.alpha_m)
    if newton.factored_step != h:
        newton.factors = None  # the iteration matrix depends on h
    n = state.q.shape[0]
    q_base = state.q + h * state.qd + h * h * (0.5 - par.beta) * state.accel
    qd_base = state.qd + h * (1.0 - par.gamma) * state.accel
    accel_base = (par.alpha_f * state.qdd - par.alpha_m * state.accel) / (1.0 - par.alpha_m)
    total = 0  # Newton iterations of this step, retries included
    diagnostics = ""

    def accepted(qdd_new: NDArray, lam_new: NDArray) -> _State:
        """The state at t from the converged unknowns (Eq. (G2))."""
        accel = accel_base + to_accel * qdd_new
        return _State(q_base + h * h * par.beta * accel, qd_base + h * par.gamma * accel, qdd_new, accel, lam_new)

    for attempt in range(2 if newton.modified else 1):
        qdd_new, lam_new = _predicted_unknowns(state, h, before if attempt == 0 else ())
        if isinstance(model, PackedSystem) and not model.forces:
            status, used, increment, gap_max = _fast_iterations(
                newton,
                model,
                t,
                h,
                beta_p,
                gamma_p,
                (q_base, qd_base, accel_base, to_accel),
                qdd_new,
                lam_new,
                refactor_each=not newton.modified or attempt == 1,
            )
            if status == CONVERGED:
                return accepted(qdd_new, lam_new), total + used, ""
            if status == NOT_FINITE:
                return None, total + used, f"NaN in the residual (iteration {used})"
            total += newton.max_iterations
            newton.factors = None
            diagnostics = f"largest constraint residual {gap_max:.3e}, last acceleration increment {increment:.3e}"
            continue
        previous = np.inf
        for iteration in range(1, newton.max_iterations + 1):
            a_new = accel_base + to_accel * qdd_new
            q_new = q_base + h * h * par.beta * a_new
            qd_new = qd_base + h * par.gamma * a_new
            residual, gap = model.residual(q_new, qd_new, qdd_new, lam_new, t)
            if not (np.all(np.isfinite(residual)) and np.all(np.isfinite(gap))):
                return None, total + iteration, f"NaN in the residual (iteration {iteration})"
            if newton.factors is None or not newton.modified or attempt == 1:
                newton.factors = _factor_iteration_matrix(model, q_new, qd_new, qdd_new, lam_new, t, beta_p, gamma_p)
                newton.factored_step = h
            # LAPACK getrs directly: what lu_solve calls, without its ~30 us of wrapper per iteration
            delta = getrs(*newton.factors, -np.concatenate([residual, gap / beta_p]))[0]
            qdd_new += delta[:n]
            lam_new += delta[n:]
            increment = np.abs(delta[:n]).max()
            position_scale = newton.tolerance * max(1.0, np.abs(q_new).max())
            velocity_scale = newton.tolerance * max(1.0, np.abs(qd_new).max())
            if (
                beta_p * increment <= position_scale
                and gamma_p * increment <= velocity_scale
                and np.abs(gap).max() <= newton.tolerance
            ):
                return accepted(qdd_new, lam_new), total + iteration, ""
            if should_refactor(iteration, increment, previous, beta_p, gamma_p, position_scale, velocity_scale):
                newton.factors = None  # rebuild the iteration matrix at the next iteration
            previous = increment
        total += newton.max_iterations
        newton.factors = None
        diagnostics = (
            f"largest constraint residual {np.abs(gap).max():.3e}, last acceleration increment {increment:.3e}"
        )
    return None, total, diagnostics


def _position_error(par: AlphaParameters, h: float, new: _State, old: _State, positions: NDArray) -> float:
    """The largest local error estimate (Eq. (G5)) of a step of length ``h`` from ``old`` to ``new`` among the
    coordinates ``positions``."""
    return float(np.abs(local_error(par.beta, h, new.qdd[positions], old.qdd[positions])).max(initial=0.0))


def precision_floor(par: AlphaParameters, h: float, q: NDArray, qd: NDArray) -> float:
    """The smallest Newton ``tolerance`` double precision can meet in a step of length ``h`` from
    positions ``q`` and velocities ``qd`` (the tests of :func:`_step`, Eq. (G3)). One unit in the last
    place of the positions, ``eps max(1, |q|)``, is a constraint gap that the scaled constraint rows
    turn into an acceleration increment of ``gap / beta'``, hence a velocity increment ``gamma' / beta'``
    times the gap; below that, the increments stall at round-off however many iterations run
    (NGsolveCMStest at 1 ms steps: 4.4e-13, and Newton indeed stalls at tolerance 1e-13)."""
    eps = np.finfo(float).eps
    ulp = eps * max(1.0, float(np.abs(q).max()))
    velocity_floor = par.gamma / (h * par.beta) * ulp / max(1.0, float(np.abs(qd).max()))
    return max(ulp, velocity_floor)


def _failure_advice(newton: _Newton, state: _State, h: float, remedy: str) -> str:
    """What to do after Newton failed: ``remedy``, unless the tolerance is below
    :func:`precision_floor`, where no step size or model change would help."""
    floor = precision_floor(newton.par, h, state.q, state.qd)
    if newton.tolerance >= floor:
        return remedy
    return (
        f"the tolerance {newton.tolerance:.1e} is below what double precision can reach at this scale "
        f"({floor:.1e}: an ulp of the positions, whose largest is {np.abs(state.q).max():.3g}, changes the "
        f"velocities by that much in a {h:.3g} s step); raise the tolerance to {10.0 ** np.ceil(np.log10(floor)):.0e} "
        "or more (a shorter step raises this floor)"
    )


def _part(k: int, j: int, parts: int, h: float) -> tuple[float, float]:
    """End time and length (s) of part ``j`` of ``parts`` of fixed step ``k`` (from 1) of length ``h`` (Eq. (G7))."""
    return (k * h, h) if parts == 1 else ((k - 1) * h + j * h / parts, h / parts)


def step_parts(step_sizes: NDArray, h: float) -> list[list[int]]:
    """How many parts each fixed step ``h`` of a run was done in (from its accepted ``step_sizes``, Eq. (G7)),
    run-length encoded: ``[[parts, steps], ...]`` in the order of the run."""
    encoded: list[list[int]] = []
    i = 0
    while i < len(step_sizes):
        parts = max(1, round(h / float(step_sizes[i])))
        if encoded and encoded[-1][0] == parts:
            encoded[-1][1] += 1
        else:
            encoded.append([parts, 1])
        i += parts
    return encoded


def part_schedule(h: float, parts: list[list[int]]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The end times and lengths (s) of every part of a run whose fixed steps ``h`` were done in ``parts``
    (:func:`step_parts`), as :func:`generalized_alpha` computes them: another solver takes the very same steps."""
    times, sizes = [], []
    k = 0
    for count, steps in parts:
        for _ in range(steps):
            k += 1
            for j in range(1, count + 1):
                t, size = _part(k, j, count, h)
                times.append(t)
                sizes.append(size)
    return np.array(times), np.array(sizes)


def replayed_limit(h: float, parts: list[list[int]]) -> Callable[[float, float], float]:
    """A ``step_limit`` for :func:`generalized_alpha` with fixed steps ``h`` that makes it take ``parts`` (another run's
    :func:`step_parts`) again: step ``k`` in exactly as many parts, whatever the run's own rules would choose."""
    counts = np.repeat([p for p, _ in parts], [n for _, n in parts])

    def limit(t0: float, t1: float) -> float:
        k = int(round(t1 / h))
        if not 1 <= k <= counts.size:
            raise ValueError(f"the replayed steps end at t = {counts.size * h:.6g} s; the run asks for t = {t1:.6g} s")
        return h / float(counts[k - 1])

    return limit


def generalized_alpha(
    system: MultibodySystem,
    q0: NDArray,
    qd0: NDArray,
    t_end: float,
    step: float,
    rho_inf: float = 0.9,
    tolerance: float = 1e-10,
    max_iterations: int = 12,
    modified_newton: bool = True,
    output_every: int = 1,
    progress: Callable[[float, float], None] | None = None,
    *,
    fast_path: bool = True,
    step_control: StepControl | None = None,
    step_limit: Callable[[float, float], float] | None = None,
    error_tolerance: float | None = None,
    held_time: float | None = None,
) -> IntegrationResult:
    """Integrate from ``t = 0`` to ``t_end`` with fixed steps ``step`` (s), or, with a
    :class:`StepControl`, with steps chosen by its error estimate (starting from ``step``);
    either way the output times are the multiples of ``output_every * step``.

    Newton stops when the increments it makes in positions (``beta' |dqdd|``) and velocities
    (``gamma' |dqdd|``) are below ``tolerance`` times ``max(1, |q|)`` and ``max(1, |qd|)`` and the
    constraints hold to ``tolerance`` (their own units, m or dimensionless). With
    ``modified_newton`` the factorised iteration matrix is kept across iterations and steps
    and rebuilt when :func:`ffrf.solvers.newton_kernels.should_refactor` asks for it (Eq. (G3) in
    ``docs/formulation.md``) or a step fails, which is then retried with a fresh matrix; each step
    starts from the prediction (G6). The converged solution is the same, only the work differs.
    Raises :class:`NewtonDivergence` with the partial results.
    ``fast_path`` evaluates Newton's residual and matrix with the whole-system kernels of
    :mod:`ffrf.system.packed_system` when the system is supported (else, and with ``False``, with the
    reference Python implementation of :class:`MultibodySystem`; both agree to round-off).
    ``newton_iterations`` of the result has one entry per accepted step (with
    ``step_control``, ``step_sizes`` in the same order).
    ``step_limit(t0, t1)`` (fixed steps only): the longest step allowed between ``t0`` and ``t1`` (s; e.g. from
    how fast the fastest coordinate moves there, Eq. (G7)); each step of length ``step`` is then done in as many
    equal parts as that needs, and a part whose Newton fails (or meets a singular iteration matrix) makes the whole
    step start over in twice as many parts, up to :data:`MAX_PARTS` (the outputs stay at the multiples of
    ``output_every * step``).
    ``error_tolerance`` (m; fixed steps only; default ``None``, off): the local error estimate of Eq. (G8), every
    coordinate in metres, that a part may make; a part above it makes the step start over in twice as many parts
    (up to :data:`MAX_PARTS`, beyond which it is accepted), a step whose Newton needed more than
    :data:`SLOW_NEWTON` iterations makes the next one start in twice as many, and the parts grow back, halving per
    step, once a step's estimate is below ``error_tolerance / GROW_MARGIN``. A run whose estimates stay below that
    takes the very same steps as without it.
    ``held_time`` (s; default ``None``): the drives and loads stay at their values at that time while the
    integration's own time runs from 0 (the passage of a snap at a fixed drive angle, Eq. (S11)).
    """
    if step <= 0 or t_end <= 0:
        raise ValueError(f"step and t_end must be positive, got step={step}, t_end={t_end}")
    par = AlphaParameters(rho_inf)
    n_steps = int(round(t_end / step))
    h = t_end / n_steps
    n = system.n_coordinates
    newton = _Newton(newton_model(system, fast_path), par, tolerance, max_iterations, modified_newton)
    newton.held_time = held_time

    q, qd = np.array(q0, dtype=float), np.array(qd0, dtype=float)
    if q.shape != (n,) or qd.shape != (n,):
        raise ValueError(f"initial state must have {n} coordinates, got {q.shape} and {qd.shape}")
    qdd, lam = consistent_accelerations(system, q, qd, newton.model_time(0.0))
    state = _State(q, qd, qdd, qdd.copy(), lam)
    before: tuple[tuple, ...] = ()  # (qdd, lambda, h) of the accepted steps before ``state``, for Newton's start (G6)
    history: dict[str, list] = {
        "time": [0.0],
        "q": [q.copy()],
        "qd": [qd.copy()],
        "qdd": [qdd.copy()],
        "lam": [lam.copy()],
    }
    iterations: list[int] = []
    step_sizes: list[float] = []
    positions = np.concatenate([np.arange(s, s + 3) for s in system.offsets[:-1]])  # each body's R (m)
    if error_tolerance is not None and not error_tolerance > 0.0:
        raise ValueError(f"error_tolerance must be positive (m) or None, got {error_tolerance}")
    scales = DisplacementScales.of(system) if error_tolerance is not None else None
    position_errors: list[float] = []
    started = wallclock.perf_counter()

    def record(t: float, s: _State) -> None:
        history["time"].append(t)
        for key, value in (("q", s.q), ("qd", s.qd), ("qdd", s.qdd), ("lam", s.lam)):
            history[key].append(value.copy())

    def result(complete: bool) -> IntegrationResult:
        return IntegrationResult(
            np.array(history["time"]),
            np.array(history["q"]),
            np.array(history["qd"]),
            np.array(history["qdd"]),
            np.array(history["lam"]),
            np.array(iterations, dtype=np.int64),
            wallclock.perf_counter() - started,
            complete,
            np.array(step_sizes),
            np.array(position_errors),
        )

    def report(t: float) -> None:
        """``progress``; a stop it asks for (:class:`Interrupted`) leaves with the outputs so far."""
        if progress is None:
            return
        try:
            progress(t, t_end)
        except Interrupted as error:
            error.partial = result(False)
            raise

    def guarded_step(t_new: float, h_new: float):
        try:
            return _step(newton, state, t_new, h_new, before)
        except _Singular as error:
            raise SingularIterationMatrix(str(error), result(False)) from None

    if step_control is None:
        carried = 0  # parts the error control (G8) asks the next step to start from (0: the step_limit's alone)
        capped = 0  # parts accepted above the tolerance of (G8) because the step was already in MAX_PARTS parts
        for k in range(1, n_steps + 1):
            t = k * h
            base = 1 if step_limit is None else max(1, int(np.ceil(h / step_limit(t - h, t) - 1e-9)))
            parts = max(base, carried)
            refinable = step_limit is not None or error_tolerance is not None
            while True:  # the step in ``parts`` equal parts (Eqs. (G7), (G8)); start over in more parts if one fails
                start, start_before, done = state, before, len(iterations)
                failure = None
                largest, slowest = 0.0, 0  # the parts' largest (G8) estimate and most Newton iterations
                for j in range(1, parts + 1):
                    t_part, h_part = _part(k, j, parts, h)
                    try:
                        new, count, diagnostics = _step(newton, state, t_part, h_part, before)
                    except _Singular as error:
                        if not refinable or parts >= MAX_PARTS:
                            raise SingularIterationMatrix(str(error), result(False)) from None
                        new, diagnostics = None, str(error)
                    if new is None:
                        failure = (t_part, h_part, diagnostics)
                        break
                    if scales is not None and error_tolerance is not None:
                        estimate = displacement_error(par.beta, h_part, new.qdd, state.qdd, scales)
                        if estimate > error_tolerance and parts < MAX_PARTS:
                            failure = (t_part, h_part, f"local error estimate (G8) {estimate:.3g} m")
                            break
                        capped += estimate > error_tolerance
                        largest, slowest = max(largest, estimate), max(slowest, count)
                    before = (*before, (state.qdd, state.lam, h_part))[-PREDICTOR_DEGREE:]
                    position_errors.append(_position_error(par, h_part, new, state, positions))
                    state = new
                    iterations.append(count)
                    step_sizes.append(h_part)
                if failure is None:
                    break
                t_fail, h_fail, diagnostics = failure
                if not refinable or parts >= MAX_PARTS:
                    raise NewtonDivergence(
                        f"Newton did not converge at t = {t_fail:.6g} s after {max_iterations} iterations "
                        f"(step {h_fail:.3g} s): {diagnostics}; "
                        + _failure_advice(newton, state, h_fail, "reduce the step size or check the constraints"),
                        result(False),
                    )
                state, before, parts = start, start_before, 2 * parts
                del iterations[done:], step_sizes[done:], position_errors[done:]
                newton.factors = None
                log.debug("step to t = %g s redone at %g s (%s); %d parts", t, t_fail, diagnostics, parts)
            if error_tolerance is not None:  # Eq. (G8): the next step's parts from this one's estimate and Newton
                if slowest > SLOW_NEWTON:
                    carried = min(MAX_PARTS, 2 * parts)
                elif largest < error_tolerance / GROW_MARGIN:
                    carried = parts // 2 if parts > base else 0
                else:
                    carried = parts if parts > base else 0
            if k % output_every == 0 or k == n_steps:
                record(t, state)
            report(t)
        if capped:  # said, not hidden: these parts' error is larger than asked for
            log.warning(
                "%d step parts kept a local error estimate (G8) above error_tolerance = %.3g m in %d parts, the most "
                "allowed: shorten the step or raise the tolerance",
                capped,
                error_tolerance,
                MAX_PARTS,
            )
        return result(True)

    outputs = list(np.minimum(h * output_every * np.arange(1, int(np.ceil(n_steps / output_every)) + 1), t_end))
    t, trial = 0.0, h
    while outputs:
        target = outputs[0]
        h_try = min(trial, target - t)
        landing = h_try >= target - t - 1e-12 * max(1.0, target)
        if landing:
            h_try = target - t
        new, count, diagnostics = guarded_step(target if landing else t + h_try, h_try)
        ratio = np.inf if new is None else step_control.error_ratio(par.beta, h_try, new.qdd, state.qdd, new.q)
        if new is None or ratio > 1.0:
            if h_try <= step_control.min_step * (1.0 + 1e-12):
                reason = diagnostics if new is None else f"local error {ratio:.3g} times the tolerance"
                raise NewtonDivergence(
                    f"no step above min_step = {step_control.min_step:g} s succeeds at "
                    f"t = {t:.6g} s ({reason}); "
                    + _failure_advice(newton, state, h_try, "relax the tolerances or check the model"),
                    result(False),
                )
            trial = max(step_control.min_step, 0.5 * h_try if new is None else step_control.next_step(h_try, ratio))
            continue
        t = target if landing else t + h_try
        before = (*before, (state.qdd, state.lam, h_try))[-PREDICTOR_DEGREE:]
        position_errors.append(_position_error(par, h_try, new, state, positions))
        state = new
        iterations.append(count)
        step_sizes.append(h_try)
        if landing:
            record(t, state)
            outputs.pop(0)
        report(t)
        # a step cut short to land on an output says nothing about the next one's size
        trial = step_control.next_step(h_try, ratio) if not landing or h_try >= trial else trial
    return result(True)

r"""Collision-free links for any single loop: where the two housings at each joint sit along its axis.

The parametric links (:func:`ffrf.geometry.link_geometry.build_link`) keep their section; what is free is where
the two links meeting at joint :math:`j` put their housings along the joint's axis :math:`h_j` (the
"connection points" of Rational Linkages' ``CollisionFreeOptimization``). A :class:`Stacking` gives, per joint,
the axial position :math:`t_j` of the middle of the two housings, from the joint point of
:func:`~ffrf.scenes.linkage_description.joint_points`, and a spacer :math:`g_j \ge 0` added to the axial gap
between them: link :math:`j`'s housing is centred at :math:`t_j - (s + g_j/2)` and link :math:`j+1`'s at
:math:`t_j + s + g_j/2` along :math:`h_j` (:math:`s` = :attr:`~ffrf.geometry.link_geometry.LinkDesign.housing_offset`).
A stacking becomes the linkage's ``attach_points`` (:meth:`Stacking.attach_points`), which every link builder takes.

:func:`design_stacking` chooses it: along one revolution of the rigid loop's driver (Eq. (L4)), every pair of links
keeps at least ``margin`` between their capsule proxies (:mod:`ffrf.geometry.link_capsules`), bounded between the
sampled poses by the links' speeds; among such stackings it takes the one with the least spacer and shift
(``docs/formulation.md``, "Collision-free links"). At a joint the two links share, the housings (coaxial, one axial
gap or more apart) and each housing against the other link's arm and mount block (which ``build_link`` trims within
one gap of the housing's radius beyond its end faces) are apart by at least the axial gap by construction and are
not compared; the margin may therefore not exceed the axial gap.
"""

from __future__ import annotations

import itertools
import logging
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize

from ffrf.errors import GeometryError
from ffrf.geometry.link_capsules import ARM, MOUNT, LinkCapsules, link_capsules, segment_distances
from ffrf.geometry.link_geometry import LinkDesign, trim_reach
from ffrf.scenes.linkage_description import drive_sign, joint_points
from kinematics import Line, SingleLoop, motion_tangents, trace_motion

__all__ = [
    "LinkBuildInput",
    "ProxyClearance",
    "SampledMotion",
    "Stacking",
    "StackingDesign",
    "design_stacking",
    "link_build_inputs",
    "order_candidates",
    "proxy_clearance",
    "sampled_motion",
]

logger = logging.getLogger(__name__)

#: Poses sampled over one revolution of the driver by default (0.25 deg apart).
DEFAULT_POSES = 1441


@dataclass(frozen=True)
class Stacking:
    """Per joint ``j``: ``offsets[j]`` (m) the axial position along :math:`h_j` of the middle of the two housings
    from the joint point, ``spacers[j]`` (m, >= 0) the room added to the axial gap between them, ``orders[j]``
    ``+1`` where link ``j``'s housing lies below link ``j + 1``'s along :math:`h_j` (as without a design), ``-1``
    where above (module docstring)."""

    offsets: tuple[float, ...]
    spacers: tuple[float, ...]
    orders: tuple[int, ...] | None = None

    @classmethod
    def nominal(cls, n: int) -> Stacking:
        """Both housings stacked about the joint point, one axial gap apart: the links as before any design."""
        return cls((0.0,) * n, (0.0,) * n)

    def order(self, joint: int) -> int:
        """``orders[joint]``, ``+1`` without orders."""
        return 1 if self.orders is None else int(self.orders[joint])

    def attach_points(self, loop: SingleLoop, design: LinkDesign | None = None) -> NDArray[np.float64]:
        """Housing centres ``(n, 2, 3)``: row ``j`` holds link ``j``'s and link ``j + 1``'s on :math:`h_j`
        (:class:`~ffrf.scenes.linkage_description.LinkageOptions`' ``attach_points``)."""
        design = LinkDesign() if design is None else design
        if len(self.offsets) != loop.n or len(self.spacers) != loop.n:
            raise ValueError(f"a stacking of {loop.n} joints needs {loop.n} offsets and spacers")
        points = joint_points(loop)
        attach = np.empty((loop.n, 2, 3))
        for j, axis in enumerate(loop.axes):
            half = self.order(j) * (design.housing_offset + 0.5 * self.spacers[j])
            attach[j, 0] = points[j] + (self.offsets[j] - half) * axis.direction
            attach[j, 1] = points[j] + (self.offsets[j] + half) * axis.direction
        return attach


class LinkBuildInput(NamedTuple):
    """What :func:`~ffrf.geometry.link_geometry.build_link` takes for one link: its two axes, the joint point on
    each (housings at ``+s`` and ``-s`` from them) and whether it carries the mount block."""

    axes: tuple[Line, Line]
    joint_points: NDArray[np.float64]
    mount: bool


def link_build_inputs(loop: SingleLoop, stacking: Stacking, design: LinkDesign | None = None) -> list[LinkBuildInput]:
    """Every link's :class:`LinkBuildInput` for ``stacking`` (link ``k`` carries :math:`h_{k-1}` and :math:`h_k`;
    link 0 the mount): the hook for checking a design on the link solids themselves."""
    design = LinkDesign() if design is None else design
    attach = stacking.attach_points(loop, design)
    s = design.housing_offset
    inputs = []
    for k in range(loop.n):
        first, second = loop.axes[k - 1], loop.axes[k]
        seats = np.stack([attach[k - 1, 1] - s * first.direction, attach[k, 0] + s * second.direction])
        inputs.append(LinkBuildInput((first, second), seats, k == 0))
    return inputs


@dataclass(frozen=True)
class SampledMotion:
    r"""The rigid loop's motion at poses ``angles`` (rad, the drive's angle, in the order of travel, ``step`` apart):
    each link's displacement ``transforms`` ``(m, n, 4, 4)`` (Eq. (L1)) and its twist per radian of drive,
    ``omega`` and ``velocity`` ``(m, n, 3)``: a point :math:`p` of link ``k`` moves at
    :math:`\omega_k \times p + v_k` per radian (Eq. (L3) with the motion's tangent)."""

    angles: NDArray[np.float64]
    step: float
    transforms: NDArray[np.float64]
    omega: NDArray[np.float64]
    velocity: NDArray[np.float64]


def sampled_motion(
    loop: SingleLoop, driver: int = 0, start: ArrayLike | None = None, n_poses: int = DEFAULT_POSES
) -> SampledMotion:
    """One revolution of joint ``driver`` from the closing pose near ``start`` (default home), ``n_poses`` poses
    from the start to the end of the turn (the way the drive turns, :func:`drive_sign`)."""
    sign = drive_sign(driver, loop.n)
    motion = trace_motion(loop, driver, n_poses=n_poses, revolution=sign * 2 * np.pi, start=start, endpoint=True)
    transforms = motion.link_transforms()
    rates = motion_tangents(loop, driver, motion.phi)
    points = np.array([axis.point for axis in loop.axes])
    directions = np.array([axis.direction for axis in loop.axes])
    n = loop.n
    # Axis i at each pose moves with link i; its Pluecker line there is (l_i, q_i x l_i).
    lines = np.einsum("mnij,nj->mni", transforms[:, :, :3, :3], directions)
    feet = np.einsum("mnij,nj->mni", transforms[:, :, :3, :3], points) + transforms[:, :, :3, 3]
    moments = np.cross(feet, lines)
    omega = np.zeros((len(rates), n, 3))
    velocity = np.zeros((len(rates), n, 3))
    for k in range(1, n):  # link k turns with joints 0..k-1 (Eq. (L1)); the base stands still
        omega[:, k] = omega[:, k - 1] + rates[:, k - 1, None] * lines[:, k - 1]
        velocity[:, k] = velocity[:, k - 1] + rates[:, k - 1, None] * moments[:, k - 1]
    angles = sign * motion.driver_angles
    return SampledMotion(angles, 2 * np.pi / (n_poses - 1), transforms, omega, velocity)


@dataclass(frozen=True)
class ProxyClearance:
    """The smallest proxy clearance (m) of each pair of links along a sampled motion, bounded between poses:
    ``pairs`` ``[(a, b), ...]``, ``clearance`` per pair, and the drive ``angle`` (rad) of its interval."""

    pairs: tuple[tuple[int, int], ...]
    clearance: NDArray[np.float64]
    angle: NDArray[np.float64]

    @property
    def smallest(self) -> tuple[float, tuple[int, int], float]:
        """``(clearance, pair, drive angle)`` of the closest pair."""
        k = int(np.argmin(self.clearance))
        return float(self.clearance[k]), self.pairs[k], float(self.angle[k])

    def summary(self) -> str:
        value, (a, b), angle = self.smallest
        where = f"links {a} and {b} at drive angle {np.degrees(angle):.1f} deg"
        return f"smallest proxy clearance {1e3 * value:.2f} mm ({where})"


class _Pairs(NamedTuple):
    """The capsule pairs compared: index of each capsule (into all links' capsules) and its link pair."""

    first: NDArray[np.int64]
    second: NDArray[np.int64]
    link_pair: NDArray[np.int64]
    link_pairs: tuple[tuple[int, int], ...]


def _shared_joint(a: int, b: int, n: int) -> int | None:
    """The joint links ``a < b`` share (link k carries joints k - 1 and k), if any."""
    if b == a + 1:
        return a
    if a == 0 and b == n - 1:
        return n - 1
    return None


def _side(link: int, joint: int) -> int:
    """Which of ``link``'s housings sits on ``joint``: 1 on its second axis (joint ``link``), 0 on its first."""
    return 1 if joint == link else 0


def _capsule_pairs(capsules: list[LinkCapsules]) -> _Pairs:
    """Every pair of capsules of two different links, without those apart by construction at a shared joint: the
    two housings there, and each of them against the other link's arm and mount block."""
    n = len(capsules)
    owner = np.concatenate([[k] * len(c.radii) for k, c in enumerate(capsules)])
    parts = np.concatenate([c.parts for c in capsules])
    first, second, pair_index = [], [], []
    link_pairs: list[tuple[int, int]] = []
    for a, b in itertools.combinations(range(n), 2):
        joint = _shared_joint(a, b, n)
        kept = False
        for i, j in itertools.product(np.flatnonzero(owner == a), np.flatnonzero(owner == b)):
            if joint is not None:
                side_a, side_b = _side(a, joint), _side(b, joint)
                if (parts[i] == side_a and parts[j] in (side_b, ARM, MOUNT)) or (
                    parts[j] == side_b and parts[i] in (ARM, MOUNT)
                ):
                    continue
            first.append(i)
            second.append(j)
            pair_index.append(len(link_pairs))
            kept = True
        if kept:
            link_pairs.append((a, b))
    return _Pairs(np.array(first), np.array(second), np.array(pair_index), tuple(link_pairs))


def _all_capsules(loop: SingleLoop, stacking: Stacking, design: LinkDesign) -> list[LinkCapsules]:
    return [
        link_capsules(*link.axes, link.joint_points, design, link.mount)
        for link in link_build_inputs(loop, stacking, design)
    ]


def _placed(motion: SampledMotion, capsules: list[LinkCapsules]) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    r"""Every capsule's segment ends ``(m, K, 3)`` at every pose, its radius ``(K,)`` and its speed bound ``(m, K)``
    per radian of drive: :math:`|\omega \times p + v|` is convex in :math:`p`, so its largest value on a segment is
    at an end, and a ball of radius :math:`r` about it adds :math:`|\omega| r`."""
    owner = np.concatenate([[k] * len(c.radii) for k, c in enumerate(capsules)])
    placed = motion.transforms[:, owner]
    rotation, shift = placed[..., :3, :3], placed[..., :3, 3]
    a = np.einsum("mkij,kj->mki", rotation, np.concatenate([c.starts for c in capsules])) + shift
    b = np.einsum("mkij,kj->mki", rotation, np.concatenate([c.ends for c in capsules])) + shift
    radii = np.concatenate([c.radii for c in capsules])
    omega, velocity = motion.omega[:, owner], motion.velocity[:, owner]
    speed = (
        np.maximum(
            np.linalg.norm(np.cross(omega, a) + velocity, axis=-1),
            np.linalg.norm(np.cross(omega, b) + velocity, axis=-1),
        )
        + np.linalg.norm(omega, axis=-1) * radii
    )
    return a, b, radii, speed


def _clearances(
    motion: SampledMotion, capsules: list[LinkCapsules], pairs: _Pairs
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Capsule clearances at every pose ``(m, P)`` and their certified minimum per interval ``(m - 1, P)``:
    ``min(f_k, f_{k+1}, (f_k + f_{k+1} - L_k step) / 2)``, ``L_k`` the two capsules' larger speed bound at the
    interval's ends (a distance between two moving sets changes at most at the sum of their speeds)."""
    a, b, radii, speed = _placed(motion, capsules)
    i, j = pairs.first, pairs.second
    f = segment_distances(a[:, i], b[:, i], a[:, j], b[:, j]) - radii[i] - radii[j]
    lipschitz = speed[:, i] + speed[:, j]
    bound = np.maximum(lipschitz[:-1], lipschitz[1:])
    certified = np.minimum(np.minimum(f[:-1], f[1:]), 0.5 * (f[:-1] + f[1:] - bound * motion.step))
    return f, certified


def _pair_clearances(
    sub: SampledMotion, capsules: list[LinkCapsules], pairs: _Pairs, chosen: NDArray[np.int64]
) -> NDArray[np.float64]:
    """Clearance of capsule pair ``chosen[r]`` at pose ``r`` of ``sub``, for each ``r``."""
    a, b, radii, _ = _placed(sub, capsules)
    rows = np.arange(len(chosen))
    i, j = pairs.first[chosen], pairs.second[chosen]
    return segment_distances(a[rows, i], b[rows, i], a[rows, j], b[rows, j]) - radii[i] - radii[j]


def _allowance(
    sub: SampledMotion, capsules: list[LinkCapsules], pairs: _Pairs, chosen: NDArray[np.int64], step: float
) -> NDArray[np.float64]:
    """Half a step's travel at the pair's speed bound at pose ``r``: how far below a sampled local minimum the
    clearance may dip between the samples."""
    _, _, _, speed = _placed(sub, capsules)
    rows = np.arange(len(chosen))
    return 0.5 * step * (speed[rows, pairs.first[chosen]] + speed[rows, pairs.second[chosen]])


def proxy_clearance(
    loop: SingleLoop, motion: SampledMotion, stacking: Stacking, design: LinkDesign | None = None
) -> ProxyClearance:
    """The smallest certified proxy clearance of every pair of links along ``motion`` (module docstring)."""
    design = LinkDesign() if design is None else design
    capsules = _all_capsules(loop, stacking, design)
    pairs = _capsule_pairs(capsules)
    _, certified = _clearances(motion, capsules, pairs)
    values, angles = [], []
    for p in range(len(pairs.link_pairs)):
        block = certified[:, pairs.link_pair == p]
        k = int(np.argmin(block.min(axis=1)))
        values.append(float(block[k].min()))
        angles.append(0.5 * float(motion.angles[k] + motion.angles[k + 1]))
    return ProxyClearance(pairs.link_pairs, np.array(values), np.array(angles))


@dataclass(frozen=True)
class StackingDesign:
    """What :func:`design_stacking` found: the ``stacking``, its proxy ``clearance`` and the ``seconds`` it took."""

    stacking: Stacking
    clearance: ProxyClearance
    margin: float
    seconds: float

    def summary(self) -> str:
        shifts = ", ".join(f"{1e3 * t:.1f}" for t in self.stacking.offsets)
        spacers = ", ".join(f"{1e3 * g:.1f}" for g in self.stacking.spacers)
        return (
            f"{self.clearance.summary()}, margin {1e3 * self.margin:.2f} mm; stack offsets [{shifts}] mm, "
            f"spacers [{spacers}] mm; designed in {self.seconds:.1f} s"
        )


#: Poses per capsule pair given to the optimiser in a round: its smallest local minima along the motion.
_POSES_PER_PAIR = 6
#: Rounds of (choose the closest poses, optimise on them) before the design is judged.
_ROUNDS = 10


def _closest_poses(f: NDArray, certified: NDArray, limit: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """``(pose, pair)`` of the local minima of each pair's clearance ``f`` ``(m, P)`` below ``limit``, at most
    :data:`_POSES_PER_PAIR` per pair, the smallest first, and every pose whose interval's bound is below ``limit``."""
    before = np.vstack([f[:1] + 1.0, f[:-1]])
    after = np.vstack([f[1:], f[-1:] + 1.0])
    poses, pairs = [], []
    for p in range(f.shape[1]):
        minima = np.flatnonzero((f[:, p] <= before[:, p]) & (f[:, p] <= after[:, p]) & (f[:, p] < limit))
        chosen = set(minima[np.argsort(f[minima, p])][:_POSES_PER_PAIR].tolist())
        for k in np.flatnonzero(certified[:, p] < limit)[:_POSES_PER_PAIR]:
            chosen.add(int(k) if f[k, p] <= f[k + 1, p] else int(k + 1))
        poses += sorted(chosen)
        pairs += [p] * len(chosen)
    return np.array(poses, dtype=np.int64), np.array(pairs, dtype=np.int64)


#: Poses of the first, coarse design of each order (2 deg apart), refined on all the poses: the coarse problem has
#: fewer local minima for SLSQP to stall at.
_COARSE_POSES = 181
#: How far above the margin the optimiser aims (m), so that the check on every interval, whose bound takes the larger
#: speed of the interval's two ends, keeps the margin.
_CUSHION = 1e-4


def order_candidates(n: int, limit: int) -> list[tuple[int, ...]]:
    """Stacking orders to try, at most ``limit``: for an even loop first the alternating one (links 1, 3, ... outside
    at both their joints, links 0, 2, ... inside, as Bennett linkages are built), then the nominal one, then the rest
    by their number of joints that differ from the first (ties in lexicographic order)."""
    every = list(itertools.product((1, -1), repeat=n))
    first = tuple(1 if j % 2 == 0 else -1 for j in range(n)) if n % 2 == 0 else (1,) * n

    def rank(order: tuple[int, ...]) -> tuple:
        differing = sum(a != b for a, b in zip(order, first, strict=True))
        return (order != first, order != (1,) * n, differing, order)

    every.sort(key=rank)
    return every[:limit]


class _Bounds(NamedTuple):
    """The optimiser's bounds (mm): offsets within ``[-offset, offset]``, spacers within ``[0, spacer]``."""

    offset: float
    spacer: float


def _design_order(
    loop: SingleLoop,
    motion: SampledMotion,
    pairs: _Pairs,
    design: LinkDesign,
    margin: float,
    limits: _Bounds,
    orders: tuple[int, ...],
    x: NDArray[np.float64],
    step: float,
) -> NDArray[np.float64]:
    """The offsets and spacers (mm) of :func:`design_stacking` for one stacking order from ``x`` (its docstring:
    rounds, two phases), the allowance at a local minimum that of poses ``step`` apart (the final sampling's)."""
    n = loop.n
    bounds = [(-limits.offset, limits.offset)] * n + [(0.0, limits.spacer)] * n
    low, high = np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds])
    target = margin + _CUSHION

    def stacking_of(x: NDArray) -> Stacking:
        return Stacking(tuple(float(v) for v in 1e-3 * x[:n]), tuple(float(v) for v in 1e-3 * x[n:]), orders)

    def cost(x: NDArray) -> float:
        return float(np.sum(x[n:]) + 0.01 * np.sum(x[:n] ** 2))

    def cost_gradient(x: NDArray) -> NDArray:
        return np.concatenate([0.02 * x[:n], np.ones(n)])

    kept: set[tuple[int, int]] = set()  # (pose, pair) entries of every round so far: no cycling between pose sets
    for _ in range(_ROUNDS):
        capsules = _all_capsules(loop, stacking_of(x), design)
        f, certified = _clearances(motion, capsules, pairs)
        if certified.min() >= margin:
            break
        kept.update(zip(*(v.tolist() for v in _closest_poses(f, certified, target + 0.02)), strict=True))
        poses, chosen = (np.array(v, dtype=np.int64) for v in zip(*sorted(kept), strict=True))
        sub = SampledMotion(
            motion.angles[poses], 0.0, motion.transforms[poses], motion.omega[poses], motion.velocity[poses]
        )
        allowance = _allowance(sub, capsules, pairs, chosen, step)

        def gaps(x: NDArray, sub=sub, chosen=chosen, allowance=allowance) -> NDArray:
            clear = _pair_clearances(sub, _all_capsules(loop, stacking_of(x), design), pairs, chosen)
            return 1e3 * (clear - allowance - target)

        if gaps(x).min() < 0.0:  # phase 1: raise the smallest clearance to the margin
            raised = minimize(
                lambda y: -y[-1] + 1e-3 * cost(y[:-1]),
                np.append(x, gaps(x).min()),
                jac=lambda y: np.append(1e-3 * cost_gradient(y[:-1]), -1.0),
                method="SLSQP",
                bounds=[*bounds, (None, 0.5)],
                constraints=[{"type": "ineq", "fun": lambda y, gaps=gaps: gaps(y[:-1]) - y[-1]}],
                options={"maxiter": 100, "ftol": 1e-6},
            )
            x = np.clip(raised.x[:-1], low, high)
            logger.info("stacking %s, phase 1: %s, smallest %.3g mm", orders, raised.message, gaps(x).min())
        if gaps(x).min() >= -1e-6:  # phase 2: the least spacers and shifts that keep the margin
            least = minimize(
                cost,
                x,
                jac=cost_gradient,
                method="SLSQP",
                bounds=bounds,
                constraints=[{"type": "ineq", "fun": gaps}],
                options={"maxiter": 100, "ftol": 1e-6},
            )
            candidate = np.clip(least.x, low, high)
            if gaps(candidate).min() >= -1e-6:
                x = candidate
            logger.info("stacking %s, phase 2: %s, cost %.4g", orders, least.message, cost(x))
    return x


def design_stacking(
    loop: SingleLoop,
    driver: int = 0,
    start: ArrayLike | None = None,
    design: LinkDesign | None = None,
    margin: float = 1e-3,
    max_offset: float | None = None,
    max_spacer: float | None = None,
    n_poses: int = DEFAULT_POSES,
    max_orders: int = 16,
) -> StackingDesign:
    r"""The :class:`Stacking` with the least spacers and shifts whose links keep ``margin`` (m) along one revolution
    of ``driver`` from the closing pose near ``start`` (module docstring; ``docs/formulation.md``, (CF5)).

    For each stacking order of :func:`order_candidates` (at most ``max_orders``), until one keeps the margin, on 181
    of the poses (with their own allowance, which asks for more room, and where that fails with the allowance of all
    the poses) and then from that result on all ``n_poses``: in rounds, the poses
    where each compared capsule pair comes closest (local minima of its clearance :math:`f`) are taken, with the
    allowance :math:`L\,\Delta/2` of the speed bound there, and SLSQP first raises the smallest
    :math:`f - L\Delta/2` to the margin (maximises :math:`z` subject to :math:`f - L\Delta/2 \ge z`), then minimises
    :math:`\sum_j g_j + \epsilon \sum_j t_j^2` (mm, :math:`\epsilon` = 0.01/mm: a 10 mm shift weighs as a 1 mm
    spacer) keeping :math:`f - L\Delta/2 \ge` ``margin`` + 0.1 mm; every round starts from the last (the first
    from the nominal offsets), so the design is deterministic. The result is judged on every interval of the
    motion (:func:`proxy_clearance`). Bounds: :math:`|t_j|` <= ``max_offset`` (default a quarter of the loop's
    size), :math:`0 \le g_j` <= ``max_spacer`` (default and at most the reach of ``build_link``'s trimming beyond
    the housing, within which a housing and the other link's arm stay apart by construction). Raises
    :class:`GeometryError` naming the closest pair of links, the drive angle and the clearance reached (of the
    order that came closest) where no stacking found within the bounds keeps the margin.
    """
    clock = time.perf_counter()
    design = LinkDesign() if design is None else design
    if not 0.0 <= margin <= design.axial_gap:
        raise ValueError(
            f"margin {1e3 * margin:.3g} mm must lie in [0, axial gap {1e3 * design.axial_gap:.3g} mm]: at a shared "
            "joint the housings are one axial gap apart by construction; raise LinkDesign.axial_gap"
        )
    n = loop.n
    # Within the trimming's reach, a housing and the other link's arm at a shared joint stay apart by construction.
    spacer_limit = trim_reach(design) - design.housing_length - design.axial_gap
    max_offset = 0.25 * loop.scale if max_offset is None else max_offset
    max_spacer = spacer_limit if max_spacer is None else min(max_spacer, spacer_limit)
    limits = _Bounds(1e3 * max_offset, 1e3 * max_spacer)
    motion = sampled_motion(loop, driver, start, n_poses)
    coarse = motion if n_poses <= _COARSE_POSES else sampled_motion(loop, driver, start, _COARSE_POSES)
    pairs = _capsule_pairs(_all_capsules(loop, Stacking.nominal(n), design))
    closest: tuple[Stacking, ProxyClearance] | None = None
    for orders in order_candidates(n, max_orders):
        for allowance_step in (coarse.step, motion.step):  # the coarse poses' own allowance, then all the poses'
            x = _design_order(loop, coarse, pairs, design, margin, limits, orders, np.zeros(2 * n), allowance_step)
            x = _design_order(loop, motion, pairs, design, margin, limits, orders, x, motion.step)
            stacking = Stacking(tuple(float(v) for v in 1e-3 * x[:n]), tuple(float(v) for v in 1e-3 * x[n:]), orders)
            clearance = proxy_clearance(loop, motion, stacking, design)
            if closest is None or clearance.smallest[0] > closest[1].smallest[0]:
                closest = (stacking, clearance)
            if clearance.smallest[0] >= margin or coarse is motion:
                break
        if closest is not None and closest[1].smallest[0] >= margin:
            break
    assert closest is not None  # max_orders >= 1
    stacking, clearance = closest
    value, (a, b), angle = clearance.smallest
    seconds = time.perf_counter() - clock
    if value < margin:
        raise GeometryError(
            f"no collision-free stacking within the bounds (offsets <= {1e3 * max_offset:.3g} mm, spacers <= "
            f"{1e3 * max_spacer:.3g} mm, {max_orders} stacking orders): links {a} and {b} come within "
            f"{1e3 * value:.2f} mm at drive angle {np.degrees(angle):.1f} deg (margin {1e3 * margin:.3g} mm); "
            "widen the bounds or slim the links"
        )
    logger.info("collision-free stacking: %s", clearance.summary())
    return StackingDesign(stacking, clearance, margin, seconds)

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
one gap of the housing's radius beyond its end faces, as far as the other housing reaches) are apart by at least the
axial gap by construction and are not compared; the margin may therefore not exceed the axial gap.
"""

from __future__ import annotations

import functools
import itertools
import logging
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import differential_evolution, minimize

from ffrf.errors import GeometryError
from ffrf.geometry.capsule_kernels import capsule_clearances
from ffrf.geometry.link_capsules import (
    ARM,
    MOUNT,
    LinkCapsules,
    closest_points,
    link_capsules,
    segment_distances,
)
from ffrf.geometry.link_geometry import LinkDesign
from ffrf.scenes.linkage_description import drive_sign, joint_points
from kinematics import Line, SingleLoop, follow_driver, motion_tangents

__all__ = [
    "LinkBuildInput",
    "ProxyClearance",
    "SampledMotion",
    "Stacking",
    "StackingDesign",
    "design_stacking",
    "designed_axial_gap",
    "link_build_inputs",
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

    @classmethod
    def from_attach_points(cls, loop: SingleLoop, attach: ArrayLike, design: LinkDesign | None = None) -> Stacking:
        """The stacking whose housings sit on ``attach`` ``(n, 2, 3)`` (points on the axes, as :meth:`attach_points`
        gives them, or a Rational Linkages design's, :func:`kinematics.rational_mechanism.attach_points`); points
        closer than two housings' offsets are pushed apart about their middle (spacer 0)."""
        design = LinkDesign() if design is None else design
        attach = np.asarray(attach, dtype=float)
        if attach.shape != (loop.n, 2, 3):
            raise ValueError(f"attach points must be (n, 2, 3) = ({loop.n}, 2, 3), got {attach.shape}")
        points = joint_points(loop)
        offsets, spacers, orders = [], [], []
        for j, axis in enumerate(loop.axes):
            along = float((attach[j, 1] - attach[j, 0]) @ axis.direction)
            offsets.append(float((0.5 * (attach[j, 0] + attach[j, 1]) - points[j]) @ axis.direction))
            spacers.append(max(0.0, abs(along) - 2.0 * design.housing_offset))
            orders.append(1 if along >= 0.0 else -1)
        return cls(tuple(offsets), tuple(spacers), tuple(orders))

    @classmethod
    def starts_from_design(
        cls, loop: SingleLoop, attach: ArrayLike | None, design: LinkDesign | None = None
    ) -> tuple[Stacking, ...]:
        """A mechanism's own design as starts of :func:`design_stacking`: ``attach`` (its connection points, as
        :meth:`from_attach_points` reads them) as a stacking, where it is a design (two points at some joint apart;
        ``None`` or every joint's two points at one place: none)."""
        if attach is None:
            return ()
        attach = np.asarray(attach, dtype=float)
        if not np.any(np.linalg.norm(attach[:, 1] - attach[:, 0], axis=1) > 0.0):
            return ()
        return (cls.from_attach_points(loop, attach, design),)

    def order(self, joint: int) -> int:
        """``orders[joint]``, ``+1`` without orders."""
        return 1 if self.orders is None else int(self.orders[joint])

    def attach_points(
        self, loop: SingleLoop, design: LinkDesign | None = None, points: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]:
        """Housing centres ``(n, 2, 3)``: row ``j`` holds link ``j``'s and link ``j + 1``'s on :math:`h_j`
        (:class:`~ffrf.scenes.linkage_description.LinkageOptions`' ``attach_points``); ``points`` the loop's
        :func:`~ffrf.scenes.linkage_description.joint_points` where the caller has them already."""
        design = LinkDesign() if design is None else design
        if len(self.offsets) != loop.n or len(self.spacers) != loop.n:
            raise ValueError(f"a stacking of {loop.n} joints needs {loop.n} offsets and spacers")
        points = joint_points(loop) if points is None else points
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


def link_build_inputs(
    loop: SingleLoop, stacking: Stacking, design: LinkDesign | None = None, points: NDArray[np.float64] | None = None
) -> list[LinkBuildInput]:
    """Every link's :class:`LinkBuildInput` for ``stacking`` (link ``k`` carries :math:`h_{k-1}` and :math:`h_k`;
    link 0 the mount): the hook for checking a design on the link solids themselves (``points`` as
    :meth:`Stacking.attach_points`)."""
    design = LinkDesign() if design is None else design
    attach = stacking.attach_points(loop, design, points)
    s = design.housing_offset
    inputs = []
    for k in range(loop.n):
        first, second = loop.axes[k - 1], loop.axes[k]
        seats = np.stack([attach[k - 1, 1] - s * first.direction, attach[k, 0] + s * second.direction])
        inputs.append(LinkBuildInput((first, second), seats, k == 0))
    return inputs


@dataclass(frozen=True)
class SampledMotion:
    r"""The rigid loop's motion at poses ``angles`` (rad, the drive's angle, in the order of travel; ``steps``
    ``(m - 1,)`` the drive's turn between consecutive poses): each link's displacement ``transforms``
    ``(m, n, 4, 4)`` (Eq. (L1)) and its twist per radian of drive, ``omega`` and ``velocity`` ``(m, n, 3)``: a point
    :math:`p` of link ``k`` moves at :math:`\omega_k \times p + v_k` per radian (Eq. (L3) with the motion's
    tangent)."""

    angles: NDArray[np.float64]
    steps: NDArray[np.float64]
    transforms: NDArray[np.float64]
    omega: NDArray[np.float64]
    velocity: NDArray[np.float64]

    def at(self, poses: NDArray[np.int64]) -> SampledMotion:
        """The motion at ``poses`` only (``steps`` of what remains between them)."""
        return SampledMotion(
            self.angles[poses],
            np.abs(np.diff(self.angles[poses])),
            self.transforms[poses],
            self.omega[poses],
            self.velocity[poses],
        )

    def spacing(self) -> NDArray[np.float64]:
        """Per pose the larger of the steps either side (``(m,)``)."""
        padded = np.concatenate([self.steps[:1], self.steps, self.steps[-1:]])
        return np.maximum(padded[:-1], padded[1:])


def sampled_motion(
    loop: SingleLoop,
    driver: int = 0,
    start: ArrayLike | None = None,
    n_poses: int = DEFAULT_POSES,
    travel: float | None = None,
) -> SampledMotion:
    """One revolution of joint ``driver`` from the closing pose near ``start`` (default home), ``n_poses`` poses
    from the start to the end of the turn (the way the drive turns, :func:`drive_sign`), equally spaced in the
    drive's angle; with ``travel`` (m) every interval where a joint point moves farther (its speed at the
    interval's ends times the step) is split into equal parts that each move it at most about ``travel``, so that
    the poses crowd where the loop moves fast for its drive (near a dead point of another joint). The joint points
    only guide the spacing: the clearance's bound between poses (:func:`proxy_clearance`) takes every capsule's own
    speed and each interval's own step."""
    sign = drive_sign(driver, loop.n)
    turns = np.linspace(0.0, sign * 2 * np.pi, n_poses)
    motion = _motion_at(loop, driver, start, turns)
    if travel is None:
        return motion
    points = joint_points(loop)
    placed = np.einsum("mkij,kj->mki", motion.transforms[:, :, :3, :3], points) + motion.transforms[:, :, :3, 3]
    # joint point k lies on axis k, which moves with link k (and is the same point of link k + 1)
    speed = np.linalg.norm(np.cross(motion.omega, placed) + motion.velocity, axis=-1).max(axis=1)
    parts = np.ceil(np.maximum(speed[:-1], speed[1:]) * motion.steps / travel).astype(int).clip(1, None)
    if parts.max() == 1:
        return motion
    refined = [np.linspace(turns[k], turns[k + 1], parts[k], endpoint=False) for k in range(len(parts))]
    return _motion_at(loop, driver, start, np.concatenate([*refined, turns[-1:]]))


def _motion_at(loop: SingleLoop, driver: int, start: ArrayLike | None, turns: NDArray) -> SampledMotion:
    """The motion with the driver turned by ``turns`` (rad, increasing in magnitude) from the closing pose near
    ``start``."""
    phi = np.zeros(loop.n) if start is None else np.asarray(start, dtype=float)
    first = 0.0 if start is None else float(phi[driver])
    motion = follow_driver(loop, driver, first + turns, start)
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
    angles = drive_sign(driver, n) * motion.driver_angles
    return SampledMotion(angles, np.abs(np.diff(angles)), transforms, omega, velocity)


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
    """The capsule pairs compared: index of each capsule (into all links' capsules) and its link pair (grouped:
    ``group_starts`` the first capsule pair of each link pair)."""

    first: NDArray[np.int64]
    second: NDArray[np.int64]
    link_pair: NDArray[np.int64]
    link_pairs: tuple[tuple[int, int], ...]
    group_starts: NDArray[np.int64]

    def per_link_pair(self, values: NDArray[np.float64]) -> NDArray[np.float64]:
        """The smallest of ``values`` ``(..., P)`` over each link pair's capsule pairs: ``(..., L)``."""
        return np.minimum.reduceat(values, self.group_starts, axis=-1)


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
    two housings there, and each of them against the other link's arm and mount block (by the links' parts: an
    arm's capsules change in number where its stubs appear)."""
    return _pairs_of_parts(tuple(c.parts for c in capsules))


@functools.lru_cache(maxsize=64)
def _pairs_of_parts(link_parts: tuple[tuple[int, ...], ...]) -> _Pairs:
    """:func:`_capsule_pairs` of links whose capsules are of ``link_parts``."""
    n = len(link_parts)
    owner = np.concatenate([[k] * len(parts) for k, parts in enumerate(link_parts)])
    parts = np.concatenate(link_parts)
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
    link_pair = np.array(pair_index)
    starts = np.flatnonzero(np.diff(link_pair, prepend=-1))
    return _Pairs(np.array(first), np.array(second), link_pair, tuple(link_pairs), starts)


def _all_capsules(
    loop: SingleLoop, stacking: Stacking, design: LinkDesign, points: NDArray[np.float64] | None = None
) -> list[LinkCapsules]:
    return [
        link_capsules(*link.axes, link.joint_points, design, link.mount)
        for link in link_build_inputs(loop, stacking, design, points)
    ]


def _owners(capsules: list[LinkCapsules]) -> NDArray[np.int64]:
    """The link of every capsule, in the order of the concatenated capsules."""
    return np.concatenate([[k] * len(c.radii) for k, c in enumerate(capsules)]).astype(np.int64)


def _placed(motion: SampledMotion, capsules: list[LinkCapsules]) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    r"""Every capsule's segment ends ``(m, K, 3)`` at every pose, its radius ``(K,)`` and its speed bound ``(m, K)``
    per radian of drive: :math:`|\omega \times p + v|` is convex in :math:`p`, so its largest value on a segment is
    at an end, and a ball of radius :math:`r` about it adds :math:`|\omega| r`."""
    owner = _owners(capsules)
    a, b, radii = _placed_ends(motion.transforms, capsules)
    omega, velocity = motion.omega[:, owner], motion.velocity[:, owner]
    speed = (
        np.maximum(
            np.linalg.norm(np.cross(omega, a) + velocity, axis=-1),
            np.linalg.norm(np.cross(omega, b) + velocity, axis=-1),
        )
        + np.linalg.norm(omega, axis=-1) * radii
    )
    return a, b, radii, speed


def _placed_ends(transforms: NDArray, capsules: list[LinkCapsules]) -> tuple[NDArray, NDArray, NDArray]:
    """Every capsule's segment ends ``(m, K, 3)`` at the poses of the links' ``transforms`` ``(m, n, 4, 4)``
    and its radius ``(K,)``."""
    placed = transforms[:, _owners(capsules)]
    rotation, shift = placed[..., :3, :3], placed[..., :3, 3]
    a = np.einsum("mkij,kj->mki", rotation, np.concatenate([c.starts for c in capsules])) + shift
    b = np.einsum("mkij,kj->mki", rotation, np.concatenate([c.ends for c in capsules])) + shift
    return a, b, np.concatenate([c.radii for c in capsules])


def _clearances(
    motion: SampledMotion, capsules: list[LinkCapsules], pairs: _Pairs
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Capsule clearances at every pose ``(m, P)`` and their certified minimum per interval ``(m - 1, P)``:
    ``min(f_k, f_{k+1}, (f_k + f_{k+1} - L_k step_k) / 2)``, ``L_k`` the two capsules' larger speed bound at the
    interval's ends (a distance between two moving sets changes at most at the sum of their speeds)."""
    a, b, radii, speed = _placed(motion, capsules)
    i, j = pairs.first, pairs.second
    f = capsule_clearances(a, b, radii, i, j)
    lipschitz = speed[:, i] + speed[:, j]
    bound = np.maximum(lipschitz[:-1], lipschitz[1:])
    certified = np.minimum(np.minimum(f[:-1], f[1:]), 0.5 * (f[:-1] + f[1:] - bound * motion.steps[:, None]))
    return f, certified


def _pair_clearances(
    sub: SampledMotion, capsules: list[LinkCapsules], pairs: _Pairs, chosen: NDArray[np.int64]
) -> NDArray[np.float64]:
    """Clearance of capsule pair ``chosen[r]`` at pose ``r`` of ``sub``, for each ``r``."""
    a, b, radii = _placed_ends(sub.transforms, capsules)
    rows = np.arange(len(chosen))
    i, j = pairs.first[chosen], pairs.second[chosen]
    return segment_distances(a[rows, i], b[rows, i], a[rows, j], b[rows, j]) - radii[i] - radii[j]


def _link_pair_clearances(
    sub: SampledMotion, capsules: list[LinkCapsules], pairs: _Pairs, chosen: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Clearance of link pair ``chosen[r]`` at pose ``r`` of ``sub`` (the smallest of its capsule pairs), and which
    capsule pair it is, for each ``r``."""
    a, b, radii = _placed_ends(sub.transforms, capsules)
    f = capsule_clearances(a, b, radii, pairs.first, pairs.second)
    f = np.where(pairs.link_pair[None, :] == chosen[:, None], f, np.inf)
    closest = np.argmin(f, axis=1)
    return f[np.arange(len(chosen)), closest], closest


class _EndRates(NamedTuple):
    """Derivatives of every capsule's segment ends (home pose) by the design variables: ``(K, 3, N)`` each."""

    starts: NDArray[np.float64]
    ends: NDArray[np.float64]


def _end_rates(inputs: list[LinkBuildInput], design: LinkDesign, orders: tuple[int, ...], step: float) -> _EndRates:
    r""":class:`_EndRates` by the offsets and spacers in mm (``x`` of :func:`_design_order`): link ``k``'s capsules
    depend on the variables only through its two seats, each moving along its axis (:meth:`Stacking.attach_points`:
    by :math:`t_j` and by :math:`\pm o_j g_j / 2`, :math:`+` on link :math:`j + 1`), so per link two central
    differences of ``step`` (m) along the axes (one-sided where a difference changes the number of the link's
    capsules, as an arm's stubs appear), chained to the variables."""
    n = len(inputs)
    columns = []
    for link in inputs:
        base = link_capsules(*link.axes, link.joint_points, design, link.mount)
        per_seat = []
        for side in (0, 1):
            shift = np.zeros((2, 3))
            shift[side] = step * link.axes[side].direction
            moved: list[LinkCapsules] = []
            for sign in (1.0, -1.0):
                shifted = link_capsules(*link.axes, link.joint_points + sign * shift, design, link.mount)
                moved.append(shifted if len(shifted.radii) == len(base.radii) else base)
            width = 2.0 * step - step * sum(m is base for m in moved)
            if width == 0.0:  # a change of shape on both sides: no derivative there
                per_seat.append((np.zeros_like(base.starts), np.zeros_like(base.ends)))
                continue
            high, low = moved
            per_seat.append(((high.starts - low.starts) / width, (high.ends - low.ends) / width))
        columns.append(per_seat)
    sizes = [len(seat[0][0]) for seat in columns]
    first = np.cumsum([0, *sizes])
    starts = np.zeros((first[-1], 3, 2 * n))
    ends = np.zeros_like(starts)
    for k, ((start_0, end_0), (start_1, end_1)) in enumerate(columns):
        rows = slice(first[k], first[k + 1])
        before, after = (k - 1) % n, k  # the joints on link k's first and second axes
        for variable, scale, start_rate, end_rate in (
            (before, 1.0, start_0, end_0),
            (n + before, 0.5 * orders[before], start_0, end_0),
            (after, 1.0, start_1, end_1),
            (n + after, -0.5 * orders[after], start_1, end_1),
        ):
            starts[rows, :, variable] += 1e-3 * scale * start_rate  # variables in mm
            ends[rows, :, variable] += 1e-3 * scale * end_rate
    return _EndRates(starts, ends)


def _pair_clearance_gradients(
    sub: SampledMotion, capsules: list[LinkCapsules], rates: _EndRates, pairs: _Pairs, chosen: NDArray[np.int64]
) -> NDArray[np.float64]:
    """Gradient ``(R, N)`` of :func:`_pair_clearances` by the design variables: the motion of the two closest points
    along their separation (the closest parameters :math:`s, t` stay put to first order, as a minimum's value
    moves only with its function); where the segments cross, along the normal of both."""
    a, b, _ = _placed_ends(sub.transforms, capsules)
    rows = np.arange(len(chosen))
    i, j = pairs.first[chosen], pairs.second[chosen]
    s, t, gap = closest_points(a[rows, i], b[rows, i], a[rows, j], b[rows, j])
    length = np.linalg.norm(gap, axis=-1)
    across = np.cross(b[rows, i] - a[rows, i], b[rows, j] - a[rows, j])
    across_length = np.linalg.norm(across, axis=-1)
    crossing = length <= 1e-12
    normal = np.where(
        crossing[:, None],
        across / np.where(across_length > 0.0, across_length, 1.0)[:, None],
        gap / np.where(crossing, 1.0, length)[:, None],
    )
    owner = _owners(capsules)
    rotation_i = sub.transforms[rows, owner[i], :3, :3]
    rotation_j = sub.transforms[rows, owner[j], :3, :3]
    moved_i = (1.0 - s)[:, None, None] * rates.starts[i] + s[:, None, None] * rates.ends[i]
    moved_j = (1.0 - t)[:, None, None] * rates.starts[j] + t[:, None, None] * rates.ends[j]
    moved = np.einsum("rab,rbn->ran", rotation_i, moved_i) - np.einsum("rab,rbn->ran", rotation_j, moved_j)
    return np.einsum("ra,ran->rn", normal, moved)


def _allowance(
    sub: SampledMotion,
    capsules: list[LinkCapsules],
    pairs: _Pairs,
    closest: NDArray[np.int64],
    spacing: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Half a step's travel at the speed bound of capsule pair ``closest[r]`` at pose ``r`` (``spacing[r]`` the
    larger step either side of it in the whole sampling): how far below a sampled local minimum the clearance may
    dip between the samples."""
    _, _, _, speed = _placed(sub, capsules)
    rows = np.arange(len(closest))
    return 0.5 * spacing * (speed[rows, pairs.first[closest]] + speed[rows, pairs.second[closest]])


def proxy_clearance(
    loop: SingleLoop, motion: SampledMotion, stacking: Stacking, design: LinkDesign | None = None
) -> ProxyClearance:
    """The smallest certified proxy clearance of every pair of links along ``motion`` (module docstring)."""
    design = LinkDesign() if design is None else design
    capsules = _all_capsules(loop, stacking, design)
    pairs = _capsule_pairs(capsules)
    _, certified = _clearances(motion, capsules, pairs)
    per_pair = pairs.per_link_pair(certified)
    k = np.argmin(per_pair, axis=0)
    angles = 0.5 * (motion.angles[k] + motion.angles[k + 1])
    return ProxyClearance(pairs.link_pairs, per_pair[k, np.arange(len(k))], angles)


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


#: Poses of the local design's first pass (2 deg apart, more where the loop moves fast).
_COARSE_POSES = 181
#: Largest travel (m) of a joint point between the poses a design is judged at (:func:`sampled_motion`): 0.25 deg
#: apart by default, more where the loop moves fast for its drive.
_TRAVEL = 2e-3
#: How far above the margin the optimiser aims (m): room for the check on every interval, whose bound takes the larger
#: speed of the interval's two ends, and for the check on the meshed solids, which bounds the clearance between its
#: own, fewer poses (Eq. (CL3); with 0.1 mm a design of bennett_ark24 kept 1.00 mm at every pose, proven 0.67 mm).
_CUSHION = 5e-4


def designed_axial_gap(margin: float, given: float | None = None) -> float:
    """The axial gap (m) of links designed to keep ``margin`` (m) when the user gives none (``given`` ``None``): the
    default one, widened to ``margin`` + 0.5 mm. Beside a joint, an arm is trimmed one axial gap from the other link's
    housing (:func:`~ffrf.geometry.link_geometry.build_link`), a distance that stays the same as the joint turns: at a
    gap equal to the margin (1 mm both by default) the check on the solids could not prove it between its poses."""
    if given is not None:
        return given
    return max(LinkDesign().axial_gap, margin + _CUSHION)


#: Step (m) of the central differences of the capsules' ends by a seat's position along its axis (they are affine in
#: it but for an arm's direction, so the difference's error is far below the clearances' tolerance).
_DIFFERENCE_STEP = 1e-6


def _cost(x: NDArray[np.float64], n: int) -> float:
    """What the design minimises (mm): the spacers, and the offsets' squares at 0.01/mm (a 10 mm shift weighs as a
    1 mm spacer)."""
    return float(np.sum(x[n:]) + 0.01 * np.sum(x[:n] ** 2))


def _with_column(matrix: NDArray[np.float64], value: float) -> NDArray[np.float64]:
    """``matrix`` with a last column of ``value``."""
    return np.hstack([matrix, np.full((len(matrix), 1), value)])


class _Bounds(NamedTuple):
    """The optimiser's bounds (mm): offsets within ``[-offset, offset]``, spacers within ``[least_spacer, spacer]``."""

    offset: float
    spacer: float
    least_spacer: float


def _design_order(
    loop: SingleLoop,
    motion: SampledMotion,
    design: LinkDesign,
    margin: float,
    limits: _Bounds,
    orders: tuple[int, ...],
    x: NDArray[np.float64],
    spacing: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """The offsets and spacers (mm) of :func:`design_stacking` for one stacking order from ``x`` (its docstring:
    rounds, two phases); the allowance at a pose from ``spacing`` (default the motion's own,
    :meth:`SampledMotion.spacing`)."""
    n = loop.n
    bounds = [(-limits.offset, limits.offset)] * n + [(limits.least_spacer, limits.spacer)] * n
    low, high = np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds])
    target = margin + _CUSHION

    def stacking_of(x: NDArray) -> Stacking:
        return Stacking(tuple(float(v) for v in 1e-3 * x[:n]), tuple(float(v) for v in 1e-3 * x[n:]), orders)

    def cost(x: NDArray) -> float:
        return _cost(x, n)

    def cost_gradient(x: NDArray) -> NDArray:
        return np.concatenate([0.02 * x[:n], np.ones(n)])

    points = joint_points(loop)

    def capsules_at(x: NDArray) -> list[LinkCapsules]:
        return _all_capsules(loop, stacking_of(x), design, points)

    kept: set[tuple[int, int]] = set()  # (pose, capsule pair) entries of the rounds so far: no cycling between sets
    structure = None  # the capsule pairs the kept entries index (an arm's stubs change them)
    minimised = False  # a start that keeps the margin still has its cost minimised once
    kept_margin: list[NDArray] = []  # every round's start that keeps the margin: the cheapest is the fallback
    reach = np.inf  # how far (mm) a step may move x: halved where a refused step changed the capsule pairs

    def judged(x: NDArray) -> tuple[float, _Pairs, NDArray, NDArray]:
        """The smallest clearance certified on every interval at ``x``, its capsule pairs, ``f`` and ``certified``."""
        capsules = capsules_at(x)
        pairs = _capsule_pairs(capsules)
        f, certified = _clearances(motion, capsules, pairs)
        return float(certified.min()), pairs, f, certified

    def refused_step(
        candidate: NDArray, x: NDArray, pairs: _Pairs, kept: set, limit: float, reach: float
    ) -> float | None:
        """``None`` where a step from ``x`` to ``candidate`` keeps the margin on every interval or, where ``x`` misses
        it, comes no closer. The round's constraints are the poses where x's capsules come closest, and a long step
        can bring others close: a step that does is refused, its closest poses join the constraints ``kept`` (or,
        where its capsule pairs differ, the reach of the next steps is halved), and the reach is returned."""
        smallest, now, f_now, certified_now = judged(candidate)
        if smallest >= min(margin, judged(x)[0]):
            return None
        if now is pairs:
            kept.update(zip(*(v.tolist() for v in _closest_poses(f_now, certified_now, limit)), strict=True))
            return reach
        return 0.5 * float(np.max(np.abs(candidate - x)))

    for _ in range(_ROUNDS):
        capsules = capsules_at(x)
        pairs = _capsule_pairs(capsules)
        f, certified = _clearances(motion, capsules, pairs)
        if certified.min() >= margin:
            kept_margin.append(x)
            if minimised:
                break
        if pairs is not structure:
            kept, structure = set(), pairs
        limit = max(target, float(f.min())) + 0.02
        kept.update(zip(*(v.tolist() for v in _closest_poses(f, certified, limit)), strict=True))
        poses, chosen = (np.array(v, dtype=np.int64) for v in zip(*sorted(kept), strict=True))
        sub = motion.at(poses)
        allowance = _allowance(sub, capsules, pairs, chosen, (motion.spacing() if spacing is None else spacing)[poses])

        def closest_at(x: NDArray, sub=sub, chosen=chosen, pairs=pairs) -> tuple[list, _Pairs, NDArray, NDArray]:
            """Capsules at ``x``, their pairs, each constraint's clearance and capsule pair: the round's capsule
            pairs, or, where an arm's stubs change them at ``x``, the closest capsule pair of the same links."""
            capsules = capsules_at(x)
            now = _capsule_pairs(capsules)
            if now is pairs:
                return capsules, now, _pair_clearances(sub, capsules, now, chosen), chosen
            clear, closest = _link_pair_clearances(sub, capsules, now, pairs.link_pair[chosen])
            return capsules, now, clear, closest

        def gaps(x: NDArray, allowance=allowance, closest_at=closest_at) -> NDArray:
            return 1e3 * (closest_at(x)[2] - allowance - target)

        def gaps_jacobian(x: NDArray, sub=sub, closest_at=closest_at) -> NDArray:
            capsules, now, _, closest = closest_at(x)
            rates = _end_rates(
                link_build_inputs(loop, stacking_of(x), design, points), design, orders, _DIFFERENCE_STEP
            )
            return 1e3 * _pair_clearance_gradients(sub, capsules, rates, now, closest)

        near = list(zip(np.maximum(low, x - reach), np.minimum(high, x + reach), strict=True))

        if gaps(x).min() < 0.0:  # phase 1: raise the smallest clearance to the margin
            weight = 1e-3 / max(1.0, cost(x))  # the cost only breaks ties, wherever the start
            raised = minimize(
                lambda y, weight=weight: -y[-1] + weight * cost(y[:-1]),
                np.append(x, gaps(x).min()),
                jac=lambda y, weight=weight: np.append(weight * cost_gradient(y[:-1]), -1.0),
                method="SLSQP",
                bounds=[*near, (None, 0.5)],
                constraints=[
                    {
                        "type": "ineq",
                        "fun": lambda y, gaps=gaps: gaps(y[:-1]) - y[-1],
                        "jac": lambda y, gaps_jacobian=gaps_jacobian: _with_column(gaps_jacobian(y[:-1]), -1.0),
                    }
                ],
                options={"maxiter": 100, "ftol": 1e-6},
            )
            candidate = np.clip(raised.x[:-1], low, high)
            shorter = refused_step(candidate, x, pairs, kept, limit, reach)
            if shorter is not None:
                reach = shorter
                logger.info("stacking %s, phase 1: a step came closer elsewhere", orders)
                continue
            x = candidate
            logger.info("stacking %s, phase 1: %s, smallest %.3g mm", orders, raised.message, gaps(x).min())
        if gaps(x).min() >= -1e-6:  # phase 2: the least spacers and shifts that keep the margin
            least = minimize(
                cost,
                x,
                jac=cost_gradient,
                method="SLSQP",
                bounds=near,
                constraints=[{"type": "ineq", "fun": gaps, "jac": gaps_jacobian}],
                options={"maxiter": 100, "ftol": 1e-6},
            )
            candidate = np.clip(least.x, low, high)
            shorter = refused_step(candidate, x, pairs, kept, limit, reach)
            if shorter is not None:
                reach = shorter
                logger.info("stacking %s, phase 2: a step to cost %.4g left the margin", orders, cost(candidate))
            else:
                minimised = True
                if gaps(candidate).min() >= -1e-6:
                    x = candidate
                logger.info("stacking %s, phase 2: %s, cost %.4g", orders, least.message, cost(x))
    capsules = capsules_at(x)
    if _clearances(motion, capsules, _capsule_pairs(capsules))[1].min() >= margin or not kept_margin:
        return x
    return min(kept_margin, key=cost)


#: Poses of the global search: 4 deg apart, and a joint point's travel between them at most about 20 mm.
_SEARCH_POSES, _SEARCH_TRAVEL = 91, 20e-3
#: The global search stops once its best stacking keeps this much (m) beyond the margin at its poses: room for the
#: minima between them, which the local design then certifies.
_SEARCH_HEADROOM = 1e-3
#: Population per variable and generations of the global search.
_SEARCH_POPULATION, _SEARCH_GENERATIONS = 12, 300


def _search_stacking(
    loop: SingleLoop,
    motion: SampledMotion,
    design: LinkDesign,
    margin: float,
    limits: _Bounds,
) -> tuple[NDArray[np.float64], tuple[int, ...]]:
    """The global stage of :func:`design_stacking`: offsets and spacers (mm) and orders (integers) by differential
    evolution (seeded, so deterministic) minimising the summed shortfall of each link pair's smallest capsule
    clearance at ``motion``'s poses below the margin and :data:`_SEARCH_HEADROOM` (plus a thousandth of the cost),
    stopped once no pair falls short."""
    n = loop.n
    points = joint_points(loop)
    target = 1e3 * (margin + _SEARCH_HEADROOM)

    bounds = np.array(
        [(-limits.offset, limits.offset)] * n + [(limits.least_spacer, limits.spacer)] * n + [(0.0, 1.0)] * n
    )
    free = bounds[:, 1] > bounds[:, 0]  # the search runs over the variables with room; the rest stay at their bound

    def split(free_values: NDArray) -> tuple[NDArray, tuple[int, ...]]:
        y = bounds[:, 0].copy()
        y[free] = free_values
        return y[: 2 * n], tuple(1 if v > 0.5 else -1 for v in y[2 * n :])

    def smallest_per_link_pair(free_values: NDArray) -> NDArray:
        x, orders = split(free_values)
        capsules = _all_capsules(loop, Stacking(tuple(1e-3 * x[:n]), tuple(1e-3 * x[n:]), orders), design, points)
        pairs = _capsule_pairs(capsules)
        a, b, radii = _placed_ends(motion.transforms, capsules)
        return 1e3 * pairs.per_link_pair(capsule_clearances(a, b, radii, pairs.first, pairs.second).min(axis=0))

    def objective(free_values: NDArray) -> float:
        x, _ = split(free_values)
        shortfall = np.maximum(target - smallest_per_link_pair(free_values), 0.0).sum()
        return float(shortfall) + 1e-3 * float(np.sum(x[n:]) + 0.01 * np.sum(x[:n] ** 2))

    def kept(intermediate_result) -> bool:
        return smallest_per_link_pair(intermediate_result.x).min() >= target

    found = differential_evolution(
        objective,
        bounds[free],
        integrality=np.arange(3 * n)[free] >= 2 * n,
        popsize=_SEARCH_POPULATION,
        maxiter=_SEARCH_GENERATIONS,
        seed=0,
        updating="deferred",
        polish=False,
        callback=kept,
    )
    logger.info(
        "stacking search: %s after %d generations, smallest %.3g mm",
        found.message,
        found.nit,
        smallest_per_link_pair(found.x).min(),
    )
    return split(np.asarray(found.x, dtype=float))


def design_stacking(
    loop: SingleLoop,
    driver: int = 0,
    start: ArrayLike | None = None,
    design: LinkDesign | None = None,
    margin: float = 1e-3,
    max_offset: float | None = None,
    max_spacer: float | None = None,
    n_poses: int = DEFAULT_POSES,
    starts: tuple[Stacking, ...] = (),
) -> StackingDesign:
    r"""The :class:`Stacking` with the least spacers and shifts whose links keep ``margin`` (m) along one revolution
    of ``driver`` from the closing pose near ``start`` (module docstring; ``docs/formulation.md``, (CF5)).

    From the nominal offsets with the order Bennett linkages are built in and from each of ``starts`` (such as the
    mechanism's own design, :meth:`Stacking.from_attach_points`), and where none of these keeps the margin also
    from a global search (:func:`_search_stacking`: differential evolution over offsets, spacers and the orders at
    91 poses, more where the loop moves fast), a local design (the cheaper that keeps the margin is taken): on 181
    poses first, then on all ``n_poses`` (more where a joint point would move over 2 mm between them,
    :func:`sampled_motion`): in rounds, the poses where each compared capsule pair comes closest (local minima of
    its clearance :math:`f`) are taken, with the allowance :math:`L\,\Delta/2` of the speed bound there, and SLSQP
    (exact gradients) first raises the smallest :math:`f - L\Delta/2` to the margin (maximises :math:`z` subject to
    :math:`f - L\Delta/2 \ge z`), then minimises :math:`\sum_j g_j + \epsilon \sum_j t_j^2` (mm,
    :math:`\epsilon` = 0.01/mm: a 10 mm shift weighs as a 1 mm spacer) keeping :math:`f - L\Delta/2 \ge`
    ``margin`` + 0.5 mm; a step is taken only where it keeps the margin on every interval (from a start that misses
    it: comes no closer), else the poses it brought close join the constraints. Deterministic (a seeded search;
    every round starts from the last). The result is judged on
    every interval of the motion (:func:`proxy_clearance`). Bounds: :math:`|t_j|` <= ``max_offset`` (default half
    the loop's size, or the starts' largest offset), :math:`g_j` from ``margin`` + 0.5 mm less the axial gap (what
    stays apart by construction then keeps that much beyond the margin, for the check on the solids) to
    ``max_spacer`` (default the loop's size: the longest DH offset, where each link's housing sits at its own foot;
    the links' trimming reaches the other housing whatever the spacer,
    :func:`~ffrf.geometry.link_geometry.trim_covering`).
    Raises :class:`GeometryError` naming the closest pair of links, the drive angle and the clearance reached where
    the design does not keep the margin.
    """
    clock = time.perf_counter()
    design = LinkDesign() if design is None else design
    if not 0.0 <= margin <= design.axial_gap:
        raise ValueError(
            f"margin {1e3 * margin:.3g} mm must lie in [0, axial gap {1e3 * design.axial_gap:.3g} mm]: at a shared "
            "joint the housings are one axial gap apart by construction; raise LinkDesign.axial_gap"
        )
    n = loop.n
    if max_offset is None:
        max_offset = max([0.5 * loop.scale] + [abs(t) for start in starts for t in start.offsets])
    max_spacer = loop.scale if max_spacer is None else max_spacer
    # What stays one axial gap and the spacer apart by construction (the two housings at a joint, each against the
    # other link's arm there) is not compared, so the spacer keeps it margin + cushion apart: a check on the solids
    # could not prove a clearance that equals the margin between its poses.
    least_spacer = min(max(0.0, margin + _CUSHION - design.axial_gap), max_spacer)
    limits = _Bounds(1e3 * max_offset, 1e3 * max_spacer, 1e3 * least_spacer)
    motion = sampled_motion(loop, driver, start, n_poses, _TRAVEL)
    search = sampled_motion(loop, driver, start, _SEARCH_POSES, _SEARCH_TRAVEL)
    coarse = sampled_motion(loop, driver, start, _COARSE_POSES, _SEARCH_TRAVEL)
    finest = np.full(len(coarse.angles), 2 * np.pi / (n_poses - 1))

    def local(x: NDArray, orders: tuple[int, ...]) -> tuple[Stacking, ProxyClearance, float]:
        """The local design from ``x``: first on the coarse poses (fewer local minima for SLSQP to stall at) with
        their own allowance, which asks for more room, and where that fails with that of the final spacing; each
        then refined on all the poses."""
        best: tuple[Stacking, ProxyClearance, float] | None = None
        for spacing in (None, finest):
            y = _design_order(loop, coarse, design, margin, limits, orders, x, spacing)
            y = _design_order(loop, motion, design, margin, limits, orders, y)
            stacking = Stacking(tuple(float(v) for v in 1e-3 * y[:n]), tuple(float(v) for v in 1e-3 * y[n:]), orders)
            found = (stacking, proxy_clearance(loop, motion, stacking, design), _cost(y, n))
            if best is None or found[1].smallest[0] > best[1].smallest[0]:
                best = found
            if found[1].smallest[0] >= margin:
                break
        assert best is not None
        return best

    nominal = np.concatenate([np.zeros(n), np.full(n, limits.least_spacer)])
    # the order Bennett linkages are built in (links 1, 3, ... outside at both their joints; all +1 for an odd loop)
    designs = [local(nominal, tuple(1 if j % 2 == 0 or n % 2 else -1 for j in range(n)))]
    for given in starts:  # each within the bounds
        x = 1e3 * np.concatenate([given.offsets, given.spacers])
        x[:n] = np.clip(x[:n], -limits.offset, limits.offset)
        x[n:] = np.clip(x[n:], limits.least_spacer, limits.spacer)
        designs.append(local(x, tuple(given.order(j) for j in range(n))))
    if all(d[1].smallest[0] < margin for d in designs):  # then from the global search's result, with its orders
        designs.append(local(*_search_stacking(loop, search, design, margin, limits)))
    keeping = [d for d in designs if d[1].smallest[0] >= margin]
    stacking, clearance, _ = (
        min(keeping, key=lambda d: d[2]) if keeping else max(designs, key=lambda d: d[1].smallest[0])
    )
    value, (a, b), angle = clearance.smallest
    seconds = time.perf_counter() - clock
    if value < margin:
        raise GeometryError(
            f"no collision-free stacking within the bounds (offsets <= {1e3 * max_offset:.3g} mm, spacers <= "
            f"{1e3 * max_spacer:.3g} mm): links {a} and {b} come within {1e3 * value:.2f} mm at drive angle "
            f"{np.degrees(angle):.1f} deg (margin {1e3 * margin:.3g} mm); widen the bounds or slim the links"
        )
    logger.info("collision-free stacking: %s", clearance.summary())
    return StackingDesign(stacking, clearance, margin, seconds)

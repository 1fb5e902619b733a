r"""Signed clearance between the links of a linkage along its rigid motion, with a bound between the poses.

At each pose the clearance of two links is the signed distance of their solids (:mod:`ffrf.output.solid_distance`,
``docs/formulation.md`` Eqs. (CL1)-(CL3)): the smallest distance between them, or minus their penetration depth; for
links that share a joint, the surface within the joint's zone is left out. Along the motion every link moves rigidly
by its displacement from home (Eq. (L1)).

Between two sampled poses (Eq. (CL4)): the clearance is 1-Lipschitz in the relative displacement of the two solids
(a distance to a set moves no more than the set), so over a drive-angle interval of length ``h`` it drops below its
end values ``c0``, ``c1`` by no more than the largest relative point speed ``S`` (m per rad of drive) allows:

.. math:: c(\theta) \ge L = \min\big(c_0,\, c_1,\, (c_0 + c_1 - S h)/2\big), \qquad
          S = \kappa \max\big(s(\theta_0),\, s(\theta_1),\, \Delta / h\big),

with :math:`s = |\omega \times c + v| + |\omega| r` the largest point speed of one link relative to the other,
from their relative twist :math:`(\omega, v)` per unit drive angle (the loop's joint rates), the link's reference
point :math:`c` (its box centre) and radius :math:`r` about it (the smaller of the two links' values), :math:`\Delta`
the largest displacement between the interval's ends (the chord) and :math:`\kappa` = :data:`SPEED_SAFETY` = 1.5,
the assumption that the speed inside an interval stays below 1.5 times its largest end (or chord) value. Where
``L`` does not prove the margin, the interval is bisected (adaptive, at most ``max_bisections`` times, not where
no bisection left could prove it) until it does or the pair misses the margin at an evaluated pose; the report
keeps the bound reached (:attr:`Clearance.bound`: a pair whose bound is below the margin although its poses keep it
is reported as not proven).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from ffrf.output.solid_distance import DEPTH_TOLERANCE, JointZone, LinkSolid, SolidPair

__all__ = ["Clearance", "RigidMotion", "clearance_at", "signed_clearance", "SPEED_SAFETY"]

#: Safety factor on the largest relative point speed of an interval (Eq. (CL4)).
SPEED_SAFETY = 1.5


class RigidMotion(Protocol):
    """The links' rigid motion over a drive angle: ``drive_angles`` the sampled angles in the motion's order (rad;
    the last closes the range, e.g. the first plus a revolution), :meth:`poses` the links' displacements from home
    ``(m, n, 4, 4)`` and twists ``(m, n, 6)`` (angular, then linear velocity at the origin, world axes, per rad of
    drive) at any angles within the range."""

    @property
    def drive_angles(self) -> NDArray[np.float64]: ...

    def poses(self, angles: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...


@dataclass(frozen=True)
class Clearance:
    """Smallest signed clearance (m) of each pair of links over the motion and where it occurs.

    ``pairs`` ``(k, 2)`` link indices; ``distance`` ``(k,)`` the smallest clearance at the poses evaluated (negative:
    the links overlap by that much); ``drive_angle`` ``(k,)`` where (rad); ``bound`` ``(k,)`` the clearance the
    pair keeps everywhere between the poses (Eq. (CL4)); ``margin`` the clearance asked for (m); ``poses`` how many
    poses were evaluated per pair (the samples and the bisections).
    """

    pairs: NDArray[np.int64]
    distance: NDArray[np.float64]
    drive_angle: NDArray[np.float64]
    bound: NDArray[np.float64]
    margin: float
    poses: NDArray[np.int64]

    @property
    def met(self) -> NDArray[np.bool_]:
        """Per pair, whether it keeps the margin along the whole motion (between the poses too)."""
        return self.bound >= self.margin

    @property
    def margin_met(self) -> bool:
        """Whether every pair keeps the margin along the whole motion."""
        return bool(np.all(self.met))

    def summary(self) -> str:
        """One line per pair, then the verdict on the margin, in mm and deg."""
        lines = []
        for (a, b), gap, angle, bound in zip(self.pairs, self.distance, self.drive_angle, self.bound, strict=True):
            what = f"overlap by {-1e3 * gap:.2f} mm" if gap < 0.0 else f"closest {1e3 * gap:.2f} mm"
            line = f"links {a}-{b}: {what} at drive angle {np.degrees(angle):.1f} deg"
            if gap >= self.margin > bound:
                line += f" (between the poses only {1e3 * bound:.2f} mm is proven)"
            lines.append(line)
        missed = [f"{a}-{b}" for (a, b), gap in zip(self.pairs, self.distance, strict=True) if gap < self.margin]
        unproven = [
            f"{a}-{b}"
            for (a, b), gap, ok in zip(self.pairs, self.distance, self.met, strict=True)
            if gap >= self.margin and not ok
        ]
        margin = f"margin {1e3 * self.margin:g} mm"
        if not missed and not unproven:
            verdict = f"{margin} met by every pair along the whole motion"
        else:
            verdict = "; ".join(
                ([f"{margin} not met by links {', '.join(missed)}"] if missed else [])
                + ([f"{margin} kept at every pose but not proven between them by links {', '.join(unproven)}"]
                   if unproven else [])
            )  # fmt: skip
        return "; ".join(lines + [verdict])


def signed_clearance(
    solids: Sequence[LinkSolid],
    motion: RigidMotion,
    joint_zones: Mapping[tuple[int, int], JointZone] | None = None,
    margin: float = 1e-3,
    *,
    max_bisections: int = 10,
    tolerance: float = DEPTH_TOLERANCE,
) -> Clearance:
    """The signed clearance of every pair of ``solids`` (link ``k`` is ``solids[k]`` at home) along ``motion``
    (module docstring, Eqs. (CL1)-(CL4)).

    ``joint_zones[(a, b)]``, ``a < b``: the zone of the joint links ``a`` and ``b`` share (left out of that pair's
    check); ``margin``: the clearance asked for (m); ``max_bisections``: how often an interval may be halved;
    ``tolerance``: of the penetration depth (m)."""
    zones = {} if joint_zones is None else dict(joint_zones)
    angles = np.asarray(motion.drive_angles, dtype=float)
    transforms, twists = motion.poses(angles)
    n = len(solids)
    if transforms.shape[1] != n:
        raise ValueError(f"the motion moves {transforms.shape[1]} links, but {n} solids are given")
    steps = np.diff(angles)
    if len(angles) < 2 or not (np.all(steps > 0.0) or np.all(steps < 0.0)):
        raise ValueError(f"the motion's drive angles must be at least two, in strict order; got {angles}")
    spheres = [_sphere(solid) for solid in solids]
    pairs, distance, where, bound, counts = [], [], [], [], []
    for a in range(n):
        for b in range(a + 1, n):
            pair = SolidPair(solids[a], solids[b], zones.get((a, b)), tolerance)
            track = _PairTrack(pair, (a, b), (spheres[a], spheres[b]), float(np.sign(steps[0])))
            track.sample(angles, transforms, twists)
            track.refine(motion, margin, max_bisections)
            pairs.append((a, b))
            distance.append(track.smallest)
            where.append(track.smallest_at)
            bound.append(track.bound)
            counts.append(len(track.angles))
    return Clearance(
        np.array(pairs, dtype=np.int64).reshape(-1, 2),
        np.array(distance),
        np.array(where),
        np.array(bound),
        float(margin),
        np.array(counts, dtype=np.int64),
    )


def clearance_at(
    solids: Sequence[LinkSolid],
    motion: RigidMotion,
    joint_zones: Mapping[tuple[int, int], JointZone] | None,
    pairs: NDArray[np.int64],
    angles: NDArray[np.float64],
    *,
    tolerance: float = DEPTH_TOLERANCE,
) -> NDArray[np.float64]:
    """The signed clearance ``(k,)`` of each row of ``pairs`` ``(k, 2)`` (a pair may come in several rows) at the
    row's drive angle ``angles`` ``(k,)`` along ``motion`` (Eqs. (CL1)-(CL3)): e.g. at the poses where
    :func:`signed_clearance` found each pair's smallest."""
    zones = {} if joint_zones is None else dict(joint_zones)
    transforms, _ = motion.poses(np.asarray(angles, dtype=float))  # one pose per row, (k, links, 4, 4)
    built: dict[tuple[int, int], SolidPair] = {}  # a pair's zone cut once, whatever its number of rows
    out = np.empty(len(pairs))
    for row, (a, b) in enumerate(np.asarray(pairs).tolist()):
        if (a, b) not in built:
            built[a, b] = SolidPair(solids[a], solids[b], zones.get((a, b)), tolerance)
        out[row] = built[a, b].clearance(np.linalg.solve(transforms[row, a], transforms[row, b]))
    return out


def _sphere(solid: LinkSolid) -> tuple[NDArray[np.float64], float]:
    """A link's reference point at home (its box centre) and its radius about it (m)."""
    centre = 0.5 * (solid.vertices.min(axis=0) + solid.vertices.max(axis=0))
    return centre, float(np.max(np.linalg.norm(solid.vertices - centre, axis=1)))


class _PairTrack:
    """The clearance of one pair at its evaluated poses, kept sorted by drive angle, and the bisection of Eq. (CL4)."""

    def __init__(
        self, pair: SolidPair, links: tuple[int, int], spheres: tuple[tuple[NDArray, float], ...], sense: float
    ) -> None:
        self.pair, (self.a, self.b) = pair, links
        self.spheres = spheres
        self.sense = sense  # +1: the drive angle grows along the motion, -1: it falls
        self.angles = np.empty(0)
        self.values = np.empty(0)
        self.relative = np.empty((0, 4, 4))
        self.speeds = np.empty((0, 2))

    def sample(self, angles: NDArray, transforms: NDArray, twists: NDArray) -> None:
        """Evaluate the clearance and the relative point speeds at the poses ``angles`` (in the motion's order)."""
        a, b = self.a, self.b
        relative = np.linalg.solve(transforms[:, a], transforms[:, b])
        values = np.array([self.pair.clearance(r) for r in relative])
        twist = twists[:, b] - twists[:, a]
        speeds = np.stack(
            [_point_speed(twist, transforms[:, k], *sphere) for k, sphere in zip((a, b), self.spheres, strict=True)],
            axis=1,
        )
        order = np.argsort(self.sense * np.concatenate([self.angles, angles]), kind="stable")
        self.angles = np.concatenate([self.angles, angles])[order]
        self.values = np.concatenate([self.values, values])[order]
        self.relative = np.concatenate([self.relative, relative])[order]
        self.speeds = np.concatenate([self.speeds, speeds])[order]

    @property
    def smallest(self) -> float:
        return float(self.values.min())

    @property
    def smallest_at(self) -> float:
        return float(self.angles[int(np.argmin(self.values))])

    def _travel(self) -> NDArray[np.float64]:
        """``S h`` of Eq. (CL4) on every interval between neighbouring evaluated poses (m)."""
        h = np.abs(np.diff(self.angles))
        ends = np.maximum(self.speeds[:-1], self.speeds[1:])  # (intervals, 2): a's points, b's points
        chords = self._chords()
        return SPEED_SAFETY * np.min(np.maximum(ends, chords / h[:, None]), axis=1) * h

    def lower_bounds(self) -> NDArray[np.float64]:
        """Eq. (CL4) on every interval between neighbouring evaluated poses."""
        c0, c1 = self.values[:-1], self.values[1:]
        return np.minimum(np.minimum(c0, c1), 0.5 * (c0 + c1 - self._travel()))

    def _chords(self) -> NDArray[np.float64]:
        """Largest displacement of each link's points relative to the other between neighbouring poses."""
        (centre_a, radius_a), (centre_b, radius_b) = self.spheres
        d0, d1 = self.relative[:-1], self.relative[1:]  # b's home frame -> a's
        inverse0, inverse1 = np.linalg.inv(d0), np.linalg.inv(d1)
        b_moves = _displacement(d1 - d0, centre_b, radius_b)
        a_moves = _displacement(inverse1 - inverse0, centre_a, radius_a)
        return np.stack([a_moves, b_moves], axis=1)

    @property
    def bound(self) -> float:
        return float(min(self.values.min(), self.lower_bounds().min())) if len(self.values) > 1 else self.smallest

    def refine(self, motion: RigidMotion, margin: float, max_bisections: int) -> None:
        """Bisect the intervals whose bound does not prove the margin, round by round, at most ``max_bisections``
        times; not once the margin is missed at an evaluated pose (the verdict stands, the bound says how deep), nor
        an interval that the bisections left could not prove: one whose ends' clearance exceeds the margin by less
        than half its travel ``S h`` halved that often (a constant clearance equal to the margin never would)."""
        for done in range(max_bisections):
            if self.smallest < margin:
                return
            slack = np.minimum(self.values[:-1], self.values[1:]) - margin
            open_ = (self.lower_bounds() < margin) & (2.0 * slack > self._travel() / 2.0 ** (max_bisections - done))
            if not open_.any():
                return
            middle = 0.5 * (self.angles[:-1] + self.angles[1:])[open_]
            transforms, twists = motion.poses(middle)
            self.sample(middle, transforms, twists)


def _point_speed(twist: NDArray, transforms: NDArray, centre: NDArray, radius: float) -> NDArray[np.float64]:
    """Largest speed of a link's points about ``centre`` (home) within ``radius`` under the relative ``twist``
    ``(m, 6)`` at its poses ``transforms`` ``(m, 4, 4)``: ``|w x c + v| + |w| r``."""
    omega, velocity = twist[:, :3], twist[:, 3:]
    current = transforms[:, :3, :3] @ centre + transforms[:, :3, 3]
    return np.linalg.norm(np.cross(omega, current) + velocity, axis=1) + np.linalg.norm(omega, axis=1) * radius


def _displacement(change: NDArray, centre: NDArray, radius: float) -> NDArray[np.float64]:
    """Bound of ``|change @ x|`` over points ``x`` within ``radius`` of ``centre``: ``|change c| + ||dR|| r``."""
    at_centre = np.linalg.norm(change[:, :3, :3] @ centre + change[:, :3, 3], axis=1)
    return at_centre + np.linalg.norm(change[:, :3, :3], ord=2, axis=(1, 2)) * radius

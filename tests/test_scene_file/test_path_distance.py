"""The distance to the ideal path is exact (ffrf.output.path_distance, Eq. (C1)), not that of a polyline through
samples of the curve: checked against closed forms (a circle run at uneven speed, a planar four-bar's coupler
curve) and against the rigid loop followed by continuation (the paper's Bennett linkage, whose curve comes from
its motion polynomial)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from ffrf.fe.materials import RIGID
from ffrf.output.path_distance import ExactCurve, distance_to_curve
from ffrf.paper.bennett_scene import build_bennett
from ffrf.scenes.linkage_description import LinkageOptions, joint_points
from ffrf.scenes.linkage_scene import build_linkage
from kinematics import SingleLoop

RADIUS = 0.1


def _uneven_circle(n: int) -> ExactCurve:
    """A circle of radius 0.1 m in z = 0.02 m run at a speed that changes 19-fold over a period:
    phi(theta) = theta + 0.9 sin(theta)."""

    def exact(angles: np.ndarray, arcs: np.ndarray) -> np.ndarray:
        phi = angles + 0.9 * np.sin(angles)
        return np.column_stack([RADIUS * np.cos(phi), RADIUS * np.sin(phi), np.full(len(phi), 0.02)])

    angles = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return ExactCurve(angles, exact(angles, np.zeros(n, dtype=np.int64)), 2 * np.pi, exact)


def _polyline_distance(points: np.ndarray, samples: np.ndarray) -> np.ndarray:
    """Distance to the closed polyline through ``samples`` (what the distance was before, issue #32)."""
    start, chord = samples, np.roll(samples, -1, axis=0) - samples
    rel = points[:, None, :] - start[None]
    s = np.clip(np.einsum("kij,ij->ki", rel, chord) / np.einsum("ij,ij->i", chord, chord), 0.0, 1.0)
    return np.min(np.linalg.norm(rel - s[..., None] * chord, axis=2), axis=1)


def test_distance_to_a_circle_run_at_uneven_speed_is_its_closed_form(rng):
    """Any point's distance to the circle is sqrt((rho - R)^2 + (z - z0)^2) (rho: its distance from the axis):
    points on the curve, in its plane inside and outside it, and off the plane, agree to 1e-12 m, where the
    polyline through the 72 samples is off by a third of a millimetre at the fast end (measured 3.3e-4 m)."""
    curve = _uneven_circle(72)
    radial = rng.uniform(-5e-3, 5e-3, 400)
    height = rng.uniform(-5e-3, 5e-3, 400)
    height[:100] = radial[:100] = 0.0  # on the curve
    phi = rng.uniform(0.0, 2 * np.pi, 400)
    points = np.column_stack([(RADIUS + radial) * np.cos(phi), (RADIUS + radial) * np.sin(phi), 0.02 + height])
    found = distance_to_curve(points, curve)
    truth = np.hypot(radial, height)
    assert np.all(found.converged)
    assert np.max(np.abs(found.distance - truth)) < 1e-12
    assert np.max(_polyline_distance(points, curve.points) - truth) > 1e-4  # the old metric: far off


def test_the_distance_to_a_curve_with_an_inner_loop_is_that_of_a_dense_search_refined_by_brent(rng):
    """A limacon r = b + a cos t (a > b: an inner loop inside the outer curve) from only 40 samples, so that a
    point's nearest sample is often on the other branch than its closest curve point: the distance of points
    anywhere around it is the independent minimum (200 000 samples, then scipy's bounded Brent between the best
    one's neighbours) to 1e-12 m."""
    from scipy.optimize import minimize_scalar

    a, b = 0.1, 0.06

    def exact(angles: np.ndarray, arcs: np.ndarray) -> np.ndarray:
        r = b + a * np.cos(angles)
        return np.column_stack([r * np.cos(angles), r * np.sin(angles), np.zeros(len(angles))])

    angles = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
    curve = ExactCurve(angles, exact(angles, np.zeros(40, dtype=np.int64)), 2 * np.pi, exact)
    points = np.column_stack([rng.uniform(-0.05, 0.17, 60), rng.uniform(-0.1, 0.1, 60), rng.uniform(-0.01, 0.01, 60)])
    dense_angles = np.linspace(0.0, 2 * np.pi, 200_000, endpoint=False)
    dense = exact(dense_angles, np.zeros(1, dtype=np.int64))
    truth = []
    for x in points:
        best = dense_angles[np.argmin(np.linalg.norm(dense - x, axis=1))]
        step = dense_angles[1]
        result = minimize_scalar(
            lambda t, x=x: float(np.linalg.norm(exact(np.array([t]), np.zeros(1, dtype=np.int64))[0] - x)),
            bounds=(best - 2 * step, best + 2 * step),
            method="bounded",
            options={"xatol": 1e-13},
        )
        truth.append(result.fun)
    found = distance_to_curve(points, curve)
    assert np.max(np.abs(found.distance - np.array(truth))) < 1e-12


def _four_bar() -> tuple[SingleLoop, float, Callable[[np.ndarray], np.ndarray]]:
    """test_linkage_scene's crank-rocker (parallel axes, m): its loop, start angle and the closed-form coupler point
    (mean of the coupler's two joints, circles about the crank pin and the rocker's pivot) at a crank angle."""
    ground, crank, coupler, rocker = 0.4, 0.1, 0.35, 0.3
    start = np.radians(60.0)
    pivot = np.array([ground, 0.0])

    def coupler_rocker_joint(b: np.ndarray) -> np.ndarray:
        distance = np.linalg.norm(pivot - b, axis=-1)[..., None]
        along = (coupler**2 - rocker**2 + distance**2) / (2 * distance)
        unit = (pivot - b) / distance
        normal = np.stack([-unit[..., 1], unit[..., 0]], axis=-1)
        return b + along * unit + np.sqrt(coupler**2 - along**2) * normal

    b0 = crank * np.array([np.cos(start), np.sin(start)])
    joints = np.array([[0.0, 0.0], b0, coupler_rocker_joint(b0), pivot])
    loop = SingleLoop.from_points_directions(np.column_stack([joints, np.zeros(4)]), np.tile([0.0, 0.0, 1.0], (4, 1)))
    z = float(joint_points(loop)[1:3, 2].mean())

    def point(angle: np.ndarray) -> np.ndarray:
        b = crank * np.column_stack([np.cos(angle), np.sin(angle)])
        return np.column_stack([0.5 * (b + coupler_rocker_joint(b)), np.full(len(b), z)])

    return loop, start, point


def test_points_of_a_four_bars_coupler_curve_are_on_the_ideal_path_of_its_rigid_loop(rng):
    """The generic loop's ideal path (720 samples of the rigid loop, closed anew between them): points of the
    closed-form coupler curve at any crank angle are on it (measured 1.5e-16 m), and points moved off its plane by
    a known offset are that far from it; the polyline through the samples is off by up to 1.2e-6 m there."""
    loop, start, point = _four_bar()
    scene = build_linkage(loop, LinkageOptions(material=RIGID, h=12e-3, order=1, n_modes=2, gravity=(0.0, 0.0, 0.0)))
    curve = scene.ideal_coupler_exact()
    angles = start + rng.uniform(0.0, 2 * np.pi, 300)
    on = point(angles)
    found = distance_to_curve(on, curve)
    assert np.all(found.converged) and np.max(found.distance) < 1e-9
    offset = rng.uniform(-1e-3, 1e-3, 300)
    off = distance_to_curve(on + offset[:, None] * np.array([0.0, 0.0, 1.0]), curve)
    assert np.max(np.abs(off.distance - np.abs(offset))) < 1e-9
    assert np.max(_polyline_distance(on, curve.points)) > 1e-7  # what a fixed sampling gave


@pytest.fixture(scope="module")
def bennett():
    return build_bennett("rigid", h=0.012, order=1, n_modes=2)


def test_points_of_the_bennett_rigid_loop_are_on_its_motion_polynomials_path(bennett, rng):
    """The paper's scene takes its ideal path from the motion polynomial; the rigid loop followed by continuation
    (kinematics.follow_driver, which knows no motion polynomial) gives points on it at any drive angle (measured
    1.8e-16 m; the polyline through 4000 samples: 6.7e-8 m), and points moved along the curve's normal by up to
    1 mm are that far (the normal from the curve's tangent, a central difference of the loop's points)."""
    curve = bennett.ideal_coupler_exact()
    angles = np.sort(bennett.start_angle + rng.uniform(0.0, 2 * np.pi, 200))
    on = bennett._rigid_coupler_points(angles)
    found = distance_to_curve(on, curve)
    assert np.all(found.converged) and np.max(found.distance) < 1e-9
    h = 1e-6
    tangent = bennett._rigid_coupler_points(angles + h) - bennett._rigid_coupler_points(angles - h)
    tangent /= np.linalg.norm(tangent, axis=1)[:, None]
    normal = np.cross(tangent, rng.normal(size=(len(angles), 3)))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    offset = rng.uniform(0.0, 1e-3, len(angles))
    off = distance_to_curve(on + offset[:, None] * normal, curve)
    assert np.max(np.abs(off.distance - offset)) < 1e-9

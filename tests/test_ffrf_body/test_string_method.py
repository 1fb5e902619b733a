"""The simplified string method (ffrf.numerics.string_method, docs/formulation.md Eq. (S9)) on the Mueller-Brown
potential, against its saddle located independently.

K. Mueller and L. D. Brown, Theor. Chim. Acta 53, 75 (1979): V(x, y) = sum_k A_k exp(a_k (x - x0_k)^2 +
b_k (x - x0_k)(y - y0_k) + c_k (y - y0_k)^2). Its minima A ~ (-0.558, 1.442) and B ~ (-0.050, 0.467) are joined by a
minimum-energy path over the saddle ~ (-0.822, 0.624), V ~ -40.66 (E, Ren and Vanden-Eijnden, J. Chem. Phys. 126,
164103 (2007), who use this case). The tests locate the minima and the saddle with scipy (minimize; root of
grad V = 0, one negative Hessian eigenvalue) and check them against these literature values before they judge
the string by them.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize, root

from ffrf.numerics.string_method import reparametrized, string_method

A = np.array([-200.0, -100.0, -170.0, 15.0])
a = np.array([-1.0, -1.0, -6.5, 0.7])
b = np.array([0.0, 0.0, 11.0, 0.6])
c = np.array([-10.0, -10.0, -6.5, 0.7])
X0 = np.array([1.0, 0.0, -0.5, -1.0])
Y0 = np.array([0.0, 0.5, 1.5, 1.0])


def mueller_brown(p: np.ndarray) -> tuple[float, np.ndarray]:
    """V and its gradient."""
    dx, dy = p[0] - X0, p[1] - Y0
    e = A * np.exp(a * dx**2 + b * dx * dy + c * dy**2)
    return float(e.sum()), np.array([(e * (2 * a * dx + b * dy)).sum(), (e * (b * dx + 2 * c * dy)).sum()])


def _hessian(p: np.ndarray, h: float = 1e-6) -> np.ndarray:
    columns = [(mueller_brown(p + h * e)[1] - mueller_brown(p - h * e)[1]) / (2 * h) for e in np.eye(2)]
    return 0.5 * (np.column_stack(columns) + np.column_stack(columns).T)


@pytest.fixture(scope="module")
def landmarks() -> dict[str, np.ndarray]:
    """The two minima and the saddle between them, found by scipy and checked against the literature."""
    minima = {
        name: minimize(lambda p: mueller_brown(p)[0], guess, jac=lambda p: mueller_brown(p)[1], tol=1e-12).x
        for name, guess in (("A", [-0.6, 1.4]), ("B", [0.0, 0.5]))
    }
    saddle = root(lambda p: mueller_brown(p)[1], [-0.8, 0.6], tol=1e-14).x
    assert np.allclose(minima["A"], [-0.558, 1.442], atol=1e-3)
    assert np.allclose(minima["B"], [-0.050, 0.467], atol=1e-3)
    assert np.allclose(saddle, [-0.822, 0.624], atol=1e-3)
    assert mueller_brown(saddle)[0] == pytest.approx(-40.66, abs=0.01)
    curvatures = np.linalg.eigvalsh(_hessian(saddle))
    assert curvatures[0] < 0.0 < curvatures[1]  # a saddle of index one
    return {**minima, "saddle": saddle}


@pytest.mark.parametrize("interpolation", ["linear", "cubic"])
def test_the_string_between_the_minima_crosses_the_saddle(landmarks, interpolation):
    """From the straight line A-B (21 images) the string converges (normal gradient below 1e-3, against 1e3 at the
    start) onto the path over the saddle: the highest point of the path (Hermite cubic of V(s) around the highest
    image) has the saddle's energy to 5e-3 (measured 1.7e-3 linear, 2.1e-3 cubic, against a barrier of 106), and
    the highest image lies within one image spacing of the saddle."""
    initial = np.linspace(landmarks["A"], landmarks["B"], 21)
    path = string_method(mueller_brown, initial, step=1e-4, tolerance=1e-3, interpolation=interpolation)
    assert path.converged
    saddle_energy = mueller_brown(landmarks["saddle"])[0]
    print("peak error", path.peak()[1] - saddle_energy)
    assert path.peak()[1] == pytest.approx(saddle_energy, abs=5e-3)
    spacing = path.arclength[-1] / 20
    assert np.linalg.norm(path.images[path.peak_index] - landmarks["saddle"]) < spacing
    assert np.array_equal(path.images[0], landmarks["A"]) and np.array_equal(path.images[-1], landmarks["B"])
    assert np.allclose(np.diff(path.arclength), spacing, rtol=2e-2)  # equal arc length, less the chords at bends


def test_a_too_long_step_is_halved_until_the_string_converges(landmarks):
    """At 6e-4, beyond 2 / (largest curvature) near the minima (about 4.7e-4), plain descent oscillates; the halving
    rule brings the step below that limit and the string converges over the saddle all the same."""
    curvature = max(np.linalg.eigvalsh(_hessian(landmarks[name]))[-1] for name in ("A", "B"))
    assert 6e-4 > 2.0 / curvature
    initial = np.linspace(landmarks["A"], landmarks["B"], 21)
    path = string_method(mueller_brown, initial, step=6e-4, tolerance=1e-3)
    assert path.converged and path.step < 2.0 / curvature
    assert path.peak()[1] == pytest.approx(mueller_brown(landmarks["saddle"])[0], abs=5e-3)


def test_a_free_start_descends_into_its_minimum_and_a_masked_component_is_held(landmarks):
    """Image 0 started off A slides into A when free (to 1e-4); with its x held it keeps x and ends where V is least
    along the line x = x_start, dV/dy = 0 (to 1e-3 of the slope at the start)."""
    start = landmarks["A"] + np.array([0.05, -0.1])
    initial = np.linspace(start, landmarks["B"], 21)
    free = string_method(mueller_brown, initial, step=1e-4, tolerance=1e-3, free_start=True)
    assert np.linalg.norm(free.images[0] - landmarks["A"]) < 1e-4
    held = string_method(mueller_brown, initial, step=1e-4, tolerance=1e-3, free_start=[False, True])
    assert held.images[0][0] == start[0]
    assert abs(mueller_brown(held.images[0])[1][1]) < 1e-3 * abs(mueller_brown(start)[1][1])


def test_reparametrisation_puts_images_at_equal_arc_length_on_the_polyline():
    """Images on a bent line at unequal spacing are moved to equal arc length on the same polyline (linear)."""
    images = np.array([[0.0, 0.0], [0.1, 0.0], [1.0, 0.0], [1.0, 2.0]])
    moved = reparametrized(images)
    assert np.allclose(moved, [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [1.0, 2.0]])

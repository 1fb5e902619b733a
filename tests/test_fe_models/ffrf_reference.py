"""Independent reference values for the ffrf tests: beam theory, torsion constants,
structured prism meshes and a mode classifier. Nothing here uses ffrf's assembly.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

__all__ = [
    "cowper_shear_coefficient",
    "rectangle_torsion_constant",
    "timoshenko_bending_frequencies",
    "torsion_frequencies",
    "prism_mesh",
    "classify_mode",
]


def cowper_shear_coefficient(nu: float) -> float:
    """Shear coefficient of a rectangle, kappa = 10 (1 + nu) / (12 + 11 nu)
    (Cowper, J. Appl. Mech. 33 (1966) 335, Table 1)."""
    return 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)


def rectangle_torsion_constant(width: float, thickness: float, n_terms: int = 50) -> float:
    """Saint-Venant torsion constant of a solid rectangle (Timoshenko & Goodier,
    Theory of Elasticity, 3rd ed., sec. 109, series solution):
    J = t^3 w / 3 [1 - 192 t / (pi^5 w) sum_{n odd} tanh(n pi w / (2 t)) / n^5], t <= w."""
    w, t = max(width, thickness), min(width, thickness)
    n = np.arange(1, 2 * n_terms, 2)
    series = np.sum(np.tanh(n * np.pi * w / (2 * t)) / n**5)
    return t**3 * w / 3.0 * (1.0 - 192.0 * t / (np.pi**5 * w) * series)


def _timoshenko_determinant(omega, E, G, kappa, rho, A, I, L, bc, rotary):
    """Determinant of the boundary conditions on the exact solution of Timoshenko's equations

        kappa G A (w'' - psi') + rho A omega^2 w = 0,
        E I psi'' + kappa G A (w' - psi) + rho I omega^2 psi = 0

    (Timoshenko, Phil. Mag. 41 (1921) 744; Han, Benaroya & Wei, J. Sound Vib. 225
    (1999) 935, sec. 5). Below the cut-off frequency the wave numbers are s = +-a,
    +-i b with a^2, -b^2 the roots of P Q z^2 + omega^2 rho (P I_r + Q A) z
    + rho A omega^2 (rho I_r omega^2 - P) = 0, P = kappa G A, Q = E I.
    """
    P, Q = kappa * G * A, E * I
    Ir = I if rotary else 0.0
    z = np.roots([P * Q, omega**2 * rho * (P * Ir + Q * A), rho * A * omega**2 * (rho * Ir * omega**2 - P)])
    z = np.sort(z.real)
    a, b = np.sqrt(z[1]), np.sqrt(-z[0])
    c = rho * A * omega**2 / P
    ka, kb = a + c / a, b - c / b  # psi = (s + c/s) w for w = exp(s x)

    def state(x):
        """Rows w, psi, psi', w' - psi for the basis cosh, sinh, cos, sin."""
        ch, sh, co, si = np.cosh(a * x), np.sinh(a * x), np.cos(b * x), np.sin(b * x)
        w = np.array([ch, sh, co, si])
        dw = np.array([a * sh, a * ch, -b * si, b * co])
        psi = np.array([ka * sh, ka * ch, -kb * si, kb * co])
        dpsi = np.array([ka * a * ch, ka * a * sh, -kb * b * co, -kb * b * si])
        return {"w": w, "psi": psi, "moment": dpsi, "shear": dw - psi}

    s0, sL = state(0.0), state(L)
    if bc == "clamped-free":
        rows = [s0["w"], s0["psi"], sL["moment"], sL["shear"]]
    elif bc == "free-free":
        rows = [s0["moment"], s0["shear"], sL["moment"], sL["shear"]]
    else:
        raise ValueError(bc)
    m = np.array(rows)
    return np.linalg.det(m / np.abs(m).max(axis=1, keepdims=True))


def timoshenko_bending_frequencies(E, nu, rho, A, I, L, bc, n=2, kappa=None, rotary=True, shear=True):
    """Lowest ``n`` bending natural frequencies (Hz) of a uniform Timoshenko beam.

    ``shear=False`` (kappa G -> infinity) and ``rotary=False`` give Euler-Bernoulli.
    """
    G = E / (2 * (1 + nu))
    kappa = cowper_shear_coefficient(nu) if kappa is None else kappa
    if not shear:
        kappa = 1e8

    def f(om):
        return _timoshenko_determinant(om, E, G, kappa, rho, A, I, L, bc, rotary)

    eb1 = (1.8751 if bc == "clamped-free" else 4.7300) ** 2 * np.sqrt(E * I / (rho * A)) / L**2
    grid = np.linspace(0.05 * eb1, 40 * eb1, 2000)
    values = np.array([f(om) for om in grid])
    roots = []
    for i in np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:])):
        roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-12 * eb1))
        if len(roots) == n:
            break
    return np.array(roots) / (2 * np.pi)


def torsion_frequencies(G, J, rho, Ip, L, bc, n=2):
    """Saint-Venant torsion of a uniform shaft (Blevins, Formulas for Natural Frequency
    and Mode Shape, ch. 8, torsion of straight beams): f_k = lambda_k / (2 pi L) sqrt(G J / (rho Ip)),
    lambda_k = (2k - 1) pi / 2 (clamped-free), k pi (free-free)."""
    k = np.arange(1, n + 1)
    lam = (2 * k - 1) * np.pi / 2 if bc == "clamped-free" else k * np.pi
    return lam / (2 * np.pi * L) * np.sqrt(G * J / (rho * Ip))


def prism_mesh(length, width, thickness, h):
    """Structured tetrahedral mesh of [0, L] x [0, w] x [0, t] (scikit-fem's init_tensor),
    with positively oriented tetrahedra."""
    from skfem import MeshTet

    axes = [np.linspace(0.0, d, max(1, round(d / h)) + 1) for d in (length, width, thickness)]
    m = MeshTet.init_tensor(*axes)
    points, tets = m.p.T.copy(), m.t.T.copy()
    p = points[tets]
    vol = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    tets[vol < 0, 2], tets[vol < 0, 3] = tets[vol < 0, 3], tets[vol < 0, 2].copy()
    return points, tets


def classify_mode(nodes, mass, shape, length, center_yz):
    """'axial', 'bend_y', 'bend_z' or 'torsion': the deformation pattern with the largest
    mass-weighted projection, patterns being each field times 1, xi, xi^2, xi^3 (xi along x; the
    low powers alone are rigid motions, to which free-free modes are orthogonal)."""
    xi = (nodes[:, 0] - 0.5 * length) / length
    dy, dz = nodes[:, 1] - center_yz[0], nodes[:, 2] - center_yz[1]
    zero = np.zeros(len(nodes))
    base = {
        "axial": np.column_stack([np.ones(len(nodes)), zero, zero]),
        "bend_y": np.column_stack([zero, np.ones(len(nodes)), zero]),
        "bend_z": np.column_stack([zero, zero, np.ones(len(nodes))]),
        "torsion": np.column_stack([zero, -dz, dy]),
    }
    scores = {}
    for name, field in base.items():
        best = 0.0
        for weight in (np.ones_like(xi), xi, xi**2, xi**3):
            f = (field * weight[:, None]).reshape(-1)
            mf = mass @ f
            best = max(best, abs(shape @ mf) / np.sqrt(f @ mf) / np.sqrt(shape @ (mass @ shape)))
        scores[name] = best
    return max(scores, key=scores.get)

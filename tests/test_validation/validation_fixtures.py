"""Shared scenes, cached solver runs and independent physics references for the Exudyn cross-checks.

Every run is cached per process (``functools.lru_cache``), so that the test modules can share
the expensive integrations. The references here use only the FE data (mass matrix moments),
never our solver's output.
"""

from __future__ import annotations

from functools import cache

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from ffrf.output.result import Result
from validation.exudyn_ffrf import run_exudyn, run_ffrf
from validation.reduced_body import ReducedBody, bar_body
from validation.single_body_scenes import SingleBodyScene, free_body_scene, pendulum_scene
from validation.twin_run import ComparedRun, TwinRun

# Agreement of the two solvers, about 100x the largest difference measured on 2026-11-24 (AMD EPYC):
#: tracked node and frame positions (m); measured 2.8e-12 m on the 0.2 m bar.
POSITION_TOLERANCE_M = 3e-10
#: Euler parameters (dimensionless); measured 8.9e-12.
EULER_TOLERANCE = 1e-9
#: modal coordinates, relative to their largest magnitude; measured 5.8e-10.
MODAL_RELATIVE_TOLERANCE = 5e-8
#: Stiffness-proportional damping of the pendulum scene (s), the same in both solvers.
PENDULUM_BETA = 1e-3
#: Number of fixed-interface modes (the basis has 6 + this many columns).
N_FIXED_INTERFACE_MODES = 4


@cache
def bar() -> ReducedBody:
    """0.2 x 0.02 x 0.01 m PLA-like bar, 8 x 2 x 2 boxes (81 nodes), HCB with 6 + 4 modes, area weights."""
    return bar_body(divisions=(8, 2, 2), n_modes=N_FIXED_INTERFACE_MODES, weights="area")


@cache
def pendulum(step: float = 1e-3, t_end: float = 1.0) -> SingleBodyScene:
    return pendulum_scene(bar(), step=step, t_end=t_end, beta=PENDULUM_BETA, rho_inf=0.8)


@cache
def free_body(tilted: bool = False, step: float = 1e-3, t_end: float = 0.2) -> SingleBodyScene:
    return free_body_scene(bar(), step=step, t_end=t_end, rho_inf=0.8, tilted=tilted)


@cache
def exudyn_run(scene: SingleBodyScene) -> TwinRun:
    return run_exudyn(scene)


@cache
def ffrf_run(scene: SingleBodyScene) -> Result:
    return run_ffrf(scene)


def tracked_nodes(run: ComparedRun) -> NDArray[np.float64]:
    """A single-body run's tracked nodes, (n, k, 3) world positions (:mod:`validation.exudyn_ffrf`)."""
    return run.sensors["tracked_nodes"]


def max_difference(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """max |a - b| over all entries (shapes must agree)."""
    assert a.shape == b.shape, f"shapes differ: {a.shape} vs {b.shape}"
    return float(np.abs(a - b).max())


def mass_moments(body: ReducedBody) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """Total mass, first moment and second-moment tensor int x x^T dm of the undeformed body,
    straight from the consistent mass matrix (exact for P1: x is in the FE space)."""
    scalar = body.mass[0::3, 0::3]
    ones = np.ones(len(body.nodes))
    weighted = scalar @ body.nodes
    return float(ones @ scalar @ ones), ones @ weighted, body.nodes.T @ weighted


def rigid_pendulum_tip(
    body: ReducedBody, scene: SingleBodyScene, times: NDArray[np.float64], node: int
) -> NDArray[np.float64]:
    """Tip path of the same body taken as rigid, hinged about world y at the origin, g along -z.

    J phi'' = m g c_x cos(phi) with J = int (x^2 + z^2) dm, c = first moment / m; phi is the
    rotation about +y (x -> (cos phi, 0, -sin phi)).
    """
    assert scene.hinge is not None and np.allclose(scene.hinge.axis, (0.0, 1.0, 0.0))
    assert np.allclose(body.frame_center, 0.0, atol=1e-12)
    mass, first, second = mass_moments(body)
    inertia = second[0, 0] + second[2, 2]
    g = -scene.gravity[2]

    def rhs(_t, y):
        return [y[1], first[0] * g * np.cos(y[0]) / inertia]

    sol = solve_ivp(rhs, (0.0, times[-1]), [0.0, 0.0], t_eval=times, rtol=1e-11, atol=1e-13, method="DOP853")
    phi = sol.y[0]
    x, y, z = body.nodes[node]
    return np.column_stack(
        [x * np.cos(phi) + z * np.sin(phi), np.full_like(phi, y), -x * np.sin(phi) + z * np.cos(phi)]
    )


def centre_of_mass_path(body: ReducedBody, result: ComparedRun) -> NDArray[np.float64]:
    """World centre of mass R + A (s0 + S1 zeta) / m along a run (S1 = first moments of the modes)."""
    from ffrf.body.euler_parameters import rotation_matrix

    mass, first, _ = mass_moments(body)
    scalar = body.mass[0::3, 0::3]
    ones = np.ones(len(body.nodes))
    s1 = np.stack([ones @ (scalar @ body.basis[a::3]) for a in range(3)])  # (3, m)
    out = np.empty_like(result.q[:, :3])
    for k in range(len(result.time)):
        a = rotation_matrix(np.ascontiguousarray(result.q[k, 3:7]))
        out[k] = result.q[k, :3] + a @ (first + s1 @ result.q[k, 7:]) / mass
    return out

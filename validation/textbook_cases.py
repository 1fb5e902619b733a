r"""Textbook buckling cases with known answers (issue #20), shared by ``tests/test_textbook`` and
``bench/textbook_buckling.py``: a von Mises truss of two flexible bars in a scene file, and a cantilever column of
n flexible segments joined rigidly, with their closed forms.

Both use box-shaped bars of Poisson's ratio 0 meshed with ``skfem.MeshTet.init_tensor``. With nu = 0 a uniform
axial strain (u linear along the bar) and pure bending (u quadratic) are exact 3D solutions whose end faces move
rigidly, so linear tetrahedra reproduce the bar's axial stiffness EA/L exactly, quadratic ones also its bending
stiffness under a pure moment, and Craig-Bampton's static modes of the rigid end interfaces contain these states
exactly (they are the condensed static solutions for the end faces' motions).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import meshio
import numpy as np
import skfem
from numpy.typing import NDArray
from scipy.linalg import eig
from scipy.optimize import root_scalar

from ffrf.mesh.tet_mesh import orient_positive
from ffrf.scenes.builder import Scene, build_scene
from ffrf.solvers.stability import equilibrium_stability
from ffrf.solvers.static_solver import static_equilibrium

#: Steel, Poisson's ratio 0 (see the module docstring).
STEEL = {"E": 2.1e11, "nu": 0.0, "rho": 7850.0}
#: A load's time law scale(t) = t, also for negative t (a continuation can pass t = 0 backwards).
LINEAR_IN_TIME = {"time": [-100.0, 100.0], "scale": [-100.0, 100.0]}


def write_box(
    path: Path, start: NDArray, axis: NDArray, lateral: NDArray, length: float, width: float, along: int, across: int
) -> None:
    """A square bar from ``start`` along the unit ``axis`` (``lateral`` a unit vector across it), ``width`` wide,
    as ``along`` x ``across`` x ``across`` boxes of six tetrahedra each, written to ``path`` (meshio)."""
    mesh = skfem.MeshTet.init_tensor(
        np.linspace(0.0, length, along + 1), *(np.linspace(-width / 2, width / 2, across + 1),) * 2
    )
    local = mesh.p.T
    other = np.cross(axis, lateral)
    points = start + np.outer(local[:, 0], axis) + np.outer(local[:, 1], lateral) + np.outer(local[:, 2], other)
    meshio.write(path, meshio.Mesh(points, [("tetra", orient_positive(points, mesh.t.T))]))


# --- von Mises truss ------------------------------------------------------------------------------------------------

#: Half span a, rise h, bar width b (m), load per unit of t (N) and the bars' elements along their length.
HALF_SPAN, RISE, BAR_WIDTH, LOAD_RATE, BAR_ELEMENTS = 1.0, 0.05, 0.1, 1e5, 10


def truss_closed_form() -> dict[str, float]:
    r"""The shallow truss of two pinned bars of axial stiffness k = EA/L0 under a load at the apex:

    .. math:: P(z) = 2 k (L_0 - L) z / L,\quad L = \sqrt{a^2 + z^2};\qquad
              P_{max} = 2 k (L_0 - L^*) z^* / L^*,\ L^* = (L_0 a^2)^{1/3},\ z^* = \sqrt{L^{*2} - a^2},

    with the bars' axial forces at the limit point and flat (z = 0) and their Euler load pi^2 EI / L0^2."""
    length = float(np.hypot(HALF_SPAN, RISE))
    area, inertia = BAR_WIDTH**2, BAR_WIDTH**4 / 12.0
    k = STEEL["E"] * area / length
    critical = (length * HALF_SPAN**2) ** (1.0 / 3.0)
    rise = float(np.sqrt(critical**2 - HALF_SPAN**2))
    return {
        "length": length,
        "stiffness": k,
        "limit_load": 2.0 * k * (length - critical) * rise / critical,
        "critical_rise": rise,
        "force_at_limit": k * (length - critical),
        "force_flat": k * (length - HALF_SPAN),
        "euler_load": np.pi**2 * STEEL["E"] * inertia / length**2,
    }


def truss_load(rise: NDArray | float) -> NDArray | float:
    """The closed-form load P(z) that holds the apex at ``rise`` z above the feet (N, downward positive)."""
    c = truss_closed_form()
    length = np.hypot(HALF_SPAN, rise)
    return 2.0 * c["stiffness"] * (c["length"] - length) * rise / length


def write_truss_scene(directory: Path, t_end: float = 1.5, outputs: int = 16) -> Path:
    """``truss.toml`` and the two bars' meshes in ``directory``: bars ``left`` and ``right`` from the feet
    (+-a, 0, 0) to the apex (0, 0, h), revolute joints about y at the feet and the apex (on the end faces'
    centres, on the bars' axes), Craig-Bampton on the two end faces with no fixed-interface modes, a dead load
    -LOAD_RATE t e_z at the apex, a quasi-static run with ``stability = true``, no gravity."""
    apex = np.array([0.0, 0.0, RISE])
    c = truss_closed_form()
    bodies = []
    for name, side in (("left", -1.0), ("right", 1.0)):
        foot = np.array([side * HALF_SPAN, 0.0, 0.0])
        axis = (apex - foot) / c["length"]
        write_box(directory / f"{name}.vtu", foot, axis, np.array([0.0, 1.0, 0.0]), c["length"], BAR_WIDTH,
                  BAR_ELEMENTS, 2)  # fmt: skip
        normal = json.dumps(axis.tolist())
        bodies.append(f"""
[[bodies]]
name = "{name}"
mesh = "{name}.vtu"
material = {{E = {STEEL["E"]}, nu = {STEEL["nu"]}, rho = {STEEL["rho"]}}}
order = 1
modes = 0
interfaces = [{{name = "foot", plane = {{point = {json.dumps(foot.tolist())}, normal = {normal}}}}},
              {{name = "apex", plane = {{point = {json.dumps(apex.tolist())}, normal = {normal}}}}}]
""")
    joints = "".join(
        f"""
[[joints]]
name = "{name}"
type = "revolute"
body0 = "{body0}"
{'interface0 = "apex"' if body0 != "ground" else ""}
body1 = "{body1}"
interface1 = "{interface1}"
axis = [0.0, 1.0, 0.0]
"""
        for name, body0, body1, interface1 in (
            ("foot_left", "ground", "left", "foot"),
            ("foot_right", "ground", "right", "foot"),
            ("apex", "left", "right", "apex"),
        )
    )
    text = f"""
[scene]
name = "von Mises truss"
gravity = [0.0, 0.0, 0.0]
mode = "quasi_static"
t_end = {t_end}
outputs = {outputs}
stability = true
{"".join(bodies)}{joints}
[[forces]]
name = "load"
type = "load"
body = "left"
interface = "apex"
force = [0.0, 0.0, {-LOAD_RATE}]
table = {{time = {LINEAR_IN_TIME["time"]}, scale = {LINEAR_IN_TIME["scale"]}}}
"""
    path = directory / "truss.toml"
    path.write_text(text)
    return path


# --- Euler column of n segments -------------------------------------------------------------------------------------

#: Column length L, width b (m; L/b = 40), axial element length (m; the same for every n) and the load per unit of t.
COLUMN_LENGTH, COLUMN_WIDTH, COLUMN_ELEMENT, COLUMN_LOAD = 1.0, 0.025, 0.0125, 1e3
BENDING_STIFFNESS = STEEL["E"] * COLUMN_WIDTH**4 / 12.0
#: Euler's load of the cantilever, pi^2 EI / (4 L^2) (N).
EULER_LOAD = np.pi**2 * BENDING_STIFFNESS / (4.0 * COLUMN_LENGTH**2)


def column_scene(n: int, directory: Path, element: float = COLUMN_ELEMENT) -> Scene:
    """A cantilever along z of ``n`` equal P2 segments (2 x 2 x L/(n element) boxes of tetrahedra), each a
    Craig-Bampton body on its bottom (frame) and top faces without fixed-interface modes, joined by fixed joints,
    the first clamped to the ground, a dead load -COLUMN_LOAD t e_z on the top face; no gravity."""
    segment = COLUMN_LENGTH / n
    bodies, joints = [], []
    for i in range(n):
        mesh = f"column{n}_{i}.vtu"
        write_box(directory / mesh, np.array([0.0, 0.0, i * segment]), np.array([0.0, 0.0, 1.0]),
                  np.array([1.0, 0.0, 0.0]), segment, COLUMN_WIDTH, round(segment / element), 2)  # fmt: skip
        faces = [
            {"name": name, "plane": {"point": [0.0, 0.0, z], "normal": [0.0, 0.0, 1.0]}}
            for name, z in (("bottom", i * segment), ("top", (i + 1) * segment))
        ]
        bodies.append({"name": f"s{i}", "mesh": mesh, "material": STEEL, "order": 2, "modes": 0, "interfaces": faces})
        below = {"body0": "ground"} if i == 0 else {"body0": f"s{i - 1}", "interface0": "top"}
        joints.append({"name": f"j{i}", "type": "fixed", **below, "body1": f"s{i}", "interface1": "bottom"})
    load = {"name": "load", "type": "load", "body": f"s{n - 1}", "interface": "top", "table": LINEAR_IN_TIME}
    description = {
        "scene": {"name": f"column of {n}", "gravity": [0.0, 0.0, 0.0], "mode": "quasi_static"},
        "bodies": bodies,
        "joints": joints,
        "forces": [dict(load, force=[0.0, 0.0, -COLUMN_LOAD])],
    }
    return build_scene(description, directory)


def smallest_squared_frequency(scene: Scene) -> Callable[[float], float]:
    """mu_min(t) of Eq. (B1) at the straight equilibrium under the load at t (each solve starts from the last)."""
    last = {"q": scene.q_initial}

    def mu(t: float) -> float:
        solution = static_equilibrium(scene.system, last["q"], t)
        last["q"] = solution.q
        return float(equilibrium_stability(scene.system, solution.q, solution.multipliers, t, 1).squared_frequencies[0])

    return mu


def buckling_load(scene: Scene, guess: float) -> float:
    """The load (N) where mu_min of Eq. (B1) reaches zero on the straight path: secant iteration on mu_min(P)
    from P = 0 and ``guess`` (mu_min is close to linear in P), to 1e-10 relative."""
    mu = smallest_squared_frequency(scene)
    root = root_scalar(mu, x0=0.0, x1=guess / COLUMN_LOAD, method="secant", rtol=1e-10)
    return float(root.root) * COLUMN_LOAD


def segment_stiffness(scene: Scene) -> NDArray[np.float64]:
    """The FE segment's 2 x 2 cantilever stiffness for its top face's lateral translation x and rotation about y,
    clamped at its bottom face: the Craig-Bampton reduced stiffness of the top interface's tx, ry static modes
    (exact condensation: no fixed-interface modes)."""
    stiffness = scene.bodies[0].reduction.reduced_stiffness
    return stiffness[np.ix_([0, 4], [0, 4])]


def beam_segment_stiffness(n: int) -> NDArray[np.float64]:
    """Euler-Bernoulli cantilever stiffness of one segment, EI / l^3 [[12, -6 l], [-6 l, 4 l^2]], l = L/n."""
    length = COLUMN_LENGTH / n
    return BENDING_STIFFNESS / length**3 * np.array([[12.0, -6.0 * length], [-6.0 * length, 4.0 * length**2]])


def chain_buckling_load(n: int, segment: NDArray) -> float:
    r"""Buckling load of the discrete structure the FFRF column is, without our solver: n linear segments of
    length l = L/n and cantilever stiffness ``segment`` (tip deflection v_i, tip rotation phi_i in the segment's
    frame, clamped at its bottom), each frame turned by theta_i = phi_0 + ... + phi_{i-1} (rigid joints,
    theta_0 = 0). A frame turned by theta carries its top to (l cos theta - v sin theta) up, so the load point
    drops by sum_i (l theta_i^2 / 2 + theta_i v_i) to second order, and the buckling load is the smallest positive
    P of det(K - P G) = 0 with K = diag(segment) and G the Hessian of that drop: the load's work on the segments'
    own bending (the integral of v'^2 / 2 within a segment) is missing, which is what a linear FFRF body lacks."""
    length = COLUMN_LENGTH / n
    size = 2 * n
    stiffness, drop = np.zeros((size, size)), np.zeros((size, size))
    for i in range(n):
        stiffness[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = segment
        turn = np.zeros(size)
        turn[1 : 2 * i : 2] = 1.0  # theta_i = sum of the rotations phi_j, j < i
        deflection = np.zeros(size)
        deflection[2 * i] = 1.0
        drop += length * np.outer(turn, turn) + np.outer(turn, deflection) + np.outer(deflection, turn)
    values = eig(stiffness, drop, right=False)
    finite = values[np.isfinite(values)].real
    return float(finite[finite > 0.0].min())

"""Bushings (a revolute joint's five equations held elastically, Eqs. (E1)-(E2)) between two flexible bars, against
conservation laws and their stiff limit: an undamped swing keeps kinetic + strain + gravity + element energy to the
trapezoidal rule's second order, a damped oscillation loses exactly the damper's work, and the bushing's deflection
from the revolute joint's solution falls as 1/k (the closed form F/k on rigid bars)."""

from __future__ import annotations

import numpy as np
import pytest
from body_fixtures import free_bar

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.static_solver import static_equilibrium
from ffrf.system.forces import MarkerLoad, spring_damper
from ffrf.system.joints import GroundFrame, fixed_joint, frame_from_axis, revolute_joint
from ffrf.system.markers import BodyMarker, rigid_interface_marker
from ffrf.system.multibody import MultibodySystem

MASS = 450.0 * 0.2 * 0.02 * 0.01  # kg, one bar of free_bar
HINGE_AXES = frame_from_axis([0.0, 1.0, 0.0])  # joint z along world y
LOAD = np.array([0.0, 0.05, -0.2])  # N, across the hinge axis and along the hanging bar
LEVER = 0.02  # m: the bushing's rotational stiffness is k * LEVER^2
STIFFNESSES = np.array([1e4, 1e5, 1e6, 1e7])  # N/m


def _two_bars(rigid: bool = False) -> tuple[tuple[FlexibleBody, FlexibleBody], dict[str, BodyMarker]]:
    """Two copies of ``free_bar`` (8 modes each; with ``rigid``, none) and a rigid marker on each end face:
    ``near0``, ``far0``, ``near1``, ``far1`` (the face at x = 0 or x = 0.2 of bar 0 or 1)."""
    (model, psi, ends, bar0), bar1 = free_bar("bar0"), free_bar("bar1")[3]
    if rigid:
        psi = np.zeros((psi.shape[0], 0))
        bar0, bar1 = (
            FlexibleBody(name, modal_moments(model.nodes, model.mass, psi), np.zeros((0, 0)), np.zeros((0, 0)))
            for name in ("bar0", "bar1")
        )
    markers = {
        f"{end}{k}": rigid_interface_marker(k, model.nodes, psi, ends[e], name=f"bar{k}:{end}")
        for k in (0, 1)
        for e, end in enumerate(("near", "far"))
    }
    return (bar0, bar1), markers


def _swing(step: float):
    """Bar 0 hinged at its x = 0 face about world y; bar 1 hung in line at bar 0's far face on a bushing (200 N/m,
    0.05 N m per rad, undamped); gravity; bar 1 started turning at (2, 0, 3) rad/s about its near face, so that it
    swings out of the hinge plane and loads every direction of the bushing. 0.1 s with generalized-alpha at
    rho_inf = 1 (the trapezoidal rule): the run, its system and the element energies along it."""
    (bar0, bar1), markers = _two_bars()
    hinge = revolute_joint(
        GroundFrame(point=markers["near0"].point, rotation=HINGE_AXES),
        markers["near0"],
        rotation1=HINGE_AXES,
        name="hinge",
    )
    joint = revolute_joint(markers["far0"], markers["near1"], HINGE_AXES, HINGE_AXES, name="bushing")
    bushing = spring_damper(joint, [200.0] * 3 + [0.05] * 2)
    system = MultibodySystem((bar0, bar1), (hinge,), gravity=np.array([0.0, 0.0, -9.81]), forces=(bushing,))
    q0 = system.initial_state(positions=[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]])
    qd0 = system.rigid_velocity(q0, 1, angular_velocity=[2.0, 0.0, 3.0], point=markers["near1"].point)
    result = generalized_alpha(system, q0, qd0, 0.1, step, rho_inf=1.0, tolerance=1e-12)
    return result, system


def test_an_undamped_bushing_between_flexible_bars_conserves_energy_to_second_order():
    """Eq. (E2): the bushing's force is minus the gradient of its energy, so kinetic + strain + gravity + element
    energy is conserved, and the trapezoidal rule keeps it to O(h^2) on these nonlinear equations (exactly only
    for linear ones). Largest |E(t) - E(0)| over 0.1 s, measured 1.93e-7, 5.06e-8, 1.21e-8 J at h = 1e-3, 5e-4,
    2.5e-4 s (observed order 1.93, 2.06; fit 2.00) of a largest kinetic energy of 1.46e-2 J; the element stores up
    to 1.0e-3 J and the bars' strain up to 1.8e-5 J, so a missing or wrong term in either would not shrink with
    h. About 10 s."""
    steps = np.array([1e-3, 5e-4, 2.5e-4])
    errors, stored = [], {}
    for step in steps:
        result, system = _swing(step)
        energies = [system.energies(q, qd) for q, qd in zip(result.q, result.qd, strict=True)]
        total = np.array([sum(e.values()) for e in energies])
        errors.append(np.max(np.abs(total - total[0])))
        stored = {kind: max(e[kind] for e in energies) for kind in ("kinetic", "strain", "elements")}
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 1.8 < order < 2.2  # the trapezoidal rule's order
    assert errors[0] < 1e-4 * stored["kinetic"]  # measured 1.3e-5
    assert min(stored["elements"], stored["strain"]) > 50.0 * errors[0]  # both terms are seen


def test_a_damped_bushing_between_free_flexible_bars_dissipates_exactly_its_work():
    """Two free bars in line (no ground, no gravity), their facing end faces joined by a bushing (200 N/m, 0.05 N m
    per rad, damping ratio 0.1 of the axial mode), pushed together at 0.1 m/s: energy at the start = energy at
    the end + the damper's work W = sum (f_n + f_n+1) / 2 . (g_n+1 - g_n), its force f = D C_q qd (Eq. (E1))
    along its equations' path g. The trapezoidal rule keeps this balance exactly for linear equations, which
    these nearly are (the bars only translate; the mesh's asymmetry turns them by 2e-6 rad): measured 1.3e-10 of
    the start energy at h = 5e-4 s, the damper taking 94 % of it. (Simpson's rule in time, ``energy_elements_work``,
    differs from W by 7.8e-4 of it here: the trapezoidal rule's O((h w)^2) dissipation error, w h = 0.075.)"""
    (bar0, bar1), markers = _two_bars()
    joint = revolute_joint(markers["far0"], markers["near1"], HINGE_AXES, HINGE_AXES, name="bushing")
    stiffness = np.array([200.0] * 3 + [0.05] * 2)
    damping = 2.0 * 0.1 * np.sqrt(200.0 * MASS / 2.0) / 200.0 * stiffness  # reduced mass m / 2 of the axial mode
    system = MultibodySystem((bar0, bar1), (), gravity=np.zeros(3), forces=(spring_damper(joint, stiffness, damping),))
    damper = spring_damper(joint, 0.0, damping)  # the same element's damping part alone
    q0 = system.initial_state(positions=[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]])
    qd0 = system.rigid_velocity(q0, 0, [0.05, 0.0, 0.0]) - system.rigid_velocity(q0, 1, [0.05, 0.0, 0.0])
    result = generalized_alpha(system, q0, qd0, 0.1, 5e-4, rho_inf=1.0, tolerance=1e-12)
    blocks = [[q[system.block(k)] for k in (0, 1)] for q in result.q]
    rates = [[qd[system.block(k)] for k in (0, 1)] for qd in result.qd]
    force = np.array([damper.joint_force(b, r, 0.0) for b, r in zip(blocks, rates, strict=True)])
    path = np.array([joint.value(b, 0.0) for b in blocks])
    work = float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(path, axis=0)))
    start, end = (float(sum(system.energies(result.q[i], result.qd[i]).values())) for i in (0, -1))
    assert work > 0.9 * start  # the damper takes most of the energy (measured 94 %)
    assert abs(start - end - work) < 1e-8 * start  # measured 1.3e-10


def _hanging_pair(rigid: bool, stiffness: float | None):
    """Bar 0 clamped at its x = 0 face; bar 1 hanging straight down from bar 0's far face on a revolute joint about
    world y (``stiffness`` None) or a bushing (``stiffness`` N/m for the translations, stiffness * (0.02 m)^2
    N m per rad for the two rotations); a load F = (0, 0.05, -0.2) N at bar 1's lower face. No gravity. The
    system, the start (bar 1 turned 90 deg about y) and bar 1's loaded marker."""
    (bar0, bar1), markers = _two_bars(rigid)
    turn = np.array([np.cos(np.pi / 4), 0.0, np.sin(np.pi / 4), 0.0])  # bar 1's x axis to world -z
    axes1 = rotation_matrix(turn).T @ HINGE_AXES  # the same joint frame, in bar 1's axes
    joint = revolute_joint(markers["far0"], markers["near1"], HINGE_AXES, axes1, name="hinge")
    clamp = fixed_joint(GroundFrame(point=markers["near0"].point), markers["near0"], name="clamp")
    load = MarkerLoad((1,), "load", markers["far1"], force=LOAD)
    if stiffness is None:
        system = MultibodySystem((bar0, bar1), (clamp, joint), gravity=np.zeros(3), forces=(load,))
    else:
        bushing = spring_damper(joint, [stiffness] * 3 + [stiffness * LEVER**2] * 2)
        system = MultibodySystem((bar0, bar1), (clamp,), gravity=np.zeros(3), forces=(load, bushing))
    start = markers["far0"].point - rotation_matrix(turn) @ markers["near1"].point
    q0 = system.initial_state(positions=[np.zeros(3), start], rotations=[np.array([1.0, 0.0, 0.0, 0.0]), turn])
    return system, q0, markers["far1"]


@pytest.mark.parametrize("rigid", [True, False], ids=["rigid bars", "flexible bars"])
def test_a_bushing_tends_to_the_revolute_joint_as_one_over_its_stiffness(rigid):
    """The loaded bar's lower face moves off the revolute joint's solution by d(k) = C / k + O(1/k^2): the bushing
    takes the joint's reaction F elastically. On rigid bars C is the closed form of the bushing alone: F / k in
    translation, and the moment L F_y about x (lever L = 0.2 m) turns it by L F_y / (k LEVER^2), which moves the
    face by L^2 F_y / (k LEVER^2) along y: k d approaches it as 1/k (measured 9.9e-3, 1.0e-3, 1.0e-4, 1.0e-5 of it
    at k = 1e4..1e7 N/m). On flexible bars the moved load also bends and twists them, which changes C by about a
    per cent (measured k d = (-3.4e-3, 4.994, -0.1916) against (0, 5.05, -0.2) N, 1.1e-2 of it), but not the rate:
    the log-log slope of |d| over k = 1e4..1e7 N/m is -1 (measured -0.9987 on both)."""
    rigid_system, q0, face = _hanging_pair(rigid, None)
    reference = static_equilibrium(rigid_system, q0).q
    where = face.position(reference[rigid_system.block(1)])
    deflections = []
    for k in STIFFNESSES:
        system, _, _ = _hanging_pair(rigid, k)
        q = static_equilibrium(system, reference).q
        deflections.append(face.position(q[system.block(1)]) - where)
    deflections = np.array(deflections)
    slope = np.polyfit(np.log(STIFFNESSES), np.log(np.linalg.norm(deflections, axis=1)), 1)[0]
    assert abs(slope + 1.0) < 0.01
    closed_form = np.array([0.0, LOAD[1] * (1.0 + 0.2**2 / LEVER**2), LOAD[2]])  # k d as k -> infinity
    scaled = STIFFNESSES[-1] * deflections[-1]
    if rigid:
        np.testing.assert_allclose(scaled, closed_form, rtol=0.0, atol=1e-4 * np.linalg.norm(closed_form))
    else:
        np.testing.assert_allclose(scaled, closed_form, rtol=0.0, atol=0.05 * np.linalg.norm(closed_form))

"""Our solver against the Exudyn twin of the flexible Bennett scene (issue 7).

Coarse PLA scene (``build_bennett("pla", h=6e-3, order=1, n_modes=2, exact_gravity=False, collision_free=False)``:
the housings centred on the joint points, where the figures below were measured; 4 links,
8..14 modes each), started from ``scene.q_start`` (undeformed links at rest, drive at its start
angle) so that gravity excites the links while the cosine ramp begins to turn the drive;
generalized-alpha, h = 1e-3 s, rho_inf = 0.9, 0.2 s; and the static equilibrium at t = 0.

Two modelling conventions matter (``validation.exudyn_conventions``):

1. where a joint point's offset from its bore centre lives: Exudyn applies the ``localHT``
   translation of ``MarkerSuperElementRigid`` in the body frame, as our scenes do by default
   (``joint_offsets="body"``); ``joint_offsets="marker"`` puts it in the marker frame
   (p = r_M + A exp(theta~) o), which Exudyn cannot express;
2. Exudyn's marker rotation Jacobian is A(omega_bar + T theta_dot), not the exact derivative of
   its orientation A exp(theta~) (which has exp(theta~) T), so its reaction C_q^T lambda is not
   the exact gradient of its constraint equations.

Three systems of ours are compared with the one Exudyn run: the production system with
Exudyn's Jacobian (must agree to round-off), the production system (our exact Jacobian; must
meet the issue's targets), and the marker-frame offsets (the convention shows; measured).
"""

from __future__ import annotations

from functools import cache

import numpy as np

from ffrf.paper.bennett_scene import assemble, build_bennett
from validation.bennett_trajectory import compare, run_ffrf_bennett, static_ffrf_bennett
from validation.exudyn_bennett import run_exudyn_bennett, static_exudyn_bennett
from validation.exudyn_conventions import exudyn_convention_system, probe_marker_offset

STEP, T_END, RHO_INF = 1e-3, 0.2, 0.9
#: Issue 7 targets: driving torque (relative) and coupler / tracked nodes (relative to the elastic motion).
TORQUE_TARGET, TRAJECTORY_TARGET = 1e-4, 1e-3


@cache
def scene(joint_offsets: str = "body"):
    return build_bennett(
        "pla", h=6e-3, order=1, n_modes=2, exact_gravity=False, joint_offsets=joint_offsets, collision_free=False
    )


@cache
def system(kind: str):
    """``production`` (body-frame offsets, exact Jacobian), ``exudyn`` (Exudyn's Jacobian), ``marker``."""
    if kind == "marker":
        return scene("marker").system
    return exudyn_convention_system(scene().system, exudyn_jacobian=(kind == "exudyn"))


@cache
def exudyn_run():
    return run_exudyn_bennett(scene(), scene().q_start, T_END, STEP, RHO_INF, tolerance=1e-14)


@cache
def ffrf_run(kind: str):
    return run_ffrf_bennett(scene(), system(kind), scene().q_start, T_END, STEP, RHO_INF, label=kind)


@cache
def differences(kind: str) -> dict:
    return compare(ffrf_run(kind), exudyn_run())


@cache
def exudyn_static():
    return static_exudyn_bennett(scene(), scene().q_start, 0.0, load_steps=2, tolerance=1e-12)[:4]


# ---------------------------------------------------------------------------------------------
# Conventions and set-up
# ---------------------------------------------------------------------------------------------


def test_exudyn_applies_the_marker_offset_in_the_body_frame():
    """Measured on a deformed link: Exudyn's marker point is R + A(x_bar + P zeta + o) to round-off,
    millimetres away from ours r_M + A exp(theta~) o; its orientation is A exp(theta~) R as ours."""
    probe = probe_marker_offset(scene())
    assert probe["theta_norm"] > 1e-2
    assert probe["body_frame_distance"] < 1e-14
    assert probe["marker_frame_distance"] > 1e-4
    assert probe["orientation_error"] < 1e-13


def test_twin_uses_a_symbolic_drive_and_reports_every_step():
    run = exudyn_run()
    assert run.metadata["symbolic"], run.metadata["notes"]
    assert run.time.shape == (int(round(T_END / STEP)) + 1,)
    assert run.metadata["timings_s"]["setup"] > 0 and run.metadata["timings_s"]["solve"] > 0


def test_the_window_exercises_elasticity_and_the_drive():
    """Guards against a vacuous comparison: the links deform (modal coordinates up to ~3e-4) and
    the coupler moves by far more than the tolerances (sag under gravity plus the ramp)."""
    d = differences("exudyn")
    assert d["zeta_scale"] > 1e-4
    assert d["coupler_motion_m"] > 1e-5
    assert d["torque_scale_Nm"] > 1e-3
    s = scene()
    assert s.drive_angle(T_END) - s.drive_angle(0.0) > 5e-4  # rad turned by the ramp in the window


# ---------------------------------------------------------------------------------------------
# Dynamics
# ---------------------------------------------------------------------------------------------


def test_with_exudyn_conventions_the_solvers_agree_to_round_off():
    """Thresholds about 100x the values measured on 2026-11-24 (AMD EPYC; the same to a factor 1.5
    under OPENBLAS_CORETYPE=Sandybridge and Prescott)."""
    d = differences("exudyn")
    assert d["coupler_m"] < 1.5e-14  # measured 1.4e-16 m
    assert d["tracked_m"] < 3e-14  # measured 2.5e-16 m
    assert d["zeta_relative"] < 5e-10  # measured 4.7e-12
    assert d["torque_relative"] < 1e-7  # limited by Exudyn's Newton on the multipliers (measured 1.4e-9 to 2.1e-9)
    q_ours, q_theirs = ffrf_run("exudyn").q, exudyn_run().q
    assert np.abs(q_ours - q_theirs).max() < 1.5e-13  # measured 1.5e-15


def test_production_system_meets_the_issue_targets():
    """Our exact marker Jacobian against Exudyn's (same offset convention): measured coupler 4.3e-5,
    tracked nodes 7.1e-5 and torque 2.4e-6 of their scales on this scene (2026-11-24), within the
    issue's 1e-3 and 1e-4, which are 14x to 42x the measured values."""
    d = differences("production")
    assert d["torque_relative"] < TORQUE_TARGET
    assert d["coupler_m"] < TRAJECTORY_TARGET * d["coupler_motion_m"]
    assert d["tracked_m"] < TRAJECTORY_TARGET * d["tracked_motion_m"]
    assert d["coupler_m"] < 1e-7  # well below a micrometre; measured 1.95e-9 m
    # and the comparison does resolve the Jacobian difference (far above round-off)
    assert d["coupler_m"] > 1e3 * differences("exudyn")["coupler_m"]


def test_marker_frame_offsets_are_resolved_by_the_comparison():
    """Marker-frame offsets differ from Exudyn by the offset convention: measured 1.2e-6 m coupler
    (3 % of its motion), torque 4 %. A modelling difference, not a solver error: our two
    conventions differ by the same amount, and the body-frame one agrees with Exudyn."""
    marker, production = differences("marker"), differences("production")
    assert marker["coupler_m"] > 100 * production["coupler_m"]
    assert marker["torque_relative"] > 100 * production["torque_relative"]
    ours = compare(ffrf_run("marker"), ffrf_run("production"))
    assert abs(ours["coupler_m"] - marker["coupler_m"]) < 2 * production["coupler_m"]


# ---------------------------------------------------------------------------------------------
# Statics
# ---------------------------------------------------------------------------------------------


def test_static_equilibrium_agrees_with_exudyn_solve_static():
    """Exudyn's static multipliers have the opposite sign (residual f + C_q^T lambda):
    ``static_exudyn_bennett`` flips it, so our torque equals minus Exudyn's TorqueLocal z."""
    s = scene()
    q_e, torque_e, coupler_e, tracked_e = exudyn_static()
    q_o, torque_o, coupler_o, tracked_o = static_ffrf_bennett(s, system("exudyn"), s.q_start)
    assert np.abs(q_o - q_e).max() < 5e-14  # measured 5.3e-16
    assert np.abs(coupler_o - coupler_e).max() < 8e-15  # measured 7.6e-17 m
    assert np.abs(tracked_o - tracked_e).max() < 2e-14  # measured 1.7e-16 m
    assert abs(torque_o) > 1e-5 and abs(torque_o - torque_e) < 1.5e-11 * abs(torque_o)  # measured 1.5e-13


def test_production_assembly_against_exudyn_statics():
    """``assemble(scene)`` (production system, our exact Jacobian) against Exudyn's statics:
    the Jacobian difference tilts the reactions by O(|theta|): measured torque 5e-7 relative,
    coupler 2e-9 m; the marker-frame offsets differ by 8e-4 in torque and 1.2e-6 m."""
    s = scene()
    q_e, torque_e, coupler_e, _ = exudyn_static()
    solution = assemble(s)
    assert abs(solution.multipliers[-1] - torque_e) < 5e-5 * abs(torque_e)  # measured 5.0e-7
    q_p, _, coupler_p, _ = static_ffrf_bennett(s, s.system, s.q_start)
    assert np.abs(coupler_p - coupler_e).max() < 2e-8  # measured 1.95e-9 m
    assert np.abs(q_p - q_e).max() < 1e-6 * max(1.0, np.abs(q_e).max())  # measured 6.0e-8
    _, torque_m, coupler_m, _ = static_ffrf_bennett(scene("marker"), system("marker"), s.q_start)
    assert np.abs(coupler_m - coupler_e).max() > 1e-7
    assert abs(torque_m - torque_e) > 1e-4 * abs(torque_e)


def test_exudyn_marker_jacobian_is_not_the_derivative_of_its_constraints():
    """Why the exact-Jacobian system differs from Exudyn: at a deformed state (Exudyn's static
    solution) our joint Jacobian equals the complex-step derivative of the constraint values to
    round-off, while the Exudyn variant (marker angular velocity A(omega_bar + T theta_dot)) is off
    in the modal columns of the rotation rows by O(|theta|) relative."""
    s = scene()
    q_e = exudyn_static()[0]
    exact_errors, exudyn_errors, scales = [], [], []
    for name, exact in ((c.name, c) for c in system("production").constraints):
        variant = next(c for c in system("exudyn").constraints if c.name == name)
        blocks = [q_e[s.system.block(i)] for i in exact.bodies]
        for j, block in enumerate(blocks):
            numeric = np.empty((exact.size, block.shape[0]))
            for k in range(block.shape[0]):
                shifted = [b.astype(complex) for b in blocks]
                shifted[j][k] += 1e-30j
                numeric[:, k] = exact.value(shifted, 0.0).imag / 1e-30
            exact_errors.append(np.abs(exact.jacobian(blocks, 0.0)[j] - numeric).max())
            exudyn_errors.append(np.abs(variant.jacobian(blocks, 0.0)[j] - numeric).max())
            scales.append(np.abs(numeric).max())
    assert max(exact_errors) < 1e-12 * max(scales)
    assert max(exudyn_errors) > 1e-6 * max(scales)

r"""The single-body scenes (:mod:`validation.single_body_scenes`: a pendulum, a free body) in
Exudyn and in our solver, both on *identical* input (:class:`validation.reduced_body.ReducedBody`):

* Exudyn: one ``ObjectFFRFreducedOrder`` with **our** basis, built by the items every twin
  uses (:mod:`validation.exudyn_items`). The hinge is a
  ``MarkerSuperElementRigid`` on the frame-interface nodes with our weights and a ground
  ``MarkerBodyRigid``, joined by ``GenericJoint(constrainedAxes=[1,1,1,1,1,0])``; the joint
  frames are rotated by the markers' ``localHT`` so that their z-axis is the hinge axis.
* Ours: :class:`ffrf.body.flexible_body.FlexibleBody` with ``exact_gravity=False`` (Exudyn's
  ``LoadMassProportional`` on ``ObjectFFRFreducedOrder`` uses the undeformed centre of mass in
  the rotational row), ``GroundPoint`` at the weighted frame-interface centre and
  ``GroundPerpendicular`` for the axis.

Conventions matched (see the report in ``docs`` / the tests):

* DOF order [x0, y0, z0, x1, ...] in both; the frame origin is the mesh origin.
* Exudyn's ODE2 coordinates are displacements from the reference; the results here are
  absolute (reference added back).
* ``AddObjectFFRFreducedOrder(initialAngularVelocity=...)`` expects the **global** angular
  velocity (``GetRigidBodyNode`` -> ``AngularVelocity2EulerParameters_t``); we give the
  body-frame one and convert with the reference rotation.
* Initial velocity: ``initialVelocity`` is the frame origin's, v - omega x A c for a scene's
  velocity v of the body point c; ours: :meth:`ffrf.system.multibody.MultibodySystem.rigid_velocity`.
* Damping: both use D = alpha M_red + beta K_red (``massProportionalDamping``,
  ``stiffnessProportionalDamping``; ours Eq. (HCB-8)) on the modal coordinates.
* Force elements and loads: :mod:`validation.single_body_forces`.
* Newton: full Newton, fixed steps, no adaptive step, consistent initial accelerations.

Both runs have rows at the output times (t = 0 included), ``q`` in our layout ``[R (3), Euler parameters (4,
scalar first), zeta (m)]`` and the sensor ``tracked_nodes``, (n, k, 3) world positions of
``SingleBodyScene.tracked_nodes``: ours a :class:`~ffrf.output.result.Result`, Exudyn's a
:class:`validation.twin_run.TwinRun` (its docstring says why), both with :func:`validation.twin_run.run_metadata`.

``exudyn`` is imported lazily, so that our solver's runs work where Exudyn is missing.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np

from ffrf.output.result import Result

from .exudyn_items import (
    add_coordinates_sensor,
    add_ffrf_body,
    add_generic_joint,
    add_ground,
    add_ground_marker,
    add_interface_marker,
    add_mesh_node_sensor,
)
from .exudyn_solvers import check_output_times, dynamic_settings, solve_dynamic
from .single_body_forces import add_exudyn_force_items, ffrf_force_elements
from .single_body_scenes import Hinge, SingleBodyScene
from .twin_run import TwinRun, run_metadata, twin_run

if TYPE_CHECKING:
    from ffrf.system.constraints import Constraint

__all__ = ["run_exudyn", "run_ffrf", "ffrf_system"]


# --------------------------------------------------------------------------------------------
# Exudyn twin
# --------------------------------------------------------------------------------------------


def _add_exudyn_hinge(mbs, scene: SingleBodyScene, hinge: Hinge, body_object: int) -> tuple[int, int]:
    """Interface marker on bore 0 (our weights) + ground marker + GenericJoint (free rz) for
    ``hinge``, the hinge of ``scene``; returns the (ground, body) markers, joint frames."""
    body = scene.body
    frame = hinge.frame()  # world = body axes at t = 0 (identity reference rotation)
    centre_world = np.asarray(scene.position, dtype=float) + body.frame_center
    m_ground = add_ground_marker(mbs, add_ground(mbs), frame, centre_world)
    m_body = add_interface_marker(mbs, body_object, body.frame_nodes, body.frame_weights, frame)
    add_generic_joint(mbs, m_ground, m_body, (1, 1, 1, 1, 1, 0))
    return m_ground, m_body


def run_exudyn(
    scene: SingleBodyScene,
    modified_newton: bool = False,
    relative_tolerance: float = 1e-12,
    absolute_tolerance: float = 1e-12,
) -> TwinRun:
    """Build the Exudyn twin of ``scene``, integrate it and return its run (module docstring).

    ``relative_tolerance``/``absolute_tolerance`` are Exudyn's Newton criteria (residual norm
    relative to the first residual of the step / absolute, mixed units).
    """
    import exudyn as exu

    started = time.perf_counter()
    n_steps = scene.n_steps  # refuses a run that is not a whole number of steps
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    body = scene.body
    rotation_ref = scene.rotation0()
    omega = rotation_ref @ np.asarray(scene.omega_bar, dtype=float)  # Exudyn expects the global omega
    items = add_ffrf_body(
        mbs,
        body.nodes,
        body.mass,
        body.stiffness,
        body.basis,
        scene.position,
        rotation_ref,
        scene.initial_zeta(),
        scene.gravity,
        scene.beta,
        velocity=np.asarray(scene.velocity, dtype=float)
        - np.cross(omega, rotation_ref @ np.asarray(scene.velocity_point)),
        angular_velocity=omega,
        alpha=scene.alpha,
    )
    hinge_markers = None if scene.hinge is None else _add_exudyn_hinge(mbs, scene, scene.hinge, items.body)
    add_exudyn_force_items(mbs, scene, items.body, hinge_markers)
    rigid_sensor = add_coordinates_sensor(mbs, items.rigid_node)
    modal_sensor = add_coordinates_sensor(mbs, items.modal_node)
    node_sensors = [add_mesh_node_sensor(mbs, items.body, node) for node in scene.tracked_nodes]
    mbs.Assemble()
    settings = dynamic_settings(
        scene.t_end, scene.step, scene.rho_inf, relative_tolerance, absolute_tolerance, modified_newton
    )
    setup = time.perf_counter() - started
    integration, iterations = solve_dynamic(mbs, settings, f"the run (h={scene.step})")

    rigid = np.asarray(mbs.GetSensorStoredData(rigid_sensor))
    modal = np.asarray(mbs.GetSensorStoredData(modal_sensor))
    reference = np.asarray(mbs.GetNodeParameter(items.rigid_node, "referenceCoordinates"), dtype=float)
    tracked = np.stack([np.asarray(mbs.GetSensorStoredData(s))[:, 1:] for s in node_sensors], axis=1)
    t = rigid[:, 0]
    check_output_times(t, scene.step * np.arange(n_steps + 1), "sensor")
    q_rigid = rigid[:, 1:] + reference  # Exudyn stores displacements from the reference
    metadata = run_metadata("exudyn", f"exudyn {exu.__version__}", setup, integration, iterations)
    return twin_run(t, np.hstack([q_rigid, modal[:, 1:]]), {"tracked_nodes": tracked}, metadata)


# --------------------------------------------------------------------------------------------
# Our solver on the same scene
# --------------------------------------------------------------------------------------------


def ffrf_system(scene: SingleBodyScene, exact_gravity: bool = False, exudyn_definitions: bool = False):
    """Our :class:`ffrf.system.multibody.MultibodySystem` of ``scene`` and its initial state (q0, qd0).

    ``exact_gravity=False`` (default) is Exudyn's simplified gravity moment; True keeps the
    deformation-dependent term (only for sensitivity studies). ``exudyn_definitions``: force elements
    with Exudyn's definitions where they differ (:mod:`validation.exudyn_force_conventions`).
    """
    from ffrf.body.flexible_body import FlexibleBody
    from ffrf.body.modal_moments import modal_moments
    from ffrf.system.constraints import GroundPerpendicular, GroundPoint
    from ffrf.system.multibody import MultibodySystem

    body = scene.body
    moments = modal_moments(body.nodes, body.mass, body.basis)
    flexible = FlexibleBody(
        "bar",
        moments,
        stiffness=body.reduced_stiffness,
        damping=scene.alpha * body.reduced_mass + scene.beta * body.reduced_stiffness,  # Eq. (HCB-8)
        exact_gravity=exact_gravity,
    )
    constraints: tuple[Constraint, ...] = ()
    if scene.hinge is not None:
        frame = scene.hinge.frame()
        centre = body.frame_center
        constraints = (
            GroundPoint(
                bodies=(0,), name="hinge", local=centre, target=np.asarray(scene.position, dtype=float) + centre
            ),
            GroundPerpendicular(
                bodies=(0,), name="hinge axis", vector=frame[:, 2].copy(), normals=np.ascontiguousarray(frame[:, :2].T)
            ),
        )
    system = MultibodySystem(
        bodies=(flexible,),
        constraints=constraints,
        gravity=np.asarray(scene.gravity, float),
        forces=ffrf_force_elements(scene, exudyn_definitions),
    )
    q0 = system.initial_state(positions=[scene.position], rotations=[scene.euler0])
    q0[7:] = scene.initial_zeta()
    omega = scene.rotation0() @ np.asarray(scene.omega_bar, dtype=float)
    qd0 = system.rigid_velocity(q0, 0, scene.velocity, omega, scene.velocity_point)
    return system, q0, qd0


def run_ffrf(
    scene: SingleBodyScene,
    tolerance: float = 1e-12,
    exact_gravity: bool = False,
    modified_newton: bool | None = None,
    exudyn_definitions: bool = False,
) -> Result:
    """Integrate ``scene`` with our generalized-alpha solver (Newton ``tolerance``, see
    :func:`ffrf.solvers.generalized_alpha.generalized_alpha`); ``modified_newton=None`` keeps the
    solver's default; ``exudyn_definitions``: see :func:`ffrf_system`. Its run (module docstring)."""
    from ffrf.body.flexible_body import node_positions
    from ffrf.solvers.generalized_alpha import generalized_alpha

    started = time.perf_counter()
    system, q0, qd0 = ffrf_system(scene, exact_gravity, exudyn_definitions)
    setup = time.perf_counter() - started
    options: dict[str, Any] = {} if modified_newton is None else {"modified_newton": modified_newton}
    result = generalized_alpha(
        system, q0, qd0, scene.t_end, scene.step, rho_inf=scene.rho_inf, tolerance=tolerance, **options
    )
    q = result.q
    solver = ("ffrf" if modified_newton is None else f"ffrf (modified_newton={modified_newton})") + (
        " with Exudyn's force definitions" if exudyn_definitions else ""
    )
    metadata = run_metadata("ffrf", solver, setup, result.wall_time, int(result.newton_iterations.sum()))
    tracked = node_positions(q, scene.body.nodes, scene.body.basis, scene.tracked_nodes)
    return Result(
        result.time,
        {"tracked_nodes": tracked},
        q,
        metadata,
        qd=result.qd,
        multipliers=result.multipliers,
        kind="scene",
    )

r"""Can the flexible linkage reach an isolated assembly of its links? The energy barrier on the way
(``docs/formulation.md``, Eqs. (S7)-(S9)).

:func:`kinematics.assemblies.nearby_assemblies` finds the isolated (rigid, non-mobile) assemblies of the nominal
loop near its motion and measures their reach kinematically (Eqs. (L6)-(L8)). Here the flexible linkage measures it
in energy. With every joint's angle prescribed (joint i at ``drive_sign(i, n) * phi_i``, the convention of
:mod:`ffrf.scenes.linkage_description`), the static equilibrium holds the potential energy V(phi) (strain and
gravity, Eq. (S7)), whose gradient is the joints' driving torques (S8)
(:class:`ffrf.solvers.forced_joints.ForcedEnergy`). For each isolated assembly:

1. the motion end: the rigid motion is followed from the run's start to the assembly's nearest pose on the motion,
   and the linkage is let settle there with the driver held (its other joints free): the driven linkage's own
   equilibrium at that drive angle;
2. the straight joint-space path from there to the assembly (images equally spaced), whose highest V less V at the
   motion end bounds the barrier from above;
3. the minimum-energy path by the simplified string method (Eq. (S9), :func:`ffrf.numerics.string_method.string_method`)
   from that straight path, both ends held (the assembly closes the rigid loop, its strain only gravity's), the step
   1.5 / (largest curvature of V at the motion end, central differences of (S8)); the barrier is the highest V on it
   (Hermite cubic around the highest image) less V at the motion end;
4. the largest von Mises stress of the links at the highest image
   (:func:`ffrf.output.assembly_stress.scene_assembly_stress`) against the material's strength, and the barrier
   against the drive's work (:func:`drive_work`).

The links are linear-elastic in their frames (Eq. (HCB-3)): far from the motion the forced strains leave the linear
range of the material and of the model, which a stress ratio above one says.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.numerics.string_method import StringPath, string_method
from ffrf.output.assembly_stress import scene_assembly_stress
from ffrf.scenes.linkage_description import drive_sign
from ffrf.scenes.linkage_scene import LinkageScene
from ffrf.solvers.forced_joints import ForcedEnergy, joint_angles
from kinematics import trace_motion
from kinematics.assemblies import Assembly, NearbyAssemblies, nearby_assemblies
from kinematics.dh import wrap_angle

__all__ = ["Reach", "ReachOptions", "drive_work", "isolated_assemblies", "linkage_energy", "reach_isolated"]

#: Step of the central differences of (S8) for the curvature of V at the motion end (rad).
CURVATURE_STEP = 1e-4
#: The string's time step times the largest curvature of V at the motion end (stable below 2, Eq. (S9)).
STEP_CURVATURE = 1.5


@dataclass(frozen=True)
class ReachOptions:
    """The string of :func:`reach_isolated`: ``images`` (both ends included), the residual
    ``tolerance`` (largest normal gradient, N m) at which it has converged, at most ``max_iterations``, and the
    re-parametrisation's ``interpolation`` (Eq. (S9))."""

    images: int = 21
    tolerance: float = 1e-3
    max_iterations: int = 5000
    interpolation: str = "linear"


@dataclass(frozen=True)
class Reach:
    """The way from the motion to one isolated ``assembly``: the motion end ``motion_phi`` (rad), the minimum-energy
    ``path`` (images from the motion end to the assembly, V in J), the energies of the straight path it started
    from, the largest von Mises stress of the links at the path's highest image (Pa) with the material's
    ``strength`` (Pa, ``None`` if unknown), the drive's work it is compared with (J, ``None`` if not given) and
    the wall time (s)."""

    assembly: Assembly
    motion_phi: NDArray[np.float64]
    path: StringPath
    straight_energies: NDArray[np.float64]
    peak_stress: float
    strength: float | None
    drive_work: float | None
    seconds: float

    @property
    def barrier(self) -> float:
        """The highest V on the minimum-energy path less V at the motion end (J)."""
        return self.path.peak()[1] - float(self.path.energies[0])

    @property
    def straight_barrier(self) -> float:
        """The highest V on the straight joint-space path less V at the motion end (J): an upper bound."""
        return float(np.max(self.straight_energies) - self.straight_energies[0])

    @property
    def stress_ratio(self) -> float | None:
        """Largest von Mises stress at the highest image over the strength."""
        return None if self.strength is None else self.peak_stress / self.strength

    @property
    def work_ratio(self) -> float | None:
        """The barrier over the drive's work."""
        return None if self.drive_work is None else self.barrier / self.drive_work

    @property
    def verdict(self) -> str:
        """``within reach`` when the drive's work covers the barrier, else ``out of reach``."""
        if self.work_ratio is None:
            return "no drive work to compare with"
        return "within reach" if self.work_ratio <= 1.0 else "out of reach"

    def as_dict(self) -> dict:
        """JSON-ready fields (SI units, angles in rad)."""
        path = self.path
        peak_s, peak_energy = path.peak()
        return {
            "assembly": self.assembly.as_dict(),
            "motion_end_phi_rad": self.motion_phi.tolist(),
            "motion_end_energy_J": float(path.energies[0]),
            "assembly_energy_J": float(path.energies[-1]),
            "barrier_J": self.barrier,
            "straight_path_barrier_J": self.straight_barrier,
            "peak_energy_J": peak_energy,
            "peak_image": path.peak_index,
            "peak_arclength_rad": peak_s,
            "path_length_rad": float(path.arclength[-1]),
            "peak_max_von_mises_pa": self.peak_stress,
            "strength_pa": self.strength,
            "stress_ratio": self.stress_ratio,
            "drive_work_J": self.drive_work,
            "work_ratio": self.work_ratio,
            "verdict": self.verdict,
            "images": int(path.images.shape[0]),
            "iterations": path.iterations,
            "converged": path.converged,
            "residual_Nm": path.residual,
            "step_rad2_per_J": path.step,
            "energies_J": path.energies.tolist(),
            "straight_energies_J": self.straight_energies.tolist(),
            "images_phi_rad": path.images.tolist(),
            "seconds": self.seconds,
        }


def drive_work(driving_torque: NDArray, drive_angle: NDArray) -> dict[str, float]:
    """What the drive of a run (its ``driving_torque``, N m, over ``drive_angle``, rad, in the order of the run)
    puts into the linkage over its last revolution: ``work_J``, the work it does where it drives rather than brakes
    (trapezoids of torque times angle that are positive; its net work over a quasi-static revolution is the change of
    potential energy, about zero), the reference of :attr:`Reach.verdict`; and ``max_torque_work_J``, 2 pi times the
    largest ``|torque|`` of that revolution, what the drive would deliver at that torque throughout."""
    torque, angle = np.asarray(driving_torque, dtype=float), np.asarray(drive_angle, dtype=float)
    last = np.abs(angle - angle[-1]) <= 2.0 * np.pi + 1e-12
    torque, angle = torque[last], angle[last]
    work = 0.5 * (torque[1:] + torque[:-1]) * np.diff(angle)
    return {
        "turn_rad": float(abs(angle[-1] - angle[0])),
        "max_abs_driving_torque_Nm": float(np.max(np.abs(torque))),
        "work_J": float(np.sum(np.maximum(work, 0.0))),
        "max_torque_work_J": float(2.0 * np.pi * np.max(np.abs(torque))),
    }


def _joint_names(scene: LinkageScene) -> tuple[str, ...]:
    """The loop's joints in order, joint i between links i and i + 1 (:mod:`ffrf.scenes.linkage_description`)."""
    names = tuple(j.name for j in scene.joints if j.name != "clamp")
    if len(names) != scene.loop.n:
        raise ValueError(f"{scene.name}: expected {scene.loop.n} loop joints besides the clamp, got {names}")
    return names


def linkage_energy(scene: LinkageScene, assembled_q: NDArray) -> ForcedEnergy:
    """V(phi) of Eq. (S7) for the linkage, every joint prescribed, starting from its assembled state ``assembled_q``
    (:func:`ffrf.scenes.assembly.assemble`) at the joint angles measured there."""
    n = scene.loop.n
    names, signs = _joint_names(scene), np.array([drive_sign(i, n) for i in range(n)])
    phi0 = joint_angles(scene.system, names, signs, assembled_q, scene.start_phi)
    return ForcedEnergy(scene.system, names, signs, phi0, assembled_q)


def isolated_assemblies(scene: LinkageScene, poses: int = 360) -> NearbyAssemblies:
    """:func:`kinematics.assemblies.nearby_assemblies` of the scene's nominal loop, its motion traced over one
    revolution of the driver from the run's start at ``poses`` poses (its defaults otherwise)."""
    motion = trace_motion(scene.loop, scene.driver, n_poses=poses, start=scene.start_phi)
    return nearby_assemblies(motion)


def _motion_end(energy: ForcedEnergy, scene: LinkageScene, assembly: Assembly) -> NDArray[np.float64]:
    """Step 1 of the module docstring: along the rigid motion to the assembly's nearest pose, then settled with the
    driver held."""
    turn = float(wrap_angle(assembly.nearest[scene.driver] - scene.start_phi[scene.driver]))
    poses = int(np.ceil(abs(turn) / energy.max_step)) + 1
    motion = trace_motion(
        scene.loop, scene.driver, n_poses=poses, revolution=turn, start=scene.start_phi, endpoint=True
    )
    for phi in motion.phi:
        energy.solve(phi)
    return energy.relax(motion.phi[-1], (energy.names[scene.driver],))


def _largest_curvature(energy: ForcedEnergy, phi: NDArray) -> float:
    """The largest eigenvalue of the Hessian of V at ``phi``, by central differences of its gradient (S8)."""
    n = phi.size
    columns = [
        (energy(phi + CURVATURE_STEP * e)[1] - energy(phi - CURVATURE_STEP * e)[1]) / (2.0 * CURVATURE_STEP)
        for e in np.eye(n)
    ]
    hessian = np.column_stack(columns)
    return float(np.linalg.eigvalsh(0.5 * (hessian + hessian.T))[-1])


def reach_isolated(
    scene: LinkageScene,
    assembled_q: NDArray,
    assemblies: Sequence[Assembly],
    drive_work: float | None = None,
    strength: float | None = None,
    options: ReachOptions | None = None,
    progress: Callable[[int, float], None] | None = None,
) -> tuple[Reach, ...]:
    """Steps 1-4 of the module docstring for each of ``assemblies`` (isolated ones of the scene's nominal loop),
    from the assembled state ``assembled_q``; ``drive_work`` (J) and ``strength`` (Pa) to compare with;
    ``progress(iteration, residual)`` of the string method."""
    options = ReachOptions() if options is None else options
    if options.images < 3:
        raise ValueError(f"the string needs at least 3 images, got {options.images}")
    energy = linkage_energy(scene, assembled_q)
    out = []
    for assembly in assemblies:
        started = time.perf_counter()
        start = _motion_end(energy, scene, assembly)
        shares = np.linspace(0.0, 1.0, options.images)[:, None]
        straight = start + shares * wrap_angle(assembly.phi - start)
        straight_energies = np.array([energy(phi)[0] for phi in straight])
        step = STEP_CURVATURE / _largest_curvature(energy, start)
        path = string_method(
            energy,
            straight,
            step,
            options.tolerance,
            options.max_iterations,
            interpolation=options.interpolation,
            progress=progress,
        )
        peak = energy.solve(path.images[path.peak_index])
        stress = scene_assembly_stress(scene, peak.q).as_dict()["max_von_mises_pa"]
        out.append(
            Reach(
                assembly,
                start,
                path,
                straight_energies,
                float(stress),
                strength,
                drive_work,
                time.perf_counter() - started,
            )
        )
    return tuple(out)

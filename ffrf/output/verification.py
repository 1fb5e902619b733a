r"""A run checks itself before it says it succeeded (``docs/validation.md``, "Every run checks itself").

Each check compares one number of the run with a tolerance derived from the run's own scale: its longest link
``L`` (m), the solvers' Newton tolerance, its energy scale (Eq. (C2)) and, for stiff links, the sag gravity gives
them. The checks (those whose sensors the run has):

* ``joint_constraints``: the largest joint constraint residual (the loop's closure at every joint; m, or rad for
  the rotation rows) against the Newton tolerance :data:`SOLVER_TOLERANCE` times ``max(1, L / 1 m)``: both
  solvers stop only when the residual is below it, so a larger one means an output that did not converge.
* ``loop_closure``: the largest distance between the two sides' points of any joint (m), against the same
  tolerance: the loop's closure measured as a length, from the bodies' poses, whatever the constraints' rows.
* ``energy_balance``: the largest residual of the balance (drive and force elements' work against the changes of
  kinetic, potential and strain energy and the damping dissipation, J) against :data:`ENERGY_RTOL` times the energy
  scale of Eq. (C2) (at least the links' weight-length energy ``m g_n L``) plus the estimated quadrature error of
  the drive's work over the output rows (:func:`ffrf.output.energy_balance.work_quadrature_error`). Where a
  quasi-static path jumps (a contact letting go, a snap), what the jump releases counts as dissipated.
* ``jumps_release_energy`` (quasi-static paths that jump): the largest energy a jump between two output rows
  gained, against the same :data:`ENERGY_RTOL` of the energy scale: a jump between equilibria under a
  position-controlled drive goes downhill; one that gains energy has left the path for a wrong state.
* ``step_error`` (dynamic runs): the median over the steps of the local error estimate of Eq. (G5) (m) against
  :data:`STEP_ERROR_RTOL` times ``L``. The median is the steady motion's; the largest estimate is the start's
  transient, which the numerical damping removes in the first steps (``docs/speed_vs_error.md``) and which is
  reported, not judged.
* ``path_distance`` (linkages): the coupler's distance to the exact ideal curve is at most its distance to the
  ideal point at the same drive angle (a point of that curve), to the distance's tolerance, 1e-12 m.
* ``clearance`` (linkages, judged when the links' clearance is computed:
  :meth:`ffrf.output.result.Result.add_clearance`, which saving a linkage's results and ``python -m ffrf`` do):
  the margin every two links must keep (m; a linkage file's ``clearance_margin``, default 1 mm) against the
  smallest clearance proven between two links along a revolution of the rigid motion (Eqs. (CL1)-(CL4); negative:
  they overlap). A linkage file's ``check_clearance = false`` leaves it out, with a note.
* ``pin_penetration`` (scenes with joints with play, :mod:`ffrf.system.clearance_joint`): the deepest penetration
  of a pin's contact into its bore along the run over the play in that direction (radial clearance, half the axial
  play), against :data:`PENETRATION_RTOL`: the penalty regularisation's error must be small against the play the run
  is about (Eq. (P5)). A direction without play (a bushing) is noted, not judged.
* ``stiff_follows_rigid`` (linkages whose links are stiff: the gravity sag ``2 U / (m |g|)`` of Eq. (C3), ``U``
  the assembled state's strain energy, below :data:`STIFF_SAG` of ``L``; without bore errors or misfit): the
  largest coupler deviation from the rigid motion against :data:`SAG_FACTOR` times that sag (the sag changes along
  the motion as the links turn against gravity) plus the Newton tolerance's ``max(1, L)``.

Warnings do not fail a run: ``assembly_strength``, where a link's peak von Mises stress of the assembled state
exceeds its material's strength (the print would break while it is assembled; skipped with a note for a material
without a strength).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ffrf.output.energy_balance import energy_scale, work_quadrature_error

__all__ = [
    "Check",
    "Verification",
    "ENERGY_RTOL",
    "SAG_FACTOR",
    "SOLVER_TOLERANCE",
    "STANDARD_GRAVITY",
    "STEP_ERROR_RTOL",
    "STIFF_SAG",
    "assembly_strength_warnings",
    "clearance_check",
    "gravity_sag",
    "scene_length",
    "verify_run",
    "play_check",
    "verify_scene_run",
    "weight_energy",
]

#: The Newton tolerance both solvers stop at (the default of ``quasi_static`` and ``generalized_alpha``; a test
#: keeps the two in step).
SOLVER_TOLERANCE = 1e-10
#: The energy balance's residual, relative to the energy scale of Eq. (C2): the books close to 0.01 % of what the
#: machine moves (a missing or wrong work term is percents); stiff links' driving torque is round-off that does
#: net work (unloaded stiff Bennett: 5.8e-6 of the scale, docs/validation.md).
ENERGY_RTOL = 1e-4
#: The steady local error estimate of Eq. (G5), relative to the longest link.
STEP_ERROR_RTOL = 1e-6
#: Links count as stiff when gravity sags them by less than this fraction of the longest link.
STIFF_SAG = 1e-6
#: How much more than the assembled state's sag a stiff link may sag along the motion (measured: the largest
#: deviation over a revolution is 4 times the sag on the Bennett linkage, 28 to 31 times on collisions_free_6r,
#: whose links turn further against gravity; docs/validation.md).
SAG_FACTOR = 1000.0
#: Standard gravity (m/s^2), for the weight-length energy that floors the energy scale (also without gravity).
STANDARD_GRAVITY = 9.80665
#: Tolerance of the exact distance to the ideal path (m), :func:`ffrf.output.path_distance.distance_to_curve`.
DISTANCE_TOLERANCE = 1e-12


@dataclass(frozen=True)
class Check:
    """One check: its ``name``, the run's ``value`` and the ``tolerance`` it must not exceed (same ``unit``)."""

    name: str
    value: float
    tolerance: float
    unit: str
    what: str

    @property
    def passed(self) -> bool:
        return bool(np.isfinite(self.value) and self.value <= self.tolerance)

    @property
    def margin(self) -> float:
        """Tolerance over value (how many times the value could grow before failing)."""
        return float("inf") if self.value <= 0.0 else self.tolerance / self.value

    def line(self) -> str:
        return f"{self.name} {self.value:.3g} {self.unit} (tolerance {self.tolerance:.3g} {self.unit}): {self.what}"

    def as_dict(self) -> dict:
        return {
            "name": self.name,
            "value": float(self.value),
            "tolerance": float(self.tolerance),
            "unit": self.unit,
            "passed": self.passed,
            "margin": self.margin if np.isfinite(self.margin) else None,  # JSON has no infinity
            "what": self.what,
        }


@dataclass(frozen=True)
class Verification:
    """The checks of a run and its warnings; ``verified`` when every check passed; ``notes``: checks not made."""

    checks: tuple[Check, ...]
    warnings: tuple[str, ...] = ()
    notes: tuple[str, ...] = field(default=())

    @property
    def verified(self) -> bool:
        return all(check.passed for check in self.checks)

    @property
    def reasons(self) -> list[str]:
        """One line per failed check."""
        return [check.line() for check in self.checks if not check.passed]

    def verdict(self) -> str:
        """The one line the command line ends with."""
        names = ", ".join(check.name for check in self.checks)
        if self.verified:
            text = f"verified: true ({names} within their tolerances"
            smallest = min(self.checks, key=lambda c: c.margin, default=None)
            if smallest is not None:
                text += f"; smallest margin {smallest.margin:.3g}x, {smallest.name}"
            return text + ")" + (f"; {len(self.warnings)} warning(s) above" if self.warnings else "")
        return "verified: false: " + "; ".join(self.reasons)

    def with_check(self, check: Check) -> Verification:
        """These checks and ``check`` (one of the same name replaced)."""
        kept = tuple(c for c in self.checks if c.name != check.name)
        return Verification(kept + (check,), self.warnings, self.notes)

    def with_note(self, note: str) -> Verification:
        """These checks with one more note (a check not made)."""
        return Verification(self.checks, self.warnings, self.notes + (note,))

    def as_dict(self) -> dict:
        return {
            "verified": self.verified,
            "verdict": self.verdict(),
            "reasons": self.reasons,
            "checks": [check.as_dict() for check in self.checks],
            "warnings": list(self.warnings),
            "notes": list(self.notes),
        }


def scene_length(scene: Any) -> float:
    """The scene's length scale (m): a linkage's longest link, else the largest extent of a body's nodes."""
    length = getattr(scene, "link_length", None)
    if length is not None:
        return float(length)
    return max(float(np.max(np.ptp(body.fe.nodes, axis=0))) for body in scene.bodies)


def _total_mass(scene: Any) -> float:
    return float(sum(body.fe.total_mass for body in scene.bodies))


def weight_energy(scene: Any) -> float:
    """``m g_n L`` (J): the bodies' mass lifted by the scene's length under standard gravity, the floor of the energy
    scale of Eq. (C2) (a size of the machine's energies that exists also where the scene has no gravity)."""
    return _total_mass(scene) * STANDARD_GRAVITY * scene_length(scene)


def gravity_sag(scene: Any, strain_energy: float) -> float:
    """The sag (m) gravity gives the assembled links, Eq. (C3), ``2 U / (m |g|)``: a linear structure under its own
    weight ``m g`` stores ``U = m |g| s / 2`` with ``s`` the mean sag along gravity (Clapeyron); 0 without gravity."""
    g = float(np.linalg.norm(scene.system.gravity))
    return 0.0 if g == 0.0 else 2.0 * strain_energy / (_total_mass(scene) * g)


def assembly_strength_warnings(scene: Any, assembly: dict | None) -> tuple[list[str], list[str]]:
    """Warnings for links whose assembled peak von Mises stress exceeds their material's strength, and notes for
    links whose material has no strength (or no elements of ours); ``assembly``: ``AssemblyStress.as_dict()``."""
    warnings: list[str] = []
    notes: list[str] = []
    if assembly is None:
        return warnings, ["no assembled state: the assembly's stresses were not checked against the strength"]
    for entry, body in zip(assembly["links"], scene.bodies, strict=True):
        peak = entry.get("max_von_mises_pa")
        material = getattr(body.fe, "material", None)
        strength = None if material is None else material.strength
        if peak is None or material is None or strength is None:
            what = "no elements of ours" if peak is None or material is None else f"{material.name!r} has no strength"
            notes.append(f"assembly_strength of link {entry['link']} not checked: {what}")
        elif peak > strength:
            warnings.append(
                f"assembly_strength: link {entry['link']} is stressed to {1e-6 * peak:.4g} MPa (von Mises) when "
                f"assembled, beyond its material's strength {1e-6 * strength:.4g} MPa ({material.name}): the part "
                "would break while being assembled; check the bore errors and the misfit"
            )
    return warnings, notes


def _constraint_check(sensors: dict, length: float) -> Check:
    return Check(
        "joint_constraints",
        float(np.max(sensors["constraint_residual"])),
        SOLVER_TOLERANCE * max(1.0, length),
        "m",
        "largest joint constraint residual (the loop's closure at every joint) against the Newton tolerance",
    )


def _closure_check(sensors: dict, length: float) -> Check | None:
    """The loop's closure measured as a length: the largest distance between the two sides' joint points of any
    joint (``J_point0``, ``J_point1`` of :func:`ffrf.output.sensors.joint_rows`); None without those sensors. A joint
    with play (its ``J_eccentricity`` sensor) opens by its play, which ``pin_penetration`` judges instead."""
    gaps = [
        float(np.max(np.linalg.norm(sensors[name] - sensors[name[:-1] + "1"], axis=-1)))
        for name in sensors
        if name.endswith("_point0")
        and name[:-1] + "1" in sensors
        and len(sensors[name])
        and name[: -len("point0")] + "eccentricity" not in sensors
    ]
    if not gaps:
        return None
    return Check(
        "loop_closure",
        max(gaps),
        SOLVER_TOLERANCE * max(1.0, length),
        "m",
        "largest distance between the two sides' points of a joint (the loop closes at every joint)",
    )


def _energy_checks(sensors: dict, floor: float) -> list[Check]:
    """The energy balance's check, and where the path jumped, that its jumps released energy."""
    residual = sensors["energy_balance_residual"]
    scale = energy_scale(sensors, floor)
    released = np.diff(sensors.get("energy_released_in_jumps", np.zeros(0)))
    jumps = (
        [
            Check(
                "jumps_release_energy",
                max(0.0, -float(np.min(released))),
                ENERGY_RTOL * scale,
                "J",
                f"largest energy the path's jumps between two outputs gained (they released "
                f"{float(np.sum(released)):.3g} J in all) against {ENERGY_RTOL:g} of the energy scale {scale:.3g} J",
            )
        ]
        if np.any(released != 0.0)
        else []
    )
    return jumps + [_balance_check(residual, scale, sensors)]


def _balance_check(residual: NDArray, scale: float, sensors: dict) -> Check:
    """The energy balance's largest residual against the scale of Eq. (C2) and the work's quadrature error."""
    return Check(
        "energy_balance",
        float(np.max(np.abs(residual))) if len(residual) else 0.0,
        ENERGY_RTOL * scale + work_quadrature_error(sensors),
        "J",
        f"largest residual of the energy balance against {ENERGY_RTOL:g} of the energy scale {scale:.3g} J "
        "(Eq. (C2)) plus the quadrature error of the drive's work (the books are kept at the outputs and on both "
        "sides of each jump of a quasi-static path: where the driving torque changes faster than they sample it, "
        "more outputs close them further)",
    )


def _near_dead_cause(poses) -> str:
    """Where the deviation from the rigid motion peaks at a near-dead pose the run passed (metadata
    ``near_dead_poses``, :func:`ffrf.scenes.linkage_steps.near_dead_poses`), the words that name it as the cause."""
    worst = max(poses, key=lambda pose: pose["max_coupler_deviation_near_m"], default=None)
    if worst is None or worst["max_coupler_deviation_near_m"] <= worst["max_coupler_deviation_elsewhere_m"]:
        return ""
    return (
        f"; it peaks at {worst['max_coupler_deviation_near_m']:.3g} m within 2 deg of the near-dead pose at drive "
        f"angle {worst['drive_angle_deg']:.4g} deg, where joint {worst['joint']} turns {worst['ratio']:.3g} times "
        f"faster than the driver ({worst['max_coupler_deviation_elsewhere_m']:.3g} m elsewhere): the rigid motion is "
        "ill-conditioned there and the load's strain is amplified (docs/hard_cases.md); drive another joint"
    )


def verify_run(result: Any, scene: Any) -> Verification:
    """The checks of the module docstring for a linkage run (:class:`ffrf.output.result.Result` of
    :class:`ffrf.scenes.linkage_scene.LinkageScene`); those whose sensors the run did not evaluate are left out."""
    sensors, metadata = result.sensors, result.metadata
    length = scene_length(scene)
    checks: list[Check] = []
    notes: list[str] = []
    if "constraint_residual" in sensors:
        checks.append(_constraint_check(sensors, length))
    closure = _closure_check(sensors, length)
    if closure is not None:
        checks.append(closure)
    if "energy_balance_residual" in sensors:
        checks += _energy_checks(sensors, float(metadata.get("energy_floor_j", weight_energy(scene))))
    play, play_notes = play_check(scene, sensors)
    checks += [] if play is None else [play]
    notes += play_notes
    estimate = metadata.get("step_error_estimate")
    if estimate is not None:
        checks.append(
            Check(
                "step_error",
                float(estimate["median_m"]),
                STEP_ERROR_RTOL * length,
                "m",
                f"median local error estimate of Eq. (G5) against {STEP_ERROR_RTOL:g} of the longest link (the "
                f"largest, {estimate['largest_m']:.2g} m at t = {estimate['largest_at_s']:.3g} s, is the start's "
                "transient and not judged)",
            )
        )
    deviation = np.linalg.norm(sensors["coupler_deviation"], axis=1)
    checks.append(
        Check(
            "path_distance",
            float(np.max(sensors["coupler_distance_to_path"] - deviation)),
            DISTANCE_TOLERANCE,
            "m",
            "distance to the exact ideal curve minus the distance to its point at the same drive angle",
        )
    )
    strain = 0.0 if result.assembly is None else sum(link.strain_energy_j for link in result.assembly.links)
    sag = gravity_sag(scene, strain)
    misfit = bool(scene.settings.get("bore_errors")) or scene.misfit_degrees > 0.0
    if sag <= STIFF_SAG * length and not misfit:
        checks.append(
            Check(
                "stiff_follows_rigid",
                float(np.max(deviation)),
                SAG_FACTOR * sag + SOLVER_TOLERANCE * max(1.0, length),
                "m",
                f"largest coupler deviation from the rigid motion against {SAG_FACTOR:g} times the gravity sag "
                f"{sag:.3g} m of the stiff links" + _near_dead_cause(metadata.get("near_dead_poses", ())),
            )
        )
    else:
        notes.append(
            "stiff_follows_rigid not checked: "
            + ("the linkage has bore errors or misfit" if misfit else f"the links sag {sag:.3g} m under gravity")
        )
    assembly = None if result.assembly is None else result.assembly.as_dict()
    warnings, strength_notes = assembly_strength_warnings(scene, assembly)
    return Verification(tuple(checks), tuple(warnings), tuple(notes + strength_notes))


def clearance_check(clearance: dict) -> Check:
    """The ``clearance`` check of the module docstring from a linkage's ``clearance`` entry (metadata, written by
    :meth:`ffrf.output.result.Result.add_clearance`): the margin against the smallest clearance proven between two
    links along the motion (the pair and the drive angle of its closest pose named)."""
    pair = min(clearance["pairs"], key=lambda p: p["between_poses_m"])
    a, b = pair["links"]
    return Check(
        "clearance",
        float(clearance["margin_m"]),
        float(pair["between_poses_m"]),
        "m",
        "the margin every two links must keep against the smallest clearance proven along the rigid motion "
        f"(links {a}-{b}, closest {1e3 * pair['clearance_m']:.3g} mm at drive angle "
        f"{np.degrees(pair['drive_angle_rad']):.4g} deg; negative: they overlap)",
    )


#: The largest penetration of a pin into its bore, relative to the play (Eq. (P5)): the penalty's regularisation
#: error must stay small against the clearance the run is about.
PENETRATION_RTOL = 0.1


def play_check(scene: Any, sensors: dict) -> tuple[Check | None, list[str]]:
    """The ``pin_penetration`` check of the joints with play: the largest penetration of a contact over its play
    (radial clearance, half the axial play) along the run; joints or directions without play go to the notes."""
    worst, where, notes = 0.0, "", []
    for joint in getattr(scene, "loose_joints", ()):
        contacts = sensors.get(f"{joint.name}_contacts")
        if contacts is None:
            continue
        plays = {"rim -": joint.radial, "rim +": joint.radial, "axial": 0.5 * joint.axial}
        for k, (name, play) in enumerate(plays.items()):
            if play == 0.0:
                notes.append(f"pin_penetration of {joint.name} {name} not checked: no play (a bushing)")
                continue
            ratio = float(np.max(contacts[:, 0, k])) / play
            if ratio > worst or not where:
                worst, where = ratio, f"{joint.name} {name}"
    if not where:
        return None, notes
    check = Check(
        "pin_penetration",
        max(worst, 0.0),
        PENETRATION_RTOL,
        "of the play",
        f"the deepest penetration of a pin into its bore against the play ({where}): the contact stiffness must be "
        "high enough that the penalty's error is small against the clearance (Eq. (P5))",
    )
    return check, notes


def verify_scene_run(scene: Any, sensors: dict, metadata: dict) -> Verification:
    """What applies to any scene's run (:func:`ffrf.scenes.scene_file.run_scene`): the joint constraints, the
    loop's closure, the energy balance when the scene has one driven joint, and the assembly's stresses against
    the strength."""
    length = scene_length(scene)
    checks = [_constraint_check(sensors, length)] if "constraint_residual" in sensors else []
    closure = _closure_check(sensors, length)
    checks += [] if closure is None else [closure]
    notes: list[str] = []
    if "energy_balance_residual" in sensors:
        checks += _energy_checks(sensors, weight_energy(scene))
    else:
        notes.append("energy_balance not checked: the scene has no single driven joint")
    play, play_notes = play_check(scene, sensors)
    checks += [] if play is None else [play]
    notes += play_notes
    warnings, strength_notes = (
        assembly_strength_warnings(scene, metadata["assembly"]) if "assembly" in metadata else ([], [])
    )
    return Verification(tuple(checks), tuple(warnings), tuple(notes + strength_notes))

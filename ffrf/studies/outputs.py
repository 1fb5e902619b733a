"""The output columns of a study's rows: what every variant reports (``docs/studies.md``, "What a variant computes")."""

from __future__ import annotations

__all__ = ["ASSEMBLY_OUTPUTS", "ENDS", "OUTPUTS", "STABILITY_OUTPUTS", "WHERE", "is_assembly_output", "output_names"]

#: Outputs of every linkage; the assembly stresses add one column per link (:func:`output_names`).
OUTPUTS = (
    "max_coupler_deviation_m",
    "max_coupler_distance_to_path_m",
    "max_abs_driving_torque_Nm",
    "assembly_strain_energy_J",
)

#: Outputs of the assembled state, which a print that assembled has even where its path stopped later.
ASSEMBLY_OUTPUTS = ("assembly_strain_energy_J",)
#: The drive angles (deg, the drive sensor's) where each print's largest coupler deviation and largest absolute driving
#: torque occur, and where its path ended (its end, or where it stopped): where to look, not outputs to rank by.
WHERE = ("max_coupler_deviation_at_deg", "max_abs_driving_torque_at_deg", "last_drive_angle_deg")


#: Outputs of a study with stability monitoring: the snaps of the path, the energy they release (J, summed) and the
#: lowest vibration frequency over the equilibria (Hz; NaN where one is unstable).
STABILITY_OUTPUTS = ("snaps", "snap_energy_released_J", "min_frequency_hz")


#: How a print's run ended (a row's ``end``): its path to the end, with or without snaps on the way (stability
#: monitoring follows a fold to where the path lands), or where and why not: a stop near a dead pose of the rigid
#: loop, or at a fold of the path where neither the traced path nor a dynamic passage from the fold finds a stable
#: equilibrium to land on (Eqs. (S6), (S11); the print snaps there, to where only a dynamic run can tell). A stop
#: that none of the named causes explains is ``stopped (unclassified)``: what a study's report counts as the
#: solver's, not the print's, failure.
ENDS = (
    "completed",
    "completed through snaps",
    "no assembly",
    "stopped at a near-dead pose",
    "stopped at a fold without landing",
    "stopped (unclassified)",
    "bad input",
    "error",
)


def is_assembly_output(name: str) -> bool:
    """Whether the output ``name`` is of the assembled state (:data:`ASSEMBLY_OUTPUTS`, the links' stresses)."""
    return name in ASSEMBLY_OUTPUTS or name.startswith("max_assembly_stress_link")


def output_names(n_links: int, stability: bool = False) -> tuple[str, ...]:
    """The output columns of a linkage of ``n_links`` links (and of its stability, if monitored)."""
    stresses = tuple(f"max_assembly_stress_link{k}_Pa" for k in range(n_links))
    return OUTPUTS + stresses + (STABILITY_OUTPUTS if stability else ())

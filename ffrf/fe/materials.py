"""Linear isotropic elastic materials (SI units).

Two constants: printed PLA (E = 1.2 GPa, nu = 0.33, rho = 450 kg/m^3, 15 % infill; the values of the
paper, Sect. "Simulation Setup"), the default material of linkages, and an "ideally rigid" reference
material used to switch flexibility off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ffrf.errors import MaterialError

__all__ = ["Material", "PLA", "PLA_TENSILE_STRENGTH", "RIGID"]


@dataclass(frozen=True)
class Material:
    """Isotropic linear elastic material.

    Parameters
    ----------
    E : float
        Young's modulus in Pa, > 0.
    nu : float
        Poisson's ratio, -1 < nu < 0.5 (positive definite elasticity tensor,
        Timoshenko & Goodier, Theory of Elasticity, sec. 6).
    rho : float
        Mass density in kg/m^3, > 0.
    name : str
        Label used in error messages and summaries.
    strength : float or None
        Stress (Pa) beyond which the material breaks (tensile strength), compared with the assembled links' peak
        von Mises stress (:mod:`ffrf.output.verification`); None: unknown, the comparison is skipped.

    Examples
    --------
    A Poisson solid (nu = 1/4) has equal Lame parameters, G = lambda = E / 2.5:

    >>> solid = Material(E=2.5e9, nu=0.25, rho=1000.0)
    >>> solid.shear_modulus, solid.lame_lambda
    (1000000000.0, 1000000000.0)
    >>> Material(E=1.2e9, nu=0.5, rho=450.0)
    Traceback (most recent call last):
    ffrf.errors.MaterialError: Material 'material': Poisson's ratio nu=0.5 must lie in (-1, 0.5); ...
    """

    E: float
    nu: float
    rho: float
    name: str = "material"
    strength: float | None = None

    def __post_init__(self) -> None:
        for label, value in (("E", self.E), ("nu", self.nu), ("rho", self.rho)):
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise MaterialError(f"Material {self.name!r}: {label}={value!r} is not a finite number")
        if self.E <= 0.0:
            raise MaterialError(
                f"Material {self.name!r}: Young's modulus E={self.E!r} Pa must be > 0 "
                "(give it in Pa, e.g. 1.2e9 for printed PLA)"
            )
        if self.rho <= 0.0:
            raise MaterialError(
                f"Material {self.name!r}: density rho={self.rho!r} kg/m^3 must be > 0 "
                "(give it in kg/m^3, e.g. 450.0 for printed PLA)"
            )
        if self.strength is not None and not (isinstance(self.strength, (int, float)) and self.strength > 0.0):
            raise MaterialError(
                f"Material {self.name!r}: strength={self.strength!r} Pa must be a number > 0 "
                "(give it in Pa, e.g. 53e6 for PLA), or leave it out"
            )
        if not -1.0 < self.nu < 0.5:
            raise MaterialError(
                f"Material {self.name!r}: Poisson's ratio nu={self.nu!r} must lie in (-1, 0.5); "
                "nu = 0.5 (incompressible) needs a mixed formulation that ffrf does not provide"
            )

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + nu)) (Timoshenko & Goodier, eq. 6)."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def lame_lambda(self) -> float:
        """First Lame parameter lambda = E nu / ((1 + nu)(1 - 2 nu))."""
        return self.E * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))


#: Tensile strength of PLA (Pa): 53 MPa at break, NatureWorks Ingeo 4043D technical data sheet (the 3D-printing
#: filament grade; ASTM D882 on injection-moulded bars). A part printed at 15 % infill fails at a lower stress in
#: the homogenised sense of :data:`PLA`, so a stress above it is conclusive and one below it is not.
PLA_TENSILE_STRENGTH = 53e6
PLA = Material(1.2e9, 0.33, 450.0, "PLA (printed, 15% infill)", strength=PLA_TENSILE_STRENGTH)
RIGID = Material(1e15, 0.33, 1250.0, "ideally rigid")

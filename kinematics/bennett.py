r"""The Bennett linkage: closure conditions, configuration curve and motion polynomial.

Notation of the paper (Sect. "Kinematics of Overconstrained Single-loop Linkages" and
"Recovery of Motion Polynomials"): joint axes :math:`h_0 \dots h_3` (vectorial unit dual
quaternions, :mod:`kinematics.pluecker`), DH parameters ``a_i, alpha_i`` with ``d_i = 0``.
Links are numbered as in the paper: link 0 (base) carries :math:`h_3, h_0`, link 1 carries
:math:`h_0, h_1`, link 2 (the coupler) carries :math:`h_1, h_2`, link 3 carries
:math:`h_2, h_3`; joint ``i`` turns about :math:`h_i`.

A rotation about :math:`h` is written :math:`t - h` with :math:`t \in \mathbb P^1`. Since
:math:`\cos\frac\psi2 + \sin\frac\psi2 h` is the rotation by :math:`\psi` about :math:`h`,
:math:`t - h` rotates by :math:`\psi = 2\,\mathrm{atan2}(-1, t)`, i.e. :math:`t = -\cot\frac\psi2`
(:math:`t = \infty` is the identity). The loop closes when (paper, Eq. closure_condition)

.. math:: (t_0 - h_0)(t_1 - h_1)(t_2 - h_2)(t_3 - h_3) \in \mathbb R\setminus\{0\}.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .dh import dh_axes, home_configuration, loop_closure_residual, wrap_angle
from .dual_quaternion import DualQuaternion
from .pluecker import Line, common_normal

__all__ = [
    "BENNETT_PARAMETERS",
    "BennettLinkage",
    "BennettConditionError",
    "MotionPolynomial",
    "PAPER_A",
    "PAPER_ALPHA",
    "bennett_violations",
]

#: The paper's Table "DH parameters of the 4R mechanism" (metres, radians).
PAPER_A = (0.110, 0.220, 0.110, 0.220)
PAPER_ALPHA = tuple(np.radians([150.0, 90.0, 150.0, 90.0]))
#: The DH parameters a Bennett linkage is free in; the others follow from its conditions (:class:`BennettLinkage`):
#: a2 = a0, alpha2 = alpha0, alpha3 = alpha1, a1 = a3 = a0 sin(alpha1) / sin(alpha0).
BENNETT_PARAMETERS = ("a0", "alpha0", "alpha1")


class BennettConditionError(ValueError):
    """DH parameters that violate a Bennett condition."""


def rotation_parameter(angle: ArrayLike) -> NDArray[np.float64]:
    r"""Parameter :math:`t = -\cot(\psi/2)` of the rotation ``t - h`` by ``angle`` (``inf`` at 0)."""
    half = 0.5 * wrap_angle(angle)
    with np.errstate(divide="ignore"):
        return np.where(np.sin(half) == 0.0, np.inf, -np.cos(half) / np.sin(half))


def rotation_angle(t: ArrayLike) -> NDArray[np.float64]:
    r"""Angle :math:`\psi = 2\,\mathrm{atan2}(-1, t)` of the rotation ``t - h``, in ``(-pi, pi]``."""
    return wrap_angle(2.0 * np.arctan2(-1.0, np.asarray(t, dtype=float)))


@dataclass(frozen=True)
class MotionPolynomial:
    r"""Polynomial :math:`C(t) = \sum_k c_k t^{\deg - k}` with dual quaternion coefficients.

    ``coefficients`` has shape ``(deg + 1, 8)``, highest degree first. For a motion
    polynomial, :math:`C(t)` is the pose (up to a real factor) for every real ``t``;
    :math:`t = \pm\infty` gives the leading coefficient.
    """

    coefficients: NDArray[np.float64]

    @property
    def degree(self) -> int:
        return self.coefficients.shape[0] - 1

    def __call__(self, t: ArrayLike) -> DualQuaternion:
        t = np.asarray(t, dtype=float)
        finite = np.isfinite(t)
        safe_t = np.where(finite, t, 0.0)[..., None]
        value = np.zeros(t.shape + (8,))
        for c in self.coefficients:  # Horner's scheme
            value = value * safe_t + c
        value = np.where(finite[..., None], value, self.coefficients[0])
        return DualQuaternion(value)


def _linear_polynomial(t_coefficient: float, axis: Line) -> NDArray[np.float64]:
    """Coefficients of ``k t - h`` as a degree-1 motion polynomial."""
    return np.array([[t_coefficient, 0, 0, 0, 0, 0, 0, 0], -axis.to_dual_quaternion().coeffs])


def _polynomial_product(p: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Product of polynomials with dual quaternion coefficients (non-commutative, p left)."""
    out = np.zeros((p.shape[0] + q.shape[0] - 1, 8))
    for i, pc in enumerate(p):
        for j, qc in enumerate(q):
            out[i + j] += (DualQuaternion(pc) * DualQuaternion(qc)).coeffs
    return out


@dataclass(frozen=True)
class BennettLinkage:
    """A Bennett 4R linkage from its DH lengths ``a`` (m) and twists ``alpha`` (rad), ``d = 0``.

    Raises :class:`BennettConditionError` naming the violated condition:
    ``a0 = a2``, ``a1 = a3``, ``alpha0 = alpha2``, ``alpha1 = alpha3`` and the Bennett
    condition ``a0 / sin(alpha0) = a1 / sin(alpha1)`` (paper, Tab. and Eq. after it).
    """

    a: tuple[float, float, float, float]
    alpha: tuple[float, float, float, float]
    rtol: float = 1e-9
    axes: tuple[Line, ...] = field(init=False, repr=False)
    coefficients: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self):
        a = np.asarray(self.a, dtype=float)
        alpha = np.asarray(self.alpha, dtype=float)
        if a.shape != (4,) or alpha.shape != (4,):
            raise BennettConditionError(f"a Bennett linkage needs 4 lengths and 4 twists, got {a.shape}, {alpha.shape}")
        _check_bennett_conditions(a, alpha, self.rtol)
        object.__setattr__(self, "a", tuple(a))
        object.__setattr__(self, "alpha", tuple(alpha))
        axes = tuple(dh_axes(a, alpha))
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "coefficients", _configuration_coefficients(axes))

    @classmethod
    def from_free(cls, a0: float, alpha0: float, alpha1: float) -> BennettLinkage:
        """The Bennett linkage of the free parameters :data:`BENNETT_PARAMETERS` (m, rad)."""
        a1 = a0 * np.sin(alpha1) / np.sin(alpha0)
        return cls((a0, a1, a0, a1), (alpha0, alpha1, alpha0, alpha1))

    @property
    def free(self) -> dict[str, float]:
        """Its free parameters :data:`BENNETT_PARAMETERS` by name (m, rad)."""
        return {"a0": self.a[0], "alpha0": self.alpha[0], "alpha1": self.alpha[1]}

    @classmethod
    def paper(cls) -> BennettLinkage:
        """The paper's linkage: a = (110, 220, 110, 220) mm, alpha = (150, 90, 150, 90) deg."""
        return cls(PAPER_A, PAPER_ALPHA)

    # -- configuration curve --------------------------------------------------------------
    @property
    def home_theta(self) -> NDArray[np.float64]:
        """DH joint angles of the home configuration (``t = inf``), see :func:`kinematics.dh.home_configuration`."""
        return home_configuration(4)

    def configuration(self, t: ArrayLike) -> NDArray[np.float64]:
        r"""Curve parameters :math:`(t_0, t_1, t_2, t_3) = (t, k_1 t, k_2 t, k_3 t)`, shape ``(..., 4)``.

        For the paper's table this is :math:`(t, \sqrt3 t, -t, -\sqrt3 t)`. The ratios ``k_i``
        are derived in :func:`_configuration_coefficients`.
        """
        t = np.asarray(t, dtype=float)
        with np.errstate(invalid="ignore"):
            return t[..., None] * self.coefficients

    def joint_angles(self, t: ArrayLike) -> NDArray[np.float64]:
        r"""DH joint angles :math:`\theta_i = \theta_i^{home} + 2\,\mathrm{atan2}(-1, t_i)`, ``(..., 4)``.

        The DH chain of :func:`kinematics.dh.dh_transform` closes exactly at these angles.
        """
        return wrap_angle(self.home_theta + rotation_angle(self.configuration(t)))

    def parameter_from_joint(self, theta: ArrayLike, joint: int = 3) -> NDArray[np.float64]:
        """Curve parameter ``t`` at which joint ``joint`` has the DH angle ``theta``."""
        if joint not in (0, 1, 2, 3):
            raise ValueError(f"joint must be 0, 1, 2 or 3, got {joint}")
        t_joint = rotation_parameter(np.asarray(theta, dtype=float) - self.home_theta[joint])
        return t_joint / self.coefficients[joint]

    def joint_angles_from_driver(self, theta: ArrayLike, joint: int = 3) -> NDArray[np.float64]:
        """All four DH joint angles when joint ``joint`` (default: the paper's driven joint 3) is at ``theta``."""
        return self.joint_angles(self.parameter_from_joint(theta, joint))

    # -- coupler motion -------------------------------------------------------------------
    def motion_polynomial(self) -> MotionPolynomial:
        r"""Coupler (link 2) relative to the base: :math:`C(t) = (t - h_0)(k_1 t - h_1)` (paper, Eq. motion)."""
        k1 = self.coefficients[1]
        return MotionPolynomial(
            _polynomial_product(_linear_polynomial(1.0, self.axes[0]), _linear_polynomial(k1, self.axes[1]))
        )

    def coupler_pose(self, t: ArrayLike) -> DualQuaternion:
        """Unit dual quaternion of the coupler's displacement from home at curve parameter ``t``."""
        return self.motion_polynomial()(t).normalized()

    def link_poses(self, t: ArrayLike) -> list[DualQuaternion]:
        r"""Displacements from home of links 0..3 (paper's numbering) at curve parameter ``t``.

        In product-of-exponentials form: link 0 (base) does not move, link 1 turns about
        :math:`h_0` by :math:`t_0 - h_0`, link 2 (coupler) moves by
        :math:`(t_0 - h_0)(t_1 - h_1)`, and link 3 turns about :math:`h_3`. From the closure
        :math:`(t_0-h_0)(t_1-h_1) \propto ((t_2-h_2)(t_3-h_3))^{-1}` and
        :math:`(t - h)^{-1} \propto t + h` (since :math:`h^2 = -1`), link 3 moves by
        :math:`t_3 + h_3`, which is :math:`-((-t_3) - h_3)`.
        """
        t = np.asarray(t, dtype=float)
        ts = self.configuration(t)
        one = DualQuaternion(np.broadcast_to(np.eye(8)[0], t.shape + (8,)))

        def factor(parameter, axis: Line, sign: float) -> DualQuaternion:
            """``parameter + sign * h``, or the identity where ``parameter`` is infinite."""
            finite = np.isfinite(parameter)
            linear = (
                np.where(finite, parameter, 0.0)[..., None] * np.eye(8)[0] + sign * axis.to_dual_quaternion().coeffs
            )
            return DualQuaternion(np.where(finite[..., None], linear, np.eye(8)[0]))

        link1 = factor(ts[..., 0], self.axes[0], -1.0)
        link2 = link1 * factor(ts[..., 1], self.axes[1], -1.0)
        link3 = factor(ts[..., 3], self.axes[3], +1.0)
        return [one, link1.normalized(), link2.normalized(), link3.normalized()]

    def coupler_point(self) -> NDArray[np.float64]:
        r"""Midpoint of the common normal of :math:`h_1` and :math:`h_2` (on the coupler), home configuration."""
        normal = common_normal(self.axes[1], self.axes[2])
        return 0.5 * (normal.foot0 + normal.foot1)

    def coupler_path(self, point: ArrayLike | None = None, n: int = 360, joint: int = 3) -> NDArray[np.float64]:
        """Path ``(n, 3)`` of a coupler point (world coordinates at home; default :meth:`coupler_point`)
        over one revolution of joint ``joint``, sampled at equal steps of its angle from home."""
        point = self.coupler_point() if point is None else np.asarray(point, dtype=float)
        angles = self.home_theta[joint] + np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
        return self.coupler_pose(self.parameter_from_joint(angles, joint)).act(point)

    def closure_residual(self, t: ArrayLike):
        """Loop-closure residual (translation m, rotation rad) at curve parameters ``t``."""
        return loop_closure_residual(self.a, self.alpha, None, self.joint_angles(t))


def bennett_violations(a: NDArray, alpha: NDArray, rtol: float = 1e-9) -> tuple[str, ...]:
    """Every Bennett condition (docs/formulation.md, Bennett linkage) that the lengths ``a`` (m) and twists
    ``alpha`` (rad) of a 4R with zero offsets violate, each named with its numbers; empty for a Bennett linkage."""
    a, alpha = np.asarray(a, dtype=float), np.asarray(alpha, dtype=float)
    scale = float(np.max(np.abs(a)))
    if scale == 0.0 or np.any(a <= 0.0):
        return (f"lengths a_i > 0 (got {a})",)
    violations = []
    for i, j in ((0, 2), (1, 3)):
        if abs(a[i] - a[j]) > rtol * scale:
            violations.append(f"opposite sides a{i} = a{j} ({1e3 * a[i]:.6g} mm vs {1e3 * a[j]:.6g} mm)")
    for i, j in ((0, 2), (1, 3)):
        if abs(wrap_angle(alpha[i] - alpha[j])) > rtol:
            twists = f"{np.degrees(alpha[i]):.9g} deg vs {np.degrees(alpha[j]):.9g} deg"
            violations.append(f"opposite twists alpha{i} = alpha{j} ({twists})")
    s0, s1 = np.sin(alpha[0]), np.sin(alpha[1])
    if abs(s0) < rtol or abs(s1) < rtol:
        violations.append("twists other than 0 and pi (those make a planar or degenerate loop)")
    elif abs(a[0] * s1 - a[1] * s0) > rtol * scale:
        violations.append(f"a0/sin(alpha0) = a1/sin(alpha1) ({1e3 * a[0] / s0:.9g} mm vs {1e3 * a[1] / s1:.9g} mm)")
    if abs(np.sin(0.5 * (alpha[1] - alpha[0]))) < rtol:
        violations.append("alpha0 != alpha1 (alpha0 = alpha1 with a0 = a1 is the degenerate, folding case)")
    return tuple(violations)


def _check_bennett_conditions(a: NDArray, alpha: NDArray, rtol: float) -> None:
    violations = bennett_violations(a, alpha, rtol)
    if violations:
        raise BennettConditionError(
            "not a Bennett linkage, violated: " + "; ".join(violations) + " (a misaligned loop is not a Bennett "
            "linkage; use kinematics.rigid_mobility to see how far it is from closing)"
        )


def _configuration_coefficients(axes: tuple[Line, ...]) -> NDArray[np.float64]:
    r"""Ratios ``k_i`` of the configuration curve :math:`t_i = k_i t` (``k_0 = 1``).

    Derivation. Put :math:`t_i = k_i t` into the closure product. Its :math:`t^3`
    coefficient is :math:`-(k_1k_2k_3 h_0 + k_2k_3 h_1 + k_1k_3 h_2 + k_1k_2 h_3)`, which
    is vectorial and must vanish. Dividing by :math:`k_1k_2k_3`:

    .. math:: h_0 + c_1 h_1 + c_2 h_2 + c_3 h_3 = 0, \qquad c_i = 1/k_i,

    six linear equations for three unknowns: they are solvable exactly because the four
    axes of a Bennett linkage are linearly dependent (they lie in one regulus). We solve
    them by least squares, check the residual, and then check that *every* coefficient
    of the closure polynomial is real (so the ansatz is a solution, not just its
    leading terms). For the paper's axes, :math:`c = (1/\sqrt3, -1, -1/\sqrt3)`.
    The result agrees with Bennett's classical relation
    :math:`k_1 = -\sin\frac{\alpha_1+\alpha_0}{2} / \sin\frac{\alpha_1-\alpha_0}{2}`
    (checked in the tests).
    """
    vectors = np.array([line.to_dual_quaternion().coeffs[[1, 2, 3, 5, 6, 7]] for line in axes])
    scale = max(1.0, float(np.max(np.abs(vectors))))
    c, *_ = np.linalg.lstsq(vectors[1:].T, -vectors[0], rcond=None)
    residual = vectors[0] + vectors[1:].T @ c
    if np.max(np.abs(residual)) > 1e-9 * scale or np.any(np.abs(c) < 1e-12):
        raise BennettConditionError(
            f"the axes are not linearly dependent (residual {np.max(np.abs(residual)):.2e}): not a Bennett linkage"
        )
    k = np.concatenate([[1.0], 1.0 / c])
    closure = np.array([[1.0, 0, 0, 0, 0, 0, 0, 0]])
    for k_i, axis in zip(k, axes, strict=True):
        closure = _polynomial_product(closure, _linear_polynomial(k_i, axis))
    imaginary = closure[:, 1:]
    if np.max(np.abs(imaginary)) > 1e-9 * scale * np.max(np.abs(closure)):
        raise BennettConditionError("the linear configuration curve does not close this loop")
    return k

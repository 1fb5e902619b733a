"""Exact kinematics of single-loop linkages: dual quaternions, Pluecker lines, DH, Bennett, any nR loop.

Conventions (stated once, tested in ``tests/kinematics``): SI units (metres, radians);
quaternions scalar first; active rotations; dual quaternion products compose like 4x4
matrices (the right factor acts first); the paper's DH convention
``r_x(alpha_{i-1}) t_x(a_{i-1}) t_z(d_i) r_z(theta_i)``; Pluecker moment ``m = p x l``
and the paper's line embedding ``l - eps m``.
"""

from .assemblies import Assembly, NearbyAssemblies, nearby_assemblies, solve_closure
from .bennett import (
    BENNETT_PARAMETERS,
    PAPER_A,
    PAPER_ALPHA,
    BennettConditionError,
    BennettLinkage,
    MotionPolynomial,
)
from .dh import (
    ClosureResidual,
    DHParameters,
    LoopClosureError,
    dh_axes,
    dh_from_axes,
    dh_matrix,
    dh_transform,
    home_configuration,
    loop_closure_residual,
    open_loop_axes,
    wrap_angle,
)
from .dual_quaternion import DualQuaternion
from .mobility import LoopMobility, MobilityReport, explain_mobility, rigid_mobility
from .pluecker import CommonNormal, Line, angle, common_normal, distance
from .single_loop import (
    LoopFoldError,
    LoopMotion,
    RateProfile,
    SingleLoop,
    close_near,
    follow_driver,
    joint_rates,
    motion_tangents,
    point_paths,
    rate_profile,
    trace_motion,
)

__all__ = [
    "BENNETT_PARAMETERS",
    "PAPER_A",
    "PAPER_ALPHA",
    "Assembly",
    "BennettConditionError",
    "BennettLinkage",
    "ClosureResidual",
    "CommonNormal",
    "DHParameters",
    "DualQuaternion",
    "Line",
    "LoopClosureError",
    "LoopFoldError",
    "LoopMobility",
    "LoopMotion",
    "MobilityReport",
    "MotionPolynomial",
    "NearbyAssemblies",
    "SingleLoop",
    "angle",
    "close_near",
    "common_normal",
    "dh_axes",
    "dh_from_axes",
    "dh_matrix",
    "dh_transform",
    "follow_driver",
    "joint_rates",
    "rate_profile",
    "RateProfile",
    "distance",
    "explain_mobility",
    "home_configuration",
    "loop_closure_residual",
    "motion_tangents",
    "nearby_assemblies",
    "open_loop_axes",
    "point_paths",
    "rigid_mobility",
    "solve_closure",
    "trace_motion",
    "wrap_angle",
]

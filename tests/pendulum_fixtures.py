"""A bar pendulum hinged about the y-axis at its x = 0 end face, for integrator tests."""

import numpy as np
from body_fixtures import bar_model

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.system.constraints import GroundPerpendicular, GroundPoint
from ffrf.system.multibody import MultibodySystem


def pendulum(n_modes: int = 3, E: float = 1e8, rho: float = 450.0, beta: float = 0.0):
    """Cantilever (clamped-interface) modes of the bar, hinged at the centre of its x = 0 face.

    Returns the system and the body-frame hinge point; gravity is -z, the hinge axis is y,
    so the bar swings in the x-z plane starting horizontal.
    """
    model = bar_model(E=E, rho=rho)
    nodes = model.nodes
    hinge_nodes = np.flatnonzero(nodes[:, 0] < 1e-9)
    hinge = nodes[hinge_nodes].mean(axis=0)
    if n_modes:
        basis = craig_bampton(model, [hinge_nodes], n_modes)
        psi, k_red = basis.basis, basis.reduced_stiffness
    else:
        psi, k_red = np.zeros((3 * nodes.shape[0], 0)), np.zeros((0, 0))
    body = FlexibleBody("bar", modal_moments(nodes, model.mass, psi), k_red, beta * k_red)
    joint = (
        GroundPoint((0,), "hinge", local=hinge, target=hinge),
        GroundPerpendicular(
            (0,), "hinge axis", vector=np.array([0.0, 1.0, 0.0]), normals=np.array([[1.0, 0, 0], [0, 0, 1.0]])
        ),
    )
    system = MultibodySystem((body,), joint, gravity=np.array([0.0, 0.0, -9.81]))
    return system, model, psi, hinge


def tip_position(q, model, psi):
    """World position of the node at the far end (x = 0.2, y = 0, z = 0)."""
    from ffrf.body.euler_parameters import rotation_matrix

    i = int(np.argmin(np.linalg.norm(model.nodes - [0.2, 0.0, 0.0], axis=1)))
    u = model.nodes[i] + psi[3 * i : 3 * i + 3] @ q[7:]
    return q[:3] + rotation_matrix(q[3:7]) @ u

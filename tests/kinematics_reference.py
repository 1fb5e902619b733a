"""Independent reference constructions used only by the tests (plain 4x4 matrices)."""

from typing import NamedTuple

import numpy as np


def rot_x(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def trans(x=0.0, y=0.0, z=0.0):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def dh_step(a, alpha, d, theta):
    """Lynch and Park, Modern Robotics, App. C: Rot(x, alpha) Trans(x, a) Trans(z, d) Rot(z, theta)."""
    return rot_x(alpha) @ trans(x=a) @ trans(z=d) @ rot_z(theta)


def random_bennett(rng):
    """Random Bennett parameters: a0 > 0, twists of either sign away from 0 and pi, a1 from the Bennett condition."""
    while True:
        alpha0, alpha1 = rng.uniform(-np.pi, np.pi, 2)
        s0, s1 = np.sin(alpha0), np.sin(alpha1)
        if min(abs(s0), abs(s1)) > 0.05 and s0 * s1 > 0 and abs(np.sin(0.5 * (alpha1 - alpha0))) > 0.05:
            a0 = rng.uniform(0.02, 0.5)
            a1 = a0 * s1 / s0
            return (a0, a1, a0, a1), (alpha0, alpha1, alpha0, alpha1)


def random_rigid_displacement(rng):
    """A random rotation matrix and translation (via QR of a Gaussian matrix)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q, rng.normal(size=3)


def bennett_dh_angles(alpha0: float, alpha1: float, theta0: float) -> np.ndarray:
    r"""DH joint angles closing a Bennett linkage (twists ``alpha0, alpha1, alpha0, alpha1``) at ``theta0``.

    Bennett's classical relation between neighbouring joint angles (Bennett 1914, "The skew isogram
    mechanism", Proc. London Math. Soc. 13, 151-173) in the convention of :func:`dh_step`, whose
    folded home is ``(0, pi, 0, pi)``:

    .. math:: \tan\frac{\theta_0}{2}\tan\frac{\theta_1}{2}
              = \sin\frac{\alpha_1+\alpha_0}{2} \Big/ \sin\frac{\alpha_1-\alpha_0}{2},
              \qquad \theta_2 = -\theta_0, \quad \theta_3 = -\theta_1 .

    :func:`goldberg_5r` checks that the chain closes at these angles.
    """
    ratio = np.sin(0.5 * (alpha1 + alpha0)) / np.sin(0.5 * (alpha1 - alpha0))
    theta1 = 2.0 * np.arctan2(ratio * np.cos(0.5 * theta0), np.sin(0.5 * theta0))
    return np.array([theta0, theta1, -theta0, -theta1])


class Goldberg5R(NamedTuple):
    """A Goldberg 5R (:func:`goldberg_5r`) and the two Bennett linkages it is made of.

    ``points``/``directions`` (5, 3): the 5R's axes ``H0..H4 = (h1, h2, h3, g2, g1)`` at home;
    ``bennett_1``/``bennett_2``: ``(a, alpha)`` of the Bennett linkages (4-tuples, paper's numbering,
    common base link ``(h3, h0)``); ``theta_1``/``theta_2``: their DH joint angles at the 5R's home;
    ``dh``: the Goldberg DH table ``(a, alpha)`` the construction should yield (``d = 0``).
    """

    points: np.ndarray
    directions: np.ndarray
    bennett_1: tuple[tuple[float, ...], tuple[float, ...]]
    bennett_2: tuple[tuple[float, ...], tuple[float, ...]]
    theta_1: np.ndarray
    theta_2: np.ndarray
    dh: tuple[np.ndarray, np.ndarray]


def goldberg_5r(a: float, alpha: float, beta: float, gamma: float, theta0: float) -> Goldberg5R:
    r"""Goldberg's 5R from two Bennett linkages with a common link (plain 4x4 matrices, :func:`dh_step`).

    Construction of Goldberg (1943, "New five-bar and six-bar linkages in three dimensions",
    Trans. ASME 65, 649-661; reviewed by Baker 1979, "The Bennett, Goldberg and Myard linkages -
    in perspective", Mech. Mach. Theory 14, 239-253): two Bennett linkages

    - I:  ``h0 -(b, beta)- h1 -(a, alpha)- h2 -(b, beta)- h3 -(a, alpha)- h0``,
    - II: ``h0 -(c, gamma)- g1 -(a, alpha)- g2 -(c, gamma)- h3 -(a, alpha)- h0``,

    with ``a / sin(alpha) = b / sin(beta) = c / sin(gamma)`` (Bennett's condition for each),
    share their link ``(h3, h0)``. The links of I and II that turn on ``h0`` are welded together
    with their common normals on one line, on opposite sides of ``h0`` (II's joint at ``h0`` half
    a turn from I's), and the common link is removed: a loop of five revolute joints
    ``h1, h2, h3, g2, g1``. The welded link spans ``g1 -> h1`` along that line, so the 5R's DH
    table, which follows from the construction (the tests check it), is Goldberg's

    .. math:: a = (a, b, c, a, b + c), \quad \alpha = (\alpha, \beta, \gamma, \alpha, \beta + \gamma),
              \quad d = 0 .

    ``theta0``: I's DH angle at ``h0`` in the home pose (``0`` folds both loops flat).
    """
    b = a * np.sin(beta) / np.sin(alpha)
    c = a * np.sin(gamma) / np.sin(alpha)
    frames = []
    thetas = []
    for length, twist, start in ((b, beta, theta0), (c, gamma, theta0 + np.pi)):
        theta = bennett_dh_angles(twist, alpha, start)
        lengths, twists = (length, a, length, a), (twist, alpha, twist, alpha)
        # World frame: z on h0, x along the common link's normal (h3 -> h0), the same for I and II; frame 0 (x
        # towards h1 or g1) is turned from it by theta_0 about h0.
        chain = [rot_z(theta[0])]
        for i in range(1, 4):
            chain.append(chain[-1] @ dh_step(lengths[i - 1], twists[i - 1], 0.0, theta[i]))
        closing = chain[3] @ dh_step(lengths[3], twists[3], 0.0, theta[0])
        if np.max(np.abs(closing - chain[0])) > 1e-12:
            raise ValueError(f"Bennett chain does not close: {np.max(np.abs(closing - chain[0])):.3e}")
        frames.append(chain)
        thetas.append(theta)
    one, two = frames
    if np.max(np.abs(one[3][:3, 2:] - two[3][:3, 2:])) > 1e-12:
        raise ValueError("the two Bennett linkages do not share the axis h3")
    axes = [one[1], one[2], one[3], two[2], two[1]]  # h1, h2, h3, g2, g1
    return Goldberg5R(
        points=np.array([f[:3, 3] for f in axes]),
        directions=np.array([f[:3, 2] for f in axes]),
        bennett_1=((b, a, b, a), (beta, alpha, beta, alpha)),
        bennett_2=((c, a, c, a), (gamma, alpha, gamma, alpha)),
        theta_1=thetas[0],
        theta_2=thetas[1],
        dh=(np.array([a, b, c, a, b + c]), np.array([alpha, beta, gamma, alpha, beta + gamma])),
    )

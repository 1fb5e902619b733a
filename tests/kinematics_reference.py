"""Independent reference constructions used only by the tests (plain 4x4 matrices)."""

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

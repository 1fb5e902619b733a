"""Finite-element models of one link: materials, mass and stiffness (scikit-fem), interfaces, modes."""

"""Shared fixtures. Random numbers are always seeded.

This folder is on ``sys.path`` during tests, so the shared reference modules next to this file
(``kinematics_reference``, ``body_fixtures``, ``pendulum_fixtures``) import from any test folder."""

import numpy as np
import pytest


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)

"""Shared fixtures. Random numbers are always seeded.

This folder is on ``sys.path`` during tests, so the shared reference modules next to this file
(``kinematics_reference``, ``body_fixtures``, ``pendulum_fixtures``) import from any test folder."""

import os

import numpy as np
import pytest

# No test reads or writes the user's disk cache of built scenes (ffrf.scenes.scene_cache): a result must not depend
# on an earlier run's files; the tests of the disk cache give it a folder of their own. Set before ffrf is imported,
# and inherited by the CLI runs the tests start.
os.environ["FFRF_CACHE_DIR"] = "off"


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)

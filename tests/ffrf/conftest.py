"""Keep the ffrf default run fast: ``@pytest.mark.slow`` studies run only when selected
explicitly with ``-m slow`` (or any ``-m`` expression that mentions ``slow``).
Only items of this directory are touched."""

from __future__ import annotations

from pathlib import Path

import pytest

_HERE = Path(__file__).parent


def pytest_collection_modifyitems(config, items):
    if "slow" in (config.getoption("markexpr") or ""):
        return
    skip_slow = pytest.mark.skip(reason="slow study: run with -m slow")
    for item in items:
        if "slow" in item.keywords and _HERE in Path(str(item.fspath)).parents:
            item.add_marker(skip_slow)

"""Dask's nanny starts workers with ``MALLOC_TRIM_THRESHOLD_=65536``, which pins glibc's mmap threshold at 128 KiB:
every larger array is mapped afresh and page-faulted in again (``ffrf.studies.runner._allocator_for_variants``).
The runner's local cluster starts its workers without it, and a worker that has it gets glibc's thresholds set.

Truth is counted, not timed: the minor page faults of allocating and filling 2 MiB arrays, which a mapped array
takes once per page (512 per array) and a reused heap block not at all."""

import os
import platform
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from ffrf.studies.runner import TRIM_VARIABLE, _client

ROOT = Path(__file__).resolve().parents[2]

FAULTS = textwrap.dedent(
    """
    import resource
    import numpy as np
    from ffrf.studies.runner import _allocator_for_variants

    def faults():
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        for _ in range(50):
            block = np.ones(2**18)  # 2 MiB, every page written
            del block
        return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before

    faults()
    pinned = faults()
    _allocator_for_variants()
    faults()
    print(pinned, faults())
    """
)


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="glibc's allocator only")
def test_a_worker_with_the_nannys_trim_threshold_stops_faulting_its_arrays_in_again():
    env = dict(os.environ, **{TRIM_VARIABLE: "65536", "PYTHONPATH": str(ROOT)})
    out = subprocess.run([sys.executable, "-c", FAULTS], env=env, capture_output=True, text=True, check=True)
    pinned, tuned = (int(x) for x in out.stdout.split())
    assert pinned >= 50 * 512 * 0.9  # every array mapped and faulted in page by page
    assert tuned < 0.05 * pinned  # the freed block is reused: no faults


def test_the_runners_local_workers_start_without_the_trim_threshold(monkeypatch):
    monkeypatch.delenv(TRIM_VARIABLE, raising=False)
    client, cluster = _client(None, 1)
    try:
        assert client.run(os.environ.get, TRIM_VARIABLE) == {w: None for w in client.scheduler_info()["workers"]}
    finally:
        client.close()
        cluster.close()
    assert TRIM_VARIABLE not in os.environ  # nor did its nanny set it in this process

"""Memory probes the benchmarks share (issue #22): a process's resident high-water mark, reset per measured part
or tracked per stage; a child process's peak; and numba's count of its runtime allocations.

* :func:`memory_start` / :func:`memory_stop`: the rise of ``VmHWM`` (``/proc/self/status``) over the resident set
  at the start of a part, after returning freed heap to the system (``malloc_trim``) and resetting the mark
  (``/proc/self/clear_refs``).
* :class:`StagePeaks`: the same mark per stage, the stages being functions wrapped in place (nested stages
  each get their own peak, the enclosing ones keep theirs).
* :func:`run_child`: a command in a new process and its peak resident set (``ru_maxrss`` of ``wait4``: the child
  and the processes it waited for; Linux takes it from the same mark, so a child that resets ``VmHWM`` reports only
  the peak since its last reset).
* :func:`nrt_counts`: numba's runtime (NRT) counts of allocations and frees, i.e. every array made inside a
  jitted function (``np.empty``, ``np.zeros``, ``copy()``, array expressions); counting switched on on first use.
"""

from __future__ import annotations

import ctypes
import functools
import importlib
import os
import subprocess
import time
from collections.abc import Callable, Sequence
from pathlib import Path

#: (module, function, stage): the functions whose calls make the stages of a scene's set-up (``bench/setup_speed.py``
#: times them, ``bench/memory.py`` takes their memory peaks).
SETUP_STAGES = (
    ("ffrf.scenes.builder", "_mesh", "gmsh_mesh"),
    ("ffrf.fe.fe_model", "_assemble", "fe_assembly"),
    ("ffrf.scenes.builder", "craig_bampton", "craig_bampton"),
    ("ffrf.reduction.craig_bampton", "factorize_spd", "factorize_k_ii"),
    ("ffrf.numerics.eigen", "shift_invert_eigsh", "lanczos"),
    ("ffrf.numerics.eigen", "count_eigenvalues_below", "sturm_count"),
    ("ffrf.scenes.builder", "modal_moments", "modal_moments"),
    ("ffrf.scenes.linkage_scene", "start_pose", "rigid_start_pose"),
    ("ffrf.scenes.linkage_scene", "_check_drive_range", "rigid_drive_range"),
)

MIB = 1024.0


def status_mb(field: str) -> float:
    """``field`` (``VmRSS``, ``VmHWM``, ...) of ``/proc/self/status`` in MiB (NaN where there is none)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return float(line.split()[1]) / MIB
    return float("nan")


def reset_peak() -> float:
    """Return freed heap to the system and reset ``VmHWM`` to the current resident set; returns that (MiB)."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except OSError:  # not glibc: the rise is then measured over a possibly inflated start
        pass
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        pass
    return status_mb("VmRSS")


def memory_start() -> float:
    """Start measuring a part: :func:`reset_peak`; returns the resident set it starts from (MiB)."""
    return reset_peak()


def memory_stop(start_mb: float) -> dict:
    """The part's ``peak_mem_mb`` (rise of ``VmHWM`` over ``start_mb``) and ``peak_rss_mb`` (``VmHWM``)."""
    peak = status_mb("VmHWM")
    return {"peak_mem_mb": peak - start_mb, "peak_rss_mb": peak}


class StagePeaks:
    """Peak resident set (``VmHWM``, MiB) per stage, the stages being functions wrapped in place.

    Every entry to and exit from a wrapped function reads ``VmHWM``, folds it into the running peak of each
    stage under way (and of the whole process), and resets the mark; so each stage gets the peak reached while it
    ran, nested stages included. ``stages[name]``: ``calls``, ``seconds``, ``peak_rss_mb``, ``start_rss_mb`` (at
    its first call) and ``rise_mb`` (its largest rise over the resident set at a call's start)."""

    def __init__(self) -> None:
        self.stages: dict[str, dict] = {}
        self.peak_rss_mb = reset_peak()
        self._open: list[dict] = []

    def _fold(self) -> float:
        peak = status_mb("VmHWM")
        self.peak_rss_mb = max(self.peak_rss_mb, peak)
        for frame in self._open:
            frame["peak"] = max(frame["peak"], peak)
        return reset_peak()

    def wrap(self, module_name: str, name: str, stage: str) -> None:
        """Replace ``module_name.name`` by a wrapper measuring it as ``stage``."""
        module = importlib.import_module(module_name)
        function = getattr(module, name)

        @functools.wraps(function)
        def measured(*args, **kwargs):
            start = self._fold()
            frame = {"peak": start}
            self._open.append(frame)
            started = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                seconds = time.perf_counter() - started
                self._fold()
                del self._open[next(i for i, f in enumerate(self._open) if f is frame)]
                entry = self.stages.setdefault(
                    stage, {"calls": 0, "seconds": 0.0, "peak_rss_mb": 0.0, "start_rss_mb": start, "rise_mb": 0.0}
                )
                entry["calls"] += 1
                entry["seconds"] += seconds
                entry["peak_rss_mb"] = max(entry["peak_rss_mb"], frame["peak"])
                entry["rise_mb"] = max(entry["rise_mb"], frame["peak"] - start)

        setattr(module, name, measured)

    def report(self) -> dict:
        """``{"peak_rss_mb": whole process, "stages": {...}}`` as of now."""
        self._fold()
        return {"peak_rss_mb": self.peak_rss_mb, "stages": self.stages}


def run_child(command: Sequence[str], env: dict | None = None, cwd: Path | None = None, log: Path | None = None):
    """Run ``command`` in a new process; returns ``(exit code, peak resident set in MiB, wall seconds)``.
    Output goes to ``log`` (or is dropped)."""
    started = time.perf_counter()
    with open(log if log is not None else os.devnull, "w") as sink:
        child = subprocess.Popen(command, env=env, cwd=cwd, stdout=sink, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)  # reaped here, so that Popen does not wait again
    return child.returncode, usage.ru_maxrss / MIB, time.perf_counter() - started


def nrt_counts() -> tuple[int, int]:
    """numba's runtime ``(allocations, frees)`` so far (counting switched on at the first call: earlier ones are
    not counted)."""
    from numba.core.runtime import rtsys

    _nrt_python = importlib.import_module("numba.core.runtime._nrt_python")  # the switch numba's config flips
    if not _nrt_python.memsys_stats_enabled():
        _nrt_python.memsys_enable_stats()
    stats = rtsys.get_allocation_stats()
    return stats.alloc, stats.free


def stop_counting() -> None:
    """Switch numba's runtime counts off again (counting adds an atomic increment to every allocation and free)."""
    importlib.import_module("numba.core.runtime._nrt_python").memsys_disable_stats()


def count_allocations(call: Callable[[], object], repeats: int = 1) -> float:
    """NRT allocations per call of ``call()`` (the result dropped at once), averaged over ``repeats``."""
    before, _ = nrt_counts()
    for _ in range(repeats):
        call()
    return (nrt_counts()[0] - before) / repeats

"""Progress and a time limit for the runs of a cross-validation (issue #39).

A :class:`RunClock` follows one run, ours or Exudyn's: a line on stderr each time the run passes another tenth of
its simulated time (or half a minute after the last line), with the wall time so far and the time left at the
rate so far; runs shorter than a few seconds stay quiet. Given a deadline, Exudyn's run stops once the deadline has
passed: its pre-step user function returns ``False``, Exudyn finishes the step it is on and ``SolveSystem`` returns
as a success at the time reached. The cross-validation then compares the outputs both runs have and says why the
rest is missing.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from typing import TextIO

__all__ = ["PROGRESS_FRACTION", "PROGRESS_SECONDS", "QUIET_SECONDS", "RunClock", "compiled_kernels"]

#: A progress line each time the run passes another this fraction of its simulated time ...
PROGRESS_FRACTION = 0.1
#: ... or this many wall seconds after the previous line ...
PROGRESS_SECONDS = 30.0
#: ... once the run has taken this many wall seconds.
QUIET_SECONDS = 5.0


@dataclass
class RunClock:
    """One run's progress (``label``: which run) towards ``t_end`` (s of simulated or quasi-time) and its
    ``deadline`` (a :func:`time.monotonic` value, or ``None``: no limit); ``stream=None`` keeps quiet, and so does
    the run's first ``quiet_s``."""

    label: str
    t_end: float
    deadline: float | None = None
    stream: TextIO | None = field(default_factory=lambda: sys.stderr)
    quiet_s: float = QUIET_SECONDS
    started: float = field(default_factory=time.monotonic)
    reached: float = 0.0
    stopped: bool = False
    _shown_fraction: float = 0.0
    _shown_at: float = field(default_factory=time.monotonic)

    def left_s(self, now: float) -> float | None:
        """Wall seconds left at the rate so far (``None`` before the run has moved)."""
        fraction = self.reached / self.t_end if self.t_end > 0 else 1.0
        if fraction <= 0.0:
            return None
        return (now - self.started) * (1.0 - fraction) / fraction

    def tick(self, t: float) -> bool:
        """The run is at ``t``: show progress when due; ``False`` once the deadline has passed (the run should stop)."""
        now = time.monotonic()
        self.reached = max(self.reached, float(t))
        fraction = min(self.reached / self.t_end, 1.0) if self.t_end > 0 else 1.0
        due = fraction >= self._shown_fraction + PROGRESS_FRACTION or now - self._shown_at >= PROGRESS_SECONDS
        if self.stream is not None and due and now - self.started >= self.quiet_s:
            self._shown_fraction, self._shown_at = fraction, now
            left = self.left_s(now)
            estimate = "" if left is None else f", about {left:.0f} s left"
            print(
                f"  {self.label}: {100 * fraction:3.0f} % (t = {self.reached:.4g} of {self.t_end:.4g} s) after "
                f"{now - self.started:.0f} s{estimate}",
                file=self.stream,
                flush=True,
            )
        if self.deadline is not None and now > self.deadline:
            self.stopped = True
            return False
        return True

    def progress(self, t: float, t_end: float) -> None:
        """Our solvers' ``progress(t, t_end)`` callback (shows progress only: our runs are not stopped)."""
        self.t_end = float(t_end)
        self.tick(t)

    def exudyn_pre_step(self, mbs: object, t: float) -> bool:
        """Exudyn's pre-step user function (``mbs.SetPreStepUserFunction``): ``False`` stops the run."""
        return self.tick(t)


#: Whether this process has compiled or loaded our kernels already (numba keeps them for the process's life).
_KERNELS_READY = False


def compiled_kernels(stream: TextIO | None = sys.stderr) -> float:
    """Compile our solver's kernels, or load them from numba's cache, before any run is timed
    (:func:`ffrf.scenes.kernel_warmup.warm_kernels`, the dynamic ones included): the report's times are then the
    runs', not the compiler's (issue #38). Returns the wall seconds it took, which the report states apart (0 when
    this process had them already: a summary's second variant, a test session's later reports)."""
    global _KERNELS_READY
    if _KERNELS_READY:
        return 0.0
    from ffrf.scenes.kernel_warmup import warm_kernels

    started = time.monotonic()
    warm_kernels(dynamic=True)
    seconds = time.monotonic() - started
    _KERNELS_READY = True
    if stream is not None:
        print(f"  our kernels compiled or loaded in {seconds:.1f} s (not in the runs' times)", file=stream, flush=True)
    return seconds

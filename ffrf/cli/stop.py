"""Stopping a command cleanly: SIGINT (Ctrl-C) and SIGTERM noted during a run stop it at its next step
(:class:`StopRequest`, one per process: :data:`STOP`), and the progress bar that checks for them."""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from ffrf.errors import Interrupted

__all__ = ["StopRequest", "STOP", "progress_printer"]


class StopRequest:
    """SIGINT (Ctrl-C) and SIGTERM during a command. Inside :meth:`deferred` (a run, the writing of its results) the
    first one is noted and the run stops at its next step (the progress callback, :meth:`check`, raises
    :class:`Interrupted`, and the solver hands over what it computed: issue #32); elsewhere, or a second time, it raises
    :class:`Interrupted` at once. :func:`main` prints one line and exits with 130 (128 + SIGINT, as shells do)."""

    def __init__(self) -> None:
        self.signal: str | None = None
        self.deferring = False

    def handle(self, number: int, frame: object) -> None:
        name = signal.Signals(number).name
        if self.signal is None and self.deferring:
            self.signal = name
            return
        raise Interrupted(f"interrupted by {name}")

    def check(self, where: str = "") -> None:
        """Raise :class:`Interrupted` if a stop was asked for (``where``: what the message adds)."""
        if self.signal is not None:
            raise Interrupted(f"interrupted by {self.signal}{where}")

    @contextmanager
    def deferred(self) -> Iterator[None]:
        before, self.deferring = self.deferring, True
        try:
            yield
        finally:
            self.deferring = before

    @contextmanager
    def installed(self) -> Iterator[None]:
        """The handlers of SIGINT and SIGTERM for one command (main thread only: Python allows no other)."""
        self.signal, self.deferring = None, False
        if threading.current_thread() is not threading.main_thread():
            yield
            return
        before = {number: signal.signal(number, self.handle) for number in (signal.SIGINT, signal.SIGTERM)}
        try:
            yield
        finally:
            for number, handler in before.items():
                signal.signal(number, handler)


STOP = StopRequest()


def progress_printer() -> Callable[[float, float], None]:
    """A progress bar on stderr (percent of the run and its time), which also stops the run at a noted signal."""
    last = [-1]

    def show(t: float, t_end: float) -> None:
        try:
            STOP.check()  # a Ctrl-C noted during the run stops it here, between two steps
        except Interrupted:
            print(file=sys.stderr)  # end the progress bar's line
            raise
        percent = int(100 * t / t_end) if t_end > 0 else 100
        if percent != last[0]:
            last[0] = percent
            bar = "#" * (percent // 4)
            print(f"\r  [{bar:<25}] {percent:3d} %  t = {t:7.2f} s", end="", file=sys.stderr, flush=True)
            if percent >= 100:
                print(file=sys.stderr)

    return show

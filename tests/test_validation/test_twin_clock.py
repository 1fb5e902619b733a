"""Progress lines and the deadline of a cross-validation's runs (:class:`validation.twin_clock.RunClock`)."""

import io
import time

from validation.twin_clock import RunClock


def test_a_line_each_tenth_of_the_run_with_the_time_left_at_the_rate_so_far():
    out = io.StringIO()
    clock = RunClock("Exudyn", 20.0, stream=out, quiet_s=0.0)
    clock.started = time.monotonic() - 10.0  # ten seconds into the run
    for t in (1.0, 2.4, 3.0, 5.0, 18.0):
        assert clock.tick(t)
    lines = out.getvalue().splitlines()
    assert [line.split("%")[0].split(":")[1].strip() for line in lines] == ["12", "25", "90"]
    # a quarter done after 10 s: 30 s left at that rate; nine tenths: about 1 s
    assert "about 30 s left" in lines[1] and "about 1 s left" in lines[2]
    assert "t = 5 of 20 s" in lines[1]


def test_quiet_while_the_run_is_short():
    out = io.StringIO()
    clock = RunClock("ours", 1.0, stream=out)  # the default quiet start
    for t in (0.2, 0.5, 1.0):
        clock.tick(t)
    assert out.getvalue() == ""


def test_the_deadline_stops_the_run_at_its_next_step():
    clock = RunClock("Exudyn", 1.0, deadline=time.monotonic() + 3600.0, stream=None)
    assert clock.exudyn_pre_step(None, 0.5) and not clock.stopped
    clock.deadline = time.monotonic() - 1.0
    assert not clock.exudyn_pre_step(None, 0.6)
    assert clock.stopped and clock.reached == 0.6


def test_our_progress_callback_takes_the_runs_end_and_never_stops_it():
    clock = RunClock("ours", 1.0, deadline=time.monotonic() - 1.0, stream=None)
    clock.progress(3.0, 12.0)  # no Interrupted: our runs finish, the limit is the twin's
    assert clock.t_end == 12.0 and clock.reached == 3.0


def test_our_kernels_are_compiled_once_per_process_before_any_run_is_timed(monkeypatch):
    """The reports call ``compiled_kernels`` first; it warms the dynamic kernels too, and only once per process."""
    import validation.twin_clock as twin_clock

    calls = []
    monkeypatch.setattr("ffrf.scenes.kernel_warmup.warm_kernels", lambda dynamic=False: calls.append(dynamic))
    monkeypatch.setattr(twin_clock, "_KERNELS_READY", False)
    first = twin_clock.compiled_kernels(None)
    assert twin_clock.compiled_kernels(None) == 0.0
    assert calls == [True] and first >= 0.0

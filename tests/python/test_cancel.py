"""Long calls report progress, release the GIL, and stop cleanly on Ctrl-C (SIGINT), on an exception
raised by progress, and on progress returning False; the module works again afterwards."""
import os
import signal
import threading
import time

import pytest

import seamvox
from conftest import sphere, torus

BIG = torus(240, 100)  # 48K faces: about 1.5 s, many progress reports


@pytest.fixture(scope="module")
def full_run():
    """Progress stages and seconds of an uninterrupted run on BIG."""
    stages, start = [], time.monotonic()
    seamvox.parameterize(*BIG, threads=2, progress=lambda s, f: stages.append(s))
    return stages, time.monotonic() - start


class Stop(Exception):
    pass


def test_progress_receives_every_stage_with_fractions():
    calls = []
    seamvox.parameterize(*torus(), progress=lambda stage, f: calls.append((stage, f)))
    stages = [s for s, _ in calls]
    assert all(isinstance(s, str) and 0.0 <= f <= 1.0 for s, f in calls)
    for expected in ("cleaning", "field", "cut", "solve"):
        assert any(s.startswith(expected) for s in stages), (expected, sorted(set(stages)))
    assert stages.index("cleaning") < min(i for i, s in enumerate(stages) if s.startswith("cut"))
    field_calls = []
    seamvox.cross_field(*sphere(2), progress=lambda stage, f: field_calls.append(stage))
    assert any(s.startswith("field") for s in field_calls) and any(s.startswith("cut") for s in field_calls)


@pytest.mark.parametrize("call", [seamvox.parameterize, seamvox.cross_field])
def test_an_exception_raised_by_progress_cancels_and_is_raised(call):
    calls = []

    def progress(stage, fraction):
        calls.append(stage)
        if len(calls) == 3:
            raise Stop(stage)

    with pytest.raises(Stop):
        call(*sphere(3), progress=progress)
    assert len(calls) == 3, "progress is not called again once it raised"
    assert seamvox.parameterize(*sphere(2)).quality["seamless"], "the module works after a cancel"


def test_progress_returning_false_cancels():
    calls = []

    def progress(stage, fraction):
        calls.append(stage)
        return len(calls) < 4

    with pytest.raises(seamvox.CancelledError) as error:
        seamvox.parameterize(*sphere(3), progress=progress)
    assert isinstance(error.value, RuntimeError) and len(calls) == 4


def test_sigint_during_the_solve_raises_keyboard_interrupt_and_stops_the_work(full_run):
    full = full_run[0]
    seen, timers = [], []

    def progress(stage, fraction):
        seen.append(stage)
        if stage.startswith("cut") and not timers:  # once the work is well under way
            timers.append(threading.Timer(0.02, os.kill, (os.getpid(), signal.SIGINT)))
            timers[0].start()

    with pytest.raises(KeyboardInterrupt):
        seamvox.parameterize(*BIG, threads=2, progress=progress)
    timers[0].join()
    assert timers and len(seen) < len(full), "the run stopped before its end"
    assert seamvox.parameterize(*sphere(2)).quality["seamless"]


def test_sigint_without_progress_callback_interrupts_a_released_gil_run(full_run):
    full = full_run[1]
    ticks, done = [], threading.Event()

    def tick():  # Python code on another thread: runs only while the call has released the GIL
        while not done.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.005)

    ticker = threading.Thread(target=tick)
    timer = threading.Timer(0.2 * full, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    ticker.start()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        seamvox.parameterize(*BIG, threads=2)
    end = time.monotonic()
    done.set()
    timer.join()
    ticker.join()
    assert end - start < 0.8 * full, (end - start, full)
    during = [t for t in ticks if start + 0.05 < t < end - 0.05]
    assert len(during) >= 5, "another Python thread ran during the call (held GIL: none would)"

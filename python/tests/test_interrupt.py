"""Ctrl-C stops a long fit with KeyboardInterrupt within a few seconds."""

import _thread
import signal
import subprocess
import sys
import threading
import time

import pytest

import hairfit
from conftest import DATA

# Far more multi-start points than the default 16: minutes of work on 2 cores.
LONG = dict(starts=50_000, subsample=5000, intervals="profile")


@pytest.fixture(autouse=True)
def python_handles_sigint():
    """A shell's background job (`scripts/test.sh &` in a script) starts with SIGINT ignored, and
    Python then installs no handler: Ctrl-C could not be what these tests send. Give the test
    Python's own handler, as an interactive session has."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def test_interrupt_main_raises_keyboard_interrupt():
    timer = threading.Timer(0.5, _thread.interrupt_main)
    started = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        hairfit.fit(str(DATA / "longitudinal_rgb.csv"), **LONG)
    timer.cancel()
    assert time.monotonic() - started < 5


SCRIPT = f"""
import signal, sys, hairfit
signal.signal(signal.SIGINT, signal.default_int_handler)
print("fitting", flush=True)
hairfit.fit({str(DATA / "longitudinal_rgb.csv")!r}, **{LONG!r})
print("finished", flush=True)
"""


def test_sigint_to_a_python_process_stops_its_fit():
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "fitting"
    time.sleep(1.0)
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=10)
    finally:
        proc.kill()
    assert time.monotonic() - sent < 5
    assert "KeyboardInterrupt" in err, err
    assert "finished" not in out
    assert proc.returncode != 0

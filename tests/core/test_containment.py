"""What a contained plugin call runs under."""

import subprocess
import sys
import time

import numpy  # noqa: F401  (loads the BLAS whose threads are limited)
import pytest

from forensics_core.containment import can_fork, run_forked
from processes import alive


def _threads():
    from threadpoolctl import threadpool_info

    return [pool["num_threads"] for pool in threadpool_info()]


def test_a_contained_call_runs_with_one_blas_thread():
    assert can_fork()
    (kind, threads), _ = run_forked(_threads, 30)
    assert kind == "value" and threads and set(threads) == {1}


_STARTS_A_CHILD_THEN_WAITS = r"""
import os, sys, time
from pathlib import Path
from forensics_core.containment import Child

def call():
    Path(sys.argv[1]).write_text(str(os.getpid()))
    time.sleep(120)

child = Child(call, 300)
time.sleep(120)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the parent-death signal is Linux's")
def test_a_contained_call_ends_with_the_process_that_started_it_even_when_that_is_killed(tmp_path):
    # Killed outright (SIGKILL, the out-of-memory killer), a parent ends none
    # of its children itself; they used to run on, and could wait for ever on
    # result pipes whose reading ends their siblings had inherited.
    marker = tmp_path / "child.pid"
    parent = subprocess.Popen([sys.executable, "-c", _STARTS_A_CHILD_THEN_WAITS, str(marker)])
    deadline = time.monotonic() + 60
    while not marker.exists() or not marker.read_text():
        assert time.monotonic() < deadline and parent.poll() is None
        time.sleep(0.05)
    child = int(marker.read_text())
    assert alive(child)
    parent.kill()
    parent.wait()
    deadline = time.monotonic() + 10
    while alive(child) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not alive(child)

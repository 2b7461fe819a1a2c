"""Ctrl-C and SIGTERM stop the command even when the exception they raise is swallowed on its way."""

import signal
import subprocess
import sys

import pytest

SWALLOWED = """
import os, signal, time
from forensics_core import stopping

stopping.install()
try:
    os.kill(os.getpid(), signal.{name})
    time.sleep(5)
except BaseException:
    pass  # as C code calling back into Python, a finaliser or an at-fork callback would
print("went on")
try:
    stopping.check()
except KeyboardInterrupt:
    print("interrupted")
except stopping.Terminated:
    print("terminated")
"""


def in_the_foreground():
    """Ctrl-C as a terminal's foreground has it: a shell starts background jobs (as CI may run this suite) with
    SIGINT ignored, and the command rightly keeps it ignored."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def in_the_background():
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize("name, said", [("SIGINT", "interrupted"), ("SIGTERM", "terminated")])
def test_a_signal_whose_exception_was_swallowed_is_raised_again_where_stopping_is_safe(name, said):
    done = subprocess.run([sys.executable, "-c", SWALLOWED.format(name=name)], capture_output=True, text=True,
                          timeout=60, preexec_fn=in_the_foreground)
    assert done.stdout.split() == ["went", "on", said], done.stderr


def test_a_ctrl_c_the_caller_ignores_stays_ignored():
    done = subprocess.run([sys.executable, "-c", SWALLOWED.format(name="SIGINT")], capture_output=True, text=True,
                          timeout=60, preexec_fn=in_the_background)
    assert done.stdout.split() == ["went", "on"], done.stderr


def test_a_child_does_not_answer_for_what_its_parent_was_asked():
    script = SWALLOWED.format(name="SIGINT").replace(
        'print("went on")', 'print("went on")\nif os.fork() == 0:\n    stopping.check()\n    os._exit(7)\n'
        'assert os.wait()[1] >> 8 == 7')
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
                          preexec_fn=in_the_foreground)
    assert done.stdout.split() == ["went", "on", "interrupted"], done.stderr

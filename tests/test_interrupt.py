"""Ctrl-C (SIGINT) stops the long calls into the core within a short time,
with or without a callback: solves of every kind of method, the spectral
estimates, the limit surface, a read that never ends. Each call runs in a
child Python that prints a line when it starts the call; the test then sends
SIGINT and expects the child to end as Python does on an uncaught
KeyboardInterrupt (a traceback, killed by SIGINT) within a bound far below
the call's own length. The core's hook itself: tests/cpp/test_interrupt.cpp.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest

# From SIGINT to the end of the child: the core asks Python's handlers every
# few milliseconds of work; the rest is the interpreter's own exit.
BOUND_S = 5.0

STARTED = "call started"


def interrupt_child(setup: str, call: str, *, after: float = 0.5, cwd=None) -> tuple[subprocess.CompletedProcess, float]:
    """Run `setup`, print STARTED, run `call` in a child Python; SIGINT it
    `after` seconds after the line; returns (the finished child, seconds from
    SIGINT to its end)."""
    script = textwrap.dedent(setup) + f"\nprint({STARTED!r}, flush=True)\n" + textwrap.dedent(call) + \
        "\nprint('call finished', flush=True)\n"
    proc = subprocess.Popen([sys.executable, "-c", script], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        line = proc.stdout.readline()
        assert line.strip() == STARTED, (line, proc.stderr.read() if proc.poll() is not None else "")
        time.sleep(after)
        assert proc.poll() is None, "the call ended before the signal: make it longer"
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
        elapsed = time.monotonic() - sent
    finally:
        proc.kill()
    return subprocess.CompletedProcess(proc.args, proc.returncode, line + out, err), elapsed


def assert_stopped_by_ctrl_c(done: subprocess.CompletedProcess, elapsed: float) -> None:
    assert "call finished" not in done.stdout, "the call ran to its end"
    assert done.stderr.rstrip().endswith("KeyboardInterrupt"), done.stderr
    assert done.returncode == -signal.SIGINT, done.stderr  # Python's exit on an uncaught KeyboardInterrupt
    assert elapsed < BOUND_S, f"{elapsed:.2f} s from SIGINT to the end"


MESH = """
import sorpia
V, F = sorpia.shapes.irregular({n})
"""

# Each converges far too slowly to finish (rates near 1 by choice of
# parameter), without a callback unless named.
SOLVES = {
    "sor on 2 threads": "sorpia.interpolate(V, F, method='sor', omega=1.999, tol=1e-300, max_iter=10**6, threads=2)",
    "wpia": "sorpia.interpolate(V, F, method='wpia', sigma=1e-4, tol=1e-300, max_iter=10**6)",
    "hss": "sorpia.interpolate(V, F, method='hss', alpha=1e6, tol=1e-300, max_iter=10**6)",
    "sor with a callback": "sorpia.interpolate(V, F, method='sor', omega=1.999, tol=1e-300, max_iter=10**6,\n"
                           "                  callback=lambda k, e: False)",
}


@pytest.mark.parametrize("name", sorted(SOLVES))
def test_ctrl_c_stops_a_solve(name):
    assert_stopped_by_ctrl_c(*interrupt_child(MESH.format(n=100000), SOLVES[name]))


def test_ctrl_c_stops_a_spectral_estimate():
    # Young's omega needs the Jacobi radius: a power method over the whole
    # mesh, seconds at this size, before the first sweep.
    assert_stopped_by_ctrl_c(*interrupt_child(
        MESH.format(n=500000), "sorpia.interpolate(V, F, method='sor', omega='young', max_iter=1)", after=0.3))


def test_ctrl_c_stops_a_tessellation():
    # Polled between the refinement steps and in the output loops; OpenSubdiv's
    # refinement of the topology (all levels in one call) runs to its end.
    assert_stopped_by_ctrl_c(*interrupt_child(MESH.format(n=10000), "sorpia.limit_surface(V, F, level=4)"))


def test_ctrl_c_stops_a_read_that_never_ends(tmp_path):
    # An OFF file announcing 10^9 vertices, streamed without end through a
    # pipe: the reader never waits long, so only its own polls can stop it.
    fifo = tmp_path / "endless.off"
    os.mkfifo(fifo)

    def stream():
        try:
            with open(fifo, "w") as w:
                w.write("OFF\n1000000000 1 0\n")
                block = "0.5 0.25 0.125\n" * 4096
                while True:
                    w.write(block)
        except (BrokenPipeError, OSError):
            pass  # the reader is gone

    writer = threading.Thread(target=stream, daemon=True)
    writer.start()
    done, elapsed = interrupt_child("import sorpia", f"sorpia.read_mesh({str(fifo)!r})", after=0.3)
    writer.join(timeout=30)
    assert_stopped_by_ctrl_c(done, elapsed)

"""The `sorpia` command as batch scripts and schedulers run it: memory limits
(ulimit -v, cgroups), Ctrl-C and SIGTERM, long names, unwritable folders, a
full disk, names that are not UTF-8.

Limits and signals are set in child processes (resource.setrlimit, signals
sent by the test), so that this process keeps its own; every child has a
timeout and a memory limit or a small input.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import sorpia
from sorpia import _core

from cli_support import assert_user_error, write_obj

MiB = 2 ** 20

# The prelude of every child: the CLI imported (so that what it imports later
# does not count against a limit set after), vm() its address space now.
PRELUDE = """
import os, re, resource, signal, sys
import numpy
import sorpia, sorpia.cli, sorpia.cli.fit, sorpia.cli.compare
def vm():
    return int(re.search(r"VmSize:\\s+(\\d+)", open("/proc/self/status").read()).group(1)) * 1024
def limit_address_space(extra):
    resource.setrlimit(resource.RLIMIT_AS, (vm() + extra, vm() + extra))
"""


def child(body: str, *, cwd, timeout=120, **popen) -> subprocess.CompletedProcess:
    """Run PRELUDE + body in a fresh Python; returns the finished process (text)."""
    script = PRELUDE + textwrap.dedent(body)
    return subprocess.run([sys.executable, "-c", script], cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          **popen)


def one_line(err: str) -> str:
    """The single line a refused or stopped command prints (no traceback, nothing else)."""
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


def leftovers(folder) -> list[str]:
    return sorted(p.name for p in Path(folder).iterdir() if "sorpia-tmp" in p.name)


@pytest.fixture
def ico_file(tmp_path):
    v, f = sorpia.shapes.icosphere(1)
    return write_obj(tmp_path / "ico.obj", v, f)


# --------------------------------------------------------------------------- memory (issue 16, items 3 and 4)

def test_out_of_memory_in_the_core_is_one_line_and_exit_2(tmp_path):
    # A 250k-vertex binary PLY (over twice the 4 MiB of address space left):
    # the core's std::bad_alloc (or numpy's MemoryError) ends the command
    # with one line naming the phase, exit 2, no traceback.
    v, f = sorpia.shapes.grid(500, 500)
    sorpia.write_mesh(tmp_path / "big.ply", v, f, binary=True)
    assert (tmp_path / "big.ply").stat().st_size > 2 * 4 * MiB
    run = child(f"""
        limit_address_space({4 * MiB})
        sys.exit(sorpia.cli.main(["fit", "big.ply", "-o", "c.ply", "-q"]))
    """, cwd=tmp_path)
    assert run.returncode == 2, run.stderr
    line = one_line(run.stderr)
    assert line.startswith("sorpia: error: not enough memory while reading big.ply"), line
    assert not (tmp_path / "c.ply").exists() and leftovers(tmp_path) == []


def test_a_memory_error_names_the_phase_it_happened_in(ico_file, tmp_path, command, monkeypatch):
    def no_memory(*args, **kwargs):
        raise MemoryError("Unable to allocate 12.0 GiB for an array with shape (4, 3)")

    monkeypatch.setattr(sorpia.cli.fit, "limit_surface", no_memory)  # the name fit calls
    code, _, err = command("fit", ico_file, "-o", tmp_path / "c.obj", "--surface", tmp_path / "s.obj",
                           "--level", 2, "-q")
    assert code == 2
    assert one_line(err) == ("sorpia: error: not enough memory (Unable to allocate 12.0 GiB for an array with "
                             "shape (4, 3)) while limit surface, level 2: free memory, raise the limit (ulimit -v, "
                             "the cgroup's memory limit) or give less work")


def test_the_level_check_honours_the_address_space_limit(ico_file, tmp_path):
    # Under `ulimit -v` (RLIMIT_AS) of 256 MiB above what the process has, the
    # memory left is at most that, though the machine may have far more free;
    # --level 8 on 80 faces (5.2M triangles, tessellation_bytes > 1 GB) is
    # refused before the solve (no control mesh written), --level 1 is done.
    need = _core.tessellation_bytes(42, 80, 8)
    if _core.available_memory_bytes() < 2 * 256 * MiB:
        pytest.skip("less than 512 MiB free here: the limit would not be what binds")
    assert need > 256 * MiB
    run = child(f"""
        limit_address_space({256 * MiB})
        print(sorpia._core.available_memory_bytes())
        code = sorpia.cli.main(["fit", "ico.obj", "-o", "c8.obj", "--surface", "s8.obj", "--level", "8", "-q"])
        if code != 2:
            sys.exit(100 + code)
        sys.exit(sorpia.cli.main(["fit", "ico.obj", "-o", "c1.obj", "--surface", "s1.obj", "--level", "1", "-q"]))
    """, cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    assert 0 < int(run.stdout) <= 256 * MiB
    line = one_line(run.stderr)
    assert line.startswith("sorpia: error: --surface at --level 8 needs about ") and "ulimit -v" in line, line
    assert not (tmp_path / "c8.obj").exists() and not (tmp_path / "s8.obj").exists()
    vs, fs = sorpia.read_mesh(tmp_path / "s1.obj")
    assert len(fs) == 80 * 4


def test_max_iter_at_int32_max_is_one_solve_not_a_memory_error(ico_file, tmp_path):
    # Nothing is reserved per allowed iteration: under 1 GiB of address space
    # to spare, --max-iter 2**31-1 converges as --max-iter 1000 does.
    run = child(f"""
        limit_address_space({1024 * MiB})
        sys.exit(sorpia.cli.main(["fit", "ico.obj", "-o", "c.obj", "--max-iter", str(2**31 - 1), "--report", "r.json",
                                  "-q"]))
    """, cwd=tmp_path)
    assert run.returncode == 0 and run.stderr == "", run.stderr
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["converged"] and report["max_iter"] == 2 ** 31 - 1
    assert len(report["history"]) == report["iterations"] + 1 < 1000


# --------------------------------------------------------------------------- Ctrl-C and SIGTERM (items 6, 10)

def open_writer(fifo: Path, proc: subprocess.Popen, timeout: float = 30.0):
    """The write end of `fifo` once the child `proc` has opened its read end
    (O_NONBLOCK: ENXIO until then), so that a child that fails first does
    not leave the test waiting."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
            os.set_blocking(fd, True)
            return os.fdopen(fd, "w")
        except OSError:
            if proc.poll() is not None or time.monotonic() > deadline:
                raise
            time.sleep(0.01)


def test_ctrl_c_during_a_read_that_waits_is_one_line_and_exit_130(tmp_path):
    # `sorpia info` on a pipe whose writer has sent half a header and waits:
    # Ctrl-C (SIGINT) stops the read at once, one line, exit 130. A reader
    # that retried on EINTR would wait for the writer; one that failed would
    # print the read's error as well.
    fifo = tmp_path / "slow.ply"
    os.mkfifo(fifo)
    proc = subprocess.Popen([sys.executable, "-m", "sorpia", "info", fifo.name], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        with open_writer(fifo, proc) as writer:
            writer.write("ply\nformat ascii 1.0\n")
            writer.flush()
            time.sleep(0.5)  # the child is in read(), waiting for more
            proc.send_signal(signal.SIGINT)
            out, err = proc.communicate(timeout=30)  # the writer is still open
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert err == "sorpia: interrupted\n" and out == ""


def test_ctrl_c_while_a_failed_read_is_reported_is_one_line(ico_file, tmp_path):
    # The read fails just as Ctrl-C arrives: Python raises KeyboardInterrupt
    # in the middle of reporting the read's error. One line, exit 130.
    run = child("""
        from sorpia import MeshFileError
        import sorpia.cli.common
        def read_then_fail(path, triangulate=False, tags=False, attributes=False, prim=None, points=False):
            os.kill(os.getpid(), signal.SIGINT)
            raise MeshFileError(f"{path}, line 3: unknown header line 'garbage'")
        sorpia.cli.common.read_mesh_file = read_then_fail  # the name the commands' reader calls
        sys.exit(sorpia.cli.main(["info", "ico.obj"]))
    """, cwd=tmp_path)
    assert run.returncode == 130 and run.stderr == "sorpia: interrupted\n", run.stderr


def test_read_mesh_on_a_pipe_goes_on_after_a_handler_that_returns_and_stops_for_one_that_raises(tmp_path):
    # SIGALRM sent to the main thread while read_mesh waits on a FIFO: a
    # handler that returns lets the read finish with the whole mesh; one that
    # raises ends it with that exception.
    v, f = sorpia.shapes.icosphere(1)
    sorpia.write_mesh(tmp_path / "ico.off", v, f)
    text = (tmp_path / "ico.off").read_text()
    main = threading.get_ident()

    class Stop(Exception):
        pass

    def read_with(handler, finish: bool):
        fifo = tmp_path / f"pipe-{finish}.off"
        os.mkfifo(fifo)
        calls = []

        def write():
            with open(fifo, "w") as w:
                w.write(text[:30])
                w.flush()
                time.sleep(0.3)  # the reader waits in read()
                signal.pthread_kill(main, signal.SIGALRM)
                time.sleep(0.3)
                if finish:
                    w.write(text[30:])

        old = signal.signal(signal.SIGALRM, lambda *a: (calls.append(1), handler()))
        writer = threading.Thread(target=write)
        writer.start()
        try:
            return sorpia.read_mesh(fifo), calls
        finally:
            writer.join()
            signal.signal(signal.SIGALRM, old)

    (v2, f2), calls = read_with(lambda: None, finish=True)
    assert calls == [1] and np.array_equal(v2, v) and np.array_equal(f2, f)

    def stop():
        raise Stop

    with pytest.raises(Stop):
        read_with(stop, finish=False)


def test_sigterm_during_a_solve_exits_143_and_leaves_no_file(ico_file, tmp_path):
    # SIGTERM (timeout, systemd, a batch scheduler send it) arrives at the 5th
    # iteration of the solve (sent from the progress callback, which the
    # solver calls each iteration): the command ends as on Ctrl-C, one line,
    # exit 143, no output and no temporary file.
    run = child("""
        from sorpia.cli.progress import Progress
        progress = Progress.__call__
        def at_iteration(self, k, error):
            if k == 5:
                os.kill(os.getpid(), signal.SIGTERM)
            return progress(self, k, error)
        Progress.__call__ = at_iteration
        sys.exit(sorpia.cli.main(["fit", "ico.obj", "-o", "c.obj", "--report", "r.json", "--method", "pia"]))
    """, cwd=tmp_path)
    assert run.returncode == 143, run.stderr
    assert run.stderr == "sorpia: terminated\n" and run.stdout == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ico.obj"]


@pytest.fixture
def big_scan(tmp_path):
    """A scan of 300k points (binary PLY): its decimation to 40,000 vertices (in rounds: a mesh is clustered
    first only above 8 times the count, in a tenth of a second) lasts seconds, far longer than the signal's
    delay."""
    v, f = sorpia.shapes.irregular(300000)
    sorpia.write_mesh(tmp_path / "scan.ply", v, f, binary=True)
    return tmp_path / "scan.ply"


@pytest.mark.parametrize("sig, code, line", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")])
def test_a_signal_during_approximate_decimation_stops_it_and_leaves_no_file(big_scan, tmp_path, sig, code, line):
    # The signal comes from a thread 0.2 s into the decimation (sorpia.decimate, which polls for it between
    # collapses): the decimation does not finish, the command ends with one line and its exit code, and none
    # of its outputs (nor a temporary) exists.
    run = child(f"""
        import threading, time
        import sorpia.cli.approximate as command
        decimate, main = command.decimate, threading.get_ident()
        def decimate_then_signal(*args, **kwargs):
            threading.Timer(0.2, signal.pthread_kill, (main, {int(sig)})).start()
            cage = decimate(*args, **kwargs)
            print("decimation finished", flush=True)
            return cage
        command.decimate = decimate_then_signal
        sys.exit(sorpia.cli.main(["approximate", "scan.ply", "-o", "c.obj", "--vertices", "40000", "--quiet",
                                  "--report", "r.json", "--surface", "s.obj"]))
    """, cwd=tmp_path)
    assert run.returncode == code, run.stderr
    assert run.stderr == f"sorpia: {line}\n" and run.stdout == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scan.ply"]


@pytest.mark.parametrize("sig, code, line", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")])
def test_a_signal_during_approximate_fit_stops_it_and_leaves_no_file(tmp_path, sig, code, line):
    # The signal comes from a thread 0.05 s after the fit's first iteration record, inside the next iteration
    # (the core polls for it): the fit does not reach its 50th iteration, the command ends with one line and
    # its exit code, no output.
    v, f = sorpia.shapes.irregular(40000)
    sorpia.write_mesh(tmp_path / "scan.ply", v, f, binary=True)
    sorpia.write_mesh(tmp_path / "cage.obj", *sorpia.decimate(v, f, 800)[:2])
    run = child(f"""
        import threading
        from sorpia.cli.progress import Progress
        note, main, records = Progress.note, threading.get_ident(), []
        def at_iteration(self, text):
            records.append(text)
            if len(records) == 1:
                threading.Timer(0.05, signal.pthread_kill, (main, {int(sig)})).start()
            return note(self, text)
        Progress.note = at_iteration
        code = sorpia.cli.main(["approximate", "scan.ply", "-o", "c.obj", "--cage", "cage.obj", "--quiet",
                                "--iterations", "50", "--tol", "0", "--report", "r.json"])
        print(len(records))
        sys.exit(code)
    """, cwd=tmp_path)
    assert run.returncode == code, run.stderr
    assert run.stderr == f"sorpia: {line}\n"
    assert 1 <= int(run.stdout) < 50
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cage.obj", "scan.ply"]


def test_sigterm_during_a_write_lets_it_finish_then_exits_and_leaves_no_temporary(tmp_path):
    # A thread watches the folder and sends SIGTERM to the main thread as soon
    # as the writer's temporary file exists: the write finishes (the file is
    # whole, under its name), then the CLI's handler raises Terminated.
    run = child("""
        import threading
        from sorpia.cli import Terminated, _sigterm_raises
        from sorpia.cli.output import write_bytes
        data = bytes(range(256)) * (256 * 1024)  # 64 MiB
        main, seen = threading.get_ident(), []
        def watch():
            while not seen:
                if any("sorpia-tmp" in name for name in os.listdir(".")):
                    seen.append(1)
                    signal.pthread_kill(main, signal.SIGTERM)
        watcher = threading.Thread(target=watch, daemon=True)
        watcher.start()
        try:
            with _sigterm_raises():
                write_bytes("out.bin", data)
                for _ in range(1000):  # the handler runs between bytecodes, after the write returns
                    pass
        except Terminated:
            print("terminated", len(seen))
            with open("out.bin", "rb") as f:
                print("whole" if f.read() == data else "NOT whole")
    """, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == ["terminated", "1", "whole"], run.stdout
    assert leftovers(tmp_path) == []


# --------------------------------------------------------------------------- names and folders (items 8, 9, 13)

def test_an_output_name_of_name_max_bytes_is_written(ico_file, tmp_path, command):
    # The temporary name does not grow with the output's: a name of exactly
    # NAME_MAX bytes works for the mesh and the report.
    name_max = os.pathconf(tmp_path, "PC_NAME_MAX")
    out = tmp_path / ("c" * (name_max - 4) + ".obj")
    report = tmp_path / ("r" * (name_max - 5) + ".json")
    code, _, err = command("fit", ico_file, "-o", out, "--report", report, "-q")
    assert code == 0, err
    v, _ = sorpia.read_mesh(ico_file)
    vc, _ = sorpia.read_mesh(out)
    assert vc.shape == v.shape and report.stat().st_size > 0 and leftovers(tmp_path) == []


def test_an_output_that_cannot_be_written_is_refused_before_the_work(ico_file, tmp_path, command):
    # Each bad output comes after a good -o: had the check waited for the
    # write, the control mesh would have been written first.
    name_max = os.pathconf(tmp_path, "PC_NAME_MAX")
    too_long = tmp_path / ("r" * (name_max - 4) + ".json")
    unwritable = Path("/proc/sorpia-test-r.json")  # /proc takes no new files, for root too
    for bad, why in ((too_long, "File name too long"), (unwritable, "cannot create a temporary file in its folder")):
        code, _, err = command("fit", ico_file, "-o", tmp_path / "c.obj", "--report", bad, "-q")
        assert_user_error(code, err)
        line = one_line(err)
        assert line.startswith(f"sorpia: error: --report {bad}: ") and why in line, line
        assert not (tmp_path / "c.obj").exists() and leftovers(tmp_path) == []
    code, _, err = command("fit", ico_file, "-o", tmp_path / ("c" * (name_max + 1) + ".obj"), "-q")
    assert_user_error(code, err)
    assert "File name too long" in one_line(err)


def test_a_full_disk_while_writing_the_report_names_the_report(tmp_path):
    # Files limited (RLIMIT_FSIZE, SIGXFSZ ignored: write() fails with EFBIG
    # as it would with ENOSPC) to a size between the control mesh's and the
    # report's: the mesh is written, the report fails with its name.
    v, f = sorpia.shapes.icosphere(0)
    write_obj(tmp_path / "ico.obj", v, f)
    sizes = child("""
        sys.exit(sorpia.cli.main(["fit", "ico.obj", "-o", "c.obj", "--report", "r.json", "-q"]))
    """, cwd=tmp_path)
    assert sizes.returncode == 0, sizes.stderr
    mesh_bytes, report_bytes = (tmp_path / "c.obj").stat().st_size, (tmp_path / "r.json").stat().st_size
    assert mesh_bytes < report_bytes
    (tmp_path / "c.obj").unlink()
    (tmp_path / "r.json").unlink()
    limit = (mesh_bytes + report_bytes) // 2
    run = child(f"""
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))
        sys.exit(sorpia.cli.main(["fit", "ico.obj", "-o", "c.obj", "--report", "r.json", "-q"]))
    """, cwd=tmp_path)
    assert_user_error(run.returncode, run.stderr)
    line = one_line(run.stderr)
    assert line.startswith("sorpia: error: r.json: writing failed (nothing was changed): "), line
    assert (tmp_path / "c.obj").stat().st_size == mesh_bytes
    assert not (tmp_path / "r.json").exists() and leftovers(tmp_path) == []


def test_names_that_are_not_utf8_are_read_and_written(tmp_path, command, monkeypatch):
    # Names as Python gets them from a Latin-1 shell (os.fsdecode: surrogates).
    monkeypatch.chdir(tmp_path)
    v, f = sorpia.shapes.icosphere(1)
    src = os.fsdecode(b"lat\xe9.obj")
    sorpia.write_mesh(src, v, f)
    out, report, surface = (os.fsdecode(n) for n in (b"c\xe9.obj", b"r\xe9.json", b"s\xe9.ply"))
    # Printed as the core's messages print them: the byte that is not UTF-8 as \xNN.
    code, stdout, err = command("info", src)
    assert code == 0 and stdout.startswith("mesh") and "lat\\xe9.obj\n" in stdout, err
    code, stdout, err = command("fit", src, "-o", out, "--report", report, "--surface", surface, "--level", 1)
    assert code == 0 and "sorpia fit: lat\\xe9.obj -> c\\xe9.obj\n" in stdout, err
    names = set(os.listdir(b"."))
    assert {b"lat\xe9.obj", b"c\xe9.obj", b"r\xe9.json", b"s\xe9.ply"} <= names
    assert sorpia.read_mesh(out)[0].shape == v.shape
    assert json.loads(Path(report).read_bytes())["converged"]

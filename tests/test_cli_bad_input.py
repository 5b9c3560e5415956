"""Bad input to the `sorpia` command: exit code 2, one line on stderr naming
the problem, no traceback, nothing written. Solver options are refused with
the library's own message (sorpia.solve.check_options), before the file is read."""

from __future__ import annotations

import numpy as np
import pytest

import sorpia

from cli_support import assert_user_error, write_obj


@pytest.mark.parametrize("case", ["missing-file", "output-is-input", "output-is-input-other-spelling",
                                  "omega-out-of-range", "omega-not-a-number", "omega-for-pia", "unknown-method",
                                  "negative-tol", "unknown-output-format", "missing-folder", "non-manifold",
                                  "garbage-file"])
def test_bad_input_exits_2_with_one_line(case, torus_file, tmp_path, command):
    src, V0, F = torus_file
    before = src.read_bytes()
    out = tmp_path / "ctrl.obj"
    args = {
        "missing-file": ["fit", tmp_path / "nope.obj", "-o", out],
        "output-is-input": ["fit", src, "-o", src],
        "output-is-input-other-spelling": ["fit", src, "-o", f"./{src.name}"],
        "omega-out-of-range": ["fit", src, "-o", out, "--omega", "2.5"],
        "omega-not-a-number": ["fit", src, "-o", out, "--omega", "fast"],
        "omega-for-pia": ["fit", src, "-o", out, "--omega", "1.5", "--method", "pia"],
        "unknown-method": ["compare", src, "--methods", "sor,newton"],
        "negative-tol": ["fit", src, "-o", out, "--tol", "-1"],
        "unknown-output-format": ["fit", src, "-o", tmp_path / "ctrl.xyz"],
        "missing-folder": ["fit", src, "-o", tmp_path / "no" / "ctrl.obj"],
        "non-manifold": ["fit", write_obj(tmp_path / "nm.obj", np.eye(4, 3),
                                          [[0, 1, 2], [0, 1, 3], [1, 0, 2]]), "-o", out],
        "garbage-file": ["info", tmp_path / "junk.obj"],
    }[case]
    (tmp_path / "junk.obj").write_bytes(b"v 1 2\nf 1 2 3 x\n\x00\xff")
    code, _, err = command(*args)
    assert_user_error(code, err)
    assert src.read_bytes() == before
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if "tmp" in p.name]  # no temporary file left


@pytest.mark.parametrize("args, option", [
    (["--omega", "2.5"], dict(omega=2.5)),
    (["--omega", "1.5", "--method", "pia"], dict(omega=1.5, method="pia")),
    (["--threads", "2", "--method", "cg"], dict(threads=2, method="cg")),
    (["--threads", "0"], dict(threads=0)),
    (["--tol", "0"], dict(tol=0.0)),
    (["--max-iter", "0"], dict(max_iter=0)),
], ids=["omega", "omega-pia", "threads-cg", "threads-0", "tol", "max-iter"])
def test_solver_options_are_refused_with_the_library_message(args, option, torus_file, tmp_path, command):
    src, _, _ = torus_file
    with pytest.raises(sorpia.ParameterError) as refused:
        sorpia.solve.check_options(**option)
    code, _, err = command("fit", src, "-o", tmp_path / "c.obj", *args)
    assert_user_error(code, err)
    assert len(err.strip().splitlines()) == 1 and err.strip().endswith(str(refused.value))


@pytest.mark.parametrize("args", [["fit", "-o", "c.obj", "--threads", "0"],
                                  ["compare", "--methods", "pia", "--threads", "0"],
                                  ["render", "-o", "f.png", "--threads", "0"],
                                  ["fit", "-o", "c.obj", "--method", "pia", "--threads", "2"]],
                         ids=["fit-0", "compare-0", "render-0", "fit-pia-2"])
def test_bad_threads_exit_2_with_one_line(args, torus_file, tmp_path, command):
    src, _, _ = torus_file
    code, _, err = command(args[0], src, *args[1:])
    assert_user_error(code, err)
    assert len(err.strip().splitlines()) == 1, err
    assert "--threads" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["torus.obj"]  # nothing written

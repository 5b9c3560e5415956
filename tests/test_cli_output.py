"""The progress line and the files the command writes besides meshes."""

from __future__ import annotations

import io
import json
import os
import stat

import numpy as np
import pytest

from sorpia.cli.output import save_figure, write_json, write_text
from sorpia.cli.progress import Progress


def test_progress_line_on_a_terminal_plain_lines_in_a_pipe():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty, pipe, off = Tty(), io.StringIO(), io.StringIO()
    for stream, enabled in ((tty, True), (pipe, True), (off, False)):
        with Progress("SOR-PIA", enabled=enabled, stream=stream) as p:
            p.status("reading mesh.obj")  # phases: on a terminal only
            p.interval = 0.0  # show every call
            for k, e in enumerate([1.0, 0.1, 0.01]):
                assert p(k, e) is False  # never stops the solver
    assert "reading mesh.obj" in tty.getvalue() and "reading" not in pipe.getvalue()
    assert tty.getvalue().count("\r") >= 4 and "\n" not in tty.getvalue()
    assert tty.getvalue().endswith("\r")  # the live line is erased at the end
    assert pipe.getvalue().splitlines()[-1] == pipe.getvalue().splitlines()[-1].strip()
    assert len(pipe.getvalue().splitlines()) == 3 and "E_k/E_0 = 1.000e-02" in pipe.getvalue()
    assert off.getvalue() == ""


def test_text_and_json_replace_the_file_whole_and_keep_its_mode(tmp_path):
    target = tmp_path / "table.md"
    target.write_text("old")
    os.chmod(target, 0o640)
    write_text(target, "new ü")
    assert target.read_text(encoding="utf-8") == "new ü"
    assert stat.S_IMODE(target.stat().st_mode) == 0o640  # the replaced file's mode, as write_mesh keeps it
    write_json(target, {"a": np.float64(1.5), "b": float("nan"), "c": np.arange(2)})
    assert json.loads(target.read_text()) == {"a": 1.5, "b": None, "c": [0, 1]}
    assert [p.name for p in tmp_path.iterdir()] == ["table.md"]  # no temporary file left


def test_a_failed_write_keeps_the_old_file(tmp_path):
    target = tmp_path / "plot.png"
    target.write_bytes(b"old")

    class Broken:
        def savefig(self, *args, **kwargs):
            raise RuntimeError("cannot draw")

    with pytest.raises(RuntimeError, match="cannot draw"):
        save_figure(Broken(), target)
    (tmp_path / "folder.md").mkdir()
    with pytest.raises(ValueError, match="folder.md"):  # sorpia.MeshFileError, naming the path
        write_text(tmp_path / "folder.md", "text")
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder.md", "plot.png"]

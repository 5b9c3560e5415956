"""The `sorpia` command as a process: the installed script and `python -m
sorpia` are one program, and its exit codes reach the shell. The help of every
subcommand is read in-process."""

from __future__ import annotations

import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

import sorpia
from sorpia import cli

from conftest import installed_script


def run(*args, cwd, script=False, timeout=300):
    """Run the command as a process; returns the CompletedProcess (text)."""
    exe = [str(_script())] if script else [sys.executable, "-m", "sorpia"]
    return subprocess.run([*exe, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=timeout)


def _script() -> Path:
    path = installed_script("sorpia")
    if path is None:
        pytest.skip(f"the sorpia script is not installed next to this Python ({sysconfig.get_path('scripts')})")
    return path


def test_script_and_module_are_the_same_program(tmp_path):
    by_script = run("--version", cwd=tmp_path, script=True)
    by_module = run("--version", cwd=tmp_path)
    assert by_script.returncode == by_module.returncode == 0
    assert by_script.stdout == by_module.stdout == f"sorpia {sorpia.__version__}\n"


def test_exit_codes_reach_the_shell(torus_file, tmp_path):
    src, _, _ = torus_file
    not_converged = run("fit", src, "-o", tmp_path / "c.obj", "--method", "pia", "--max-iter", 2, "-q", cwd=tmp_path,
                        script=True)
    assert not_converged.returncode == 1 and not_converged.stdout == ""
    refused = run("fit", src, "-o", tmp_path / "c.xyz", cwd=tmp_path)
    assert refused.returncode == 2 and "Traceback" not in refused.stderr
    assert refused.stderr.startswith("sorpia: error: -o ")


def test_help_explains_every_option_with_its_default(monkeypatch, command):
    # A wide terminal, so that argparse does not break 'edge-and-corner' at a hyphen.
    monkeypatch.setenv("COLUMNS", "400")
    parser = cli.build_parser()
    subparsers = next(a for a in parser._actions if a.dest == "command").choices
    code, top, _ = command("--help")
    assert code == 0
    for name, sub in subparsers.items():
        assert name in top
        code, stdout, err = command(name, "--help")
        assert code == 0, err
        text = " ".join(stdout.split())
        for action in sub._actions:
            if not action.option_strings or action.dest == "help":
                continue
            assert action.option_strings[-1] in text, (name, action.option_strings)
            assert action.help, (name, action.option_strings)
            if action.default not in (None, False):
                shown = action.default if isinstance(action.default, str) else repr(action.default)
                assert f"(default: {shown})" in text, (name, action.option_strings, shown)
        assert "exit codes" in text

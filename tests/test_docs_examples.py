"""Every example in the README and docs/ runs as written (issue 20, item 8).

The fenced blocks are taken from the pages as they are: the ```python blocks of
a page run one after the other in one namespace (a page is one session, as a
reader pastes it), the ```bash lines that call `sorpia` run the command, each
in a folder holding the small files the examples name (made here: `mesh.ply`,
`part.obj`, ...). A shell line that is not a `sorpia` command must be listed in
NOT_RUN with the reason, so that a new example cannot go untested unnoticed."""

from __future__ import annotations

import importlib
import re
import shlex
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import sorpia

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted([ROOT / "README.md", *(ROOT / "docs").rglob("*.md")]) if (ROOT / "docs").is_dir() else []

# Shell lines of the pages that the tests do not run, by their first words, with the reason.
NOT_RUN = {
    "make": "sets up the machine (apt, .venv, the build): what this test suite runs inside",
    "apt-get": "installs system packages",
    "pip install": "installs the package under test",
    "cmake": "configures and builds the C++ tests, which ctest runs",
    "tests/fuzz/run.sh": "runs the fuzzer for minutes",
    "python bench/": "a benchmark: speed is measured by bench/ programs, never in tests",
    "sorpia-bench": "a benchmark: speed is measured by bench/ programs, never in tests",
}

FENCE = re.compile(r"^( *)```(\w*)\n(.*?)^\1```", re.MULTILINE | re.DOTALL)


def blocks(page: Path, language: str) -> list[str]:
    """The page's fenced blocks in `language`, dedented, in page order."""
    return [textwrap.dedent(m.group(3)) for m in FENCE.finditer(page.read_text()) if m.group(2) == language]


def shell_commands(block: str) -> list[list[str]]:
    """The commands of a shell block as word lists: continuation lines joined, comments and blank lines dropped."""
    text = block.replace("\\\n", " ")
    return [words for words in (shlex.split(raw, comments=True) for raw in text.splitlines()) if words]


def not_run(words: list[str]) -> bool:
    line = " ".join(words)
    return any(line.startswith(prefix) for prefix in NOT_RUN)


# The optional extras an example may need, found by what its text names: (pattern, module, reason).
EXTRAS = [(re.compile(r"\.usd[ac]?\b|\bpxr\b"), "pxr", "usd-core is not installed (pip install 'sorpia[usd]')"),
          (re.compile(r"\.png\b|--plot\b|\bsorpia render\b|\bmatplotlib\b"), "matplotlib",
           "matplotlib is not installed (pip install 'sorpia[plot]')"),
          (re.compile(r"\bdask\b"), "distributed", "dask.distributed is not installed (pip install 'sorpia[dask]')")]


def installed(module: str) -> bool:
    try:
        importlib.import_module(module)
    except ImportError:
        return False
    return True


def skip_without_extras(text: str) -> None:
    """Skip, saying which, when `text` (a page's examples) needs an optional extra that is not installed."""
    for pattern, module, reason in EXTRAS:
        if pattern.search(text) and not installed(module):
            pytest.skip(reason)


def page_id(page: Path) -> str:
    return str(page.relative_to(ROOT))


def _quad_cylinder(around: int = 20, rings: int = 10):
    """200 quads and two 20-gons: a closed cylinder (the files.md example's 'cylinder.obj')."""
    t = np.linspace(0, 2 * np.pi, around, endpoint=False)
    V = np.array([[np.cos(a), np.sin(a), z] for z in np.linspace(0, 2, rings + 1) for a in t])
    quads = [[r * around + i, r * around + (i + 1) % around, (r + 1) * around + (i + 1) % around,
              (r + 1) * around + i] for r in range(rings) for i in range(around)]
    caps = [list(range(around))[::-1], list(range(rings * around, (rings + 1) * around))]
    return V, quads + caps


def make_files(folder: Path) -> None:
    """The input files the examples name, small enough for every command to take a second."""
    tri_V, tri_F = sorpia.shapes.irregular(300, seed=5)
    for name in ("mesh.obj", "mesh.ply"):
        sorpia.write_mesh(folder / name, tri_V, tri_F)
    ico_V, ico_F = sorpia.shapes.icosphere(2)
    sorpia.write_mesh(folder / "part.stl", ico_V, ico_F)
    # A quad part with every kind of tag and texture coordinates (a seam-free map: x, y).
    qV, qF = sorpia.shapes.quad_torus(16, 8)
    corners = np.ascontiguousarray(qF.reshape(-1), dtype=np.int32)
    sorpia.write_mesh(folder / "part.obj", qV, qF, creases=(qF[:6, :2], np.inf), corners=([20], [2.0]),
                      holes=[40], uvs=sorpia.FaceVarying(qV[:, :2], corners))
    sorpia.write_mesh(folder / "textured.obj", qV, qF, uvs=sorpia.FaceVarying(qV[:, :2], corners))
    for name in ("car.obj", "osd_catmark_car.obj"):
        sorpia.write_mesh(folder / name, qV, qF, creases=(qF[:6, :2], np.full(6, 3.0)))
    sorpia.write_mesh(folder / "cylinder.obj", *_quad_cylinder())
    # A USD stage: the tagged quad part as /World/Part, Catmull-Clark, with its texture coordinates (st).
    if installed("pxr"):  # the pages that read it skip without usd-core
        sorpia.write_mesh(folder / "scene.usda", qV, qF, scheme="catmull-clark", creases=(qF[:6, :2], np.inf),
                          corners=([20], [2.0]), uvs=sorpia.FaceVarying(qV[:, :2], corners), prim="/World/Part")
    # Files to repair: a quad grid with a duplicated face (bad.obj, polygons kept), an irregular triangle mesh
    # with a duplicated and a reversed face (scan.ply).
    gV, gF = sorpia.shapes.quad_grid(6, 5)
    sorpia.write_mesh(folder / "bad.obj", gV, np.vstack([gF, gF[3:4]]))
    scan_F = np.vstack([tri_F, tri_F[:1]])
    scan_F[5] = scan_F[5, ::-1]
    sorpia.write_mesh(folder / "scan.ply", tri_V, scan_F)


@pytest.fixture
def example_folder(tmp_path, monkeypatch):
    make_files(tmp_path)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_pages_found():
    if not PAGES:
        pytest.skip("README.md and docs/ are not beside the tests (an installed package without its sources)")
    assert ROOT / "README.md" in PAGES and any(blocks(p, "python") for p in PAGES)


@pytest.mark.parametrize("page", [p for p in PAGES if blocks(p, "python")], ids=page_id)
def test_python_examples_run(page, example_folder):
    skip_without_extras("\n".join(blocks(page, "python")))
    namespace: dict = {"__name__": "__example__"}
    for i, code in enumerate(blocks(page, "python")):
        exec(compile(code, f"{page_id(page)} (python block {i + 1})", "exec"), namespace)  # noqa: S102


@pytest.mark.parametrize("page", [p for p in PAGES if blocks(p, "bash")], ids=page_id)
def test_shell_examples_run(page, example_folder, command):
    skip_without_extras("\n".join(blocks(page, "bash")))
    ran = 0
    for block in blocks(page, "bash"):
        for words in shell_commands(block):
            line = shlex.join(words)
            if words[0] == "sorpia":
                code, stdout, err = command(*words[1:])
                assert code == 0, f"{page_id(page)}: {line}\n{err}"
                ran += 1
            elif words[:2] == ["python", "-c"]:
                run = subprocess.run([sys.executable, *words[1:]], capture_output=True, text=True, timeout=60)
                assert run.returncode == 0, f"{page_id(page)}: {line}\n{run.stderr}"
                ran += 1
            else:
                assert not_run(words), (
                    f"{page_id(page)}: {line!r} is neither run by this test nor listed in NOT_RUN with a reason")
    if not ran:
        pytest.skip(f"{page_id(page)}: every shell line is in NOT_RUN (set-up, build or benchmark)")


def test_help_texts_hold_for_what_each_command_does():
    """Each command's help names only options it has and outputs it writes, and no scheme as the only one."""
    from sorpia.cli import build_parser
    from sorpia.cli.common import CLI_SCHEMES

    parser = build_parser()
    subparsers = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction").choices
    for name, sub in subparsers.items():
        options = {o for a in sub._actions for o in a.option_strings}
        own = " ".join(" ".join(filter(None, [sub.description, *(a.help for a in sub._actions)])).split())
        text = own + " " + " ".join((sub.epilog or "").split())
        mentioned = set(re.findall(r"(?<![\w-])--[a-z][a-z-]*", own))  # the exit codes' text is the program's
        # --scheme names a value of another command's option only where this command has --scheme.
        assert mentioned <= options, (name, mentioned - options)
        solves = name in ("fit", "compare", "render", "demo")
        assert ("; 1 a solve" in text) == solves, name  # exit code 1 where a solve can fall short
        # The control mesh is written by fit alone.
        assert ("control mesh is written" in text) == (name == "fit"), name
        # No claim that holds for one scheme only, where the command takes both.
        if "--scheme" in options:
            assert set(sub._option_string_actions["--scheme"].choices) == set(CLI_SCHEMES)
            for one_scheme in ("a triangle mesh", "triangles per input triangle", "Loop limit surface interpolates",
                               "whether Loop PIA can run"):
                assert one_scheme not in text, (name, one_scheme)

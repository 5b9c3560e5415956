"""The type stubs of the compiled module, python/sorpia/_core.pyi, generated from the installed sorpia._core by
pybind11-stubgen (from the signatures pybind11 writes into its docstrings).

    python tools/core_stubs.py          rewrite python/sorpia/_core.pyi (`make stubs`)
    python tools/core_stubs.py --check  exit 1, with a diff, if it differs from what the module gives

tests/test_typing.py runs the check: stubs that drift from the module are a defect. The output depends on the
versions of pybind11 (which writes the signatures) and pybind11-stubgen; the Makefile and the test extra pin both.
"""

from __future__ import annotations

import difflib
import subprocess
import sys
import tempfile
from pathlib import Path

STUB = Path(__file__).resolve().parent.parent / "python" / "sorpia" / "_core.pyi"
# Enum defaults print as <Scheme.loop: 0>: tell stubgen where the enums live. The default Tags() prints as an
# object address, which has no expression: written as `...` (the stub's usual "has a default").
OPTIONS = ["--enum-class-locations", "Scheme:sorpia._core", "--enum-class-locations", "Boundary:sorpia._core",
           "--ignore-invalid-expressions", r"<sorpia\._core\.Tags object at 0x[0-9a-f]+>", "--exit-code"]


def generate() -> str:
    """The stub text for the sorpia._core that this Python imports."""
    with tempfile.TemporaryDirectory() as out:
        run = subprocess.run([sys.executable, "-m", "pybind11_stubgen", "sorpia._core", "-o", out, *OPTIONS],
                             capture_output=True, text=True)
        if run.returncode != 0:
            raise SystemExit(f"pybind11-stubgen failed:\n{run.stdout}{run.stderr}")
        return (Path(out) / "sorpia" / "_core.pyi").read_text()


def main(argv: list[str]) -> int:
    text = generate()
    if argv == ["--check"]:
        if STUB.read_text() == text:
            return 0
        sys.stdout.writelines(difflib.unified_diff(STUB.read_text().splitlines(True), text.splitlines(True),
                                                   str(STUB), "generated from sorpia._core"))
        print(f"\n{STUB} differs from the installed module: run `make stubs` and commit it")
        return 1
    if argv:
        raise SystemExit(f"usage: {sys.argv[0]} [--check]")
    STUB.write_text(text)
    print(f"wrote {STUB}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

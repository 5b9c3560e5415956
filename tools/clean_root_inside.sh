#!/bin/bash
# Run by tools/clean_root_test.sh inside the clean root (Debian bookworm minbase, python3 and python3-venv; no
# OpenSubdiv, OpenMesh or compiler), as a new user would install and use the wheel:
#   np1: Blender's numpy (1.26) and no scipy: `pip install --no-deps` of the wheel, then numpy; the compiled
#        module's libraries (only sorpia.libs and what the manylinux policy allows), `import sorpia` without
#        scipy and test_without_scipy.py, `sorpia demo`; then scipy (a release that takes numpy 1.26) and the
#        pytest selection.
#   np2: `pip install` of the wheel with its dependencies (numpy 2.x, scipy), `sorpia demo`, the selection.
#   clean_root_inside.sh WORK WHEEL_NAME   (WORK: the run's folder, holding wheel/, tests/, noscipy/)
set -euo pipefail
work=$1
wheel=$work/wheel/$2
cd "$work"
mkdir -p home "$TMPDIR"
# PyPI's files are kept in the root between runs (pip's own cache stays empty behind this machine's proxy):
# pip installs from here alone, and asks PyPI (`pip download`, which fetches only what is not here yet) when
# what is here does not satisfy the requirements. --no-compile: Python compiles what it imports, not all of scipy.
wheels=/var/cache/sorpia-wheels
mkdir -p "$wheels"
install() {
  local venv=$1
  shift
  "$venv/bin/pip" install -q --no-compile --no-index --find-links "$wheels" "$@" 2>/dev/null && return
  "$venv/bin/pip" download -q -d "$wheels" "$@"
  "$venv/bin/pip" install -q --no-compile --no-index --find-links "$wheels" "$@"
}

step() {
  local start=$SECONDS
  echo "-- $1"
  shift
  "$@"
  echo "   $((SECONDS - start)) s"
}

# The libraries the compiled module and sorpia-bench load: every one found, and each either grafted into
# sorpia.libs or one the manylinux policy lets a wheel take from the system.
check_libraries() {
  local venv=$1 file name path bad=0
  # auditwheel moves sorpia-bench to sorpia.scripts/ and leaves a launcher in bin/.
  local site=("$venv"/lib/python3*/site-packages)
  for file in "${site[0]}"/sorpia/_core*.so "${site[0]}"/sorpia.scripts/*; do
    [ -e "$file" ] || continue
    if ldd "$file" | grep -q "not found"; then
      ldd "$file"
      echo "$file: libraries not found" >&2
      return 1
    fi
    while read -r name path; do
      case "$path" in
        */sorpia.libs/*) echo "   $(basename "$file"): $name (in the wheel)" ;;
        *) case "$name" in
             libc.so.6|libm.so.6|libstdc++.so.6|libgcc_s.so.1|libpthread.so.0|libdl.so.2|librt.so.1)
               echo "   $(basename "$file"): $name (the system's, as manylinux allows)" ;;
             *) echo "$(basename "$file"): $name from $path, neither in the wheel nor allowed by manylinux" >&2
                bad=1 ;;
           esac ;;
      esac
    done < <(ldd "$file" | awk '$2 == "=>" { print $1, $3 }')
  done
  return "$bad"
}

selection() {
  (cd tests && "../$1/bin/python" -m pytest -q -p no:cacheprovider test_*.py)
}

versions() {
  "$1/bin/python" -c 'import numpy, scipy; print("numpy", numpy.__version__, "scipy", scipy.__version__)'
}

demo() {
  (cd home && "../$1/bin/sorpia" demo --out "demo-$1" | tail -n 12)
}

echo "clean root: $(. /etc/os-release && echo "$PRETTY_NAME"), $(python3 --version), $(ldd --version | head -n 1)"
step "np1: venv, the wheel without its dependencies (pip warns that scipy is missing: meant), numpy 1.26.4" \
  eval 'python3 -m venv np1 && np1/bin/pip install -q --no-compile --no-deps "$wheel" &&
        install np1 numpy==1.26.4 pytest'
step "np1: the compiled module's libraries" check_libraries np1
step "np1: import sorpia and the functions that need no scipy, without scipy" \
  bash -c "cd noscipy && ../np1/bin/python -m pytest -q -p no:cacheprovider test_without_scipy.py"
step "np1: sorpia demo (numpy 1.26.4, no scipy, no matplotlib)" demo np1
step "np1: scipy for numpy 1.26.4" install np1 scipy numpy==1.26.4
step "np1: pytest selection ($(versions np1))" selection np1
step "np2: venv, pip install of the wheel with its dependencies (numpy 2.x, scipy)" \
  eval 'python3 -m venv np2 && install np2 "numpy>=2" scipy pytest &&
        np2/bin/pip install -q --no-compile --no-index --find-links "$wheels" "$wheel" "numpy>=2"'
step "np2: sorpia demo" demo np2
step "np2: sorpia-bench (the executable, through auditwheel's launcher)" \
  eval 'np2/bin/sorpia-bench icosphere:3 | tail -n 2'
step "np2: pytest selection ($(versions np2))" selection np2

#!/usr/bin/env bash
# Coverage-guided fuzzing of sorpia's mesh file readers (libFuzzer, with
# AddressSanitizer and UndefinedBehaviorSanitizer). Not part of `make test`:
#
#   tests/fuzz/run.sh [seconds=600] [jobs=1]
#   tests/fuzz/run.sh triage        # only classify what is in build/fuzz/artifacts
#
# Needs clang and its runtime (Debian: apt-get install clang libclang-rt-14-dev)
# and the sorpia dependencies (libopenmesh-dev, libosd-dev). Builds
# build/fuzz/fuzz_readers, grows the corpus in build/fuzz/corpus (started from
# tests/fuzz/seeds) and writes any crashing input to build/fuzz/artifacts/.
# Reproduce one with: build/fuzz/fuzz_readers build/fuzz/artifacts/crash-...
set -euo pipefail
seconds=${1:-600}
jobs=${2:-1}
root=$(cd "$(dirname "$0")/../.." && pwd)
out="$root/build/fuzz"
CXX=${CXX:-clang++}
if ! command -v "$CXX" >/dev/null; then
  echo "run.sh: $CXX not found; install it with: apt-get install clang libclang-rt-14-dev" >&2
  exit 2
fi
mkdir -p "$out/corpus" "$out/artifacts"
# OpenSubdiv's headers: only a non-default prefix needs a flag (-isystem /usr/include breaks #include_next).
osd_h=$(find /usr/include /usr/local/include -path '*opensubdiv/far/topologyRefiner.h' -print -quit)
osd_flags=()
case "$osd_h" in /usr/include/*|"") ;; *) osd_flags=(-isystem "${osd_h%/opensubdiv/far/topologyRefiner.h}") ;; esac
cpp="$root/cpp"
# The readers, the topology validation and the limit: what a file goes through (the layers base, mesh, io, limit).
sources=("$cpp"/io/src/io.cpp "$cpp"/io/src/io_obj.cpp "$cpp"/io/src/io_off.cpp "$cpp"/io/src/io_ply.cpp
         "$cpp"/io/src/io_stl.cpp "$cpp"/mesh/src/topology.cpp "$cpp"/limit/src/limit.cpp
         "$cpp"/limit/src/limit_operator.cpp "$cpp"/limit/src/limit_operator_catmark.cpp "$cpp"/limit/src/limit_masks.cpp
         "$cpp"/base/src/interrupt.cpp "$cpp"/base/src/subdivision.cpp "$cpp"/limit/src/refined_rows.cpp)
includes=()
for layer in base mesh io limit; do includes+=(-I"$cpp/$layer/include" -I"$cpp/$layer/src"); done
if [ ! -x "$out/fuzz_readers" ] || [ -n "$(find "${sources[@]}" "$root/tests/fuzz/fuzz_readers.cpp" "$cpp" -newer "$out/fuzz_readers" -print -quit)" ]; then
  echo "building $out/fuzz_readers"
  "$CXX" -std=c++17 -g -O1 -fno-omit-frame-pointer -fsanitize=fuzzer,address,undefined \
    -fno-sanitize-recover=undefined -DSORPIA_VERSION='"fuzz"' \
    "${includes[@]}" "${osd_flags[@]}" \
    "$root/tests/fuzz/fuzz_readers.cpp" "${sources[@]}" \
    -o "$out/fuzz_readers" -lOpenMeshCore -losdCPU
fi
cp -n "$root"/tests/fuzz/seeds/* "$out/corpus/" 2>/dev/null || true
# OpenMesh and OpenSubdiv are not built with ASan: leaks inside them are not ours.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:allocator_may_return_null=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# Triage: what went wrong, one line per kind of finding, with a count and an example input.
triage() {
  export LC_ALL=C  # the messages may hold invalid UTF-8: sed must treat them as bytes
  echo "== findings in $out/artifacts (count, kind, example) =="
  for a in "$out"/artifacts/*; do
    [ -f "$a" ] || continue
    why=$("$out/fuzz_readers" "$a" 2>&1 | grep -a -m1 -E "sorpia fuzz finding|ERROR: AddressSanitizer|runtime error|ERROR: libFuzzer" |
          sed -E 's/(sorpia fuzz finding: [^:]*).*/\1/; s/0x[0-9a-f]+/0x?/g' || true)
    printf '%s\t%s\n' "${why:-no longer reproduces}" "$(basename "$a")"
  done | sort | awk -F'\t' '{n[$1]++; ex[$1]=$2} END {for (k in n) printf "%6d  %s  (e.g. %s)\n", n[k], k, ex[k]}'
}
if [ "$seconds" = triage ]; then
  triage
  exit 0
fi
# Fork mode with -ignore_*: one finding does not end the run; every crashing,
# leaking-memory or slow input is kept in artifacts/ and the run goes on.
"$out/fuzz_readers" "$out/corpus" -dict="$root/tests/fuzz/mesh.dict" \
  -artifact_prefix="$out/artifacts/" -max_total_time="$seconds" -fork="$jobs" \
  -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
  -max_len=65536 -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 || true
triage

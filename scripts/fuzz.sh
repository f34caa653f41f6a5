#!/usr/bin/env bash
# Build the libFuzzer harnesses (fuzz/) with clang-14 into their own folder and
# run each in turn for SECONDS (default 20), one at a time and at the lowest
# priority. Seeds come from fuzz/corpus/<harness>/ (read only); what the
# fuzzer adds goes to <build>/corpus/<harness>/, crashes to <build>/artifacts/.
# Exits non-zero when any harness finds a crash, leak, timeout or OOM.
#   GLINT_FUZZ_BUILD_DIR  build folder (default: <checkout>/build-fuzz)
#   GLINT_FUZZ_ONLY       run only this harness (exr, trace or raster)
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${GLINT_FUZZ_BUILD_DIR:-$root/build-fuzz}
seconds=${1:-20}

source "$root/scripts/ccache.sh"
# Only the library and the harnesses: no Python, tests, tools or GL (the
# harnesses drive the CPU backend and the EXR reader).
CC=clang-14 CXX=clang++-14 cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DGLINT_BUILD_FUZZERS=ON -DGLINT_SANITIZE=address,undefined -DGLINT_BUILD_PYTHON=OFF \
  -DGLINT_BUILD_TESTS=OFF -DGLINT_BUILD_TOOLS=OFF -DGLINT_BUILD_BENCHMARKS=OFF \
  -DGLINT_WITH_GL=OFF "${launcher[@]}" >/dev/null || exit 1
cmake --build "$build" -j2 || exit 1

export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
status=0
for h in exr trace raster; do
  [[ -n "${GLINT_FUZZ_ONLY:-}" && "$GLINT_FUZZ_ONLY" != "$h" ]] && continue
  work="$build/corpus/$h" artifacts="$build/artifacts/$h/"
  mkdir -p "$work" "$artifacts"
  echo "== fuzz_$h for ${seconds}s"
  # -timeout: a march or rasterization that takes 10 s on a 48x48 image is a hang.
  nice -n 19 "$build/fuzz/fuzz_$h" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$artifacts" "$work" "$root/fuzz/corpus/$h" 2>&1 |
    grep -E "^(#[0-9]+ +DONE|stat::number_of_executed_units|stat::peak_rss|==[0-9]+==ERROR|SUMMARY|artifact_prefix|Test unit written|.*Done [0-9]+ runs)" 
  rc=${PIPESTATUS[0]}
  if ((rc != 0)); then
    echo "fuzz_$h: FAILED (exit $rc); inputs in $artifacts"
    status=1
  fi
done
exit $status

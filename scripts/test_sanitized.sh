#!/usr/bin/env bash
# Build Glint with AddressSanitizer and UndefinedBehaviorSanitizer into its own
# folder and run the tests there: the C++ tests through ctest, then (unless
# --cpp-only) tests/python against the sanitized glint_core module. Any
# sanitizer report fails the run. See docs/hardening.md.
#   GLINT_ASAN_BUILD_DIR  build folder (default: <checkout>/build-asan)
#   --cpp-only            ctest only (what scripts/test.sh runs in CI)
# tests/addon imports no native code and tests/blender runs Blender, whose own
# binary is not built with ASan, so neither is run here.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${GLINT_ASAN_BUILD_DIR:-$root/build-asan}
cpp_only=0
[[ "${1:-}" == --cpp-only ]] && cpp_only=1

source "$root/scripts/ccache.sh"
# RelWithDebInfo: optimised enough that the marches finish within the tests'
# time limits, with line numbers in every report. No benchmarks: never run here.
# float-cast-overflow is named on its own: GCC's "undefined" leaves it out, and
# a NaN or huge coordinate turned into a pixel index is exactly that bug.
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DGLINT_SANITIZE=address,undefined,float-cast-overflow -DGLINT_BUILD_BENCHMARKS=OFF "${launcher[@]}" >/dev/null || exit 1
targets=()
# CI: what ctest runs (the C++ tests and the corpus replays), no module or tool.
((cpp_only)) && targets=(--target glint_tests fuzz_replay_exr fuzz_replay_trace fuzz_replay_raster)
cmake --build "$build" -j2 "${targets[@]}" || exit 1

# halt_on_error: the first report ends the process with a failure, so a test
# cannot pass over one. Leaks are checked in the C++ tests.
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:detect_stack_use_after_return=1"

status=0
echo "== ctest (address,undefined)"
ctest --test-dir "$build" --output-on-failure -j2 || status=1

if ((cpp_only == 0)); then
  echo "== pytest tests/python (address,undefined)"
  # /usr/bin/python3 is not built with ASan: the runtime must be loaded first,
  # ahead of the module that needs it, and libstdc++ with it, or ASan's
  # __cxa_throw hook finds no library to forward to on the first C++ exception
  # (a CHECK failure that ends the process). log_path: pytest captures the
  # test's stderr, so a report would otherwise vanish with the process.
  # Python's own allocations are not freed at exit by design: no leak check.
  preload="$(g++ -print-file-name=libasan.so) $(g++ -print-file-name=libstdc++.so.6)"
  logs="$build/asan-logs"
  rm -rf "$logs" && mkdir -p "$logs"
  cd "$root" && \
    GLINT_BUILD_DIR="$build" LD_PRELOAD="$preload" \
    ASAN_OPTIONS="halt_on_error=1:detect_leaks=0:log_path=$logs/asan" \
    UBSAN_OPTIONS="$UBSAN_OPTIONS:log_path=$logs/ubsan" \
    /usr/bin/python3 -m pytest -q -p no:cacheprovider tests/python || status=1
  if compgen -G "$logs/*" >/dev/null; then
    echo "sanitizer reports from the Python tests:"
    cat "$logs"/*
    status=1
  fi
fi
exit $status

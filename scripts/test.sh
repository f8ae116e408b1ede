#!/usr/bin/env bash
# Every hairdyn test: C++ (ctest), then pytest inside Debian's blender 3.4 binary, then pytest
# with the bpy module of the venv (bpy 5.0, Python 3.11), then with bpy 5.3 on Python 3.13
# (.venv313, where setup.sh found a Python 3.13). Every suite runs; the script fails if any
# failed.
set -uo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"

passed=0
failed=0
failures=()
suite() {
  local name=$1
  shift
  echo "=== $name: $*"
  if "$@"; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    failures+=("$name")
  fi
}

# The C++ tests again under AddressSanitizer + UndefinedBehaviorSanitizer (float-cast-overflow
# included) in their own build; the longest runs (the thread-count comparison, the LCP solver's
# tolerance against its time step and the real Sintel assets) stay in the plain suite to keep
# this one short.
sanitized_ctest() {
  # -O1 without debug info: the sanitizers' recommended level, and half the compile time
  # of RelWithDebInfo on two cores (reports still name the functions).
  cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS=-O1 -DHAIRDYN_SANITIZE=ON \
    -DHAIRDYN_BENCHMARKS=OFF -DPython_EXECUTABLE=/usr/bin/python3.11 >/dev/null &&
    cmake --build build-sanitize -j2 --target hairdyn_tests _native >/dev/null &&
    ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
      ctest --test-dir build-sanitize --output-on-failure --timeout 600 -j2 \
      -E 'SameResultOnAnyThreadCount|Sintel|DefaultSolverTolerance' &&
    sanitized_fuzz
}

# The bindings under the same sanitizers: the add-on's Python files beside the module built
# with them (build-sanitize/python/hairdyn), and the native fuzz's seeds against it. Python's
# own allocator is off, so that AddressSanitizer sees Python's objects too (a binding holding a
# handle to an object nothing owns reads freed memory there, where it crashes only at times in
# a plain run); the sanitizer runtime and libstdc++ are preloaded, as the module needs them
# loaded before Python's own libraries.
sanitized_fuzz() {
  local package=build-sanitize/python
  find "$package/hairdyn" -name '*.py' -delete # none left from files the add-on no longer has
  (cd addon && find hairdyn -name '*.py' -exec cp --parents {} "../$package/" \;) || return 1
  local preload seed log
  preload="$(g++ -print-file-name=libasan.so) $(g++ -print-file-name=libstdc++.so)"
  for seed in 1 2 3 4 5 6 7 8; do
    log="build-sanitize/native_fuzz_$seed.log"
    if ! LD_PRELOAD="$preload" PYTHONMALLOC=malloc ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 \
      UBSAN_OPTIONS=print_stacktrace=1 .venv/bin/python python_tests/native_fuzz.py "$package" \
      "$seed" 1500 >"$log" 2>&1; then
      tail -n 40 "$log"
      echo "the bindings' fuzz under the sanitizers failed (seed $seed): $log"
      return 1
    fi
  done
}

export HAIRDYN_ARTIFACTS="$ROOT/out/test_artifacts"
suite "Style (ruff, clang-format)" scripts/check_style.sh
suite "C++ (ctest)" ctest --test-dir build --output-on-failure --timeout 300
suite "C++ and the bindings' fuzz under ASan + UBSan (build-sanitize)" sanitized_ctest
suite "Python in the blender binary ($(blender --version 2>/dev/null | head -n 1))" \
  blender -b --factory-startup --python-exit-code 1 --python python_tests/run_in_blender.py -- -q -rs
suite "Python with the bpy module (bpy $(.venv/bin/python -c 'import importlib.metadata as m; print(m.version("bpy"))'))" \
  .venv/bin/python -m pytest python_tests -q -rs -p no:cacheprovider
if [ -x .venv313/bin/python ]; then
  suite "Python with the bpy module on Python 3.13 (bpy $(.venv313/bin/python -c 'import importlib.metadata as m; print(m.version("bpy"))'))" \
    .venv313/bin/python -m pytest python_tests -q -rs -p no:cacheprovider
else
  echo "=== Python with the bpy module on Python 3.13: skipped: no .venv313 (setup.sh makes it" \
       "only where a CPython 3.13 exists; this machine has none on PATH or under ~/.pyenv)"
fi

if ((failed)); then
  echo "failed suites: ${failures[*]}"
fi
echo "suites: $passed passed, $failed failed"
exit $((failed > 0))

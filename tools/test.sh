#!/usr/bin/env bash
# All tests: host build + ctest (unit, codec, port, cross-build checks), the
# same suite under AddressSanitizer/UBSan, the Python tests, and the vcan HIL
# test (natively where vcan exists, else inside a QEMU VM).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
source tools/setup.sh
jobs=$(nproc)
stages=0 # each stage exits the script on failure; count those that ran

echo "== host build and tests"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$jobs"
ctest --test-dir build --output-on-failure -j "$jobs"
stages=$((stages + 1))

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DHSTPF_SANITIZE=ON >/dev/null
cmake --build build-asan -j "$jobs"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan --output-on-failure -j "$jobs" -LE nosan
stages=$((stages + 1))

if [ -d tests/python ]; then
  echo "== Python tests"
  HSTPF_BUILD_DIR="$root/build" python -m pytest -q tests/python
  stages=$((stages + 1))
fi

if [ -x tests/hil/run_hil.sh ]; then
  echo "== HIL: hstpfd on vcan0"
  tests/hil/run_hil.sh
  stages=$((stages + 1))
fi
echo "== all test stages passed"
echo "stages: $stages passed, 0 failed"

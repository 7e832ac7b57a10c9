#!/usr/bin/env bash
# Compiler gates: the whole tree with gcc and clang, as C99 and C11, and
# lib/ as 32-bit code (-m32, built and run on the fuzz corpus of the
# estimator), all with -Werror (cmake/warnings.cmake). One line per gate;
# a compiler's output only when it fails. Usage: cmake/gates.sh [JOBS]
# Build directories: build-gate-*. Exit 1 if any gate fails.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
jobs=${1:-$(nproc)}
fail=0

gate() { # name cc std [extra cmake args...] -- build targets
  local name=$1 cc=$2 std=$3
  shift 3
  local args=() targets=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do args+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  targets=("$@")
  local dir="build-gate-$name" log t0
  log=$(mktemp)
  t0=$(date +%s)
  if ! command -v "$cc" >/dev/null 2>&1; then
    echo "  gate $name: SKIPPED ($cc not installed; tools/setup.sh installs it)"
    rm -f "$log"
    return 0
  fi
  local tflags=()
  for t in "${targets[@]}"; do tflags+=(--target "$t"); done
  if CC=$cc cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DHSTPF_C_STANDARD="$std" "${args[@]}" >"$log" 2>&1 &&
     cmake --build "$dir" -j "$jobs" "${tflags[@]}" >>"$log" 2>&1; then
    echo "  gate $name: ok ($(( $(date +%s) - t0 )) s)"
  else
    echo "  gate $name: FAILED"
    grep -E 'error|warning' "$log" | head -20
    fail=1
  fi
  rm -f "$log"
}

gate gcc-c11 gcc 11
gate clang-c99 clang 99
gate clang-c11 clang 11
# 32-bit: the library alone (no host programs: there is no 32-bit cmocka),
# then the estimator's fuzz replay linked to it and run on its seed corpus
for cc in gcc clang; do
  gate "$cc-m32" "$cc" 99 -DCMAKE_C_FLAGS=-m32 -DHSTPF_BUILD_HOST=OFF -- hstpf
  dir="build-gate-$cc-m32"
  [ -f "$dir/lib/libhstpf.a" ] || { command -v "$cc" >/dev/null 2>&1 && fail=1; continue; }
  if "$cc" -m32 -std=c99 -O2 -Wall -Wextra -Werror -pedantic -D_POSIX_C_SOURCE=200809L -Ilib/include \
       tests/fuzz/fuzz_filter.c tests/fuzz/replay_main.c "$dir/lib/libhstpf.a" -lm -o "$dir/fuzz_filter_replay" &&
     "$dir/fuzz_filter_replay" tests/fuzz/corpus/filter >/dev/null 2>&1; then
    echo "  gate $cc-m32 run: ok (the estimator on the fuzz seed corpus, 32-bit)"
  else
    echo "  gate $cc-m32 run: FAILED ($dir/fuzz_filter_replay tests/fuzz/corpus/filter)"
    fail=1
  fi
done
exit $fail

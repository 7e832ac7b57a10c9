#!/usr/bin/env bash
# Branch coverage of lib/ and port/src/ by gcovr, from a build made with
# --coverage whose tests have run (tools/test.sh: build-cov, ctest with
# the VM test included, so socketcan.c is counted from the run inside the
# VM: the guest mounts the host's file system and writes its .gcda files
# into build-cov). Prints the per-file table and fails below the floors.
# Usage: cmake/coverage.sh BUILD_DIR [--md]   (--md: markdown rows)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
build=$1
md=${2:-}

# Floors, percent of branches taken (gcovr's figure, rounded down): the
# goals of issue 11. Measured 95.6 % and 88.0 % (docs/quality.md, per
# file); the daemon's timing-dependent paths vary by a few branches between
# runs, and a VM test that stops early counts 19 fewer in socketcan.c.
LIB_FLOOR=95
PORT_FLOOR=85

command -v gcovr >/dev/null || { echo "coverage: gcovr not installed (tools/setup.sh installs it)" >&2; exit 2; }

table() { # filter regex -> gcovr text table
  gcovr -r . "$build" -f "$1" -b --txt 2>/dev/null
}
pct() { # the TOTAL line's percentage of a table on stdin
  awk '/^TOTAL/ { sub("%", "", $4); print $4 }'
}

lib=$(table 'lib/')
port=$(table 'port/src/')
if [ "$md" = "--md" ]; then
  printf '%s\n%s\n' "$lib" "$port" | awk '/^(lib|port)\// { printf "| %s | %s | %s | %s |\n", $1, $2, $3, $4 }'
  exit 0
fi
printf '%s\n' "$lib" | sed -n '/^File/,/^TOTAL/p'
printf '%s\n' "$port" | sed -n '/^lib\|^port/p;/^TOTAL/p'
lib_pct=$(printf '%s\n' "$lib" | pct)
port_pct=$(printf '%s\n' "$port" | pct)
rc=0
if [ "${lib_pct:-0}" -lt "$LIB_FLOOR" ]; then
  echo "coverage: lib/ branches ${lib_pct}% below the floor ${LIB_FLOOR}%" >&2
  rc=1
fi
if [ "${port_pct:-0}" -lt "$PORT_FLOOR" ]; then
  echo "coverage: port/src/ branches ${port_pct}% below the floor ${PORT_FLOOR}%" >&2
  rc=1
fi
echo "coverage: lib/ ${lib_pct}% (floor ${LIB_FLOOR}%), port/src/ ${port_pct}% (floor ${PORT_FLOOR}%) of branches"
exit $rc

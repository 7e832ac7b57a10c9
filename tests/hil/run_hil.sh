#!/usr/bin/env bash
# The HIL stage of tools/test.sh (tests/hil/hil_replay.sh): the simulated
# run on the host, the bus part of the replay test (hstpfd on vcan0,
# natively where vcan exists, else in the QEMU VM of tests/hil/vm), then its
# scoring and checks on the host.
#   tests/hil/run_hil.sh [BUILD_DIR]
# HSTPF_HIL_KEEP=DIR keeps the run's files (logs, summaries, scores, plots).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=${1:-$root/build}
dir=$(mktemp -d "${TMPDIR:-/tmp}/hstpf-hil.XXXXXX")
keep=${HSTPF_HIL_KEEP:-}
trap '[ -z "$keep" ] || { mkdir -p "$keep" && cp -r "$dir"/. "$keep"/; }; rm -rf "$dir"' EXIT
"$root/tests/hil/hil_replay.sh" --sim "$dir"
t0=$(date +%s)
"$root/tests/hil/with_vcan.sh" "$root/tests/hil/hil_replay.sh" --bus "$dir" "$build"
t1=$(date +%s)
"$root/tests/hil/hil_replay.sh" --score "$dir"
t2=$(date +%s)
echo "hil: 2 replays passed (bus part $((t1 - t0)) s, scoring $((t2 - t1)) s)"

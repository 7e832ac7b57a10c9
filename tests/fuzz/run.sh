#!/usr/bin/env bash
# Runs one libFuzzer target for a bounded time on a copy of its seed corpus
# and prints one line of figures. Usage:
#   tests/fuzz/run.sh BUILD_DIR TARGET SECONDS [WORK_DIR]
# BUILD_DIR holds build-fuzz's tests/fuzz/fuzz_TARGET (tools/test.sh makes
# it); WORK_DIR (default a temporary directory, removed after) keeps the
# grown corpus and any crash reproducer (crash-*, leak-*, timeout-*).
# Exit status: 0 no finding, 1 a finding (reproducer path printed).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
build=$1 target=$2 secs=$3
work=${4:-}
bin="$build/tests/fuzz/fuzz_$target"
[ -x "$bin" ] || { echo "fuzz: no $bin (build it with -DHSTPF_FUZZ=ON and clang)" >&2; exit 2; }
tmp=""
if [ -z "$work" ]; then
  tmp=$(mktemp -d)
  work=$tmp
fi
trap '[ -n "$tmp" ] && rm -rf "$tmp"' EXIT
mkdir -p "$work/corpus"
cp -n "$here/corpus/$target/"* "$work/corpus/" 2>/dev/null || true
dict=()
[ -f "$here/$target.dict" ] && dict=(-dict="$here/$target.dict")
log="$work/fuzz.log"
set +e
# one process, one job: the machine's cores are shared; rss limit 2 GB
"$bin" -max_total_time="$secs" -timeout=25 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/" "${dict[@]}" "$work/corpus" >"$log" 2>&1
rc=$?
set -e
execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
corpus=$(find "$work/corpus" -type f | wc -l)
if [ "$rc" -ne 0 ]; then
  art=$(ls "$work"/crash-* "$work"/leak-* "$work"/timeout-* "$work"/oom-* 2>/dev/null | head -1 || true)
  echo "fuzz $target: FINDING after ${execs:-?} executions (${secs} s); reproducer: ${art:-none}" >&2
  grep -E 'fuzz invariant|runtime error|ERROR: (AddressSanitizer|libFuzzer|LeakSanitizer)' "$log" | head -3 >&2
  if [ -n "$tmp" ] && [ -n "$art" ]; then
    keep="${TMPDIR:-/tmp}/hstpf-fuzz-$target-$(basename "$art")"
    cp "$art" "$keep"
    echo "fuzz $target: reproducer kept as $keep" >&2
  fi
  exit 1
fi
echo "fuzz $target: ${secs} s, ${execs:-0} executions, coverage ${cov:-0} edges (${ft:-0} features), corpus $corpus inputs, no finding"

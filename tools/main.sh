#!/usr/bin/env bash
# The main job: a paper Case 1 run through the bus. hstpf-simulate writes the
# E2E-protected position and traction frames (candump log) and the truth;
# hstpfd estimates from the log on the same code path as on a CAN interface
# and writes its own frames; hstpf-score decodes them with the DBC, compares
# with the truth and draws the plots. Options go to hstpf-simulate (e.g.
# --type SS8 --noise case2 --seed 3).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
source tools/setup.sh >&2
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" >/dev/null
out=out/main
mkdir -p "$out"
config=port/config/case1.ini
for a in "$@"; do [ "$a" = case2 ] && config=port/config/case2.ini; done
echo "== simulate (paper Case 1 unless told otherwise)"
hstpf-simulate --type CRH3 --profile paper --noise case1 --duration 1800 --seed 1 "$@" -o "$out/run.log"
echo "== hstpfd --log $out/run.log  ($config)"
build/port/hstpfd --config "$config" --log "$out/run.log" --frames-out "$out/bus.log" --frames-out-inputs 1 \
  --out "$out/steps.jsonl" --summary "$out/summary.json" > /dev/null
python3 -c "
import json; s = json.load(open('$out/summary.json'))
print('declared :', s['declared'], '(%s)' % s['status'], 'at t = %s s' % s['decision_time_s'])
print('theta    : c0 = %.4f  c1 = %.6f  c2 = %.7f' % tuple(s['theta']))
print('weights  :', ', '.join('%s %.4f' % kv for kv in s['weights'].items()))
print('state    : s = %.1f m, v = %.2f km/h' % (s['position_m'], 3.6 * s['speed_mps']))
"
echo "== hstpf-score against the truth"
hstpf-score "$out/bus.log" --truth "$out/run_truth.csv" --input-log "$out/run.log" --plots "$out/plots" \
  --json "$out/score.json"
echo
echo "summary: $out/summary.json   every step: $out/steps.jsonl   plots: $out/plots/"

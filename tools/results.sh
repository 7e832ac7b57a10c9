#!/usr/bin/env bash
# Regenerates docs/results: every Monte Carlo scenario (100 seeds each), the
# Case 2 ablation, and the figures. A few minutes on 2 cores.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
source tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" >/dev/null
mc=build/tools/montecarlo/hstpf-mc
out=out/results
mkdir -p "$out" docs/img
# One setting for every case and truth; only the noise model is the case's.
settings=(--edge-soft 0.2)
seeds=${HSTPF_SEEDS:-100}
for s in paper1 paper2 all17 all17-coast all17-coast-loss hilly-ignored hilly-known; do
  echo "== $s"
  trace=()
  n=$seeds
  case $s in paper1|paper2) trace=(--trace "$out/trace_$s.csv") ;; hilly-*) n=$(( seeds < 30 ? seeds : 30 )) ;; esac
  "$mc" --scenario "$s" --seeds "$n" "${settings[@]}" --json "$out/$s.json" "${trace[@]}" | tee "$out/$s.txt"
done
echo "== Case 2 ablation"
{
  echo "variant | result"
  for v in "base:--edge-soft 0.2" "hard edge:--edge-soft 0" "no roughening:--edge-soft 0.2 --rough 0" \
           "resample always:--edge-soft 0.2 --resample always" "paper Eq.13:--edge-soft 0.2 --weights paper" \
           "shallow floor 10:--edge-soft 0.2 --floor-depth 10" "deep floor 1000:--edge-soft 0.2 --floor-depth 1000"; do
    name=${v%%:*}; args=${v#*:}
    # shellcheck disable=SC2086
    echo "$name | $("$mc" --scenario paper2 --seeds "$seeds" $args 2>/dev/null | tail -1)"
  done
} | tee "$out/ablation_case2.txt"
python tools/figures/make_figures.py --trace1 "$out/trace_paper1.csv" --trace2 "$out/trace_paper2.csv" \
  --json "$out"/paper1.json "$out"/paper2.json "$out"/all17.json "$out"/all17-coast.json "$out"/all17-coast-loss.json \
  --out docs/img

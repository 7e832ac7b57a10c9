#!/usr/bin/env bash
# Regenerates docs/results: every Monte Carlo scenario (100 seeds each), the
# journeys, the Case 2 ablation, and the figures (docs/results.md gives the
# time it took when last run whole; hours of CPU). Name sections to run only
# those: tools/results.sh journeys offtable (--list names them; a section
# reads only its own outputs, but oracle those of cases and journeys, and
# figures those of cases). HSTPF_SEEDS sets most scenarios' seeds (100);
# HSTPF_GRID17_SEEDS only those of issue 13's 17-model grid scenarios, the
# slowest (default HSTPF_SEEDS).
set -euo pipefail
sections=(cases journeys offtable prior spread norefine particle issue13 cells offtable-t offtable-case2 oracle
          journeys-case2 lattice declaration ablation figures)
usage() {
  echo "usage: $0 [--list] [SECTION ...]   (no SECTION: all of them, in order)" >&2
  exit 2
}
only=()
for a in "$@"; do
  case $a in
  --list) printf '%s\n' "${sections[@]}"; exit 0 ;;
  -h|--help) usage ;;
  *) [[ " ${sections[*]} " == *" $a "* ]] || { echo "$0: no section '$a' (--list names them)" >&2; usage; }
     only+=("$a") ;;
  esac
done
# section NAME: run it? (every section when none is named)
section() {
  [ ${#only[@]} -eq 0 ] && return 0
  [[ " ${only[*]} " == *" $1 "* ]]
}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
source tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" >/dev/null
mc=build/tools/montecarlo/hstpf-mc
out=out/results
mkdir -p "$out" docs/img
# One setting for every case and truth; only the noise model is the case's.
# Library defaults otherwise: engine auto (Kalman for Gaussian noise, the
# grid for any other), M = 100, declaration at q > 0.99 held 30 s. The two
# below act on the particle engine only.
settings=(--e-blur 0.2 --rough 0.7)
seeds=${HSTPF_SEEDS:-100}
gseeds=${HSTPF_GRID17_SEEDS:-$seeds}
if section cases; then
for s in paper1 paper2 all17 all17-coast all17-coast-loss hilly-ignored hilly-known; do
  echo "== $s"
  trace=()
  case $s in paper1|paper2) trace=(--trace "$out/trace_$s.csv") ;; esac
  oracle=()
  case $s in paper1|paper2|all17) oracle=(--oracle) ;; esac # the on-table oracle (below) rides along
  "$mc" --scenario "$s" --seeds "$seeds" "${settings[@]}" "${oracle[@]}" --json "$out/$s.json" "${trace[@]}" | tee "$out/$s.txt"
done
fi
if section journeys; then
echo "== journeys: 17 types, the library's defaults (no option), Case 1 noise"
for s in stops day start300 start300-prior clock+30 clock-30 clock+1 clock+3-t outage outage-stop gain5 restart tracgap silent swap swap-near gap29 fix5 stuck30 late10 late60 shunt4; do
  echo "== $s"
  oracle=()
  case $s in stops) oracle=(--oracle) ;; esac
  "$mc" --scenario "$s" --seeds "$seeds" "${oracle[@]}" --json "$out/$s.json" | tee "$out/$s.txt"
done
# the traction gap as hstpfd fed it before the twenty-fifth session (the last value), and on the particle engine
"$mc" --scenario tracgap --seeds "$seeds" --gap-hold | tee "$out/tracgap-hold.txt"
"$mc" --scenario tracgap --seeds "$seeds" --engine particle | tee "$out/tracgap-particle.txt"
# a consist coupled or split during a 5-min stop: the library's consist_change_p, and without it
for s in couple couple-near; do
  echo "== $s"
  "$mc" --scenario "$s" --seeds "$seeds" --json "$out/$s.json" | tee "$out/$s.txt"
  "$mc" --scenario "$s" --seeds "$seeds" --consist-p 0 | tee "$out/$s-p0.txt"
done
# a unit stepped at 10 Hz, a fix every step: Case 1's train (noises scaled to 0.1 s) and Case 1's
# figures taken per 0.1 s step, on the line and on the paper's run, with the traction check and without it
for s in stops-10hz all17-10hz stops-10hz-raw all17-10hz-raw late60-10hz fixbias20-10hz stopstep12-10hz; do
  echo "== $s"
  "$mc" --scenario "$s" --seeds "$seeds" --json "$out/$s.json" | tee "$out/$s.txt"
  "$mc" --scenario "$s" --seeds "$seeds" --no-traction-check | tee "$out/$s-nocheck.txt"
done
# a traction present but wrong (its sign swapped; a gain 20 % low), with the traction check and without it
for s in tracsign gain-20; do
  echo "== $s"
  "$mc" --scenario "$s" --seeds "$seeds" --json "$out/$s.json" | tee "$out/$s.txt"
  "$mc" --scenario "$s" --seeds "$seeds" --no-traction-check | tee "$out/$s-nocheck.txt"
done
# steps in the fixes' reference (a GNSS bias, lone outliers), with cfg.fix_step and without it
for s in fixbias20 fixbias14 fixbias10 spikes20 burst100 burst100-t stopstep12 stopstep-12 stopstep12-t stopstep12-mix fixbias20-t late60-t; do
  echo "== $s"
  "$mc" --scenario "$s" --seeds "$seeds" --json "$out/$s.json" | tee "$out/$s.txt"
  "$mc" --scenario "$s" --seeds "$seeds" --no-fix-step | tee "$out/$s-nostep.txt"
done
fi
if section offtable; then
echo "== trains not on Table 1: defaults (the continuous hypothesis on), then without it"
for s in off10 off15 off20 grade8 mass10 mass20 absent gain-5; do
  echo "== $s"
  # --oracle: also when the data can tell the truth from a row (its own line; the filter's figures unchanged)
  "$mc" --scenario "$s" --seeds "$seeds" --oracle --json "$out/$s.json" | tee "$out/$s.txt"
  "$mc" --scenario "$s" --seeds "$seeds" --no-refine | tee "$out/$s-norefine.txt"
done
fi
if section prior; then
echo "== the continuous hypothesis's prior weight: on-table speed against off-table safety"
for q in 0.03 0.02 0.003 0.001; do
  for s in paper1 all17 off15 mass20 absent grade8; do
    "$mc" --scenario "$s" --seeds "$seeds" --refine-prior "$q" | tee "$out/$s-prior$q.txt"
  done
done
fi
if section spread; then
echo "== the rows' spread (refine_spread, default 0.3): the band against the decisions"
for sp in 0.2 0.4; do
  for s in paper1 all17 stops off10 off15 off20 mass10 mass20 absent; do
    "$mc" --scenario "$s" --seeds "$seeds" --refine-spread "$sp" | tee "$out/$s-spread$sp.txt"
  done
done
fi
if section norefine; then
echo "== on-table figures without the continuous hypothesis"
for s in paper1 all17 stops; do
  "$mc" --scenario "$s" --seeds "$seeds" --no-refine | tee "$out/$s-norefine.txt"
done
.venv/bin/python tools/figures/theta_limit.py --json "$out/theta_limit.json" | tee "$out/theta_limit.txt"
.venv/bin/python tools/figures/theta_limit.py --scale 1.1 1.1 1.1 | tee "$out/theta_limit_mass10.txt"
.venv/bin/python tools/figures/theta_limit.py --scale 1.2 0.8 1.2 | tee "$out/theta_limit_off20.txt"
fi
if section particle; then
echo "== particle engine on the Gaussian cases (the paper's method) and on Case 2"
for s in paper1 all17 paper2; do
  "$mc" --scenario "$s" --seeds "$seeds" "${settings[@]}" --engine particle | tee "$out/$s-particle.txt"
done
fi
if section issue13; then
echo "== issue 13: all 17 types with Case 2 noise, and heavy-tailed position noise; grid and particle engines"
# 17 models on the grid engine cost about 2 s of CPU per 1800-s run, so a
# scenario of 1700 runs is about an hour of CPU (docs/results.md gives the
# measured times): HSTPF_GRID17_SEEDS sets their seeds (default: the study's).
# The grid engine takes no option (it has no blur or roughening); the
# particle engine keeps the study's settings, at the library's M and at 256;
# a table density takes no blur, so the heavy scenarios' particles have only
# the roughening.
for s in all17-case2 all17-coast-case2; do
  echo "== $s"
  "$mc" --scenario "$s" --seeds "$gseeds" --engine grid --json "$out/$s-grid.json" | tee "$out/$s-grid.txt"
  "$mc" --scenario "$s" --seeds "$gseeds" "${settings[@]}" --engine particle \
    --json "$out/$s-particle.json" | tee "$out/$s-particle.txt"
  "$mc" --scenario "$s" --seeds "$gseeds" "${settings[@]}" --engine particle --particles 256 \
    --json "$out/$s-particle256.json" | tee "$out/$s-particle256.txt"
done
for s in heavy-t heavy-mix; do
  echo "== $s"
  "$mc" --scenario "$s" --seeds "$gseeds" --engine grid --json "$out/$s-grid.json" | tee "$out/$s-grid.txt"
  # every row on the grid (the default until the eighteenth session: grid_rows, docs/grid.md)
  "$mc" --scenario "$s" --seeds "$gseeds" --engine grid --grid-rows 0 --json "$out/$s-grid-allrows.json" \
    | tee "$out/$s-grid-allrows.txt"
  "$mc" --scenario "$s" --seeds "$gseeds" --rough 0.7 --engine particle --particles 256 \
    --json "$out/$s-particle256.json" | tee "$out/$s-particle256.txt"
  # reference: the filter told only a Gaussian of the noise's sd (the Kalman engine)
  "$mc" --scenario "$s" --seeds "$gseeds" --gauss-e --json "$out/$s-gauss.json" | tee "$out/$s-gauss.txt"
done
fi
if section cells; then
echo "== the grid's cells (position x speed): paper Case 2 on seeds 1-100 and 1001-1100"
# Each shape is a compile-time capacity: the library built again at it.
for shape in "48 48" "24 96" "20 72"; do
  set -- $shape
  b=build-grid-$1x$2
  cmake -S . -B "$b" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_C_FLAGS="-DHSTPF_GRID_NS=$1 -DHSTPF_GRID_NV=$2" >/dev/null
  cmake --build "$b" -j "$(nproc)" --target hstpf-mc >/dev/null
  for first in 1 1001; do
    echo "$1 x $2 | seeds $first.. | $("$b/tools/montecarlo/hstpf-mc" --scenario paper2 --seeds "$seeds" \
      --first-seed "$first" | tail -1)"
  done
done | tee "$out/grid_cells.txt"
fi
if section offtable-t; then
echo "== trains not on Table 1 with Student-t fixes: the grid engine's continuous hypothesis"
for s in stops-t off15-t grade8-t restart-t tracgap-t; do
  "$mc" --scenario "$s" --seeds "$gseeds" --json "$out/$s.json" | tee "$out/$s.txt"
done
# the line with stops with every row on the grid: the truth's declaration, paired with the defaults' 3 rows
"$mc" --scenario stops-t --seeds "$gseeds" --grid-rows 0 --json "$out/stops-t-allrows.json" | tee "$out/stops-t-allrows.txt"
for s in off15-t grade8-t; do
  "$mc" --scenario "$s" --seeds "$gseeds" --no-refine | tee "$out/$s-norefine.txt"
done
fi
if section offtable-case2; then
echo "== trains not on Table 1 under Case 2 noise: the defaults (the hypothesis on its own grid since the"
echo "   fifteenth session) and the rows alone (--no-refine; what the defaults did before)"
# HSTPF_OFF_CASE2_SEEDS: seeds per truth (17 models x 1800 s: about 40 min of CPU per 100 seeds)
oseeds=${HSTPF_OFF_CASE2_SEEDS:-$gseeds}
for s in off15-case2 grade8-case2 mass20-case2 absent-case2; do
  "$mc" --scenario "$s" --seeds "$oseeds" --oracle --json "$out/$s.json" | tee "$out/$s.txt"
  "$mc" --scenario "$s" --seeds 10 --first-seed 11 --no-refine --json "$out/$s-norefine.json" | tee "$out/$s-norefine.txt"
done
fi
if section oracle; then
echo "== what the data allow (hstpf-mc --oracle): on the table, when the row leads every train 10 % from it"
echo "   by log 99 (the off-table runs above carry their own oracle lines); docs/results.md, Seventeenth session"
for s in paper1 paper2 all17 stops; do # run above with --oracle: their oracle lines
  grep '^oracle' "$out/$s.txt" | tee "$out/$s-oracle.txt"
done
"$mc" --scenario paper2 --seeds "$seeds" --oracle-gauss | tee "$out/paper2-oracle-gauss.txt"
"$mc" --scenario all17-case2 --seeds "${HSTPF_ORACLE17_SEEDS:-20}" --oracle | tee "$out/all17-case2-oracle.txt"
fi
if section journeys-case2; then
echo "== issue 13's journey: the line with stops, Case 2 noise, 17 types (the grid engine by default)"
"$mc" --scenario stops-case2 --seeds "$gseeds" --json "$out/stops-case2.json" | tee "$out/stops-case2.txt"
# HSTPF_EVENTS_CASE2_SEEDS: their seeds per truth (20; docs/results.md's figures are at 100, about 20 min each)
eseeds=${HSTPF_EVENTS_CASE2_SEEDS:-20}
for s in start300-case2 clock+30-case2 clock-30-case2 outage-case2; do
  "$mc" --scenario "$s" --seeds "$eseeds" --json "$out/$s.json" | tee "$out/$s.txt"
done
# the same journeys through the daemon (hstpfd --log, its defaults, models = all, noise = case2)
tools/journeys_case2.sh --seeds 5 --out "$out/journeys-case2" | tee "$out/journeys-case2.txt"
fi
if section lattice; then
echo "== the grid's speed lattice (cfg.grid_speed_lattice, the default): paper Case 2 on seeds 1-2000"
echo "   with it and without it (the remapped box, the default until the thirteenth session; docs/grid.md)"
"$mc" --scenario paper2 --seeds 2000 --json "$out/paper2-2000.json" | tail -1 | tee "$out/paper2-2000.txt"
"$mc" --scenario paper2 --seeds 2000 --no-speed-lattice --json "$out/paper2-remap.json" | tee "$out/paper2-remap.txt"
# the grid against a particle filter on the exact Case 2 densities, seed by seed
.venv/bin/python tools/figures/oracle_case2.py --mc "$mc" --seeds 20 --particles 50000 | tee "$out/oracle_case2.txt"
fi
if section declaration; then
echo "== declaration rule (17 types, both engines)"
{
  echo "engine | threshold | hold [s] | result"
  for r in "kalman 0.9 30" "kalman 0.9 300" "kalman 0.99 30" "kalman 0.99 60" "particle 0.9 30"; do
    set -- $r
    echo "$1 | $2 | $3 | $("$mc" --scenario all17 --seeds "$seeds" "${settings[@]}" --engine "$1" \
      --threshold "$2" --hold "$3" | tail -1)"
  done
  echo "particle | 0.99 | 30 | $(tail -1 "$out/all17-particle.txt")"
} | tee "$out/declaration_rule.txt"
fi
if section ablation; then
echo "== Case 2 ablation"
{
  echo "variant | result"
  for v in "base:--e-blur 0.2 --rough 0.7" "no blur, soft edge 0.2:--edge-soft 0.2 --rough 0.7" \
           "no blur, soft edge 0.2, roughening 0.2 (first session):--edge-soft 0.2" \
           "no blur, hard edge:--rough 0.7" "roughening 0.2:--e-blur 0.2" "no roughening:--e-blur 0.2 --rough 0" \
           "resample always:--e-blur 0.2 --rough 0.7 --resample always" \
           "paper Eq.13:--e-blur 0.2 --rough 0.7 --weights paper" \
           "shallow floor 10:--e-blur 0.2 --rough 0.7 --floor-depth 10" \
           "deep floor 700 (the largest the library takes):--e-blur 0.2 --rough 0.7 --floor-depth 700" \
           "threshold 0.9:--e-blur 0.2 --rough 0.7 --threshold 0.9" \
           "M = 256:--e-blur 0.2 --rough 0.7 --particles 256"; do
    name=${v%%:*}; args=${v#*:}
    # shellcheck disable=SC2086
    row=$("$mc" --scenario paper2 --seeds "$seeds" --engine particle $args 2>/dev/null | tail -1) || true
    [[ $row == CRH3* ]] || { echo "ablation '$name' failed: hstpf-mc --scenario paper2 $args" >&2; exit 1; }
    echo "$name | $row"
  done
} | tee "$out/ablation_case2.txt"
fi
if section figures; then
python tools/figures/make_figures.py --trace1 "$out/trace_paper1.csv" --trace2 "$out/trace_paper2.csv" \
  --json "$out"/paper1.json "$out"/paper2.json "$out"/all17.json "$out"/all17-coast.json "$out"/all17-coast-loss.json \
  --out docs/img
fi

#!/usr/bin/env bash
# HIL test (issue 3): hstpfd on vcan0, fed by hstpf-replay of a simulated
# paper Case 1 run played 10 x faster, its frames recorded by hstpf-record
# and scored against the truth by hstpf-score. The fixes carry their fix
# time and the estimates theirs (EstQuality.EstTime); hstpfd dates the
# traction and its predictions by the fixes' latency, so the accuracy
# checks hold however late the replay, the VM or hstpfd run (issue 12;
# docs/vm.md). Then the same with faults injected (corrupt, duplicate,
# drop, a 2 s silence): each must be detected and counted as injected, and
# CRH3 still declared.
#
#   hil_replay.sh [BUILD_DIR]          all of it (needs vcan0)
#   hil_replay.sh --sim DIR            only the simulated run, into DIR
#   hil_replay.sh --bus DIR [BUILD]    only the bus part (simulating first if
#                                      DIR has no run yet), its files into DIR
#   hil_replay.sh --score DIR          only the scoring and the checks of DIR
#
# tests/hil/run_hil.sh simulates and scores on the host and runs only the bus
# part through tests/hil/with_vcan.sh (vcan0 natively or in the QEMU VM):
# under the VM's emulation numpy, the simulation and the plots took most of
# the stage's time.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
phase=all
case "${1:-}" in
--sim | --bus | --score) phase=${1#--}; dir=${2:?"$1 needs a folder"}; shift 2 ;;
esac
iface=${HSTPF_VCAN_IFACE:-vcan0}
export CAN_INTERFACE=socketcan # python-can has no default interface; -c names the channel
speed=${HSTPF_HIL_SPEED:-10}
dur=${HSTPF_HIL_DURATION:-600}
if [ "$phase" = all ]; then
  tmp=$(mktemp -d "${TMPDIR:-/tmp}/hstpf-hil.XXXXXX")
  # HSTPF_HIL_KEEP=DIR: copy the run's files (logs, summaries, scores) there
  keep=${HSTPF_HIL_KEEP:-}
  trap 'kill $(jobs -p) 2>/dev/null || true; [ -z "$keep" ] || { mkdir -p "$keep" && cp -r "$tmp"/. "$keep"/; }; rm -rf "$tmp"' EXIT
else
  mkdir -p "$dir"
  tmp=$(cd "$dir" && pwd)
  trap 'kill $(jobs -p) 2>/dev/null || true' EXIT
fi
fail() { echo "hil_replay: FAIL: $*" >&2; cat "$tmp"/*.err >&2 2>/dev/null || true; exit 1; }

bus_once() { # name, replay options...
  local name=$1 pid rec
  shift
  "$bin" --iface "$iface" --config "$root/port/config/case1.ini" --time-scale "$speed" \
      --summary "$tmp/$name.summary.json" > "$tmp/$name.out" 2> "$tmp/$name.hstpfd.err" &
  pid=$!
  hstpf-record -c "$iface" -o "$tmp/$name.bus.log" --quiet 3 --first-timeout 60 2> "$tmp/$name.record.err" &
  rec=$!
  sleep 2
  kill -0 $pid 2>/dev/null || fail "$name: hstpfd did not start"
  hstpf-replay "$tmp/run.log" -c "$iface" --speed "$speed" "$@" > "$tmp/$name.replay.json" \
      2> "$tmp/$name.replay.err" || fail "$name: replay failed"
  sleep 1
  kill -TERM $pid
  wait $pid || fail "$name: hstpfd exit status $? after SIGTERM"
  wait $rec || true
}

score_once() { # name
  local name=$1
  hstpf-score "$tmp/$name.bus.log" --truth "$tmp/run_truth.csv" --input-log "$tmp/run.log" --speed "$speed" \
      --json "$tmp/$name.score.json" --plots "$tmp/$name-plots" > "$tmp/$name.score.txt" 2> "$tmp/$name.score.err" \
      || fail "$name: score failed"
  echo "== $name"; cat "$tmp/$name.score.txt"
}

if [ "$phase" != score ] && { [ "$phase" != bus ] || [ ! -s "$tmp/run.log" ]; }; then
  hstpf-simulate --type CRH3 --profile paper --noise case1 --duration "$dur" --seed 7 -o "$tmp/run.log" > "$tmp/sim.json"
fi
[ "$phase" != sim ] || exit 0
if [ "$phase" != score ]; then
  bin=$(cd "${1:-$root/build}" && pwd)/port/hstpfd
  bus_once clean
  bus_once faults --ids 0x100,0x101 --seed 3 --corrupt 0.01 --duplicate 0.01 --drop 0.01 --silence-window 300:302
  [ "$phase" = all ] || { echo "hil_replay: bus part done, files in $tmp"; exit 0; }
fi
score_once clean
score_once faults

python3 - "$tmp" <<'PY' || fail "checks failed"
import json, sys
tmp = sys.argv[1]
ok = True
def check(cond, what):
    global ok
    print(("pass  " if cond else "FAIL  ") + what)
    ok = ok and cond
for name in ("clean", "faults"):
    s = json.load(open(f"{tmp}/{name}.summary.json"))
    sc = json.load(open(f"{tmp}/{name}.score.json"))
    check(s["declared"] == "CRH3", f"{name}: declared {s['declared']} (CRH3)")
    # Monte Carlo, Case 1 with the library's defaults (the continuous-theta
    # hypothesis on): the worst of 100 seeds crosses at 707 s
    # (docs/results.md); 800 s leaves room for the VM's timing jitter
    check(0 < s["decision_time_s"] <= 800, f"{name}: decision at {s['decision_time_s']} s (<= 800 s)")
    th = s["theta"]
    err = max(abs(th[0] - 0.79) / 0.79, abs(th[1] - 0.0064) / 0.0064, abs(th[2] - 0.000115) / 0.000115)
    check(err < 0.05, f"{name}: theta within 5 % of CRH3 ({100 * err:.2f} %)")
    # accuracy against the truth: better than the raw measurement (sd sqrt 5),
    # however late the replay delivered the fixes (fixes, traction and
    # estimates dated by the fix clock; docs/vm.md, five runs under a CPU hog)
    check(sc["position_rms_m"] < 5 ** 0.5, f"{name}: position RMS {sc['position_rms_m']:.2f} m (< 2.24 m, the measurement's)")
    check(sc["speed_rms_mps"] < 1.0, f"{name}: speed RMS {sc['speed_rms_mps']:.2f} m/s (< 1 m/s)")
    # the fixes dated by their own time, the estimates by theirs (docs/can.md)
    check(s["scheduler"]["fix_dated"] >= 0.9 * s["frames"]["position"],
          f"{name}: {s['scheduler']['fix_dated']} of {s['frames']['position']} fixes dated by FixTime")
    check(sc["state_frames_dated"] >= 0.9 * sc["state_frames"],
          f"{name}: {sc['state_frames_dated']} of {sc['state_frames']} estimates dated by EstTime")
    lat = sc["inputs"].get("rx_latency_ms", {})
    rp = json.load(open(f"{tmp}/{name}.replay.json"))
    print(f"      late fixes (older than the last step, dropped) {s['faults']['late_position']}, "
          f"fix clock re-dated {s['scheduler']['fix_clock_steps']}, replay {rp.get('wall_s')} s wall, "
          f"sent up to {rp.get('behind_s', {}).get('max')} s behind schedule")
    print(f"      receive latency of the fixes (fix-clock ms, x{1 / sc['inputs'].get('rx_s_per_fix_s', 1):.1f} replay): "
          f"p50 {lat.get('p50')}, p99 {lat.get('p99')}, max {lat.get('max')}")
    print(f"      score: {json.dumps({k: sc[k] for k in sc if not isinstance(sc[k], (dict, list))})[:400]}")
f = json.load(open(f"{tmp}/faults.summary.json"))["faults"]
inj = json.load(open(f"{tmp}/faults.replay.json"))["totals"]
# isolated faults map one to one; neighbours can merge (docs/can.md): 10 %
near = lambda a, b: abs(a - b) <= max(2, 0.1 * b)
check(near(f["bad_crc"], inj["corrupt"]), f"faults: bad CRC counted {f['bad_crc']} of {inj['corrupt']} corrupted")
check(near(f["repeated"], inj["duplicate"]), f"faults: repeated counter {f['repeated']} of {inj['duplicate']} duplicated")
check(f["lost"] + f["counter_jump"] >= 0.9 * inj["drop"], f"faults: lost+jump {f['lost'] + f['counter_jump']} for {inj['drop']} dropped")
check(f["stale_events"] >= 1, f"faults: 2 s silence counted as stale ({f['stale_events']} events)")
sys.exit(0 if ok else 1)
PY
echo "hil_replay: 2 runs passed"

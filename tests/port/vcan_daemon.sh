#!/usr/bin/env bash
# The hstpfd socket path on a virtual CAN bus: run through
#   tests/hil/with_vcan.sh tests/port/vcan_daemon.sh BUILD_DIR
# (vcan0 natively, or inside the QEMU VM). Needs root for ip link.
#
# hstpfd runs on vcan0 while hstpfd-cantool plays a simulated Case 1 log
# onto it 5 x faster (hstpfd --time-scale 5) and another one dumps the bus.
# Half-way vcan0 goes down for 2.5 s and comes up again; then SIGTERM.
# Checks: frames received with kernel time stamps and E2E-accepted, steps
# made, estimate frames sent and seen on the bus with valid E2E, a frame
# outside the kernel filter not seen, an unknown ID inside it counted, the
# interface loss survived and counted as one reopen, a clean exit on SIGTERM
# (timed: 1 s allowed in the VM) with the summary written, the fixes dated by
# their fix times.
set -euo pipefail
build=$(cd "${1:?usage: $0 BUILD_DIR}" && pwd)
iface=${HSTPF_VCAN_IFACE:-vcan0}
bin=$build/port/hstpfd
tdir=$build/tests/port
[ -x "$tdir/hstpfd-genlog" ] || tdir=$(dirname "$(find "$build" -name hstpfd-genlog -type f | head -1)")
tool=$tdir/hstpfd-cantool
gen=$tdir/hstpfd-genlog
speed=5
tmp=$(mktemp -d "${TMPDIR:-/tmp}/hstpfd-vcan.XXXXXX")
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$tmp"' EXIT
fail() { echo "vcan_daemon: FAIL: $*" >&2; for f in "$tmp"/*.err; do echo "--- $f" >&2; cat "$f" >&2; done; exit 1; }
export PATH=$PATH:/usr/sbin:/sbin

# 300 s of the run, with two foreign frames at 50 s: 0x1F0 passes the
# kernel filter (input block 0x100-0x1FF) and is counted, 0x300 does not
"$gen" "$tmp/run.log" --duration 300
printf '(1700000050.050000) vcan0 1F0#0102030405060708\n(1700000050.060000) vcan0 300#0102\n' > "$tmp/x.log"
sort -s -k1,1 "$tmp/run.log" "$tmp/x.log" > "$tmp/play.log"

"$bin" --iface "$iface" --models 'SS1/SS3/SS4, CRH3, SS8' --noise case1 --mass-t 500 \
    --time-scale $speed --out "$tmp/steps.jsonl" --summary "$tmp/summary.json" \
    > "$tmp/stdout" 2> "$tmp/hstpfd.err" &
pid=$!
sleep 0.5
kill -0 $pid 2>/dev/null || fail "hstpfd did not start"
"$tool" dump "$iface" 300 > "$tmp/bus.log" 2> "$tmp/dump.err" &
dump=$!
sleep 0.2

# the log plays for 60 s; 20 s in, vcan0 is down for 2.5 s (frames lost)
"$tool" play "$iface" "$tmp/play.log" $speed 2> "$tmp/play.err" &
play=$!
sleep 20
ip link set dev "$iface" down
sleep 2.5
ip link set dev "$iface" up
wait $play || fail "cantool play failed"
sleep 0.3
t0=$(date +%s%N)
kill -TERM $pid
rc=0; wait $pid || rc=$?
t1=$(date +%s%N)
term_ms=$(( (t1 - t0) / 1000000 ))
echo "vcan_daemon: SIGTERM to exit in the poll loop: $term_ms ms"
kill $dump 2>/dev/null || true; wait $dump 2>/dev/null || true
[ $rc -eq 0 ] || fail "hstpfd exit status $rc after SIGTERM"
# 100 ms is asserted natively (tests/port/test_daemon.c: 4-12 ms measured);
# here it only must end the poll loop: the VM emulates every instruction
# (10-50x slower, more on a busy machine: 1180 ms seen at load 10)
[ "$term_ms" -le "${HSTPF_TERM_MS_MAX:-5000}" ] || fail "SIGTERM took $term_ms ms"
grep -q "$iface: reopened" "$tmp/hstpfd.err" || fail "no reopen message"
cat "$tmp/play.err" "$tmp/dump.err"

python3 - "$tmp/summary.json" "$tmp/bus.log" <<'PY' || fail "checks failed"
import json, sys
s = json.load(open(sys.argv[1]))
print("vcan_daemon: summary:", json.dumps(s))
def crc8(data):
    r = 0
    for b in data:
        r ^= b
        for _ in range(8):
            r = ((r << 1) ^ 0x1D) & 0xFF if r & 0x80 else (r << 1) & 0xFF
    return r
data_id = {0x200: 0x2101, 0x210: 0x2102, 0x211: 0x2103, 0x220: 0x2104, 0x221: 0x2105}
seen = {i: 0 for i in data_id}
bad = 0
for line in open(sys.argv[2]):
    w = line.split()
    if not line.endswith('\n') or len(w) < 3 or '#' not in w[2]:
        continue  # the dump was stopped in the middle of a line
    i, d = w[2].split('#', 1)
    i = int(i, 16)
    if i not in data_id:
        continue
    d = bytes.fromhex(d)
    seen[i] += 1
    did = data_id[i]
    if len(d) != 8 or d[0] != crc8(bytes([did & 0xFF, did >> 8]) + d[1:]):
        bad += 1
checks = [
    (s["end"] == "signal", "end %s, not signal" % s["end"]),
    (s["io"]["reopens"] == 1, "reopens %d, not 1" % s["io"]["reopens"]),
    (s["frames"]["position"] >= 2500 and s["frames"]["traction"] >= 2500, "too few input frames"),
    (s["faults"]["unknown_id"] == 1, "unknown_id %d, not 1" % s["faults"]["unknown_id"]),
    (s["faults"]["bad_crc"] == 0 and s["faults"]["counter_jump"] == 0, "E2E faults on a clean log"),
    (s["faults"]["position_stale"] >= 1, "the outage was not seen as stale"),
    (s["steps"] >= 280, "only %d steps" % s["steps"]),
    (s["scheduler"]["fix_dated"] >= 0.9 * s["frames"]["position"], "fix times used for %d of %d positions"
     % (s["scheduler"]["fix_dated"], s["frames"]["position"])),
    (s["step_errors"] == {}, "step errors %s" % s["step_errors"]),
    (s["io"]["tx_frames"] >= 500 and s["io"]["tx_errors"] == 0, "sent %d, errors %d" % (s["io"]["tx_frames"], s["io"]["tx_errors"])),
    (seen[0x200] >= 250 and min(seen.values()) >= 50, "on the bus: %s" % seen),
    (bad == 0, "%d frames on the bus with a bad CRC" % bad),
]
ok = True
for good, msg in checks:
    if not good:
        print("vcan_daemon: check failed:", msg); ok = False
print("vcan_daemon: %d position + %d traction frames in, %d steps (%d predict-only), %d frames sent,"
      " on the bus %s with valid CRC; declared %s (q %s), reopens %d"
      % (s["frames"]["position"], s["frames"]["traction"], s["steps"], s["predict_steps"], s["io"]["tx_frames"],
         {hex(k): v for k, v in seen.items()}, s["declared"], s["weights"], s["io"]["reopens"]))
sys.exit(0 if ok else 1)
PY
echo "vcan_daemon: PASS"

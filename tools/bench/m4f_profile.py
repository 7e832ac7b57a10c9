#!/usr/bin/env python3
"""Where the Cortex-M4F firmware spends its instructions: runs the cross
test's firmware under qemu-system-arm (-icount shift=0, as the cross test)
and samples the program counter through QEMU's monitor every few ms, then
counts the samples by function (arm-none-eabi-nm) from the first sample
in a function whose name starts with --from (default: the grid engine's
pass, the firmware's last). Under -icount, wall time is proportional to
instructions executed, so the shares are shares of instructions.

    python3 tools/bench/m4f_profile.py build/cross-m4f/fw-build/hstpf-m4f-fw.elf

The helpers (soft-float double, libm) are also listed by their caller (the
link register at the sample). A sample is the CPU state QEMU last wrote
back, so a share is good to about 1 / sqrt(samples).
"""
import argparse
import bisect
import collections
import os
import re
import socket
import subprocess
import tempfile
import time


# the run-time library's and libm's: soft-float double, memory, maths
HELPER = re.compile(r"^(__|mem|exp|log|sqrt|floor|ceil|erf|pow|fabs)")


def symbols(elf, nm):
    out = subprocess.run([nm, "-S", "-n", elf], check=True, capture_output=True, text=True).stdout
    syms = []
    for line in out.splitlines():
        p = line.split()
        if len(p) >= 4 and p[2] in "tTwW":
            syms.append((int(p[0], 16), int(p[1], 16), p[3]))
    syms.sort()
    return syms


def sample(elf, qemu, interval):
    sock = os.path.join(tempfile.mkdtemp(), "mon.sock")
    q = subprocess.Popen([qemu, "-M", "mps2-an386", "-icount", "shift=0", "-nographic",
                          "-monitor", "unix:%s,server,nowait" % sock, "-serial", "none",
                          "-semihosting-config", "enable=on,target=native", "-kernel", elf],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(100):
        if os.path.exists(sock):
            break
        time.sleep(0.05)
    s = socket.socket(socket.AF_UNIX)
    s.connect(sock)
    s.settimeout(2)

    def cmd(c):
        s.sendall((c + "\n").encode())
        out = b""
        try:
            while b"(qemu)" not in out:
                d = s.recv(65536)
                if not d:
                    break
                out += d
        except socket.timeout:
            pass
        return out.decode(errors="replace")

    cmd("")
    rows = []
    while q.poll() is None:
        try:
            o = cmd("info registers")
        except OSError:
            break
        pc, lr = re.search(r"R15=([0-9a-f]{8})", o), re.search(r"R14=([0-9a-f]{8})", o)
        if pc and lr:
            rows.append((int(pc.group(1), 16), int(lr.group(1), 16)))
        time.sleep(interval)
    q.wait()
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("elf")
    ap.add_argument("--from", dest="start", default="hstpf__grid",
                    help="count from the first sample in a function with this prefix")
    ap.add_argument("--interval", type=float, default=0.01, help="seconds between samples")
    ap.add_argument("--top", type=int, default=20)
    ap.add_argument("--qemu", default="qemu-system-arm")
    ap.add_argument("--nm", default="arm-none-eabi-nm")
    a = ap.parse_args()
    syms = symbols(a.elf, a.nm)
    starts = [x[0] for x in syms]

    def name(pc):
        i = bisect.bisect_right(starts, pc & ~1) - 1
        return syms[i][2] if i >= 0 and pc < syms[i][0] + syms[i][1] + 2 else "?"

    rows = sample(a.elf, a.qemu, a.interval)
    first = next((i for i, (pc, _) in enumerate(rows) if name(pc).startswith(a.start)), None)
    if first is None:
        raise SystemExit("no sample in a function starting with %r (%d samples)" % (a.start, len(rows)))
    rows = rows[first:]
    own, helper = collections.Counter(), collections.Counter()
    for pc, lr in rows:
        n = name(pc)
        own[n] += 1
        if HELPER.match(n):
            helper["%s <- %s" % (n, name(lr))] += 1
    total = len(rows)
    print("%d samples from the first in %s*" % (total, a.start))
    for n, c in own.most_common(a.top):
        print("%5.1f %%  %s" % (100.0 * c / total, n))
    print("helpers by caller:")
    for n, c in helper.most_common(a.top // 2):
        print("%5.1f %%  %s" % (100.0 * c / total, n))


if __name__ == "__main__":
    main()

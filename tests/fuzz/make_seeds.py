#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets (tests/fuzz/corpus/<target>/).

Deterministic: the same files on every run. The byte layouts mirror the
readers in fuzz.h (fuzz_u8/u16/u64, fuzz_range, fuzz_double) and the order
in which each target reads its input. Usage: python3 make_seeds.py
[HSTPFD_BINARY] (with the daemon, its --print-config output is a seed too).
"""
import os
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))


def write(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def u8(v):
    return struct.pack("<B", v & 0xFF)


def u16(v):
    return struct.pack("<H", v & 0xFFFF)


def u64(v):
    return struct.pack("<Q", v)


def rng(v, lo, hi):
    """fuzz_range: lo + (hi - lo) * k / 65535."""
    k = round((v - lo) / (hi - lo) * 65535.0)
    return u16(max(0, min(65535, k)))


def dbl(v, lo, hi):
    """fuzz_double with a selector that takes the plausible range."""
    return u8(0) + rng(v, lo, hi)


# ---- candump: real lines of every kind the reader knows ------------------
write("candump", "classic.log",
      "(1700000000.000001) vcan0 100#4101E803000000F4\n"
      "(1700000000.100000) vcan0 101#27020A0000000000 R\n"
      "(1700000000.200000) vcan0 200#0000000000000000\n")
write("candump", "kinds.log",
      "# a comment\n; another\n\n"
      "(12.5) can1 18FF0102#0102030405060708 T\n"
      "(1.0) vcan0 123##1" + "00112233445566778899AABB\n"
      "(1.0) vcan0 123#R4\n(1.0) vcan0 1ABCDEF0#R\n"
      "(5.0) vcan0 20000044#0000000000000000\n"
      "(1.0) vcan0 123#01.02.03\n(1.0) vcan0 123#0102030405060708_C\n")
write("candump", "asc.asc", "date Mon Nov 23 01:00:00.000 am 2026\nbase hex  timestamps absolute\n"
      "   0.010000 1  123             Rx   d 8 00 11 22 33 44 55 66 77\n")
write("candump", "blf.blf", b"LOGG\x90\x00\x00\x00\x01\x02\x03")

# ---- config: the example files, every key, quoting ----------------------
for name in ("case1.ini", "case2.ini", "train.ini"):
    with open(os.path.join(REPO, "port", "config", name)) as f:
        write("config", name, f.read())
write("config", "quoted.ini",
      'log = "#run.log"  # a comment\nout = ";x"\nsummary = "a \\"b\\" \\\\c"\n'
      'models = "#m:1:0.01:0.0001", CRH3\nnoise_e = gamma:0.5:0.2:0\n[section]\n')
if len(sys.argv) > 1:
    out = subprocess.run([sys.argv[1], "--print-config"], check=True, capture_output=True, text=True).stdout
    write("config", "print-config.ini", out)

# ---- frames: clean streams of both inputs, polls, outputs ---------------
def frames_seed(n, with_outputs, corrupt_every=0):
    b = u8(2) + u16(500) + u16(500)  # max_delta 3, timeouts 501 ms
    for k in range(n):
        # op 1: a well-formed input frame 100 ms later
        corrupt = 1 if corrupt_every and k % corrupt_every == corrupt_every - 1 else 0
        b += u8(1) + u8(100) + u8(k & 1) + u8(corrupt) + u8(1) + dbl(50.0 * k, -1e8, 1e8) if k % 2 == 0 else \
            u8(1) + u8(100) + u8(1) + u8(corrupt) + u8(1) + dbl(20.0, -1e4, 1e4)
        if with_outputs and k % 10 == 0:
            b += u8(3) + u8(0) + u8(k % 5) + u8(1) + dbl(50.0 * k, -3e7, 3e7) + dbl(50.0, -400.0, 400.0)
            b += u8(1) + u8(2) + dbl(0.99, 0.0, 1.0) + u8(2) + dbl(0.99, 0.0, 1.0)
            b += dbl(5.0, 0.0, 70.0) + dbl(0.01, 0.0, 0.1) + dbl(0.0001, 0.0, 0.002) + u8(0) + u8(0)
            b += b"\0" * 32
        if k % 25 == 24:
            b += u8(2) + u8(200)  # poll
    return b


write("frames", "clean.bin", frames_seed(200, False))
write("frames", "outputs.bin", frames_seed(100, True))
write("frames", "corrupt.bin", frames_seed(100, False, corrupt_every=7))

# ---- filter: default and study-like configurations, 150 steps -----------
def filter_seed(models, particles, engine_byte, options=b"", steps=150, speed=50.0, gap_at=None):
    b = u8(len(models) - 1) + b"".join(u8(m) for m in models) + u8(particles) + u64(1) + u8(engine_byte)
    b += u8(1) + options if options else u8(0)
    for k in range(steps):
        if gap_at is not None and k == gap_at:
            b += u8(0x40 | 1) + dbl(30.0, 0.0, 70.0) + rng(0.0, -5.0, 5.0)
            continue
        b += u8(1) + rng(((k * 37) % 11 - 5) * 0.5, -5.0, 5.0)  # dt 1, traction 5, fix near truth
    return b


def case2_options(engine_particle=True):
    o = dbl(0.06, 0.0, 1.0)
    o += u8(1) + dbl(0.02, 1e-3, 10.0) + dbl(0.1, 1e-3, 1.0) + dbl(0.0, -1.0, 1.0)     # noise_s gamma
    o += u8(1) + dbl(0.1, 1e-3, 10.0) + dbl(0.05, 1e-3, 1.0) + dbl(0.0, -1.0, 1.0)     # noise_v gamma
    o += u8(1) + dbl(0.5, 1e-3, 10.0) + dbl(0.2, 1e-3, 10.0) + dbl(0.0, -10.0, 10.0)   # noise_e gamma
    o += dbl(1.0, 0.1, 10.0) + dbl(0.0, -10.0, 100.0) + dbl(1.0, 0.0, 10.0)
    o += dbl(0.5, 0.0, 1.0) + dbl(0.2, 0.0, 2.0) + dbl(0.0, 0.0, 10.0) + dbl(0.0, 0.0, 1.0)
    o += dbl(1e-9, 0.0, 0.1) + dbl(0.99, 0.5, 1.0) + dbl(30.0, 0.0, 100.0) + dbl(0.5, 0.0, 1.0)
    o += dbl(30.0, 0.0, 60.0) + dbl(1000.0, 0.0, 2000.0) + u8(5) + u8(0) + dbl(0.2, 0.0, 1.0)
    return o


write("filter", "kalman_3.bin", filter_seed([5, 2, 16], 20, 2))
write("filter", "particle_3.bin", filter_seed([5, 2, 16], 20, 0))
write("filter", "paired_4.bin", filter_seed([0, 1, 2, 3], 16, 0 | (1 << 2)))
write("filter", "case2_particle.bin", filter_seed([5, 2, 16], 16, 0, case2_options()))
write("filter", "gap.bin", filter_seed([2], 10, 2, steps=80, gap_at=40))

#!/usr/bin/env python3
"""Markdown tables for docs/results.md from the outputs of tools/results.sh
(out/results/*.txt): the journeys' totals and the trains not on Table 1,
so that the figures in the document are the run's, not retyped."""
import argparse
import re
import sys
from pathlib import Path

JOURNEYS = ["stops", "day", "start300", "clock+30", "clock-30", "outage", "gain5"]
OFFTABLE = ["off10", "off15", "off20", "grade8"]


def last(path: Path, prefix: str) -> str:
    lines = [ln for ln in path.read_text().splitlines() if ln.startswith(prefix)]
    if not lines:
        raise SystemExit(f"{path}: no line starting with {prefix!r}")
    return lines[-1]


def num(pattern: str, text: str) -> str:
    m = re.search(pattern, text)
    if not m:
        raise SystemExit(f"not found: {pattern!r} in {text[:80]}...")
    return m.group(1)


def journeys(d: Path) -> str:
    out = ["| scenario | false declarations (runs) | from a standstill | outside the pair | pair runs ending "
           "outside the pair | TV across a stop, median / max | lowest speed at rest [m/s] | W(v) error at the "
           "end outside the pairs, worst truth's mean / worst run | position error 10 s after, median / max [m] "
           "| outliers / gated re-acquisitions | 95 % coverage, position / speed | disagreements |",
           "|" + "---|" * 12]
    for s in JOURNEYS:
        t = last(d / f"{s}.txt", "total:")
        out.append("| `{}` | {} ({}) | {} | {} | {} | {} / {} | {} | {} / {} | {} / {} | {} / {} | {} / {} | {} |".format(
            s, num(r"false declarations (\d+)", t), num(r"false declarations \d+ \(([\d.]+%)\)", t),
            num(r"(\d+) from a standstill", t), num(r"(\d+) outside the pair;", t),
            num(r"pairs ending outside the pair (\d+ of \d+)", t),
            num(r"TV across a stop median ([\d.]+)", t), num(r"TV across a stop median [\d.]+ max ([\d.]+)", t),
            num(r"speed at rest min ([+\-\d.]+)", t), num(r"worst truth mean ([\d.]+%)", t),
            num(r"worst truth mean [\d.]+%, max ([\d.]+%)", t), num(r"after the event median ([\d.]+) m", t),
            num(r"after the event median [\d.]+ m max ([\d.]+) m", t), num(r"outliers (\d+)", t),
            num(r"re-acquisitions \(gated\) (\d+)", t), num(r"coverage position ([\d.]+%)", t),
            num(r"coverage position [\d.]+% speed ([\d.]+%)", t), num(r"disagreements (\d+)", t)))
    return "\n".join(out)


def offtable(d: Path) -> str:
    out = ["| scenario | hypothesis | W(v) error at the end, median / p90 | 95 % band covers the truth | "
           "'no type fits' at the end | runs with a type declared |", "|---|---|---|---|---|---|"]
    for s in OFFTABLE:
        for f, label in ((d / f"{s}.txt", "on (default)"), (d / f"{s}-norefine.txt", "off")):
            t = last(f, "trains off the table:")
            out.append("| `{}` | {} | {} / {} | {} | {} | {} |".format(
                s, label, num(r"median ([\d.]+%)", t), num(r"p90 ([\d.]+%)", t),
                num(r"covers the truth in ([\d.]+%)", t), num(r"fits' at the end in ([\d.]+%)", t),
                num(r"a type declared in ([\d.]+%)", t)))
    return "\n".join(out)


def studies(d: Path) -> str:
    """The paper's cases (their truth's row) and the 17-type studies (their total line)."""
    out = ["| scenario | result (hstpf-mc's own line) |", "|---|---|"]
    for s in ["paper1", "paper2", "paper1-particle", "paper2-particle"]:
        f = d / f"{s}.txt"
        if f.exists():
            hdr = last(f, "truth ")
            row = last(f, "CRH3 ")
            cols = dict(zip(hdr.split()[1:], row.split()[1:]))
            out.append(f"| `{s}` | success {cols['success']}, decision x_med / p90 / max {cols['x_med']} / "
                       f"{cols['x_p90']} / {cols['x_max']} s, declaration t_med {cols['t_med']} s, false "
                       f"{cols['false']}, position RMS {cols['pos_rms']} m |")
    for s in ["all17", "all17-coast", "all17-coast-loss", "hilly-ignored", "hilly-known", "all17-particle"]:
        f = d / f"{s}.txt"
        if f.exists():
            out.append(f"| `{s}` | {last(f, 'total:')[len('total: '):]} |")
    for s in ["paper1", "all17", "stops"]:
        f = d / f"{s}-norefine.txt"
        if f.exists():
            line = f.read_text().strip().splitlines()[-1]
            out.append(f"| `{s} --no-refine` | {line} |")
    return "\n".join(out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--dir", default="out/results", help="tools/results.sh's output folder")
    a = p.parse_args(argv)
    d = Path(a.dir)
    print("### Every study, current library\n")
    print(studies(d))
    print("\n### Journeys, totals\n")
    print(journeys(d))
    print("\n### Trains not on Table 1\n")
    print(offtable(d))
    return 0


if __name__ == "__main__":
    sys.exit(main())

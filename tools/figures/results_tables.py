#!/usr/bin/env python3
"""Markdown tables for docs/results.md from the outputs of tools/results.sh
(out/results/*.txt, *.json): the journeys' totals, the trains not on
Table 1 and issue 13's scenarios (one table each, grid and particle engines
side by side), so that the figures in the document are the run's, not
retyped."""
import argparse
import json
import re
import sys
from pathlib import Path

JOURNEYS = ["stops", "day", "start300", "clock+30", "clock-30", "outage", "gain5", "stops-case2", "start300-case2",
            "clock+30-case2", "clock-30-case2", "outage-case2"]
OFFTABLE = ["off10", "off15", "off20", "grade8", "mass10", "mass20", "absent", "gain-5", "gain5"]
# the same questions on the grid engine, with Student-t position noise (stops-t: a row)
OFFTABLE_T = ["stops-t", "off15-t", "grade8-t"]
# and under Case 2 noise (the grid engine; tools/results.sh's HSTPF_OFF_CASE2_SEEDS)
OFFTABLE_CASE2 = ["off15-case2", "grade8-case2", "mass20-case2", "absent-case2"]
# the pointwise band's coverage, as hstpf-mc words it now and before the curve's band
BAND = r"covers the truth at 68 of 71 speeds in ([\d.]+%)|covers the truth in ([\d.]+%)"


def last(path: Path, prefix: str, missing: str = None) -> str:
    """The last line of path starting with prefix; missing (when given) for
    no such line or no such file."""
    if missing is not None and not path.exists():
        return missing
    lines = [ln for ln in path.read_text().splitlines() if ln.startswith(prefix)]
    if not lines:
        if missing is not None:
            return missing
        raise SystemExit(f"{path}: no line starting with {prefix!r}")
    return lines[-1]


def num(pattern: str, text: str) -> str:
    m = re.search(pattern, text)
    if not m:
        raise SystemExit(f"not found: {pattern!r} in {text[:80]}...")
    return next(g for g in m.groups() if g is not None)  # the alternative that matched


def journeys(d: Path) -> str:
    out = ["| scenario | false declarations (runs) | from a standstill | outside the pair | pair runs ending "
           "outside the pair | TV across a stop, median / max | lowest speed at rest [m/s] | W(v) error at the "
           "end outside the pairs, worst truth's mean / worst run | position error 10 s after, median / max [m] "
           "| outliers / gated re-acquisitions | 95 % coverage, position / speed | disagreements |",
           "|" + "---|" * 12]
    for s in JOURNEYS:
        if not (d / f"{s}.txt").exists():  # stops-case2 runs with the grid scenarios
            continue
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


def present(d: Path, names, *prefixes):
    """(name, the last line of each prefix) for the scenarios of names whose
    output d holds, in the order of names."""
    for s in names:
        if (d / f"{s}.txt").exists():
            yield (s, *(last(d / f"{s}.txt", p) for p in prefixes))


RESTARTS = ["restart", "restart-t"]


def restarts(d: Path) -> str:
    """The reference restarted at a stop (hstpf-mc's restart scenarios): how
    soon the estimate is valid again, and how right it is then."""
    out = ["| scenario | runs restarted | valid again after, median / p90 / max [s] | never | steps valid after it "
           "| max position error at a valid step after it [m] | false declarations (runs) |",
           "|" + "---|" * 7]
    for s, r, t in present(d, RESTARTS, "reference restarted", "total:"):
        out.append("| `{}` | {} | {} / {} / {} | {} | {} | {} | {} ({}) |".format(
            s, num(r"in (\d+ of \d+) runs", r), num(r"after a median (\d+) s", r), num(r"p90 (\d+) s", r),
            num(r"max (\d+) s", r), num(r"never in (\d+)", r), num(r"valid at ([\d.]+%)", r),
            num(r"after it max ([\d.]+) m", r), num(r"false declarations (\d+)", t),
            num(r"false declarations \d+ \(([\d.]+%)\)", t)))
    return "\n".join(out)


TRACGAPS = [("tracgap", "traction unknown (the default)"), ("tracgap-hold", "the last traction fed (before)"),
            ("tracgap-particle", "traction unknown, particle engine"), ("tracgap-t", "traction unknown, Student-t fixes (grid)")]


def tracgaps(d: Path) -> str:
    """The traction unit silent across a departure (hstpf-mc's tracgap
    scenarios): what was published meanwhile."""
    out = ["| scenario | what the filter is fed | valid steps > 5 sd off in the gap and 30 s after (runs) | largest speed "
           "error at a valid step [m/s] | standstill while the train moved [steps] | weights' TV across the gap, "
           "median / max |", "|" + "---|" * 6]
    what_of = dict(TRACGAPS)
    for s, g in present(d, [n for n, _ in TRACGAPS], "traction gap"):
        what = what_of[s]
        out.append("| `{}` | {} | {} ({}) | {} | {} | {} / {} |".format(
            s, what, num(r"30 s after: (\d+)", g), num(r"30 s after: \d+ in (\d+ of \d+) runs", g),
            num(r"at a valid step ([\d.]+) m/s", g), num(r"train moved: (\d+) steps", g),
            num(r"gap median ([\d.]+)", g), num(r"gap median [\d.]+ max ([\d.]+)", g)))
    return "\n".join(out)


# what is published at the stops and under a traction that is wrong (the
# journeys' "standstill published" line); -nocheck: cfg.traction_check = 0
HONESTY = ["stops", "day", "start300", "restart", "tracgap", "swap", "off15", "grade8", "stops-t", "stops-case2",
           "tracsign", "tracsign-nocheck", "gain-20", "gain-20-nocheck", "gap29", "gap29-before", "fix5",
           "fix5-before", "stuck30", "stuck30-before", "late10", "late10-before", "late60", "late60-before"]


def honesty(d: Path) -> str:
    """Steps published at standstill while the train moved, valid steps whose
    speed was more than 5 sd off, the traction taken for wrong, and the
    traction check's margin (hstpf-mc's journeys)."""
    out = ["| scenario | standstill while the train moved: steps (runs) | valid steps with the speed > 5 sd and "
           "0.3 m/s off (runs) | traction taken for wrong: steps (runs) | its CUSUM while believed, max [nats] | "
           "false declarations (runs) |", "|" + "---|" * 6]
    for s, h, t in present(d, HONESTY, "standstill published", "total:"):
        out.append("| `{}` | {} ({}) | {} ({}) | {} ({}) | {} | {} ({}) |".format(
            s, num(r"moved: (\d+) steps", h), num(r"moved: \d+ steps in (\d+) runs", h),
            num(r"0.3 m/s off: (\d+)", h), num(r"0.3 m/s off: \d+ in (\d+) runs", h),
            num(r"at (\d+) steps in", h), num(r"traction_fault\) at \d+ steps in (\d+) runs", h),
            num(r"at most ([\d.]+) nats", h), num(r"false declarations (\d+)", t),
            num(r"false declarations \d+ \(([\d.]+%)\)", t)))
    return "\n".join(out)


SWAPS = ["swap", "swap-near", "couple", "couple-p0", "couple-near", "couple-near-p0"]


def swaps(d: Path) -> str:
    """A consist that changes at a station (hstpf-mc's swap and couple
    scenarios; -p0: with --consist-p 0): how long the first truth's type
    stays declared after the change, how soon the new one is, and W(v)
    against the new truth at the end."""
    out = ["| scenario | a type declared at the change | the first truth declared after the change: runs, median / "
           "max time after it | the new truth declared: runs, median time after the change | W(300 km/h) error "
           "while a wrong type was declared and valid, max | W(v) error against the new truth at the end, median / "
           "p90 |", "|" + "---|" * 6]
    for s, g in present(d, SWAPS, "type changed"):
        out.append("| `{}` | {} | {}, {} / {} s | {}, {} | {} | {} / {} |".format(
            s, num(r"declared then in (\d+ of \d+) runs", g), num(r"kept after the change in (\d+)", g),
            num(r"for a median (\d+) s", g), num(r"for a median \d+ s, max (\d+) s", g),
            num(r"the new truth declared in (\d+)", g), num(r"the new truth declared in \d+, a median (\d+ s)", g),
            num(r"declared and valid, max ([\d.]+%)", g), num(r"at the end \(\d+ runs\) median ([\d.]+%)", g),
            num(r"at the end \(\d+ runs\) median [\d.]+% p90 ([\d.]+%)", g)))
    return "\n".join(out)


def far_split(path: Path) -> str:
    """The runs whose truth is >= 10 % from every row (issue 10's off-table
    runs): how many, 'no type fits' at the end, a type declared; '-' for an
    output older than the split."""
    t = last(path, "by the truth's W(v) distance", missing="")
    if not t:
        return "-"
    return "{}: {}, {}".format(num(r">= 10%: (\d+) runs", t), num(r">= 10%: \d+ runs, 'no type fits' at the end ([\d.]+%)", t),
                               num(r">= 10%: \d+ runs, [^,]+, a type declared ([\d.]+%)", t))


def offtable(d: Path, names=None) -> str:
    out = ["| scenario | hypothesis | W(v) error at the end, median / p90 | 95 % band covers the truth | "
           "'no type fits' at the end | runs with a type declared | truth >= 10 % from every row: runs: "
           "'no type fits', a type declared |", "|---|---|---|---|---|---|---|"]
    for s in names or OFFTABLE:
        for f, label in ((d / f"{s}.txt", "on (default)"), (d / f"{s}-norefine.txt", "off")):
            if not f.exists():
                continue
            t = last(f, "trains off the table:")
            out.append("| `{}` | {} | {} / {} | {} | {} | {} | {} |".format(
                s, label, num(r"median ([\d.]+%)", t), num(r"p90 ([\d.]+%)", t),
                num(BAND, t),
                num(r"fits' at the end in ([\d.]+%)", t), num(r"a type declared in ([\d.]+%)", t), far_split(f)))
    return "\n".join(out)


def lead_cols(t: str):
    """An oracle line's "leads ... by log 99 from the end of a median M (p10
    A, p90 B) to the end, never in N runs": M, A, B, N."""
    return (num(r"from the end of a median ([^ ]+(?: s)?) \(", t), num(r"\(p10 ([^,]+),", t),
            num(r"p90 ([^)]+)\) to the end", t), num(r"never in (\d+) runs", t))


def oracle(d: Path, names) -> str:
    """hstpf-mc --oracle's line (runs >= 10 % from every row): when the
    truth's own theta leads its nearest row by log 99 for good, and its
    log-likelihood ratio against a row wrongly declared, at the declaration.
    Empty when no output of names has the line."""
    out = ["| scenario | runs >= 10 % off | the truth leads its nearest row by log 99 for good from: median (p10, "
           "p90) | never | a wrong row declared (not among the 4 nearest) | the truth's log-likelihood ratio against "
           "it then: median / p90 / max | below log 99 | below 0 | the nearest row leads its 8 trains 10 % off at "
           "some step | the nearest row wrongly declared / at a step where it led its 8 |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for s in names:
        f = d / f"{s}.txt"
        t = last(f, "oracle (", missing="")
        if not t:
            continue
        nb = last(f, "oracle, the nearest row against", missing="")
        nbs = ("{} runs".format(num(r"at some step in (\d+) of", nb)),
               "{} / {}".format(num(r"declared the nearest row in (\d+) runs", nb), num(r"and in (\d+) of them", nb))
               ) if nb else ("-", "-")
        out.append("| `{}` | {} | {} ({}, {}) | {} | {} ({}) | {} / {} / {} | {} | {} | {} | {} |".format(
            s, num(r"off: (\d+) runs", t), *lead_cols(t),
            num(r"first declared in (\d+) runs", t), num(r"\((\d+) not among", t),
            num(r"then median ([^,]+),", t), num(r"then median [^,]+, p90 ([^,]+),", t),
            num(r", max ([^;]+);", t), num(r"below log 99 in (\d+)", t), num(r"below 0 in (\d+)", t), *nbs))
    return "\n".join(out) if len(out) > 2 else ""


# scenario, its output (tools/results.sh)
ORACLE_ON = [(s, f"{s}-oracle.txt") for s in ["paper1", "paper2", "all17", "stops", "all17-case2"]] + [
    ("paper2-oracle-gauss", "paper2-oracle-gauss.txt")]


def oracle_on(d: Path) -> str:
    """hstpf-mc --oracle on the table (out/results/S-oracle.txt, and paper2 on
    the noises' moments): when the row leads every train 10 % from it by log
    99, beside today's declaration. Empty when none ran."""
    out = ["| scenario | runs | the row leads all 8 by log 99 for good from: median (p10, p90) | never | today's "
           "declaration: median (p90) | declared before that | paired: excluded minus declared, median | counted "
           "from the lead: excluded from, median (p90); paired |", "|---|---|---|---|---|---|---|---|"]
    for s, name in ORACLE_ON:
        f = d / name
        t = last(f, "oracle (", missing="")
        if not t:
            continue
        p = last(f, "oracle, paired", missing="")
        out.append("| `{}` | {} | {} ({}, {}) | {} | {} ({}) | {} | {} | {} |".format(
            s, num(r"no hypothesis\): (\d+) runs", t), *lead_cols(t),
            num(r"at a median ([^ ]+(?: s)?) \(p90", t), num(r"at a median [^(]+\(p90 ([^,]+),", t),
            num(r"before the row led all 8 for good in (\d+)", t),
            num(r"minus declared median ([^ ]+(?: s)?) \(min", p) if p else "-",
            "{} ({}); {}".format(num(r"excluded from a median ([^ ]+(?: s)?) \(", p),
                                 num(r"excluded from a median [^(]+\(p90 ([^)]+)\)", p),
                                 num(r"minus declared median ([^ ]+(?: s)?) in \d+ runs\n?$", p)) if p else "-"))
    return "\n".join(out) if len(out) > 2 else ""


def prior(d: Path) -> str:
    """The continuous hypothesis's prior weight: identification on the table
    (Case 1's decision, all17's success) against off-table declarations and
    the band (the default 0.01 is the scenarios' own run)."""
    off = ["off15", "mass20", "absent", "grade8"]
    out = ["| `refine_prior_q` | Case 1 decision x_med / p90 / max [s] | all17: success | "
           + " | ".join(f"{s}: a type declared" for s in off) + " | mass20: band covers |",
           "|---|---|---|" + "---|" * len(off) + "---|"]
    tags = [("0.03", "-prior0.03"), ("0.02", "-prior0.02"), ("0.01 (default)", ""),
            ("0.003", "-prior0.003"), ("0.001", "-prior0.001"), ("off (`--no-refine`)", "-norefine")]
    for label, tag in tags:
        files = [d / f"{s}{tag}.txt" for s in ["paper1", "all17"] + off]
        if not all(f.exists() for f in files):
            continue
        # paper1: its CRH3 row
        row = [ln for ln in files[0].read_text().splitlines() if ln.startswith("CRH3 ")][-1].split()
        offt = [last(f, "trains off the table:") for f in files[2:]]
        out.append("| {} | {} / {} / {} | {} | {} | {} |".format(
            label, row[2], row[3], row[4], num(r"success ([\d.]+%)", last(files[1], "total:")),
            " | ".join(num(r"a type declared in ([\d.]+%)", t) for t in offt),
            num(BAND, offt[1])))
    return "\n".join(out)


def spread(d: Path) -> str:
    """The rows' spread (refine_spread): the band's coverage against the
    decisions (the default 0.3 is the scenarios' own run)."""
    band = ["stops", "off10", "off15", "off20", "mass10", "mass20", "absent"]
    out = ["| `refine_spread` | Case 1 decision x_med / p90 / max [s] | all17: success, false | "
           + " | ".join(f"{s}: band covers" for s in band) + " | off15: a type declared |",
           "|---|---|---|" + "---|" * len(band) + "---|"]
    for sp in ("0.2", "0.3", "0.4"):
        tag = "" if sp == "0.3" else f"-spread{sp}"
        files = [d / f"paper1{tag}.txt", d / f"all17{tag}.txt"] + [d / f"{s}{tag}.txt" for s in band]
        if not all(f.exists() for f in files):
            continue
        row = last(files[0], "CRH3 ").split()
        a17 = last(files[1], "total:")
        cov = [num(BAND, last(f, "trains off the table:")) for f in files[2:]]
        out.append("| {} | {} / {} / {} | {}, {} | {} | {} |".format(
            sp + (" (default)" if sp == "0.3" else ""), row[2], row[3], row[4],
            num(r"success ([\d.]+%)", a17), num(r"false declarations \d+ \(([\d.]+%)\)", a17),
            " | ".join(cov), num(r"a type declared in ([\d.]+%)", last(files[4], "trains off the table:"))))
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
            lines = f.read_text().strip().splitlines()
            # the journeys' summary line, not the split by distance that follows it
            line = next((ln for ln in reversed(lines) if ln.startswith("trains off the table:")), lines[-1])
            out.append(f"| `{s} --no-refine` | {line} |")
    return "\n".join(out)


ISSUE13 = {
    "all17-case2": "all 17 types, Case 2 noise, paper profile",
    "all17-coast-case2": "all 17 types, Case 2 noise, coast-and-brake profile",
    "heavy-t": "all 17 types, Student-t(3) position noise, paper profile",
    "heavy-mix": "all 17 types, 95/5 % multipath mixture position noise, paper profile",
}
ENGINES = [("grid", "grid 20 x 72 (library defaults)"),
           ("grid-allrows", "grid 20 x 72, every row on the grid (`--grid-rows 0`)"),
           ("particle", "particles, M = 100 (the library's), blur 0.2 m, roughening 0.7"),
           ("particle256", "particles, M = 256, blur 0.2 m, roughening 0.7"),
           ("gauss", "reference: Kalman, told only N(0, sd^2) of the noise (`--gauss-e`)")]


def median(v):
    v = sorted(v)
    return v[(len(v) - 1) // 2] if v else None


def wrong_types(js: dict) -> str:
    """The runs that declared a wrong type, as 'truth -> declared (runs)'."""
    pairs = {}
    for tr in js["results"]:
        for r in tr["runs"]:
            if r["false_decl"]:
                key = f"{tr['truth']} -> {r['false_model']}"
                pairs[key] = pairs.get(key, 0) + 1
    return "; ".join(f"{k} ({n})" for k, n in sorted(pairs.items(), key=lambda kv: (-kv[1], kv[0]))) or "none"


def issue13(d: Path, scenario: str) -> str:
    """One row per engine that has an output: hstpf-mc's total line; the
    pooled median decision time, the wrong types, the runs that end on a
    wrong type and the pooled state RMS from its JSON."""
    out = ["| engine | runs | success | decision x_med [s] | false declarations | wrong types (truth -> declared) "
           "| a wrong type declared at the end | W(v) error > 5 % | worst truth's mean W(v) error "
           "| position RMS [m] | speed RMS [m/s] |",
           "|" + "---|" * 11]
    for tag, label in ENGINES:
        if scenario.startswith("heavy") and tag == "particle256":
            label = "particles, M = 256, roughening 0.7 (a table takes no blur)"
        f = d / f"{scenario}-{tag}.txt"
        if not f.exists():
            continue
        t = last(f, "total:")
        js = json.loads((d / f"{scenario}-{tag}.json").read_text())
        runs = [r for tr in js["results"] for r in tr["runs"]]
        wrong_end = sum(1 for tr in js["results"] for r in tr["runs"] if r["final_declared"] not in ("", tr["truth"]))
        xm = median([r["t_cross"] for r in runs if r["success"]])
        # pooled over the runs: the root of the mean of each run's mean square
        prms = (sum(r["pos_rms"] ** 2 for r in runs) / len(runs)) ** 0.5
        vrms = (sum(r["spd_rms"] ** 2 for r in runs) / len(runs)) ** 0.5
        out.append("| {} | {} | {} | {} | {} ({}) | {} | {} | {} ({}) | {} | {} | {} |".format(
            label, num(r"total: (\d+) runs", t), num(r"success ([\d.]+%)", t),
            f"{xm:.0f}" if xm is not None else "-",
            num(r"false declarations (\d+)", t), num(r"false declarations \d+ \(([\d.]+%)\)", t),
            wrong_types(js), wrong_end, num(r"W\(v\) error > 5% in (\d+)", t), num(r"W\(v\) error > 5% in \d+ \(([\d.]+%)\)", t),
            num(r"worst truth's mean W\(v\) error ([\d.]+%)", t), f"{prms:.3f}", f"{vrms:.4f}"))
    return "\n".join(out)


def paired_declaration(d: Path, scenario: str, tag: str, label: str) -> str:
    """The truth's own declaration (hstpf-mc's t_declare, -1: never) in
    scenario.json against scenario-tag.json, seed by seed: how many runs
    declare it in each, and over the runs that declare it in both the
    difference of the times (median, mean with its standard error, how
    many later and sooner). Empty when either file is missing."""
    fa, fb = d / f"{scenario}.json", d / f"{scenario}-{tag}.json"
    if not (fa.exists() and fb.exists()):
        return ""

    def runs(f):
        return {(tr["truth"], r["seed"]): r for tr in json.loads(f.read_text())["results"] for r in tr["runs"]}

    ra, rb = runs(fa), runs(fb)
    keys = sorted(set(ra) & set(rb))
    ta = [ra[k]["t_declare"] for k in keys]
    tb = [rb[k]["t_declare"] for k in keys]
    diff = [x - y for x, y in zip(ta, tb) if x >= 0 and y >= 0]
    n = len(diff)
    mean = sum(diff) / n if n else 0.0
    se = (sum((x - mean) ** 2 for x in diff) / (n - 1)) ** 0.5 / n ** 0.5 if n > 1 else 0.0
    fals = [sum(r[k]["false_decl"] for k in keys) for r in (ra, rb)]
    out = [f"| runs | the truth declared: defaults / {label} | in both | defaults minus {label}: median, "
           "mean +- se [s] | later / sooner / same | false declarations: defaults / " + label + " |",
           "|---|---|---|---|---|---|",
           f"| {len(keys)} | {sum(t >= 0 for t in ta)} / {sum(t >= 0 for t in tb)} | {n} | "
           + (f"{median(diff):+.0f}, {mean:+.1f} +- {se:.1f}" if n else "-")
           + f" | {sum(x > 0 for x in diff)} / {sum(x < 0 for x in diff)} / {sum(x == 0 for x in diff)} | "
           f"{fals[0]} / {fals[1]} |"]
    return "\n".join(out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--dir", default="out/results", help="tools/results.sh's output folder")
    p.add_argument("--issue13-only", action="store_true",
                   help="only issue 13's scenario tables (a folder with just those outputs)")
    a = p.parse_args(argv)
    d = Path(a.dir)
    if not a.issue13_only:
        print("### Every study, current library\n")
        print(studies(d))
        print("\n### Journeys, totals\n")
        print(journeys(d))
        print("\n### The reference restarted at a stop\n")
        print(restarts(d))
        print("\n### The traction unknown across a departure\n")
        print(tracgaps(d))
        print("\n### A consist that changes at a station\n")
        print(swaps(d))
        print("\n### At the stops, and under a traction that is wrong\n")
        print(honesty(d))
        print("\n### Trains not on Table 1\n")
        print(offtable(d))
        if any((d / f"{s}.txt").exists() for s in OFFTABLE_T):
            print("\n### Trains not on Table 1, with Student-t fixes (grid engine)\n")
            print(offtable(d, OFFTABLE_T))
        if any((d / f"{s}.txt").exists() for s in OFFTABLE_CASE2):
            print("\n### Trains not on Table 1 under Case 2 noise (grid engine)\n")
            print(offtable(d, OFFTABLE_CASE2))
        ot = oracle_on(d)
        if ot:
            print("\n### When the data exclude trains 10 % from the row (hstpf-mc --oracle, on the table)\n")
            print(ot)
        ot = oracle(d, OFFTABLE + OFFTABLE_CASE2)
        if ot:
            print("\n### When the data can tell an off-table truth from a row (hstpf-mc --oracle)\n")
            print(ot)
        pt = paired_declaration(d, "stops-t", "allrows", "every row on the grid")
        if pt:
            print("\n### `stops-t`: the truth's declaration with 3 rows on the grid and with every row\n")
            print(pt)
        print("\n### The continuous hypothesis's prior weight\n")
        print(prior(d))
        print("\n### The rows' spread\n")
        print(spread(d))
    for sc, title in ISSUE13.items():
        if any((d / f"{sc}-{tag}.txt").exists() for tag, _ in ENGINES):
            print(f"\n### `{sc}`: {title}\n")
            print(issue13(d, sc))
    return 0


if __name__ == "__main__":
    sys.exit(main())

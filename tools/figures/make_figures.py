#!/usr/bin/env python3
"""Figures for docs/results.md from hstpf-mc outputs (traces and JSON).

Reproduces the paper's Figures 1-4 (Case 1) and 5-8 (Case 2) from one traced
run each, and draws the Monte Carlo decision-time distributions. Every
figure names its run (truth, seed, noise), marks the declaration time, and
takes the declaration rule from the configuration (--config, else the
library's defaults); 95 % bands are drawn when the trace has sd columns."""
import json
import os
import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hstpf_tools import cli, runconfig  # noqa: E402
from hstpf_tools.table1 import TABLE1  # noqa: E402

CASE_MODELS = {1: ["SS1/SS3/SS4", "CRH3", "SS8"], 2: ["CRH1", "CRH3", "CRH5"]}
CASE_NOISE = {1: "Case 1 (Gaussian)", 2: "Case 2 (Gamma)"}
CASE_SCENARIO = {1: "paper1", 2: "paper2"}
Z95 = 1.959963984540054
# sd columns a trace may carry (hstpf-mc --trace), first found is used
SD_COLUMNS = {"s": ("s_sd", "pos_sd", "position_sd_m"), "v": ("v_sd", "spd_sd", "speed_sd", "speed_sd_mps"),
              "c0": ("c0_sd",), "c1": ("c1_sd",), "c2": ("c2_sd",)}
MC_SOURCE = Path(__file__).resolve().parents[1] / "montecarlo" / "mc.c"


def theta_for(name):
    return next(r for r in TABLE1 if r[0] == name)[1:]


def load_trace(path):
    try:
        return np.genfromtxt(path, delimiter=",", names=True)
    except (OSError, ValueError) as exc:
        raise cli.input_error(path, exc) from exc


def sd_column(d, key):
    for c in SD_COLUMNS[key]:
        if c in d.dtype.names and np.any(np.isfinite(d[c]) & (d[c] > 0)):
            return d[c]
    return None


def decision(d):
    """(time s, model index) at which the final, unbroken declaration began;
    (None, None) when the run ends undeclared."""
    dec = d["declared"].astype(int)
    if dec[-1] < 0:
        return None, None
    k = len(dec) - 1
    while k > 0 and dec[k - 1] == dec[-1]:
        k -= 1
    return float(d["t"][k]), int(dec[-1])


def identity(case, jsons):
    """The traced run: hstpf-mc --trace writes the first run of the first job,
    whose truth and seed the scenario's JSON holds (results[0].runs[0])."""
    for path in jsons:
        d = json.load(open(path))
        if d.get("scenario") == CASE_SCENARIO[case]:
            r0 = d["results"][0]
            return {"truth": r0["truth"], "seed": r0["runs"][0]["seed"], "noise": CASE_NOISE[case],
                    "threshold": d.get("declare_threshold"), "hold_s": d.get("declare_hold_s")}
    return {"truth": None, "seed": None, "noise": CASE_NOISE[case]}


def who(ident):
    return ", ".join(x for x in ("truth %s" % ident["truth"] if ident["truth"] else "",
                                 "seed %s" % ident["seed"] if ident["seed"] is not None else "",
                                 ident["noise"]) if x)


def mark(ax, t_dec, name, th_scale=1.0):
    if t_dec is not None:
        ax.axvline(t_dec / th_scale, color="tab:red", ls=":", lw=1.2,
                   label="declared %s at %.0f s" % (name, t_dec))


def paper_figures(trace, case, outdir, first_fig, rule, ident):
    d = load_trace(trace)
    th = d["t"] / 3600.0  # hours, as the paper's axes
    names = CASE_MODELS[case]
    truth = ident["truth"] or "CRH3"  # the paper's cases have one truth (hstpf-mc's scenarios)
    true_theta = theta_for(truth)
    title = who(dict(ident, truth=truth))
    t_dec, k_dec = decision(d)
    dec_name = names[k_dec] if k_dec is not None else None
    q = np.vstack([d["q%d" % k] for k in range(len(names))])
    files = []

    fig, ax = plt.subplots(figsize=(7, 4.2))
    for k, (n, mk) in enumerate(zip(names, ["o", "*", "s"])):
        ax.plot(th, q[k], marker=mk, markevery=max(1, len(th) // 25), label=n)
    if rule.get("threshold") is not None:
        hold = ", held %g s" % rule["hold_s"] if rule.get("hold_s") is not None else ""
        ax.axhline(rule["threshold"], color="grey", ls="--", lw=0.8,
                   label="declaration: q > %g%s (%s)" % (rule["threshold"], hold, rule["source"]))
    mark(ax, t_dec, dec_name, 3600.0)
    ax.set(xlabel="time k [h]", ylabel="model weight q", ylim=(-0.02, 1.02))
    ax.set_title("Fig. %d: weights of each parameter group\n%s" % (first_fig, title), fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    files.append(save(fig, outdir, "case%d_fig%d_weights.png" % (case, first_fig)))

    fig, axs = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for a, key, scale, unit in ((axs[0], "s", 1e-3, "position s [km]"), (axs[1], "v", 3.6, "speed v [km/h]")):
        a.plot(th, d[key + "_true"] * scale, label="true")
        est = d[key + "_est"] * scale
        a.plot(th, est, "--", label="estimate")
        sd = sd_column(d, key)
        if sd is not None:
            a.fill_between(th, est - Z95 * sd * scale, est + Z95 * sd * scale, alpha=0.25, lw=0, label="95 % band")
        mark(a, t_dec, dec_name, 3600.0)
        a.set(ylabel=unit)
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    axs[1].set(xlabel="time k [h]")
    axs[0].set_title("Fig. %d: true and estimated state\n%s" % (first_fig + 1, title), fontsize=10)
    files.append(save(fig, outdir, "case%d_fig%d_state.png" % (case, first_fig + 1)))

    fig, axs = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    for k, (col, unit) in enumerate([("c0", "N/kN"), ("c1", "N/kN per km/h"), ("c2", "N/kN per (km/h)^2")]):
        axs[k].plot(th, d[col], ".", ms=2, label="estimate")
        sd = sd_column(d, col)
        if sd is not None:
            axs[k].fill_between(th, d[col] - Z95 * sd, d[col] + Z95 * sd, alpha=0.25, lw=0, label="95 % band")
        axs[k].axhline(true_theta[k], color="k", label="true (%s)" % truth)
        mark(axs[k], t_dec, dec_name, 3600.0)
        axs[k].set(ylabel="%s [%s]" % (col, unit))
        axs[k].grid(alpha=0.3)
        axs[k].legend(loc="upper right", fontsize=7)
    axs[2].set(xlabel="time k [h]")
    axs[0].set_title("Fig. %d: estimated parameters\n%s" % (first_fig + 2, title), fontsize=10)
    files.append(save(fig, outdir, "case%d_fig%d_params.png" % (case, first_fig + 2)))

    fig, axs = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for k, col in enumerate(["c0", "c1", "c2"]):
        axs[0].plot(th, 100 * (d[col] - true_theta[k]) / true_theta[k], label=col)
    axs[0].axhspan(-5, 5, color="g", alpha=0.1, label="+-5 %")
    axs[0].set(ylabel="parameter error [%]")
    for key, label in (("s", "position"), ("v", "speed")):
        ok = d[key + "_true"] > 1.0
        err = 100 * (d[key + "_est"][ok] - d[key + "_true"][ok]) / d[key + "_true"][ok]
        line, = axs[1].plot(th[ok], err, label=label)
        sd = sd_column(d, key)
        if sd is not None:
            band = 100 * Z95 * sd[ok] / d[key + "_true"][ok]
            axs[1].fill_between(th[ok], err - band, err + band, color=line.get_color(), alpha=0.2, lw=0,
                                label="95 %% band (%s)" % label)
    axs[1].set(xlabel="time k [h]", ylabel="state error [%]", ylim=(-20, 20))
    for a in axs:
        mark(a, t_dec, dec_name, 3600.0)
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    axs[0].set_title("Fig. %d: relative errors of parameters and states\n%s" % (first_fig + 3, title), fontsize=10)
    files.append(save(fig, outdir, "case%d_fig%d_errors.png" % (case, first_fig + 3)))
    return files


def mc_success_threshold(src=MC_SOURCE):
    """hstpf-mc's success criterion (the paper's Table 2 threshold): the true
    weight above it from some time to the end; None if mc.c is not here."""
    try:
        m = re.search(r"static const double thr\s*=\s*([0-9.]+)\s*;", Path(src).read_text())
    except OSError:
        return None
    return float(m.group(1)) if m else None


def decision_figure(jsons, outdir, rule):
    """Per scenario: when the true weight stays above hstpf-mc's success
    threshold (decision) and when the declaration rule declares the true
    type (declaration)."""
    thr = mc_success_threshold()
    runs = set()
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.8), sharey=True)
    rule_text = "q > %s held %s s" % (("%g" % rule["threshold"]) if rule.get("threshold") is not None else "?",
                                       ("%g" % rule["hold_s"]) if rule.get("hold_s") is not None else "?")
    for ax, key, what in ((axs[0], "t_cross", "decision: true weight > %s from then on" %
                           ("%g" % thr if thr is not None else "hstpf-mc's threshold")),
                          (axs[1], "t_declare", "declaration: %s (%s)" % (rule_text, rule["source"]))):
        data, labels = [], []
        for path in jsons:
            d = json.load(open(path))
            runs.add(d.get("seeds"))
            t = [r[key] for res in d["results"] for r in res["runs"] if r[key] >= 0 and
                 (key == "t_declare" or r["success"])]
            if t:
                data.append(t)
                labels.append("%s\n(n=%d)" % (d["scenario"], len(t)))
        ax.boxplot(data, showfliers=True)
        ax.set_xticks(range(1, len(labels) + 1))
        ax.set_xticklabels(labels)
        ax.set_title(what, fontsize=10)
        ax.grid(alpha=0.3)
        plt.setp(ax.get_xticklabels(), fontsize=7)
    axs[0].set_ylabel("time [s]")
    seeds = " or ".join(str(s) for s in sorted(x for x in runs if x is not None))
    fig.suptitle("Monte Carlo decision and declaration times, true type, %s seeds per truth" % seeds)
    return save(fig, outdir, "mc_decision_times.png")


def save(fig, outdir, name):
    fig.tight_layout()
    path = os.path.join(outdir, name)
    try:
        fig.savefig(path, dpi=110)
    except OSError as exc:
        raise cli.output_error(path, exc) from exc
    finally:
        plt.close(fig)
    return path


def _main(argv):
    ap = cli.Parser(prog="make_figures.py", description=__doc__,
                    formatter_class=__import__("argparse").RawDescriptionHelpFormatter)
    ap.add_argument("--trace1", required=True, help="hstpf-mc --scenario paper1 --trace CSV")
    ap.add_argument("--trace2", required=True, help="hstpf-mc --scenario paper2 --trace CSV")
    ap.add_argument("--json", nargs="*", default=[],
                    help="hstpf-mc --json outputs (paper1/paper2 name the traced runs)")
    ap.add_argument("--config", help="hstpfd config file whose declare_threshold / declare_hold_s the runs used "
                    "(default: the library's defaults, as hstpf-mc uses them)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    rule = runconfig.declaration(a.config)
    try:
        os.makedirs(a.out, exist_ok=True)
    except OSError as exc:
        raise cli.output_error(a.out, exc) from exc
    for p in a.json:
        try:
            json.load(open(p))
        except (OSError, ValueError) as exc:
            raise cli.input_error(p, exc) from exc
    files = []
    for case, trace, first in ((1, a.trace1, 1), (2, a.trace2, 5)):
        ident = identity(case, a.json)
        r = dict(rule)
        if ident.get("threshold") is not None:  # the run's own record wins
            r.update(threshold=ident["threshold"], hold_s=ident.get("hold_s"), source="hstpf-mc JSON")
        files += paper_figures(trace, case, a.out, first, r, ident)
    if a.json:
        files.append(decision_figure(a.json, a.out, rule))
    for f in files:
        print(f)
    return 0


def main(argv=None):
    return cli.run("make_figures.py", _main, argv)


if __name__ == "__main__":
    sys.exit(main())

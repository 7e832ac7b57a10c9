#!/usr/bin/env python3
"""Figures for docs/results.md from hstpf-mc outputs (traces and JSON).

Reproduces the paper's Figures 1-4 (Case 1) and 5-8 (Case 2) from one traced
run each, and draws the Monte Carlo decision-time distributions."""
import argparse
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hstpf_tools.table1 import TABLE1  # noqa: E402


def theta_for(name):
    return next(r for r in TABLE1 if r[0] == name)

CASE_MODELS = {1: ["SS1/SS3/SS4", "CRH3", "SS8"], 2: ["CRH1", "CRH3", "CRH5"]}
CRH3 = theta_for("CRH3")[1:]  # Table 1, from lib/src/train_types.c


def load_trace(path):
    d = np.genfromtxt(path, delimiter=",", names=True)
    return d


def paper_figures(trace, case, outdir, first_fig):
    d = load_trace(trace)
    th = d["t"] / 3600.0  # hours, as the paper's axes
    names = CASE_MODELS[case]
    q = np.vstack([d["q%d" % k] for k in range(3)])
    files = []

    fig, ax = plt.subplots(figsize=(7, 4))
    for k, (n, mk) in enumerate(zip(names, ["o", "*", "s"])):
        ax.plot(th, q[k], marker=mk, markevery=max(1, len(th) // 25), label=n)
    ax.set(xlabel="time k [h]", ylabel="model weight q", ylim=(-0.02, 1.02),
           title="Fig. %d: weights of each parameter group (Case %d)" % (first_fig, case))
    ax.grid(alpha=0.3)
    ax.legend()
    files.append(save(fig, outdir, "case%d_fig%d_weights.png" % (case, first_fig)))

    fig, axs = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    axs[0].plot(th, d["s_true"] / 1000, label="true")
    axs[0].plot(th, d["s_est"] / 1000, "--", label="estimate")
    axs[0].set(ylabel="position s [km]")
    axs[1].plot(th, d["v_true"] * 3.6, label="true")
    axs[1].plot(th, d["v_est"] * 3.6, "--", label="estimate")
    axs[1].set(xlabel="time k [h]", ylabel="speed v [km/h]")
    for a in axs:
        a.grid(alpha=0.3)
        a.legend()
    axs[0].set_title("Fig. %d: true and estimated state (Case %d)" % (first_fig + 1, case))
    files.append(save(fig, outdir, "case%d_fig%d_state.png" % (case, first_fig + 1)))

    fig, axs = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    for k, (col, unit) in enumerate([("c0", "N/kN"), ("c1", "N/kN per km/h"), ("c2", "N/kN per (km/h)^2")]):
        axs[k].plot(th, d[col], ".", ms=2, label="estimate")
        axs[k].axhline(CRH3[k], color="k", label="true (CRH3)")
        axs[k].set(ylabel="%s [%s]" % (col, unit))
        axs[k].grid(alpha=0.3)
        axs[k].legend(loc="upper right")
    axs[2].set(xlabel="time k [h]")
    axs[0].set_title("Fig. %d: estimated parameters (Case %d)" % (first_fig + 2, case))
    files.append(save(fig, outdir, "case%d_fig%d_params.png" % (case, first_fig + 2)))

    fig, axs = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for k, col in enumerate(["c0", "c1", "c2"]):
        axs[0].plot(th, 100 * (d[col] - CRH3[k]) / CRH3[k], label=col)
    axs[0].axhspan(-5, 5, color="g", alpha=0.1, label="+-5 %")
    axs[0].set(ylabel="parameter error [%]")
    ok = d["s_true"] > 1.0
    axs[1].plot(th[ok], 100 * (d["s_est"][ok] - d["s_true"][ok]) / d["s_true"][ok], label="position")
    ok = d["v_true"] > 1.0
    axs[1].plot(th[ok], 100 * (d["v_est"][ok] - d["v_true"][ok]) / d["v_true"][ok], label="speed")
    axs[1].set(xlabel="time k [h]", ylabel="state error [%]", ylim=(-20, 20))
    for a in axs:
        a.grid(alpha=0.3)
        a.legend()
    axs[0].set_title("Fig. %d: relative errors of parameters and states (Case %d)" % (first_fig + 3, case))
    files.append(save(fig, outdir, "case%d_fig%d_errors.png" % (case, first_fig + 3)))
    return files


def decision_figure(jsons, outdir):
    """Per scenario: when the true weight stays above 0.9 (decision) and
    when Table 2's rule declares the true type (declaration)."""
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.8), sharey=True)
    for ax, key, what in ((axs[0], "t_cross", "decision: true weight > 0.9 from then on"),
                          (axs[1], "t_declare", "declaration: q > 0.99 held 30 s")):
        data, labels = [], []
        for path in jsons:
            d = json.load(open(path))
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
    fig.suptitle("Monte Carlo decision and declaration times, true type, M = 100")
    return save(fig, outdir, "mc_decision_times.png")


def save(fig, outdir, name):
    fig.tight_layout()
    path = os.path.join(outdir, name)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--trace1", required=True)
    ap.add_argument("--trace2", required=True)
    ap.add_argument("--json", nargs="*", default=[])
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    files = paper_figures(a.trace1, 1, a.out, 1) + paper_figures(a.trace2, 2, a.out, 5)
    if a.json:
        files.append(decision_figure(a.json, a.out))
    for f in files:
        print(f)


if __name__ == "__main__":
    main()

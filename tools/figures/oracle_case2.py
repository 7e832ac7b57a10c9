#!/usr/bin/env python3
"""Exact-density reference for paper Case 2 (Gamma noise), run on the grid
engine's own data: for each seed, hstpf-mc writes a trace of paper2 (the
fixes, the traction and each model's log-likelihood increments), and a
bootstrap particle filter on the exact Gamma densities (numpy, M particles
per model, no blur, no floor) runs CRH1, CRH3 and CRH5 on the same fixes.
Both decisions are scored as hstpf-mc scores them (the last step the true
model's weight was at or below 0.9, plus one; weights floored at the
library's q_floor). It shows what the data hold against what the grid
makes of them, seed by seed.

    .venv/bin/python tools/figures/oracle_case2.py --mc build/tools/montecarlo/hstpf-mc --seeds 30
    .venv/bin/python tools/figures/oracle_case2.py --seeds 3 --repeats 8    # its own noise

The initial speed: --prior flat (uniform on 0-3 m/s, what the filter knows:
it acquires from two fixes) or --prior rest (the run's true start, at rest,
which no filter is told). A particle filter's likelihood is unbiased but
noisy; a model whose every particle misses a fix has an exact zero there
(a one-sided noise: a model with less drag than the truth runs ahead of
the fixes), which the library's floor turns into a finite penalty."""
import argparse
import csv
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

from hstpf_tools.model import NOISE_CASES, theta_for, xi

MODELS = ("CRH1", "CRH3", "CRH5")  # paper Case 2's bank; the truth is CRH3
TRUE = 1
Q_FLOOR = 1e-9  # the library's default cfg.q_floor
THR = 0.9       # hstpf-mc's success threshold
TIMES = (12, 100, 150)  # the log-ratios compared: the start, and around the decisions


def gamma_logpdf(x, shape, scale):
    out = np.full(x.shape, -np.inf)
    m = x > 0
    out[m] = (shape - 1) * np.log(x[m]) - x[m] / scale - math.lgamma(shape) - shape * math.log(scale)
    return out


def particle_loglik(y, u, name, M, prior, rng):
    """Per-step log-likelihood increments of one model (step 0: 0)."""
    ns, nv, ne = NOISE_CASES["case2"]
    th = theta_for(name)
    k = xi()
    s = y[0] - ne.sample(rng, M)
    v = np.zeros(M) if prior == "rest" else rng.uniform(0.0, 3.0, M)
    out = np.zeros(len(y))
    for t in range(1, len(y)):
        acc = k * (u[t - 1] - th.resistance(v))
        s, v = s + v + ns.sample(rng, M), np.maximum(v + acc + nv.sample(rng, M), 0.0)
        lw = gamma_logpdf(y[t] - s, ne.a, ne.b)
        mx = lw.max()
        if not np.isfinite(mx):
            out[t:] = -np.inf
            break
        w = np.exp(lw - mx)
        sw = w.sum()
        out[t] = mx + math.log(sw / M)
        idx = np.searchsorted(np.cumsum(w / sw), (rng.random() + np.arange(M)) / M)
        idx = np.minimum(idx, M - 1)
        s, v = s[idx], v[idx]
    return out


def t_cross(inc):
    """hstpf-mc's t_cross from per-model increments (rows: models)."""
    q = np.full(inc.shape[0], 1.0 / inc.shape[0])
    last_below = 0
    for t in range(1, inc.shape[1]):
        lw = np.log(q) + np.where(np.isfinite(inc[:, t]), inc[:, t], -1e30)
        q = np.exp(lw - lw.max())
        q = np.maximum(q / q.sum(), Q_FLOOR)
        q /= q.sum()
        if q[TRUE] <= THR:
            last_below = t
    return last_below + 1


def trace(mc, seed, path):
    subprocess.run([mc, "--scenario", "paper2", "--seeds", "1", "--first-seed", str(seed), "--threads", "1",
                    "--trace", path, "--trace-seed", str(seed)], check=True, stdout=subprocess.DEVNULL)
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mc", default="build/tools/montecarlo/hstpf-mc", help="the hstpf-mc binary")
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--particles", type=int, default=16000, help="per model (16 000)")
    ap.add_argument("--prior", choices=("flat", "rest"), default="flat")
    ap.add_argument("--steps", type=int, default=400, help="steps compared (every run decides before 400 s)")
    ap.add_argument("--repeats", type=int, default=1,
                    help="runs of the particle filter per seed, each with its own random stream: the spread "
                         "between them is the reference's own Monte Carlo noise")
    a = ap.parse_args(argv)
    if a.steps <= max(TIMES):
        ap.error("--steps must exceed %d (the last log-ratio compared)" % max(TIMES))
    rows_out = []
    with tempfile.TemporaryDirectory() as tmp:
        print("seed  grid  exact  lr(CRH3:CRH5) at 12 s grid / exact  at 100 s  at 150 s")
        for seed in range(a.first_seed, a.first_seed + a.seeds):
            rows = trace(a.mc, seed, os.path.join(tmp, "t.csv"))[: a.steps]
            y = np.array([float(r["y"]) for r in rows])
            u = np.array([float(r["u"]) for r in rows])
            g = np.array([[float(r["ll%d" % i]) for r in rows] for i in range(len(MODELS))])
            g[:, 0] = 0.0
            cg = np.cumsum(g, 1)
            tg = t_cross(g)
            pooled = []  # each repeat's sums at 100 and 150 s, per model
            for rep in range(a.repeats):
                rng = np.random.default_rng([seed, rep])
                ref = np.array([particle_loglik(y, u, m, a.particles, a.prior, rng) for m in MODELS])
                cr = np.cumsum(ref, 1)
                tr = t_cross(ref)
                lr = [(cg[TRUE, t] - cg[2, t], cr[TRUE, t] - cr[2, t]) for t in TIMES]
                rows_out.append((tg, tr, lr))
                pooled.append([[cr[i, t] for t in TIMES] for i in range(len(MODELS))])
                print("%4d  %4d  %5d  " % (seed, tg, tr) + "  ".join("%6.2f / %6.2f" % x for x in lr), flush=True)
            if a.repeats > 1:
                # the likelihood's estimate is unbiased, its log is not (it is low by about half its
                # relative variance, more for a model few particles fit): the mean of the repeats'
                # likelihoods, not of their logs, is the less biased
                c = np.array(pooled)  # repeats x models x times
                m = c.max(0)
                lme = m + np.log(np.mean(np.exp(c - m), 0))
                print("      pooled over %d repeats (log of the mean likelihood): lr %s; mean of the logs %s"
                      % (a.repeats, " ".join("%.2f" % (lme[TRUE, j] - lme[2, j]) for j in range(len(TIMES))),
                         " ".join("%.2f" % (c[:, TRUE, j].mean() - c[:, 2, j].mean()) for j in range(len(TIMES)))),
                      flush=True)
    tg = np.array([r[0] for r in rows_out], float)
    tr = np.array([r[1] for r in rows_out], float)
    d = tr - tg
    print("median decision: grid %.1f s, exact %.1f s; exact minus grid, seed by seed: mean %+.1f +- %.1f s, "
          "the exact sooner in %d of %d, by 30 s in %d" % (np.median(tg), np.median(tr), d.mean(),
                                                          d.std() / math.sqrt(len(d)), int((d < 0).sum()), len(d),
                                                          int((tr <= 30).sum())))
    for j, t in enumerate(TIMES):
        fin = np.array([np.isfinite(r[2][j][1]) for r in rows_out])
        gl = np.array([r[2][j][0] for r in rows_out])
        rl = np.array([r[2][j][1] for r in rows_out])
        print("at %d s: CRH5 an exact zero (every particle missed a fix) in %d of %d; median log-ratio of the rest: "
              "grid %.2f, exact %.2f" % (t, int((~fin).sum()), len(fin), np.median(gl[fin]) if fin.any() else float("nan"),
                                          np.median(rl[fin]) if fin.any() else float("nan")))
    return 0


if __name__ == "__main__":
    sys.exit(main())

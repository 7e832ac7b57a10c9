"""The train model of hstpf (docs/model.md, lib/include/hstpf/hstpf.h).

Per step of length T (s), the same rule as tools/sim/hstpf_sim.c:
    a  = xi (u - W(v) - g(s)),  xi = 9.81 / (1 + gamma) / 1000
    held (v == 0 and xi (u - c0 - g) <= 0: nothing can start the train, e.g.
    the holding brake at a platform): s+ = s, v+ = 0, no process noise
    otherwise:
    v+ = max(0, v + T a + w_v)  (resistance and braking cannot reverse the train)
    s+ = s + T v + w_s
    y  = s + e
u, W, g in N/kN; W(v) = c0 + c1 V + c2 V^2 with V = 3.6 v km/h; g from the
track profile: gradient (per mille, + uphill) + 600 / R (R in m, 0 straight).
"""
import bisect
import csv
import math
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .frames import type_index
from .table1 import TABLE1

G = 9.81


def xi(gamma: float = 0.06) -> float:
    """Acceleration per unit force, (m/s^2) per (N/kN)."""
    return G / (1.0 + gamma) / 1000.0


@dataclass(frozen=True)
class Theta:
    name: str
    c0: float
    c1: float
    c2: float

    def resistance(self, v_mps):
        """W in N/kN at speed v (m/s); works on numpy arrays."""
        V = 3.6 * v_mps
        return self.c0 + self.c1 * V + self.c2 * V * V


def theta_for(name: Optional[str] = None, coeffs: Optional[Sequence[float]] = None) -> Theta:
    """A Table 1 row by name, or custom coefficients (c0, c1, c2)."""
    if coeffs is not None:
        c0, c1, c2 = (float(c) for c in coeffs)
        return Theta(name or "custom", c0, c1, c2)
    row = TABLE1[type_index(name or "CRH3")]
    return Theta(*row)


def force_kn(u_nkn, mass_t: float):
    """Total force (kN) from unit force (N/kN) and train mass (t)."""
    return u_nkn * mass_t * G / 1000.0


def unit_force(f_kn, mass_t: float):
    """Unit force (N/kN) from total force (kN): u = 1000 F / (m g)."""
    return f_kn * 1000.0 / (mass_t * G)


class Track:
    """Piecewise-constant track profile; before the first segment g = 0."""

    def __init__(self, segments: Sequence[Sequence[float]] = ()):
        segs = sorted((float(a), float(b), float(c)) for a, b, c in segments)
        for _, grad, r in segs:
            if r != 0 and r < 100:
                raise ValueError(f"curve radius {r} m: use 0 (straight) or >= 100 m")
            if abs(grad) > 100:
                raise ValueError(f"gradient {grad} per mille out of [-100, 100]")
        self.starts = [s[0] for s in segs]
        self.g = [s[1] + (600.0 / s[2] if s[2] else 0.0) for s in segs]

    @classmethod
    def from_csv(cls, path: str) -> "Track":
        """CSV with columns start_m, gradient_permille, curve_radius_m."""
        with open(path, newline="") as f:
            rows = [r for r in csv.DictReader(f)]
        return cls([(r["start_m"], r["gradient_permille"], r["curve_radius_m"]) for r in rows])

    def resistance(self, s: float) -> float:
        i = bisect.bisect_right(self.starts, s) - 1
        return self.g[i] if i >= 0 else 0.0


# ---- noise ------------------------------------------------------------------


@dataclass(frozen=True)
class Noise:
    """One noise channel: 'none', normal(mean, sd) or gamma(shape, scale, loc)."""

    kind: str = "none"
    a: float = 0.0  # normal: mean; gamma: shape
    b: float = 0.0  # normal: sd;   gamma: scale
    loc: float = 0.0  # gamma location

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        if self.kind == "normal":
            return rng.normal(self.a, self.b, n)
        if self.kind == "gamma":
            return self.loc + rng.gamma(self.a, self.b, n)
        return np.zeros(n)

    @property
    def mean(self) -> float:
        return {"normal": self.a, "gamma": self.loc + self.a * self.b}.get(self.kind, 0.0)

    @property
    def var(self) -> float:
        return {"normal": self.b**2, "gamma": self.a * self.b**2}.get(self.kind, 0.0)

    @classmethod
    def parse(cls, spec: str) -> "Noise":
        """'none' | 'normal:mean=M,var=V' (or sd=S) | 'gamma:shape=K,scale=S[,loc=L]'."""
        kind, _, rest = spec.partition(":")
        kw = {}
        for part in filter(None, rest.split(",")):
            k, _, v = part.partition("=")
            kw[k.strip()] = float(v)
        kind = kind.strip().lower()
        if kind in ("none", "zero", ""):
            return cls()
        if kind in ("normal", "gauss", "gaussian"):
            if "var" in kw and "sd" in kw:
                raise ValueError("give var or sd, not both")
            sd = math.sqrt(kw["var"]) if "var" in kw else kw.get("sd", 0.0)
            if sd < 0:
                raise ValueError("sd must be >= 0")
            return cls("normal", kw.get("mean", 0.0), sd)
        if kind == "gamma":
            if kw.get("shape", 0) <= 0 or kw.get("scale", 0) <= 0:
                raise ValueError("gamma needs shape > 0 and scale > 0")
            return cls("gamma", kw["shape"], kw["scale"], kw.get("loc", 0.0))
        raise ValueError(f"unknown noise {spec!r}")


# The paper's cases (our reading: N's second argument a variance, Gamma(shape, scale)).
NOISE_CASES = {
    "none": (Noise(), Noise(), Noise()),
    "case1": (Noise("normal", 0.0, math.sqrt(0.02)), Noise("normal", 0.0, math.sqrt(0.05)), Noise("normal", 0.0, math.sqrt(5.0))),
    "case2": (Noise("gamma", 0.02, 0.1), Noise("gamma", 0.1, 0.05), Noise("gamma", 0.5, 0.2)),
}


# ---- speed profiles -----------------------------------------------------------

# Phases: ("accel", target_kmh, a_mps2), ("cruise", seconds), ("coast", seconds),
# ("brake", target_kmh, d_mps2), ("stop", seconds). A profile's list repeats
# until the run ends. Phase changes follow the noise-free nominal train, so
# the schedule does not depend on the noise draws.
PAPER_ACCEL = (350.0 / 3.6) / 396.0
PROFILES = {
    # The paper: 0 to 350 km/h in 396 s at constant acceleration, then cruise.
    "paper": [("accel", 350.0, PAPER_ACCEL), ("cruise", 1e12)],
    # Accelerate, cruise, coast, brake to a lower speed, again, then to a stop.
    "coast-brake": [
        ("accel", 300.0, 0.35), ("cruise", 300.0), ("coast", 180.0), ("brake", 200.0, 0.5),
        ("cruise", 200.0), ("accel", 300.0, 0.3), ("cruise", 200.0), ("coast", 120.0),
        ("brake", 0.0, 0.6), ("stop", 60.0),
    ],
    # Station to station: accelerate, cruise, brake to a stop, dwell.
    "stops": [("accel", 250.0, 0.4), ("cruise", 400.0), ("brake", 0.0, 0.5), ("stop", 120.0)],
}


def _journey(first_dwell_s, legs):
    """Phases of a timetable as hstpf-mc's journeys (tools/montecarlo/mc.c):
    legs of (cruise km/h, s from departure to braking, dwell s; < 0 = run to
    the end), accelerating at 0.4 and braking at 0.5 m/s^2; held at the end."""
    ph = [("stop", first_dwell_s)] if first_dwell_s > 0 else []
    for kmh, run_s, dwell_s in legs:
        ph.append(("accel", kmh, 0.4))
        if dwell_s < 0:
            return ph + [("cruise", 1e12)]
        ph += [("cruise", max(0.0, run_s - kmh / 3.6 / 0.4)), ("brake", 0.0, 0.5), ("stop", dwell_s)]
    return ph + [("stop", 1e12)]


# hstpf-mc's "stops" line (41 min, 5 stations) and "day" (4 h, 12 stations).
PROFILES["line"] = _journey(30.0, [(300, 250, 120), (250, 200, 120), (300, 250, 120), (200, 150, 120),
                                   (300, 200, 120)])
PROFILES["day"] = _journey(60.0, [(300, 900, 120), (250, 600, 120), (350, 1200, 120), (200, 400, 120),
                                  (300, 800, 120), (160, 300, 120), (300, 1000, 120), (250, 600, 120),
                                  (350, 1100, 120), (200, 500, 120), (300, 900, 120), (250, 700, 120),
                                  (300, 0, -1)])

HOLD_BRAKE = -50.0  # N/kN: the holding brake, reported as traction during a "stop"


def held(theta: Theta, v: float, u: float, g: float) -> bool:
    """The train stands and nothing can start it: v == 0, u - c0 - g <= 0."""
    return v == 0.0 and u - theta.c0 - g <= 0.0


@dataclass
class Run:
    """A simulated run on the model grid t_k = k T, k = 0..n."""

    t: np.ndarray  # s
    s: np.ndarray  # true position, m
    v: np.ndarray  # true speed, m/s
    u: np.ndarray  # unit force applied over [t_k, t_k+1), N/kN
    g: np.ndarray  # track resistance at s_k, N/kN
    phase: List[str]
    theta: Theta
    dt: float
    change_t: Optional[float] = None  # when the consist changed to change_theta (None: it did not)
    change_theta: Optional[Theta] = None


def simulate(
    theta: Theta,
    profile: str = "paper",
    duration_s: float = 1800.0,
    dt: float = 1.0,
    noise=NOISE_CASES["case1"],
    rng: Optional[np.random.Generator] = None,
    track: Optional[Track] = None,
    gamma: float = 0.06,
    change: Optional[Tuple[float, Theta]] = None,
) -> Run:
    """Runs the model from rest at s = 0 for duration_s (n = round(duration/T) steps).

    profile: a name of PROFILES or a list of phases in the same form.

    noise = (w_s, w_v, e); only w_s, w_v are used here (e is per frame).
    The true traction makes the noise-free train follow the profile:
    u = a_profile / xi + W(v) + g(s) with the current true speed and
    position; coasting is u = 0; a stop reports the holding brake
    (HOLD_BRAKE), which brings the train to rest and holds it there.

    change = (T, theta2): the consist is coupled or split at the first step
    from T at which the train is held at rest; from there its resistance is
    theta2's (Run.change_t says when).
    """
    if dt <= 0 or duration_s <= 0:
        raise ValueError("duration and step must be > 0")
    rng = rng if rng is not None else np.random.default_rng()
    track = track or Track()
    phases = PROFILES[profile] if isinstance(profile, str) else list(profile)  # a name or a phase list
    k_xi = xi(gamma)
    n = int(round(duration_s / dt))
    ws = noise[0].sample(rng, n)
    wv = noise[1].sample(rng, n)
    t = np.arange(n + 1) * dt
    s = np.zeros(n + 1)
    v = np.zeros(n + 1)
    u = np.zeros(n + 1)
    g = np.zeros(n + 1)
    names = []
    W = theta.resistance
    theta0, change_t = theta, None
    pi, p_start = 0, 0.0  # phase index, start time
    s_nom = v_nom = 0.0  # the noise-free nominal train that drives phase changes

    def phase_done(ph, t_now):
        kind = ph[0]
        if kind == "accel":
            return v_nom >= ph[1] / 3.6 - 1e-9
        if kind == "brake":
            return v_nom <= ph[1] / 3.6 + 1e-9
        return t_now - p_start >= ph[1] - 1e-9

    for k in range(n + 1):
        # advance past finished phases (bounded: a cycle of instant phases stops)
        for _ in range(2 * len(phases)):
            if not phase_done(phases[pi], t[k]):
                break
            pi, p_start = (pi + 1) % len(phases), t[k]
        ph = phases[pi]
        kind = ph[0]
        g[k] = track.resistance(s[k])
        g_nom = track.resistance(s_nom)
        if kind == "accel":
            a = min(ph[2], (ph[1] / 3.6 - v_nom) / dt)
        elif kind == "brake":
            a = -min(ph[2], (v_nom - ph[1] / 3.6) / dt)
        elif kind == "cruise":
            a = 0.0
        elif kind == "stop":
            a = "hold"
        else:
            a = None  # coast
        if a is None:
            u[k] = 0.0
            a_nom = k_xi * (0.0 - W(v_nom) - g_nom)
        elif a == "hold":
            u[k] = HOLD_BRAKE
            a_nom = 0.0
        else:
            u[k] = a / k_xi + W(v[k]) + g[k]
            a_nom = 0.0 if kind == "stop" else a
        names.append(kind)
        if k == n:
            break
        # nominal train: no noise
        v_new = v_nom + dt * a_nom
        if v_nom >= 0 and v_new < 0:
            v_new = 0.0
        s_nom, v_nom = s_nom + dt * v_nom, (0.0 if kind == "stop" else v_new)
        # true train
        if change is not None and change_t is None and t[k] >= change[0] and held(theta, v[k], u[k], g[k]):
            theta, change_t = change[1], float(t[k])
            W = theta.resistance
        if held(theta, v[k], u[k], g[k]):
            s[k + 1], v[k + 1] = s[k], 0.0
        else:
            acc = k_xi * (u[k] - W(v[k]) - g[k])
            s[k + 1] = s[k] + dt * v[k] + ws[k]
            v[k + 1] = max(0.0, v[k] + dt * acc + wv[k])
    return Run(t, s, v, u, g, names, theta0, dt, change_t, theta if change_t is not None else None)


def sample_frames(run: Run, period_s: float, e_noise: Noise, rng: np.random.Generator,
                  u_noise_sd: float = 0.0):
    """Frame times n P within the run, with measured positions and traction.

    Position: linear interpolation of the true position between grid points
    (exact at t_k, where y_k = s_k + e as in the paper) plus a fresh e per
    frame. Traction: the step's u (zero-order hold over [t_k, t_k+1)), plus
    optional Gaussian noise of sd u_noise_sd N/kN per frame.
    """
    t_end = run.t[-1]
    m = int(math.floor(t_end / period_s + 1e-9)) + 1
    tf = np.arange(m) * period_s
    s_true = np.interp(tf, run.t, run.s)
    y = s_true + e_noise.sample(rng, m)
    k = np.minimum(np.floor(tf / run.dt + 1e-9).astype(int), len(run.u) - 1)
    u = run.u[k] + (rng.normal(0.0, u_noise_sd, m) if u_noise_sd > 0 else 0.0)
    return tf, y, u

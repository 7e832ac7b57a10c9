"""tools/figures/oracle_case2.py: the reference's pieces against hand-derived
values (the Gamma density, hstpf-mc's decision time) and its particle filter
against the exact likelihood of a case it can be computed by hand."""
import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

_spec = importlib.util.spec_from_file_location(
    "oracle_case2", Path(__file__).resolve().parents[2] / "tools" / "figures" / "oracle_case2.py")
oc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(oc)


def test_gamma_logpdf_by_hand():
    # shape 1: the exponential, log(1/scale) - x/scale; zero and below: -inf
    x = np.array([-1.0, 0.0, 0.5, 2.0])
    got = oc.gamma_logpdf(x, 1.0, 0.5)
    assert got[0] == -math.inf and got[1] == -math.inf
    assert got[2:] == pytest.approx([math.log(2.0) - 1.0, math.log(2.0) - 4.0])
    # shape 0.5, scale 0.2 at 0.1: (k-1) ln x - x/s - lgamma(k) - k ln s, with Gamma(1/2) = sqrt(pi)
    want = -0.5 * math.log(0.1) - 0.5 - 0.5 * math.log(math.pi) - 0.5 * math.log(0.2)
    assert oc.gamma_logpdf(np.array([0.1]), 0.5, 0.2)[0] == pytest.approx(want)


def test_t_cross_as_hstpf_mc_scores_it():
    # three models, the true one (index 1) gains 1 nat per step on each other
    # from step 3: q1 = 1 / (1 + 2 e^-n) after n such steps passes 0.9 at n = 3
    # (0.909; n = 2: 0.787), so its last step at or below 0.9 is step 4
    inc = np.zeros((3, 12))
    inc[1, 3:] = 1.0
    assert oc.t_cross(inc) == 5
    # a model at an exact zero (-inf) drops to the floor and the rest decides
    inc = np.zeros((3, 6))
    inc[0, 2:] = -math.inf
    inc[1, 2:] = 3.0
    assert oc.t_cross(inc) == 2
    # never above 0.9: the last step's index plus one
    assert oc.t_cross(np.zeros((3, 7))) == 7


def _integrate(f, x):
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x)))


def test_particle_likelihood_of_a_known_state():
    # at rest without traction a model does not move within the step (s1 =
    # s0 + ws with the start's speed 0), so step 1's likelihood is that of
    # the two fixes: E over e0 of p_e(y1 - y0 + e0 - ws). Here by quadrature
    # without ws (its mean, 2 mm, moves the answer by 0.02 nats: the density's
    # log-slope near 0.15 m is -8 per metre), against M = 200 000 particles
    # (Monte Carlo error about 0.003): tolerance 0.05 nats
    y = np.array([0.30, 0.35])
    u = np.array([0.0, 0.0])
    rng = np.random.default_rng(7)
    inc = oc.particle_loglik(y, u, "CRH3", 200000, "rest", rng)
    e = np.linspace(0.0, 4.0, 400001)[1:]
    pe = np.exp(oc.gamma_logpdf(e, 0.5, 0.2))
    pe /= _integrate(pe, e)
    want = _integrate(pe * np.exp(oc.gamma_logpdf(0.05 + e, 0.5, 0.2)), e)
    assert inc[0] == 0.0
    assert inc[1] == pytest.approx(math.log(want), abs=0.05)

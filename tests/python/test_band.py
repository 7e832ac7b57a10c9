"""EstBand: the five W(v) standard deviations give sd(V) exactly at every
speed (hstpf-score's band_sd), and the speeds agree with the DBC."""
import re

import numpy as np
import pytest

from hstpf_tools.frames import BAND_SPEEDS_KMH, EST_BAND, load_db
from hstpf_tools.score import band_sd


def test_band_sd_is_exact_for_any_covariance():
    rng = np.random.default_rng(7)
    v = np.linspace(0.0, 400.0, 81)
    for _ in range(20):
        a = rng.normal(size=(3, 3)) * np.array([0.3, 0.003, 5e-5])  # scales of c0, c1, c2 (N/kN, per km/h, ...)
        cov = a @ a.T  # positive semi-definite, correlated
        h = lambda x: np.stack([np.ones_like(x), x, x * x])  # noqa: E731
        want = np.sqrt(np.einsum("in,ij,jn->n", h(v), cov, h(v)))
        s = np.array(BAND_SPEEDS_KMH)
        frame = {f"WSd{k}": float(x) for k, x in enumerate(np.sqrt(np.einsum("in,ij,jn->n", h(s), cov, h(s))))}
        # exact up to the fit's round-off, relative to the band's largest sd (sd^2 spans ~1e13 over 0-400 km/h)
        assert band_sd(frame, v) == pytest.approx(want, rel=1e-6, abs=1e-6 * want.max())


def test_band_speeds_match_the_dbc():
    msg = load_db().get_message_by_name(EST_BAND)
    said = [float(x) for x in re.findall(r"V = ([\d.]+), ([\d.]+), ([\d.]+), ([\d.]+) and ([\d.]+) km/h",
                                          msg.comment)[0]]
    assert said == list(BAND_SPEEDS_KMH)
    assert [s.name for s in msg.signals if s.name.startswith("WSd")] == [f"WSd{k}" for k in range(5)]


def test_band_pairs_only_with_its_own_step():
    from hstpf_tools.score import band_at
    ok = {f"WSd{k}": 0.2 for k in range(5)}
    series = {EST_BAND: [(9.0, {**ok, "BandValid": 1}), (10.0, {**ok, "BandValid": 0})]}
    assert band_at(series, 10.0) is None  # the step's band was not valid: no older one instead
    series[EST_BAND].append((11.0, {**ok, "BandValid": 1, "WSd0": 0.3}))
    assert band_at(series, 11.0)["WSd0"] == 0.3
    assert band_at({}, 11.0) is None


def test_curve_band_z_is_the_headers_and_the_chi_square_quantile():
    """Z_CURVE is hstpf.h's HSTPF_BAND_Z_CURVE, and its square the chi-square 95 %
    quantile with 3 degrees of freedom: F(x) = erf(sqrt(x / 2)) - sqrt(2 x / pi) exp(-x / 2)."""
    import math
    import pathlib

    from hstpf_tools.score import Z_CURVE

    header = pathlib.Path(__file__).resolve().parents[2] / "lib" / "include" / "hstpf" / "hstpf.h"
    said = re.search(r"#define HSTPF_BAND_Z_CURVE ([\d.]+)", header.read_text())
    assert said and float(said.group(1)) == Z_CURVE
    x = Z_CURVE * Z_CURVE
    cdf = math.erf(math.sqrt(x / 2)) - math.sqrt(2 * x / math.pi) * math.exp(-x / 2)
    assert cdf == pytest.approx(0.95, abs=1e-4)


def test_curve_band_holds_the_curve_when_theta_is_in_its_ellipsoid():
    """Scheffe: |h'(e)| <= Z_CURVE sqrt(h' S h) at every speed exactly when e' S^-1 e <= Z_CURVE^2
    (the largest ratio over h is sqrt(e' S^-1 e), reached at h = S^-1 e); checked on random
    covariances and errors, at a dense grid of speeds including the maximising one."""
    from hstpf_tools.score import Z_CURVE

    rng = np.random.default_rng(11)
    for _ in range(200):
        a = rng.normal(size=(3, 3)) * np.array([0.3, 0.003, 5e-5])
        cov = a @ a.T + np.diag([1e-4, 1e-8, 1e-12])
        e = rng.multivariate_normal(np.zeros(3), cov) * rng.uniform(0.5, 2.0)
        nees = float(e @ np.linalg.solve(cov, e))
        ratio = lambda h: abs(h @ e) / np.sqrt(h @ cov @ h)  # noqa: E731
        hs = np.linalg.solve(cov, e)
        assert ratio(hs) == pytest.approx(np.sqrt(nees), rel=1e-9)
        v = np.linspace(-1000.0, 1000.0, 2001)
        grid_max = max(ratio(np.array([1.0, x, x * x])) for x in v)
        assert grid_max <= np.sqrt(nees) * (1 + 1e-9)
        if nees <= Z_CURVE ** 2:
            assert grid_max <= Z_CURVE * (1 + 1e-9)

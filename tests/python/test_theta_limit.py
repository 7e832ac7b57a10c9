"""tools/figures/theta_limit.py: the bound and the evidence behave as the
Fisher information says (hand-derived properties, not recorded values)."""
import importlib.util
from pathlib import Path

import pytest

from hstpf_tools import model

_spec = importlib.util.spec_from_file_location(
    "theta_limit", Path(__file__).resolve().parents[2] / "tools" / "figures" / "theta_limit.py")
tl = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(tl)


def _scaled(row, f):
    return model.Theta("t", row.c0 * f[0], row.c1 * f[1], row.c2 * f[2])


def test_evidence_zero_on_the_row_and_quadratic_in_the_offset():
    row = model.theta_for("CRH3")
    on = tl.bound("line", 2460.0, row, 1, row)
    assert on["evidence_nats"] == 0.0
    # the same trajectory (same truth, same seed) at d and 2d: 1/2 d'Id is
    # quadratic, but the truth changes the trajectory, so compare with the
    # information of each run: evidence(2d) / evidence(d) near 4
    e1 = tl.bound("line", 2460.0, _scaled(row, (1.05, 1.05, 1.05)), 1, row)["evidence_nats"]
    e2 = tl.bound("line", 2460.0, _scaled(row, (1.10, 1.10, 1.10)), 1, row)["evidence_nats"]
    assert e1 > 0.0
    assert e2 / e1 == pytest.approx(4.0, rel=0.15)


def test_more_data_tighter_bound():
    row = model.theta_for("CRH3")
    line = tl.bound("line", 2460.0, row, 1, row)
    day = tl.bound("day", 14400.0, row, 1, row)
    assert day["w_rel_sd_rms"] < line["w_rel_sd_rms"]

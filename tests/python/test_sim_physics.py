"""The truth physics of tools/hstpf_tools/model.py, the same rule as the C
simulator (tools/sim/hstpf_sim.h, tests/unit/test_sim.c): a train never
reverses, and a train at rest that nothing can start is held (no noise)."""
import numpy as np
import pytest

from hstpf_tools import model

XI = 9.81 / 1.06 / 1000.0


def test_held_rule_values():
    th = model.Theta("x", 1.0, 0.0, 0.0)
    assert model.held(th, 0.0, model.HOLD_BRAKE, 0.0)
    assert model.held(th, 0.0, 0.0, 0.0)  # u = 0 at a platform
    assert model.held(th, 0.0, 1.0, 0.0)  # exactly c0 cannot start it
    assert not model.held(th, 0.0, 1.5, 0.0)
    assert model.held(th, 0.0, 1.5, 0.5)  # uphill: c0 + g = 1.5
    assert not model.held(th, 0.0, 0.0, -2.0)  # downhill pulls it away
    assert not model.held(th, 1e-9, -50.0, 0.0)


def test_stop_with_noise_is_held_and_reports_the_brake():
    """Case 1 noise: while a stop holds the train, s and v do not move at all
    and the reported traction is the holding brake; v never goes below 0."""
    rng = np.random.default_rng(5)
    run = model.simulate(model.theta_for("CRH3"), "stops", 3000.0, 1.0, model.NOISE_CASES["case1"], rng)
    assert run.v.min() >= 0.0
    stop = np.array([p == "stop" for p in run.phase])
    assert np.all(run.u[stop] == model.HOLD_BRAKE)
    held = np.array([model.held(run.theta, v, u, g) for v, u, g in zip(run.v, run.u, run.g)])
    assert held[:-1].sum() > 300  # several 120 s dwells in 3000 s
    assert np.all(held[:-1] <= stop[:-1])  # only the stop phases hold it here
    k = np.nonzero(held[:-1])[0]
    assert np.all(run.s[k + 1] == run.s[k]) and np.all(run.v[k + 1] == 0.0)


def test_departure_from_rest():
    """The paper's profile starts from rest with u = a / xi + c0 > c0 (no
    noise): it departs, v1 = T a, and s moves from the second step."""
    th = model.theta_for("CRH3")
    run = model.simulate(th, "paper", 2.0, 1.0, model.NOISE_CASES["none"])
    assert run.u[0] == pytest.approx(model.PAPER_ACCEL / XI + th.c0)
    assert run.v[1] == pytest.approx(model.PAPER_ACCEL)
    assert run.s[1] == 0.0 and run.s[2] == pytest.approx(model.PAPER_ACCEL)


@pytest.mark.parametrize("profile,duration,rests", [("line", 2460.0, 6), ("day", 14400.0, 13)])
def test_journey_profiles_noise_free(profile, duration, rests):
    """hstpf-mc's timetables in Python, without noise: the origin's dwell and
    every station's 120 s exactly, held with the brake reported, no
    reversal, cruise speeds as listed (<= 300 km/h on the line, 350 in the day)."""
    run = model.simulate(model.theta_for("CRH3"), profile, duration, 1.0, model.NOISE_CASES["none"])
    v = run.v
    starts = [k for k in range(len(v)) if v[k] == 0.0 and (k == 0 or v[k - 1] > 0.0)]
    ends = [k - 1 for k in range(1, len(v)) if v[k] > 0.0 and v[k - 1] == 0.0]  # departure samples
    assert len(starts) == rests
    first = 30 if profile == "line" else 60
    assert ends[0] - starts[0] == first
    assert all(e - s == 120 for s, e in zip(starts[1:], ends[1:]))
    assert v.min() >= 0.0 and np.all(np.diff(run.s) >= 0.0)
    assert v.max() * 3.6 == pytest.approx(300.0 if profile == "line" else 350.0)
    for s, e in zip(starts, ends):
        assert np.all(run.u[s:e] == model.HOLD_BRAKE)

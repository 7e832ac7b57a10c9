"""tools/figures/make_figures.py on synthetic hstpf-mc traces whose
declaration time, identity and sd are known."""
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from hstpf_tools import runconfig

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("make_figures", ROOT / "tools" / "figures" / "make_figures.py")
mf = importlib.util.module_from_spec(spec)
spec.loader.exec_module(mf)

T_DECL = 700.0
S_SD, V_SD = 3.0, 0.2


def trace(path: Path, with_sd: bool, declared_model: int = 1) -> Path:
    """1800 s at 1 s; model `declared_model` declared from T_DECL on (after
    a wrong, withdrawn declaration of model 0 from 300 to 400 s)."""
    t = np.arange(0.0, 1801.0)
    v = np.minimum(t * 0.245, 97.0)
    s = np.cumsum(v)
    dec = np.full(t.shape, -1)
    dec[(t >= 300) & (t < 400)] = 0
    dec[t >= T_DECL] = declared_model
    cols = {"t": t, "s_true": s, "v_true": v, "u": 0 * t, "y": s, "has_y": 1 + 0 * t, "s_est": s + 1, "v_est": v,
            "c0": 0.8 + 0 * t, "c1": 0.0064 + 0 * t, "c2": 0.000115 + 0 * t, "declared": dec,
            "q0": 0.1 + 0 * t, "q1": 0.8 + 0 * t, "q2": 0.1 + 0 * t}
    if with_sd:
        cols.update(pos_sd=S_SD + 0 * t, spd_sd=V_SD + 0 * t)  # as hstpf-mc --trace names them
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="")
    return path


def mc_json(path: Path, scenario: str, truth: str, seed: int) -> Path:
    runs = [{"seed": seed + i, "success": 1, "t_cross": 100.0 + i, "t_declare": 130.0 + i} for i in range(5)]
    path.write_text(json.dumps({"scenario": scenario, "seeds": 5, "results": [{"truth": truth, "runs": runs}]}))
    return path


@pytest.fixture
def figures(monkeypatch):
    saved = {}

    def keep(fig, outdir, name):
        saved[name] = fig
        return name

    monkeypatch.setattr(mf, "save", keep)
    yield saved
    import matplotlib.pyplot as plt

    plt.close("all")


def dotted_x(ax):
    return [ln.get_xdata()[0] for ln in ax.lines if ln.get_linestyle() == ":"]


def test_figures_name_the_run_mark_the_declaration_and_draw_bands(tmp_path, figures):
    cfg = tmp_path / "c.ini"
    cfg.write_text("declare_threshold = 0.95\ndeclare_hold_s = 45\n")
    j1 = mc_json(tmp_path / "p1.json", "paper1", "CRH3", 1)
    j2 = mc_json(tmp_path / "p2.json", "paper2", "CRH3", 7)
    assert mf.main(["--trace1", str(trace(tmp_path / "t1.csv", True)),
                    "--trace2", str(trace(tmp_path / "t2.csv", False)),
                    "--json", str(j1), str(j2), "--config", str(cfg), "--out", str(tmp_path / "img")]) == 0
    assert len(figures) == 9
    w1 = figures["case1_fig1_weights.png"].axes[0]
    assert "truth CRH3, seed 1, Case 1 (Gaussian)" in w1.get_title()
    assert "seed 7, Case 2 (Gamma)" in figures["case2_fig5_weights.png"].axes[0].get_title()
    assert [ln.get_ydata()[0] for ln in w1.lines if ln.get_linestyle() == "--"] == [0.95]
    legend = [t.get_text() for t in w1.get_legend().get_texts()]
    assert "declaration: q > 0.95, held 45 s (c.ini)" in legend
    assert "declared CRH3 at 700 s" in legend  # the final declaration, not the withdrawn one at 300 s
    for name, fig in figures.items():
        if name.startswith("case"):
            for ax in fig.axes:
                assert dotted_x(ax) == [pytest.approx(T_DECL / 3600)], name
    # bands: case 1's trace has sd columns, case 2's has none
    s1 = figures["case1_fig2_state.png"].axes
    v = s1[1].collections[0].get_paths()[0].vertices
    at = v[np.isclose(v[:, 0], 1000 / 3600)]
    assert (at[:, 1].max() - at[:, 1].min()) / 2 == pytest.approx(1.96 * V_SD * 3.6, rel=1e-3)
    assert all(len(ax.collections) == 0 for ax in figures["case2_fig6_state.png"].axes)
    dec = figures["mc_decision_times.png"]
    assert "q > 0.95 held 45 s (c.ini)" in dec.axes[1].get_title()
    assert "> %g" % mf.mc_success_threshold() in dec.axes[0].get_title()


def test_default_rule_is_the_library_default(tmp_path, figures):
    assert mf.main(["--trace1", str(trace(tmp_path / "t1.csv", False)), "--trace2",
                    str(trace(tmp_path / "t2.csv", False, declared_model=2)), "--out", str(tmp_path / "img")]) == 0
    w = figures["case1_fig1_weights.png"].axes[0]
    assert [ln.get_ydata()[0] for ln in w.lines if ln.get_linestyle() == "--"] == \
        [runconfig.library_default("declare_threshold")]
    assert "declared CRH5 at 700 s" in [t.get_text() for t in
                                        figures["case2_fig5_weights.png"].axes[0].get_legend().get_texts()]


def test_missing_trace_is_one_line_exit_3(tmp_path, capsys):
    assert mf.main(["--trace1", "/nonexistent/t.csv", "--trace2", "/nonexistent/t.csv", "--out", str(tmp_path)]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("make_figures.py: cannot read /nonexistent/t.csv")

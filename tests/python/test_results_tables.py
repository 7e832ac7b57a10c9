"""tools/figures/results_tables.py's issue 13 tables on a synthetic
hstpf-mc output whose counts are known."""
import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("results_tables", ROOT / "tools" / "figures" / "results_tables.py")
rt = importlib.util.module_from_spec(spec)
spec.loader.exec_module(rt)

TOTAL = ("total: 6 runs, success 66.7%, false declarations 3 (50.0%), W(v) error > 5% in 1 (16.7%), "
         "worst truth's mean W(v) error 4.25%, position RMS 0.051 m, speed RMS 0.0280 m/s")


def write(d: Path, scenario: str, tag: str) -> None:
    # CRH2: two runs declare CRH3; CRH3: one declares CRH2; successes cross at 100, 200, 300, 400 s;
    # at the end CRH2's run 2 declares CRH3 and CRH3's run 3 CRH5 (synthetic: that column reads only
    # final_declared), the others the truth or nothing
    runs = {"CRH2": [(1, 100.0, 1, "CRH3", "CRH2"), (0, -1.0, 1, "CRH3", "CRH3"), (1, 200.0, 0, "", "")],
            "CRH3": [(1, 300.0, 0, "", "CRH3"), (1, 400.0, 1, "CRH2", "CRH3"), (0, -1.0, 0, "", "CRH5")]}
    js = {"scenario": scenario, "results": [
        {"truth": t, "runs": [{"seed": i + 1, "success": s, "t_cross": x, "false_decl": f, "false_model": m,
                               "final_declared": e, "pos_rms": 0.1 * (i + 1), "spd_rms": 0.01}
                              for i, (s, x, f, m, e) in enumerate(rr)]}
        for t, rr in runs.items()]}
    (d / f"{scenario}-{tag}.json").write_text(json.dumps(js))
    (d / f"{scenario}-{tag}.txt").write_text("scenario ...\ntruth ...\n" + TOTAL + "\n")


def test_issue13_row(tmp_path):
    write(tmp_path, "heavy-t", "grid")
    table = rt.issue13(tmp_path, "heavy-t").splitlines()
    assert len(table) == 3  # header, rule, the one engine present
    cells = [c.strip() for c in table[2].strip("|").split("|")]
    assert cells[0].startswith("grid")
    assert cells[1:4] == ["6", "66.7%", "200"]  # the lower median of 100, 200, 300, 400
    assert cells[4] == "3 (50.0%)"
    assert cells[5] == "CRH2 -> CRH3 (2); CRH3 -> CRH2 (1)"
    assert cells[6] == "2"  # ending on CRH3 (truth CRH2) and on CRH5 (truth CRH3)
    # position RMS: sqrt(mean(0.1^2, 0.2^2, 0.3^2)) over both truths = sqrt(0.14 / 3)
    assert cells[7:] == ["1 (16.7%)", "4.25%", "0.216", "0.0100"]


def test_issue13_every_row_on_the_grid(tmp_path):
    # the grid with every row on it (--grid-rows 0) is its own row, after the defaults'
    write(tmp_path, "heavy-t", "grid")
    write(tmp_path, "heavy-t", "grid-allrows")
    table = rt.issue13(tmp_path, "heavy-t").splitlines()
    assert len(table) == 4
    assert table[2].startswith("| grid 20 x 72 (library defaults)")
    assert "every row on the grid" in table[3] and "`--grid-rows 0`" in table[3]


def test_issue13_only_prints_present_scenarios(tmp_path, capsys):
    write(tmp_path, "all17-case2", "particle256")
    assert rt.main(["--dir", str(tmp_path), "--issue13-only"]) == 0
    out = capsys.readouterr().out
    assert "### `all17-case2`" in out and "M = 256" in out
    assert "heavy-t" not in out and "Journeys" not in out


def test_spread_rows(tmp_path):
    # the default (0.3) reads the scenarios' own files, the others their -spreadX files; a
    # value whose files are missing gets no row
    crh3 = "CRH3                      100.0%     {}     291     706     274   0.0%   0.0%   0.00%   0.00%     0\n"
    off = ("trains off the table: W(v) error at the end median 3.11% p90 13.54%; the 95% band covers "
           "the truth in {}% of runs; 'no type fits' at the end in 0.0%; a type declared in {}% (refine on)\n")
    for tag, x_med, cov in (("", 208, 90), ("-spread0.4", 209, 95)):
        (tmp_path / f"paper1{tag}.txt").write_text("truth ...\n" + crh3.format(x_med))
        (tmp_path / f"all17{tag}.txt").write_text(TOTAL + "\n")
        for i, s in enumerate(["stops", "off10", "off15", "off20", "mass10", "mass20", "absent"]):
            (tmp_path / f"{s}{tag}.txt").write_text(off.format(f"{cov + i}.0", f"{i}.5"))
    table = rt.spread(tmp_path).splitlines()
    assert len(table) == 4  # header, rule, 0.3 and 0.4 (no 0.2 files)
    cells = [c.strip() for c in table[2].strip("|").split("|")]
    assert cells[:3] == ["0.3 (default)", "208 / 291 / 706", "66.7%, 50.0%"]
    assert cells[3:10] == ["90.0%", "91.0%", "92.0%", "93.0%", "94.0%", "95.0%", "96.0%"]
    assert cells[10] == "2.5%"  # off15's own line
    assert table[3].startswith("| 0.4 | 209 / 291 / 706 |")


def test_prior_rows(tmp_path):
    # the default (0.01) reads the scenarios' own files, the others their -priorQ files (the
    # -norefine paper1 file holds the CRH3 row alone); a value whose files are missing gets no row
    crh3 = "CRH3                      100.0%     {}     291     706     274   0.0%   0.0%   0.00%   0.00%     0\n"
    off = ("trains off the table: W(v) error at the end median 3.11% p90 13.54%; the 95% band covers "
           "the truth in {}% of runs; 'no type fits' at the end in 0.0%; a type declared in {}% (refine on)\n")
    for tag, x_med, base in (("", 208, 1), ("-prior0.03", 222, 5), ("-norefine", 207, 9)):
        head = "" if tag == "-norefine" else "truth ...\n"
        (tmp_path / f"paper1{tag}.txt").write_text(head + crh3.format(x_med))
        (tmp_path / f"all17{tag}.txt").write_text(TOTAL + "\n")
        for i, s in enumerate(["off15", "mass20", "absent", "grade8"]):
            (tmp_path / f"{s}{tag}.txt").write_text(off.format(f"{80 + base + i}.0", f"{base + i}.5"))
    table = rt.prior(tmp_path).splitlines()
    assert len(table) == 5  # header, rule, 0.03, 0.01, off (no 0.02, 0.003, 0.001 files)
    rows = [[c.strip() for c in ln.strip("|").split("|")] for ln in table[2:]]
    assert [r[0] for r in rows] == ["0.03", "0.01 (default)", "off (`--no-refine`)"]
    assert rows[1][1:] == ["208 / 291 / 706", "66.7%", "1.5%", "2.5%", "3.5%", "4.5%", "82.0%"]
    assert rows[0][1] == "222 / 291 / 706" and rows[0][-1] == "86.0%"
    assert rows[2][1] == "207 / 291 / 706" and rows[2][3] == "9.5%"


def test_offtable_student_t_rows(tmp_path):
    # the Student-t scenarios get their own table, only with their files present
    off = ("trains off the table: W(v) error at the end median 3.11% p90 13.54%; the 95% band covers "
           "the truth in 91.0% of runs; 'no type fits' at the end in {}%; a type declared in 0.5% (refine on)\n")
    (tmp_path / "grade8-t.txt").write_text(off.format("61.8"))
    (tmp_path / "grade8-t-norefine.txt").write_text(off.format("0.0"))
    table = rt.offtable(tmp_path, rt.OFFTABLE_T).splitlines()
    assert len(table) == 4  # header, rule, on and off (no stops-t, off15-t files)
    assert table[2].startswith("| `grade8-t` | on (default) | 3.11% / 13.54% | 91.0% | 61.8% | 0.5% |")
    assert table[3].startswith("| `grade8-t` | off |")


def test_offtable_far_split(tmp_path):
    # hstpf-mc's current wording: the pointwise band, the curve's band, and the runs whose truth is
    # >= 10 % from every row; an older output without the split gets '-'
    off = ("trains off the table: W(v) error at the end median 1.64% p90 4.52%; the pointwise 95% band (+- 1.96 sd) "
           "covers the truth at 68 of 71 speeds in 78.9% of runs; 'no type fits' at the end in 98.5%; a type "
           "declared in 21.9% (refine on)\n"
           "the curve's 95% band (+- 2.796 sd) covers the truth at every speed in 94.9% of runs; theta within its "
           "95% ellipsoid (theta_cov) at the end in 92.4% of 1700 runs with a regular theta_cov\n")
    split = ("by the truth's W(v) distance from its nearest bank row (RMS over 0..350 km/h, relative to the row): "
             ">= 10%: 950 runs, "
             "'no type fits' at the end 99.1%, a type declared 3.2% (at the end 0.4%); < 10%: 750 runs, 97.6%, "
             "44.0% (1.9%)\n")
    (tmp_path / "off15.txt").write_text(off + split)
    (tmp_path / "off15-norefine.txt").write_text(off)
    table = rt.offtable(tmp_path, ["off15"]).splitlines()
    assert len(table) == 4
    assert table[2] == "| `off15` | on (default) | 1.64% / 4.52% | 78.9% | 98.5% | 21.9% | 950: 99.1%, 3.2% |"
    assert table[3].endswith("| 21.9% | - |")


def test_oracle_rows(tmp_path):
    # hstpf-mc --oracle's line, once with times and ratios, once with none ("never", "-")
    line = ("oracle (the truth's own theta scored beside its 4 nearest rows, the same engine, no hypothesis), runs "
            ">= 10% off: {n} runs; the truth leads its nearest row by log 99 from the end of a median {m} (p10 {a}, "
            "p90 {b}) to the end, never in {nv} runs; a wrong row first declared in {d} runs ({o} not among the 4 "
            "nearest): the truth's log-likelihood ratio against it then median {lm}, p90 {lp}, max {lx}; below log "
            "99 in {bl}, below 0 in {bz}\n")
    (tmp_path / "off15-case2.txt").write_text("trains off the table: ...\n" + line.format(
        n=929, m="412 s", a="180 s", b="never", nv=120, d=116, o=3, lm="0.85 nats", lp="3.10 nats", lx="7.02 nats",
        bl=110, bz=41))
    (tmp_path / "off15.txt").write_text(line.format(
        n=52, m="never", a="294 s", b="never", nv=34, d=0, o=0, lm="-", lp="-", lx="-", bl=0, bz=0))
    (tmp_path / "absent.txt").write_text("trains off the table: no oracle line\n")
    table = rt.oracle(tmp_path, ["off15", "absent", "off15-case2", "mass20"]).splitlines()
    assert len(table) == 4  # header, rule, off15, off15-case2
    assert table[2] == "| `off15` | 52 | never (294 s, never) | 34 | 0 (0) | - / - / - | 0 | 0 | - | - |"
    assert table[3] == ("| `off15-case2` | 929 | 412 s (180 s, never) | 120 | 116 (3) | 0.85 nats / 3.10 nats / "
                        "7.02 nats | 110 | 41 | - | - |")
    assert rt.oracle(tmp_path, ["absent"]) == ""


def test_oracle_neighbour_columns(tmp_path):
    # the second off-table oracle line: the nearest row against its eight trains 10 % off
    first = ("oracle (the truth's own theta scored beside its 4 nearest rows, the same engine, no hypothesis), runs "
             ">= 10% off: 409 runs; the truth leads its nearest row by log 99 from the end of a median 66 s (p10 38 s, "
             "p90 142 s) to the end, never in 0 runs; a wrong row first declared in 27 runs (2 not among the 4 "
             "nearest): the truth's log-likelihood ratio against it then median 5.27 nats, p90 21.75 nats, max 3745.03 "
             "nats; below log 99 in 11, below 0 in 2\n")
    nb = ("oracle, the nearest row against 8 trains 10% from it in W(v) (the test of the on-table line): it leads all "
          "8 by log 99 at some step in 73 of 409 runs (first at a median 190 s); the filter declared the nearest row "
          "in 22 runs (not the truth's own row), and in 15 of them at a step where the row led all 8 (a rule that "
          "also asks this test would have declared it); another row (not tested) in 5\n")
    (tmp_path / "mass20-case2.txt").write_text(first + nb)
    row = rt.oracle(tmp_path, ["mass20-case2"]).splitlines()[2]
    assert row.endswith("| 11 | 2 | 73 runs | 22 / 15 |")


def test_oracle_on_the_table_rows(tmp_path):
    on = ("oracle (8 trains 10% from the truth's row in W(v), one per sign pattern of c0, c1, c2, scored beside it, "
          "{eng}, no hypothesis): 100 runs; the row leads all 8 by log 99 from the end of a median {m} (p10 {a}, "
          "p90 {b}) to the end, never in {nv} runs; the truth declared (and so at the end) in 100 runs, at a median "
          "197 s (p90 216 s, max 273 s), before the row led all 8 for good in {bf}\n")
    paired = ("oracle, paired with the declaration (runs with both): excluded all 8 minus declared median 27 s (min -45 "
              "s, max 148 s) in 100 runs; counting their evidence only from when the row took the lead for good (a "
              "median 115 s): excluded from a median 229 s (p90 252 s), never in 0 of 100 runs; minus declared "
              "median 31 s in 100 runs\n")
    (tmp_path / "paper2-oracle.txt").write_text("CRH3 ...\n" + on.format(
        eng="the same engine", m="228 s", a="192 s", b="248 s", nv=0, bf=84) + paired)
    (tmp_path / "paper1-oracle.txt").write_text(on.format(
        eng="the same engine", m="never", a="never", b="never", nv=100, bf=100))
    (tmp_path / "paper2-oracle-gauss.txt").write_text(on.format(
        eng="the Kalman engine on the noises' mean and sd", m="291 s", a="276 s", b="315 s", nv=0, bf=100))
    table = rt.oracle_on(tmp_path).splitlines()
    assert len(table) == 5  # header, rule, paper1, paper2, the moments
    assert table[2] == "| `paper1` | 100 | never (never, never) | 100 | 197 s (216 s) | 100 | - | - |"
    assert table[3] == "| `paper2` | 100 | 228 s (192 s, 248 s) | 0 | 197 s (216 s) | 84 | 27 s | 229 s (252 s); 31 s |"
    assert table[4].startswith("| `paper2-oracle-gauss` | 100 | 291 s (276 s, 315 s) | 0 |")
    assert rt.oracle_on(tmp_path / "none") == ""


def test_paired_declaration(tmp_path):
    # seed by seed: (defaults, every row) declaration times, -1 = never
    pairs = {"CRH1": [(100, 90), (250, 250), (-1, 300)], "DFH3": [(400, 100), (200, -1), (60, 80)]}

    def js(i):
        return {"results": [{"truth": t, "runs": [{"seed": k + 1, "t_declare": p[i], "false_decl": int(t == "CRH1"
                                                                                                       and k == 0 and i == 0)}
                                                  for k, p in enumerate(pp)]} for t, pp in pairs.items()]}
    (tmp_path / "stops-t.json").write_text(json.dumps(js(0)))
    assert rt.paired_declaration(tmp_path, "stops-t", "allrows", "every row") == ""  # the other file missing
    (tmp_path / "stops-t-allrows.json").write_text(json.dumps(js(1)))
    row = rt.paired_declaration(tmp_path, "stops-t", "allrows", "every row").splitlines()[2]
    cells = [c.strip() for c in row.strip("|").split("|")]
    # declared in both: differences +10, 0, +300, -20: lower median 0, mean 72.5,
    # sd sqrt((62.5^2 + 72.5^2 + 227.5^2 + 92.5^2) / 3) = 152.2, se 152.2 / 2 = 76.1
    assert cells == ["6", "5 / 5", "4", "+0, +72.5 +- 76.1", "2 / 1 / 1", "1 / 0"]


def one_row(tmp_path, name: str, text: str, table_fn):
    """The cells of the one data row table_fn makes of hstpf-mc output text
    written as name.txt (the other scenarios of its table absent)."""
    (tmp_path / f"{name}.txt").write_text(text)
    table = table_fn(tmp_path).splitlines()
    assert len(table) == 3  # header, rule, the one scenario present
    return [c.strip() for c in table[2].strip("|").split("|")]


def test_restarts_row(tmp_path):
    # hstpf-mc's own wording (the restart scenario's two lines)
    cells = one_row(tmp_path, "restart",
                    "total: 170 runs; false declarations 2 (1.2%), 0 from a standstill, 0 outside the pair; ...\n"
                    "reference restarted at a stop in 170 of 170 runs; valid again after a median 35 s, p90 36 s, "
                    "max 61 s (never in 0); valid at 97.7% of the steps after it; |position error| at a valid step "
                    "after it max 6.11 m\n", rt.restarts)
    assert cells == ["`restart`", "170 of 170", "35 / 36 / 61", "0", "97.7%", "6.11", "2 (1.2%)"]


def test_tracgaps_row(tmp_path):
    # hstpf-mc's own wording (the tracgap scenario's line)
    cells = one_row(tmp_path, "tracgap-hold",
                    "traction gap of 20-60 s from 1010 s (the last traction fed): valid steps more than 5 sd off in "
                    "it and 30 s after: 2851 in 154 of 170 runs; largest speed error at a valid step 7.75 m/s; "
                    "standstill published while the train moved: 1946 steps; the weights' TV across the gap median "
                    "0.0050 max 0.7688\n", rt.tracgaps)
    assert cells == ["`tracgap-hold`", "the last traction fed (before)", "2851 (154 of 170)", "7.75", "1946",
                     "0.0050 / 0.7688"]


def test_swaps_row(tmp_path):
    # hstpf-mc's own wording (the swap scenario's line)
    cells = one_row(tmp_path, "swap",
                    "type changed at a stop (row + 8): a type declared then in 123 of 1700 runs; the old type kept "
                    "after the change in 128, for a median 219 s, max 1460 s; the new truth declared in 181, a "
                    "median 275 s after it; W(300 km/h) error while a wrong type was declared and valid, max 79.1%; "
                    "W(v) error against the new truth at the end (1700 runs) median 9.57% p90 32.72%\n", rt.swaps)
    assert cells == ["`swap`", "123 of 1700", "128, 219 / 1460 s", "181, 275 s", "79.1%", "9.57% / 32.72%"]


def test_honesty_row(tmp_path):
    # hstpf-mc's own wording (a journey's total and "standstill published" lines)
    cells = one_row(tmp_path, "tracsign",
                    "total: 1700 runs; false declarations 3 (0.2%), 0 from a standstill, 0 outside the pair; ...\n"
                    "standstill published while the train moved: 1416 steps in 169 runs; valid steps with the speed "
                    "more than 5 sd and 0.3 m/s off: 6018 in 340 runs; the traction taken for wrong (traction_fault) "
                    "at 480562 steps in 339 runs, its CUSUM while the traction was believed at most 24.97 nats\n",
                    rt.honesty)
    assert cells == ["`tracsign`", "1416 (169)", "6018 (340)", "480562 (339)", "24.97", "3 (0.2%)"]

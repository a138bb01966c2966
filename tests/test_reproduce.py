"""`hydroarm reproduce`: the files, the numbers behind them, and the paper's statements."""

import csv
import io
import json

import numpy as np
import pytest

from hydroarm.cli import main
from hydroarm.io.progress import Progress
from hydroarm.paper.reproduce import OUTPUT_FILES, reproduce

PNG = b"\x89PNG\r\n\x1a\n"


def read_csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


def test_all_files_written(repro):
    out, _ = repro
    for name in OUTPUT_FILES:
        assert (out / name).is_file(), name
        if name.endswith(".png"):
            assert (out / name).read_bytes()[:8] == PNG
    assert (out / "notes.txt").read_text() == "mine"
    assert not list(out.parent.glob(".hydroarm-reproduce-*"))  # no staging left


def test_table3_csv(repro):
    out, _ = repro
    rows = read_csv(out / "table3.csv")
    assert list(rows[0]) == ["load", "direction", "model_mm_s", "paper_mm_s", "rel_error"]
    assert len(rows) == 10 and {r["direction"] for r in rows} == {"raise", "lower"}
    published = [r for r in rows if r["paper_mm_s"]]
    assert sorted({r["load"] for r in published}) == ["10", "6"]
    for r in published:
        # issue limit 3 %; achieved ~1 % (docs/model.md says what limits it)
        assert abs(float(r["model_mm_s"]) / float(r["paper_mm_s"]) - 1) < 0.03
        assert float(r["rel_error"]) == pytest.approx(
            float(r["model_mm_s"]) / float(r["paper_mm_s"]) - 1, abs=1e-5
        )
    for r in rows:
        if not r["paper_mm_s"]:
            assert r["rel_error"] == ""


def test_table2_csv(repro):
    out, _ = repro
    rows = read_csv(out / "table2.csv")
    assert [r["load"] for r in rows] == ["1", "2", "3", "4", "5"]
    for r in rows:
        for c in ("output_torque_Nm", "gamma_theory_pct", "gamma_real_pct"):
            # within 1 %: the paper's rounding (imperial products; 5.09 N m for load 5)
            assert float(r[c]) == pytest.approx(float(r[f"paper_{c}"]), rel=0.01)
    assert "5.09 N m (45.0 lbf in)" in (out / "report.md").read_text()


def test_stall_analysis_matches_print(repro):
    out, _ = repro
    st = json.loads((out / "stall_analysis.json").read_text())
    checks = [
        st[k]
        for k in (
            "theoretical_stall_force_kN",
            "crank_torque_Nm",
            "expected_output_torque_Nm",
            "torque_loss_Nm",
            "torque_loss_pct",
        )
    ]
    # the measured stall torque is an input given twice by the paper, 5.09 N m and 45.0 lbf in,
    # which differ by 0.1 % (its rounding); the JSON says so
    ms = st["measured_stall_torque_Nm"]
    assert ms["value"] == pytest.approx(5.09, rel=2e-3) and "rounding" in ms["note"]
    checks += [
        st["elbow"]["loss_pct"],
        st["friction"]["spring_balance_loss_pct"],
        st["friction"]["stiction_pct_of_stall"],
    ]
    for c in checks:
        assert c["matches_print"], c
    rr = st["rerating_loads_1_5_to_6_10"]
    assert [r["to_load"] for r in rr] == [6, 7, 8, 9, 10]
    for r in rr:
        # W·X of the re-rated load vs the printed load: the γ_real rounding (3 s.f.)
        assert abs(r["torque_rel_diff"]) < 0.01


def test_experiment_comparison(repro):
    out, _ = repro
    rows = {r["quantity"]: r for r in read_csv(out / "experiment_comparison.csv")}
    for q in (
        "table1_load1_raise_mm_s",
        "table1_load5_lower_mm_s",
        "mean_raise_mm_s",
        "mean_lower_mm_s",
        "lower_over_raise_pct",
        "no_load_time_constant_ms",
        "no_load_start_time_constant_ms",
        "max_loaded_time_constant_tested_ms",
        "max_time_constant_to_stall_ms",
    ):
        assert q in rows
    assert float(rows["mean_raise_mm_s"]["measured"]) == 22.6
    # Model 2 against the arm: the paper claims 3 %; ±8 % is the experiment's own scatter
    for q in (
        "table1_load1_raise_mm_s",
        "table1_load1_lower_mm_s",
        "table1_load5_raise_mm_s",
        "table1_load5_lower_mm_s",
    ):
        assert abs(float(rows[q]["rel_error"])) < 0.079
    # Model 1 (real loads, same model) misses the arm's lowering/raising split by far more
    # than the experiment's scatter: that is why the paper re-rated the loads
    assert float(rows["model1_load5_raise_mm_s"]["rel_error"]) > 0.15
    # the no-load constant: measured 25.8 ms (4 readings 24-28 ms, ±8 %)
    assert abs(float(rows["no_load_time_constant_ms"]["rel_error"])) < 0.08


def test_fig07_fig08_data_trends(repro):
    _, data = repro
    for runs, _light, heavy in ((data["model1"], 1, 5), (data["model2"], 6, 10)):
        v = {k: r.metrics()["saturation_velocity_m_s"] for k, r in runs.items()}
        # "lowering the heaviest load produces the fastest arm motion whereas raising the
        # heaviest is the slowest"
        assert v[(heavy, "lower")] == max(v.values())
        assert v[(heavy, "raise")] == min(v.values())
        for (_k, _d), r in runs.items():
            span = np.degrees(r.theta[-1] - r.theta[0])
            assert abs(span) == pytest.approx(120, abs=2.0)  # the 120° test range


def test_fig09_fig10_transients_smooth(repro):
    _, data = repro
    for (_k, d), r in data["transients"].items():
        assert r.metrics()["stalled"] is False
        tc = r.metrics()["time_constant_start_s"]
        assert 5e-3 < tc < 50e-3
        # "smooth transition to the saturated flow region": in the first 150 ms the velocity
        # never reverses, and any ringing after the first maximum swings by less than 5 % of
        # the saturation velocity (the model's damping ratio is ~0.65 for load 6, so a ~3 %
        # overshoot remains, invisible at the scale of the paper's traces)
        w = r.t <= 0.15
        v = r.xdot[w] * (1 if d == "raise" else -1)
        assert np.all(v >= -1e-9)
        dv = np.diff(v)
        ext = v[1:-1][np.sign(dv[:-1]) * np.sign(dv[1:]) < 0]
        if ext.size > 1:
            assert np.max(np.abs(np.diff(ext))) < 0.05 * r.metrics()["saturation_velocity_m_s"]


def test_fig11_statements(repro):
    _, data = repro
    s = {x["statement"]: x["holds"] for x in data["statements"]}
    sw = data["sweep"]
    # every statement the paper makes about Fig. 11 and its time constants holds
    assert all(s.values()), [k for k, v in s.items() if not v]
    assert len(s) == 7
    # ... and below the 50 ms requirement everywhere up to stall
    assert np.all(sw["tc_raise_ms"] < 50) and np.all(sw["tc_lower_ms"] < 50)
    # the no-load formula: the calibrated set gives the measured 25.8 ms, the printed 23.4
    assert sw["no_load_formula_ms"] == pytest.approx(25.8, rel=0.01)
    assert sw["printed_formula_ms"] == pytest.approx(23.4, rel=0.01)


def test_report_html_embeds_figures(repro):
    out, _ = repro
    h = (out / "report.html").read_text()
    # figs 7-11, linear step, validation, Fig. 6 (the leave-one-load-out figure is validate's)
    assert h.count("data:image/png;base64,") == 8
    md = (out / "report.md").read_text()
    assert "Table III" in md and "fig11_time_constant_vs_stall_ratio.png" in md


def test_failure_leaves_nothing(tmp_path, monkeypatch, reuse_validation):
    # a figure fails while the results are staged; the validation step before it is the
    # `repro` run's (reuse_validation): the same values, not computed a second time
    import hydroarm.plotting.paper as pl

    def boom(*a, **k):
        raise RuntimeError("plot failed")

    monkeypatch.setattr(pl, "fig_time_constant_sweep", boom)
    out = tmp_path / "r"
    with pytest.raises(RuntimeError):
        reproduce(out, sweep_points=3)
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_progress_quiet_when_not_a_terminal():
    buf = io.StringIO()
    p = Progress(2, stream=buf)
    p("stage")
    assert buf.getvalue() == ""
    p = Progress(2, stream=buf, enabled=True)
    p("stage")
    assert buf.getvalue().startswith("[1/2] stage")


def test_cli_out_is_a_file(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["reproduce", "--out", str(f)]) == 2
    assert "is not a folder" in capsys.readouterr().err


def test_validation_csv(repro):
    # issue 4: the required columns and rows, hydroarm's error against the measurement
    out, _ = repro
    rows = {r["quantity"]: r for r in read_csv(out / "validation.csv")}
    with open(out / "validation.csv") as fh:
        assert (
            fh.readline().strip()
            == "quantity,measured,paper_model1,paper_model2,hydroarm,rel_error"
        )
    for q in (
        "table1_load1_raise_mm_s",
        "table1_load1_lower_mm_s",
        "table1_load5_raise_mm_s",
        "table1_load5_lower_mm_s",
        "stall_mass_kg",
        "no_load_time_constant_ms",
    ):
        r = rows[q]
        rel = float(r["hydroarm"]) / float(r["measured"]) - 1
        assert float(r["rel_error"]) == pytest.approx(rel, abs=1e-5)  # 6 s.f. in the file
    for q in ("table1_load1_raise_mm_s", "table1_load5_lower_mm_s"):
        assert abs(float(rows[q]["rel_error"])) < 0.05
    whatif = read_csv(out / "whatif.csv")
    assert len(whatif) == 4
    # a better gearbox lifts more: the what-if must show it
    assert float(whatif[1]["stall_mass_kg"]) > 2 * float(whatif[0]["stall_mass_kg"])


@pytest.fixture(scope="module")
def validated(tmp_path_factory):
    """``hydroarm validate``'s outputs (reproduce leaves the leave-one-load-out refits out)."""
    out = tmp_path_factory.mktemp("validate") / "v"
    assert main(["validate", "--out", str(out)]) == 0
    return out


def test_validation_leave_one_load_out(validated, repro):
    # issue 16: the measured arm fitted on load 1 alone predicting load 5, and the other way
    # round, beside the in-sample fit (ucl-arm-measured, fitted on both loads)
    out = validated
    rows = read_csv(out / "leave_one_load_out.csv")
    vrows = {r["quantity"]: r for r in read_csv(out / "validation.csv")}
    assert [r["quantity"] for r in rows] == [
        "table1_load1_raise_mm_s",
        "table1_load1_lower_mm_s",
        "table1_load5_raise_mm_s",
        "table1_load5_lower_mm_s",
    ]
    for r in rows:
        v = vrows[r["quantity"]]
        # the in-sample column is validation.csv's hydroarm column (6 s.f. in both files)
        assert float(r["in_sample"]) == pytest.approx(float(v["hydroarm"]), rel=1e-5)
        assert float(r["measured"]) == float(v["measured"])
        # a prediction, not a fit: worse than in-sample, but a useful one (within 10 %)
        assert abs(float(r["predicted_rel_error"])) > abs(float(r["in_sample_rel_error"]))
        assert abs(float(r["predicted_rel_error"])) < 0.10
    assert rows[0]["fitted_on"] == "load 5 and the stall"
    report = (out / "validation.md").read_text()
    assert "Prediction: fitted on one load, predicting the other" in report
    assert "(leave_one_load_out.png)" in report
    # reproduce's validation files are validate's, less the refits
    rep = repro[0]
    assert not (rep / "leave_one_load_out.csv").exists()
    assert (rep / "validation.csv").read_text() == (out / "validation.csv").read_text()


def test_validate_cli_refuses_a_file_as_folder(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["validate", "--out", str(f)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--out" in err[0]


def test_reproduce_command_prints_headline(repro, monkeypatch, capsys):
    """`hydroarm reproduce` ends with Table III against the paper and where it wrote."""
    out, data = repro
    monkeypatch.setattr("hydroarm.cli.reproduce", lambda folder: data)
    assert main(["reproduce", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    published = [r for r in data["table3"] if r["paper_mm_s"] is not None]
    assert len(published) == 4
    for r in published:
        assert f"{r['model_mm_s']:6.1f}  (paper {r['paper_mm_s']:.1f})" in text
    assert f"written to {out}/" in text


def test_linear_view_section_is_linearize(repro):
    """The report's "linear view of the paper's servo": its table and prose quote
    `linearize` at the horizontal for loads 6 and 10 of both paper sets, and its figure is
    written."""
    import hydroarm as ha

    out, data = repro
    md = (out / "report.md").read_text()
    section = md[md.index("## Linear view of the paper's servo") :]
    rows = data["linear_view"]["rows"]
    assert [(r["set"], r["load"]) for r in rows] == [
        (s, k) for s in ("paper-printed", "paper-calibrated") for k in (6, 10)
    ]
    for r in rows:
        j = ha.parameter_set(r["set"])
        s = ha.linearize(
            ha.saturation_test(j, ha.paper_load(r["load"]), "raise"), at=j.horizontal_angle
        ).summary()
        assert r["omega_h_rad_s"] == s["hydraulic_natural_frequency_rad_s"]
        assert r["zeta_h"] == s["hydraulic_damping_ratio"]
        assert r["k_v_1_s"] == s["velocity_constant_1_s"]
        assert r["time_constant_ms"] == 1e3 * s["time_constant_s"]
        assert r["gain_margin_db"] == s["gain_margin_db"]
        assert r["phase_margin_deg"] == s["phase_margin_deg"]
        assert r["bandwidth_rad_s"] == s["bandwidth_rad_s"]
        assert r["overshoot_pct"] == s["step_overshoot_percent"]
        assert f"| {r['set']} | {r['load']} | {s['hydraulic_natural_frequency_rad_s']:.4g} |" in (
            section
        )
    p6 = rows[0]
    assert f"ω_h = {p6['omega_h_rad_s']:.1f} rad/s with load 6" in section
    assert f"1/K_v = A/K_q = {p6['time_constant_ms']:.1f} ms" in section
    assert "'standard formula' 23 ms" in section
    assert f"overshoots by {p6['overshoot_pct']:.1f} % with load 6" in section
    n = data["linear_view"]["notes"]
    assert n["travel_over_band"] > 10  # the paper's steps saturate the valve
    assert n["large_step_overshoot_pct_travel"] < 0.1 * rows[3]["overshoot_pct"]
    assert (out / "linear_small_step.png").read_bytes()[:8] == PNG

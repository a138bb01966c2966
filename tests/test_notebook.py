"""Notebook-friendly results (issue 33): every result type has a short one-line repr (no
arrays) and an HTML summary table; progress shows as a tqdm.auto bar in a Jupyter kernel (and
as today's lines elsewhere); the single-axes plot functions draw on a given ``ax`` and return
its figure; ``replace`` takes pint quantities."""

import inspect
import io
import re
import types
from pathlib import Path

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import hydroarm as ha  # noqa: E402
from hydroarm.analysis.design import DesignResult  # noqa: E402
from hydroarm.analysis.fit import FitResult  # noqa: E402
from hydroarm.analysis.sensitivity import SensitivityResult  # noqa: E402
from hydroarm.arm.result import ArmResult  # noqa: E402
from hydroarm.errors import HydroarmError  # noqa: E402
from hydroarm.io import progress as progress_mod  # noqa: E402
from hydroarm.io.circuit import load_circuit  # noqa: E402
from hydroarm.io.units import registry  # noqa: E402
from hydroarm.model.circuit import simulate as simulate_circuit  # noqa: E402
from hydroarm.plotting import fit as fit_plots  # noqa: E402
from hydroarm.plotting import linear as linear_plots  # noqa: E402
from hydroarm.plotting import paper as paper_plots  # noqa: E402
from hydroarm.plotting import sensitivity as sens_plots  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
REPR_CHARS = 400  # "short": one line of a notebook cell's output, well under a screen


@pytest.fixture(scope="module")
def joint_result():
    sc = ha.saturation_test(ha.shoulder_elevation(), ha.paper_load(6), "raise", duration=0.05)
    return ha.simulate(sc)


@pytest.fixture(scope="module")
def servo_result():
    return ha.load_scenario(EXAMPLES / "position_servo.toml").replace(duration=0.01).run()


@pytest.fixture(scope="module")
def circuit_result():
    return simulate_circuit(load_circuit(EXAMPLES / "orifice_rig.toml"))


def _check_short(r, *words):
    text = repr(r)
    assert "\n" not in text and len(text) <= REPR_CHARS, text
    assert "array(" not in text and "[[" not in text, text
    assert text.startswith(type(r).__name__ + "(")
    for w in words:
        assert w in text, (w, text)
    page = r._repr_html_()
    assert page.count("<table") >= 1 and page.count("<tr>") >= 2
    assert "array(" not in page
    return page


def test_joint_result(joint_result):
    page = _check_short(joint_result, "load 6 raise", "5001 samples", "euler")
    assert "p_bar" in page and "theta_deg" in page  # the traces' final, min, max
    peak = float(np.max(joint_result.p) / 1e5)
    assert f"{peak:.4g} bar" in page


def test_servo_and_circuit_results(servo_result, circuit_result):
    page = _check_short(servo_result, "electro-hydraulic position servo", "rk4")
    assert "position_m" in page
    page = _check_short(circuit_result, "orifice test rig", "components: 5")
    assert "supply_pressure_bar" in page


def test_other_results_with_their_fields():
    """The analysis results (their runs take minutes) with only the fields their summary
    reads: the repr and the table name the study and what it found, never an array."""
    study = types.SimpleNamespace(name="redesign", cases=(1, 2))
    ev = types.SimpleNamespace(
        x=np.zeros((64, 3)),
        feasible=np.r_[np.ones(10, bool), np.zeros(54, bool)],
        smallest_margin=np.linspace(0, 1, 64),
    )
    d = object.__new__(DesignResult)
    d.__dict__.update(
        study=study, evaluation=ev, pareto=np.r_[np.ones(3, bool), np.zeros(61, bool)],
        elapsed_s=2.0, evaluation_s=1.5,
    )  # fmt: skip
    _check_short(d, "redesign", "designs: 64", "10 of 64", "Pareto designs: 3")

    f = object.__new__(FitResult)
    problem = types.SimpleNamespace(parameters=("flow_coefficient",), system=None, servo=None)
    f.__dict__.update(
        problem=problem, estimate=np.array([1.23e-4]), std_error=np.array([2e-6]),
        residual_sd=0.9, evaluations=42, elapsed_s=3.0, warnings=[],
    )  # fmt: skip
    page = _check_short(f, "flow_coefficient", "0.000123 ± 2e-06")
    assert "evaluations" in page

    s = object.__new__(SensitivityResult)
    plan = types.SimpleNamespace(method="sobol", samples=64, names=["a", "b"])
    s.__dict__.update(
        plan=plan, name="servo tolerances", outputs={"settling_time_s": None},
        X=np.zeros((256, 2)), total_s=5.0,
    )  # fmt: skip
    _check_short(s, "servo tolerances", "sobol, 64 samples", "a, b")

    joint = types.SimpleNamespace(name="elbow_reach", angle_offset=0.0)
    sc = types.SimpleNamespace(
        name="block stacking", method="rk4", step=1e-3, joints=(joint,), joint=lambda n: joint
    )
    t = np.linspace(0, 1, 11)
    a = ArmResult(
        t=t, theta=np.zeros((11, 1)), omega=np.zeros((11, 1)), p=np.zeros((11, 1)),
        y=np.zeros((11, 1)), supply_pressure=np.full(11, 60e5), scenario=sc,
    )  # fmt: skip
    page = _check_short(a, "block stacking", "elbow_reach")
    assert "elbow_reach_deg" in page and "60 bar" in page


def test_every_result_class_is_summarised():
    import hydroarm

    root = Path(hydroarm.__file__).parent
    classes = {
        m.group(1)
        for p in root.rglob("*.py")
        for m in re.finditer(r"^class (\w*Result)\b", p.read_text(), re.M)
    }
    from hydroarm.analysis.systems import SystemDesignResult
    from hydroarm.model.circuit import CircuitResult

    known = {
        c.__name__: c
        for c in (
            ha.SimulationResult, ha.ServoResult, CircuitResult, ArmResult, DesignResult,
            FitResult, SensitivityResult, SystemDesignResult,
        )
    }  # fmt: skip
    assert classes == set(known)
    for c in known.values():
        assert "_repr_html_" in dir(c) and "_summary" in dir(c)
        assert c.__repr__ is not object.__repr__ and "dataclass" not in str(c.__repr__)


# ------------------------------------------------------------------ progress ---
def test_progress_is_a_bar_in_a_notebook(monkeypatch):
    monkeypatch.setattr(progress_mod, "in_notebook", lambda: True)
    p = progress_mod.Progress(3)
    from tqdm.auto import tqdm

    assert isinstance(p.bar, tqdm)
    for label in ("a", "b", "c"):
        p(label)
    assert p.bar.n == 3 and p.bar.total == 3
    assert p.bar.disable or p.bar.desc.startswith("c")


def test_progress_lines_unchanged_outside_a_notebook(monkeypatch):
    monkeypatch.setattr(progress_mod, "in_notebook", lambda: False)
    assert progress_mod.Progress(3).bar is None
    monkeypatch.setattr(progress_mod, "in_notebook", lambda: True)
    buf = io.StringIO()  # a stream given: the lines, as on a terminal
    p = progress_mod.Progress(2, stream=buf, enabled=True)
    assert p.bar is None
    p("a")
    assert buf.getvalue().startswith("[1/2] a (")


def test_not_a_notebook_here():
    assert progress_mod.in_notebook() is False  # pytest is not a Jupyter kernel


def test_sweep_bar_in_a_notebook(monkeypatch):
    from hydroarm.batch import sweep as sweep_mod

    monkeypatch.setattr(sweep_mod, "notebook_bar", progress_mod.notebook_bar)
    monkeypatch.setattr(progress_mod, "in_notebook", lambda: True)
    bar = sweep_mod._Bar(4)
    assert bar.bar is not None
    for done in range(1, 5):
        bar(done, done * 1000)
    assert bar.bar.n == 4


# ------------------------------------------------------------------- ax= ---
SINGLE_AXES = [
    fit_plots.fit_targets_figure,
    linear_plots.pole_figure,
    linear_plots.step_figure,
    paper_plots.fig_model_runs,
    paper_plots.fig_time_constant_sweep,
    paper_plots.fig_validation,
    paper_plots.fig_leave_one_out,
    paper_plots.fig_gearbox_efficiency,
    sens_plots.sobol_figure,
    sens_plots.morris_figure,
]


def test_single_axes_functions_take_ax():
    from hydroarm.plotting.circuit import plot_outputs
    from hydroarm.plotting.joint import plot_result

    for f in [*SINGLE_AXES, plot_outputs, plot_result]:
        assert "ax" in inspect.signature(f).parameters, f.__name__


def test_plots_draw_on_the_given_axes(joint_result):
    rows = [
        {"quantity": "v", "measured": 10.0, "paper_model1": 12.0, "paper_model2": 9.0,
         "hydroarm": 10.5},
    ]  # fmt: skip
    calls = [
        lambda ax: fit_plots.fit_targets_figure(["a", "b"], [0.5, -1.0], ax=ax),
        lambda ax: linear_plots.pole_figure(np.array([-10 + 50j, -10 - 50j]), ax=ax),
        lambda ax: linear_plots.step_figure(
            np.linspace(0, 0.1, 50),
            np.linspace(0, 1, 50),
            {"RiseTime": 0.05, "SettlingTime": 0.08, "Overshoot": 0.0, "PeakTime": 0.1},
            ax=ax,
        ),  # fmt: skip
        lambda ax: paper_plots.fig_model_runs({(6, "raise"): joint_result}, "runs", ax=ax),
        lambda ax: paper_plots.fig_validation(rows, ax=ax),
        lambda ax: paper_plots.fig_leave_one_out(
            [
                {
                    "quantity": "v",
                    "fitted_on": "load 1",
                    "in_sample_rel_error": 0.01,
                    "predicted_rel_error": 0.03,
                }
            ],
            ax=ax,
        ),  # fmt: skip
        lambda ax: paper_plots.fig_gearbox_efficiency(ha.shoulder_elevation(), ax=ax),
        lambda ax: sens_plots.sobol_figure(
            ["a", "b"], [0.5, 0.2], [0.05, 0.05], [0.6, 0.3], [0.05, 0.05], metric="m", ax=ax
        ),
        lambda ax: sens_plots.morris_figure(
            ["a", "b"], [1.0, 0.5], [0.1, 0.1], [0.2, 0.1], metric="m", unit="s", ax=ax
        ),
    ]
    for call in calls:
        fig, (left, right) = plt.subplots(1, 2)
        out = call(right)
        assert out is fig
        assert right.has_data() and not left.has_data()
        assert len(fig.axes) == 2  # nothing added to the user's figure
        plt.close(fig)
    # without ax: a figure of its own, as before
    fig = fit_plots.fit_targets_figure(["a"], [0.5])
    assert len(fig.axes) == 1
    plt.close(fig)


# ------------------------------------------------------------------- pint ---
def test_joint_replace_takes_pint_quantities():
    u = registry()
    j = ha.shoulder_elevation()
    j2 = j.replace(supply_pressure=30 * u.bar, horizontal_angle=30 * u.deg)
    assert j2.supply_pressure == pytest.approx(30e5, rel=1e-15)  # 1 bar = 10⁵ Pa exactly
    assert j2.horizontal_angle == pytest.approx(np.pi / 6, rel=1e-15)
    assert j.replace(supply_pressure=30e5) == j2.replace(horizontal_angle=j.horizontal_angle)
    with pytest.raises(HydroarmError, match=r"joint\.supply_pressure: 3 millimeter"):
        j.replace(supply_pressure=3 * u.mm)
    with pytest.raises(HydroarmError, match="joint.supply_pressure: must be positive"):
        j.replace(supply_pressure=-3 * u.bar)  # the joint's own checks follow


def test_servo_replace_takes_pint_quantities():
    u = registry()
    sc = ha.load_scenario(EXAMPLES / "position_servo.toml")
    s2 = sc.replace(supply_pressure=30 * u.bar, duration=50 * u.ms, mass=2 * u.tonne)
    assert s2.parameters["supply_pressure"] == pytest.approx(30e5, rel=1e-15)
    assert s2.duration == pytest.approx(0.05, rel=1e-15)
    assert s2.parameters["mass"] == pytest.approx(2000.0, rel=1e-15)
    assert s2.vector().dtype == float
    with pytest.raises(HydroarmError, match="mass: 2 second"):
        sc.replace(mass=2 * u.s)

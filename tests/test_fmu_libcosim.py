"""A second FMI importer (issue 33): the joint's FMU run in libcosimpy (the Open Simulation
Platform's libcosim, C++, through its Python wheel) gives FMPy's trajectories bit for bit,
and both are ``hydroarm simulate``'s.

Each importer runs the FMU in a process of its own (pythonfmu's binary is loaded once per
process: tests/fmu_worker.py says why). libcosimpy publishes wheels for some platforms and
Python versions only (x86-64 Linux and Windows); where it has none this module is skipped."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
pytest.importorskip("libcosimpy", reason="libcosimpy has no wheel for this Python or platform")

import hydroarm as ha  # noqa: E402

HERE = Path(__file__).parent
RAISE = HERE.parent / "examples" / "load6_raise.toml"
STOP = 0.2  # [s] of the raise test (the jack under way at saturation speed)
COMM = 1e-3  # [s] the communication step: 100 of the joint's 10 us steps
OUTPUTS = ["theta", "omega", "p", "x"]


def _worker(script, tmp, spec):
    tmp.mkdir(parents=True, exist_ok=True)
    spec_path, out = tmp / "spec.json", tmp / "out.npz"
    spec_path.write_text(json.dumps(spec))
    p = subprocess.run(
        [sys.executable, str(HERE / script), str(spec_path), str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, (p.stdout + p.stderr)[-3000:]
    with np.load(out) as z:
        return {k: z[k] for k in z.files}


@pytest.mark.slow
def test_fmpy_and_libcosim_give_identical_traces(tmp_path):
    fmu = ha.export_fmu(RAISE, tmp_path / "joint.fmu")["path"]
    sc = ha.load_scenario(RAISE)
    lever = float(sc.lever(0.0)[0])  # the raise test's lever, stepped at t = 0, held
    fmpy_run = {
        "stop_time": STOP,
        "output_interval": COMM,
        "input": {"times": [0.0, STOP], "signals": {"lever": [lever, lever]}},
        "output": OUTPUTS,
    }
    fmpy = _worker(
        "fmu_worker.py",
        tmp_path / "fmpy",
        {"fmu": str(fmu), "runs": [{"name": "raise", "kwargs": fmpy_run}], "state": False},
    )
    fmpy = {k.split("/", 1)[1]: v for k, v in fmpy.items() if k.startswith("raise/")}
    steps = int(round(STOP / COMM))
    cosim = _worker(
        "fmu_libcosim_worker.py",
        tmp_path / "cosim",
        {
            "fmu": str(fmu),
            "step": COMM,
            "steps": steps,
            "inputs": {"lever": lever},
            "outputs": OUTPUTS,
        },
    )
    # FMPy records the initial values too; libcosim the values after each step
    assert len(fmpy["time"]) == steps + 1 and len(cosim["time"]) == steps
    # libcosim counts time in whole nanoseconds, FMPy in floats: the same instants to 1 ns
    np.testing.assert_allclose(cosim["time"], fmpy["time"][1:], rtol=0, atol=1e-9)
    ref = ha.simulate(sc.replace(duration=STOP, record_every=int(round(COMM / sc.step))))
    for name in OUTPUTS:
        assert np.array_equal(cosim[name], fmpy[name][1:]), name  # bit for bit
        assert np.array_equal(fmpy[name], getattr(ref, name)), name
    assert cosim["x"][-1] - fmpy["x"][0] > 0.004  # the jack moved (about 5 mm in 0.2 s)


# ------------------------------------------------- hydroarm absent on the target ---
NEEDS = "this FMU needs hydroarm"  # the FMU's log line (hydroarm/fmu/export.py SCRIPT)


def _absent(host, fmu):
    return subprocess.run(
        [sys.executable, str(HERE / "fmu_absent_worker.py"), host, str(fmu)],
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.mark.slow
def test_without_hydroarm_the_host_gets_an_fmi_status_not_a_crash(tmp_path):
    """pythonfmu 0.7's runtime crashed its host (libcosim: SIGSEGV) when the slave class
    could not be imported; the FMU's script now stands in a slave that says what is missing
    in the FMU's log, at status fmi2Error, and refuses every step with fmi2Discard (a
    Python slave's one failure status that is not fatal; docs/fmu.md "FMI statuses")."""
    fmu = ha.export_fmu(RAISE, tmp_path / "joint.fmu")["path"]
    p = _absent("fmpy", fmu)
    assert p.returncode == 0, (p.returncode, (p.stdout + p.stderr)[-3000:])
    statuses = dict(ln.split()[1:] for ln in p.stdout.splitlines() if ln.startswith("status "))
    ok, discard = "0", "2"  # FMI 2.0 status codes
    assert statuses == {
        "setupExperiment": ok,
        "enterInitializationMode": ok,
        "exitInitializationMode": ok,
        "getReal": ok,
        "doStep": discard,
        "terminate": ok,
    }, p.stdout
    error = 3  # the log message's status: fmi2Error
    assert any(
        ln.startswith(f"[log {error}] hydroarm: error: {NEEDS}") for ln in p.stdout.splitlines()
    )
    assert "pip install hydroarm" in p.stdout and p.stdout.rstrip().endswith("done")
    p = _absent("libcosim", fmu)
    assert p.returncode == 0, (p.returncode, (p.stdout + p.stderr)[-3000:])
    assert "step False" in p.stdout and p.stdout.rstrip().endswith("done")
    assert NEEDS in p.stdout + p.stderr  # libcosim's log (on stderr)

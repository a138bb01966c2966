"""Runs FMUs in FMPy in a process of its own, for tests/test_fmu.py.

pythonfmu's binary (0.7) cannot be unloaded and loaded again, nor two of them loaded, in one
process without crashing it (NTNU-IHB/PythonFMU#228, #213); so each FMU runs in a fresh
Python, one FMPy instance for all its runs (``reset`` between them, as FMPy's maintainers
advise for repeated runs; it crashed after a rollback and with the arm, so those get
processes of their own). Usage: ``python fmu_worker.py SPEC.json OUT.npz``; SPEC holds the
FMU path and the runs (keyword arguments of ``fmpy.simulate_fmu``, an ``input`` as
``{"times": [...], "signals": {name: [...]}}``); OUT gets each run's outputs as
``<run>/<variable>`` arrays, a failed run's error text as ``<run>/error``, and with
``"state": true`` (the joint) or ``{"outputs": [...], "input": name, "value": v}`` the
rollback check's values (``state/*``); with ``"statuses": true`` (the joint) the FMI status
of each call of :func:`statuses` (``statuses/<call>``)."""

import json
import os
import sys

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.simulation import instantiate_fmu


def log(env, instance, status, category, message):
    """The FMU's log messages, printed (the test reads them)."""
    print(f"[{(category or b'').decode()}] {(message or b'').decode()}")


def signal(spec):
    names = list(spec["signals"])
    sig = np.zeros(len(spec["times"]), dtype=[("time", float)] + [(n, float) for n in names])
    sig["time"] = spec["times"]
    for n in names:
        sig[n] = spec["signals"][n]
    return sig


def rollback(fmu, md, names):
    """Values after the same 30 steps run three times: straight on, after a rollback
    (get/set state) and after a serialised state is read back. ``names``: the outputs read
    and the input changed before the rollback (default: the joint's)."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outputs = names.get("outputs", ["theta", "omega", "p"])
    changed = names.get("input", "lever")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()

    def run(t, n, h=1e-3):
        for _ in range(n):
            fmu.doStep(t, h)
            t += h
        return fmu.getReal([vr[n] for n in outputs])

    run(0.0, 30)
    state = fmu.getFMUstate()
    blob = fmu.serializeFMUstate(state)
    first = run(0.03, 30)
    fmu.setReal([vr[changed]], [names.get("value", 0.0)])  # another input, then roll back
    run(0.06, 10)
    fmu.setFMUstate(state)
    second = run(0.03, 30)
    fmu.setFMUstate(fmu.deSerializeFMUstate(blob))
    third = run(0.03, 30)
    fmu.freeFMUstate(state)
    fmu.terminate()
    return {"state/first": first, "state/second": second, "state/third": third}


def statuses(fmu, md):
    """The status of each call of a sequence that a master may meet (issue 31): a
    communication step past the budget, a NaN input, a corrupt serialized state, each
    followed by a good call on the same instance (it stays usable)."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    got = {}

    def call(name, f, *args):
        print(f"[call] {name}", flush=True)
        try:
            r = f(*args)
            got[name] = 0
            return r
        except FMICallException as exc:
            got[name] = exc.status
            return None

    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    start_lever = fmu.getReal([vr["lever"]])[0]
    fmu.setReal([vr["lever"]], [float("nan")])  # a bad input when initialisation ends
    call("exit_init_nan_input", fmu.exitInitializationMode)
    call("step_nan_input", fmu.doStep, 0.0, 1e-3)
    fmu.setReal([vr["lever"]], [start_lever])
    call("huge_step", fmu.doStep, 0.0, 1e7)
    call("after_huge_step", fmu.doStep, 0.0, 1e-3)
    good = fmu.getFMUstate()
    lever = fmu.getReal([vr["lever"]])[0]
    fmu.setReal([vr["lever"]], [float("nan")])
    call("nan_input", fmu.doStep, 1e-3, 1e-3)
    fmu.setReal([vr["lever"]], [lever])
    call("after_nan_input", fmu.doStep, 1e-3, 1e-3)
    bad = call("deserialize_corrupt", fmu.deSerializeFMUstate, b"\xff\x00 not a state")
    if bad is not None:
        call("set_corrupt", fmu.setFMUstate, bad)
        call("step_after_corrupt", fmu.doStep, 2e-3, 1e-3)
    call("set_good", fmu.setFMUstate, good)
    call("step_after_good", fmu.doStep, 1e-3, 1e-3)
    got["theta_finite"] = int(np.isfinite(fmu.getReal([vr["theta"]])[0]))
    fmu.terminate()
    return {f"statuses/{k}": np.array(v) for k, v in got.items()}


def main(spec_path, out_path):
    spec = json.loads(open(spec_path).read())
    md = read_model_description(spec["fmu"])
    folder = extract(spec["fmu"])
    fmu = instantiate_fmu(folder, md, "CoSimulation", debug_logging=True, logger=log)
    out = {}
    if spec.get("statuses"):
        out.update(statuses(fmu, md))
    if spec.get("state"):
        names = spec["state"] if isinstance(spec["state"], dict) else {}
        out.update(rollback(fmu, md, names))
    for i, run in enumerate(spec["runs"]):
        if i or spec.get("state"):
            fmu.reset()
        kw = dict(run["kwargs"])
        if "input" in kw:
            kw["input"] = signal(kw["input"])
        try:
            res = simulate_fmu(folder, model_description=md, fmu_instance=fmu, **kw)
        except Exception as exc:  # what the FMU reported, for the test to read
            out[f"{run['name']}/error"] = np.array(str(exc))
            continue
        for name in res.dtype.names:
            out[f"{run['name']}/{name}"] = res[name]
    np.savez(out_path, **out)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
    sys.stdout.flush()
    # leave without the interpreter's teardown: pythonfmu 0.7's library has corrupted the
    # heap while being torn down after an FMU error or a rollback (the results are saved)
    os._exit(0)

"""Runs an FMU in libcosimpy (the Open Simulation Platform's libcosim, a second FMI importer
beside FMPy) in a process of its own, for tests/test_fmu_libcosim.py (pythonfmu's binary is
loaded once per process: tests/fmu_worker.py says why).

Usage: ``python fmu_libcosim_worker.py SPEC.json OUT.npz``; SPEC holds ``fmu``,
``step`` [s] (the communication step), ``steps``, ``inputs`` ({name: value}, held through
the run), ``outputs`` (names); OUT gets ``time`` and each output after each step."""

import json
import sys

import numpy as np
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave

NS = 1_000_000_000  # libcosim's time unit: the nanosecond


def main(spec_path, out_path):
    spec = json.loads(open(spec_path).read())
    step_ns = int(round(spec["step"] * NS))
    ex = CosimExecution.from_step_size(step_size=step_ns)
    i = ex.add_local_slave(CosimLocalSlave(fmu_path=spec["fmu"], instance_name="fmu"))
    refs = {v.name.decode(): v.reference for v in ex.slave_variables(i)}
    for name, value in spec["inputs"].items():
        ex.real_initial_value(i, refs[name], float(value))
    observer = CosimObserver.create_last_value()
    ex.add_observer(observer)
    vrs = [refs[n] for n in spec["outputs"]]
    rows, times = [], []
    for k in range(spec["steps"]):
        if not ex.step():  # libcosim initialises the FMU before the first step
            raise SystemExit(f"libcosim: step {k + 1} failed")
        rows.append(observer.last_real_values(i, vrs))
        times.append(ex.status().current_time / NS)
    got = np.array(rows, dtype=float)
    columns = {n: got[:, j] for j, n in enumerate(spec["outputs"])}
    np.savez(out_path, time=np.array(times), **columns)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

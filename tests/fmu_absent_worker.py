"""Runs a hydroarm FMU in a Python where hydroarm cannot be imported, for
tests/test_fmu_libcosim.py: the target that lacks hydroarm (docs/fmu.md).

Usage: ``python fmu_absent_worker.py fmpy|libcosim FMU``. ``import hydroarm`` fails in this
process (``sys.modules["hydroarm"] = None``), and so in the FMU's slave, which runs in this
interpreter. Prints one ``status <call> <FMI status>`` line per call (fmpy) or ``step
<True|False>`` (libcosim), and the FMU's log lines; exits 0 unless the host crashed."""

import sys

sys.modules["hydroarm"] = None  # hydroarm absent: `import hydroarm` raises ImportError


def log(env, instance, status, category, message):
    print(f"[log {status}] {(message or b'').decode()}", flush=True)


def fmpy(path):
    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.simulation import instantiate_fmu

    md = read_model_description(path)
    fmu = instantiate_fmu(extract(path), md, "CoSimulation", debug_logging=True, logger=log)
    output = next(v.valueReference for v in md.modelVariables if v.causality == "output")
    calls = [
        ("setupExperiment", lambda: fmu.setupExperiment(startTime=0.0)),
        ("enterInitializationMode", fmu.enterInitializationMode),
        ("exitInitializationMode", fmu.exitInitializationMode),
        ("getReal", lambda: fmu.getReal([output])),
        ("doStep", lambda: fmu.doStep(0.0, 1e-3)),
        ("terminate", fmu.terminate),
    ]
    for name, call in calls:
        try:
            call()
            status = 0
        except FMICallException as exc:
            status = exc.status
        print(f"status {name} {status}", flush=True)
    fmu.freeInstance()


def libcosim(path):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimSlave import CosimLocalSlave

    ex = CosimExecution.from_step_size(step_size=1_000_000)  # 1 ms, in ns
    ex.add_local_slave(CosimLocalSlave(fmu_path=path, instance_name="fmu"))
    print(f"step {ex.step()}", flush=True)


if __name__ == "__main__":
    {"fmpy": fmpy, "libcosim": libcosim}[sys.argv[1]](sys.argv[2])
    print("done", flush=True)

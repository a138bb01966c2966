"""Export the load-6 raise test as an FMU and run it in FMPy (docs/fmu.md).

Run:  python examples/fmu_fmpy.py   (needs hydroarm[fmu]: pythonfmu and fmpy)
"""

import os
import sys
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.simulation import instantiate_fmu

import hydroarm as ha

config = Path(__file__).with_name("load6_raise.toml")
ha.export_fmu(config, "servo.fmu")  # the same as: hydroarm fmu --config ... --out servo.fmu

# the master: FMPy, communicating every 1 ms; the lever input held at the raise test's target
sc = ha.load_scenario(config).replace(duration=0.5, record_every=100)
y = float(sc.lever(0.0)[0])  # [m]
lever = np.array([(0.0, y), (0.5, y)], dtype=[("time", float), ("lever", float)])
# one instance, kept loaded: pythonfmu's library must not be unloaded while Python runs
# (FMPy's simulate_fmu unloads it when it made the instance; docs/fmu.md "One FMU per process")
md = read_model_description("servo.fmu")
folder = extract("servo.fmu")
instance = instantiate_fmu(folder, md, "CoSimulation")
res = simulate_fmu(
    folder,
    model_description=md,
    fmu_instance=instance,
    stop_time=0.5,
    output_interval=1e-3,
    input=lever,  # parameters: start_values={"joint.supply_pressure": 25e5, ...}
    output=["theta", "x", "p", "supply_flow"],
)

ref = ha.simulate(sc)  # hydroarm's own run at the same internal step
print(f"jack travel in 0.5 s: {(res['x'][-1] - res['x'][0]) * 1e3:.2f} mm")
print(f"peak supply flow: {res['supply_flow'].max() * 6e4:.3f} l/min")
print("same as hydroarm simulate:", bool(np.array_equal(res["theta"], ref.theta)))

# leave without the interpreter's teardown: pythonfmu 0.7's library can corrupt the heap while
# the process tears down after an FMU has run in it (upstream NTNU-IHB/PythonFMU#213, #228;
# docs/fmu.md "One FMU per process"); the results are printed above
sys.stdout.flush()
os._exit(0)

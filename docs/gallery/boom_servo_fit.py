"""A fit: the boom's viscous friction from a measured lift
========================================================

`hydroarm.fit` estimates parameters from measured traces (docs/fit.md). Here the
"measurement" is synthetic: the boom servo run with a viscous friction of 4200 N·s/m, sampled
and given 0.1 mm of noise. The fit recovers the friction with its standard error; the
measured samples and the fitted model are drawn with
`hydroarm.plotting.fit.fit_trace_figure`.
"""

import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import numpy as np

import hydroarm as ha
from hydroarm.io.examples import examples_folder
from hydroarm.plotting.fit import fit_trace_figure

EXAMPLES = examples_folder()  # the example files: examples/ in a checkout, or in the wheel

servo = ha.load_scenario(EXAMPLES / "boom_servo.toml")
truth = 4200.0  # [N*s/m]
run = servo.replace(viscous_friction=truth, duration=1.2).run().to_pandas()
sampled = run[(run.t_s >= 0.15) & (np.arange(len(run)) % 5 == 0)]
noise = np.random.default_rng(7).normal(0.0, 0.1e-3, len(sampled))

work = Path(tempfile.mkdtemp())
sampled.assign(position_m=sampled.position_m + noise)[["t_s", "position_m"]].to_csv(
    work / "lift.csv", index=False
)
(work / "fit.toml").write_text(f'''
name = "boom: viscous friction from a synthetic lift"
[system]
file = "{(EXAMPLES / "boom_servo.toml").as_posix()}"
duration = "1.2 s"
[fit]
parameters = ["viscous_friction"]
[[trace]]
csv = "lift.csv"
columns = {{ t = "t_s", position_m = "position_m" }}
''')
fitted = ha.fit(work / "fit.toml")
estimate, error = fitted.estimate[0], fitted.std_error[0]
print(f"viscous friction {estimate:.0f} ± {error:.0f} N·s/m (truth {truth:.0f})")

trace = fitted.problem.traces[0]
fig = fit_trace_figure(
    trace.t,
    np.ravel(trace.values),
    np.ravel(fitted.fitted[0]),
    "position_m",
    title=f"fitted viscous friction {estimate:.0f} ± {error:.0f} N·s/m (truth {truth:.0f})",
)
fig.savefig("boom_servo_fit.png", dpi=100)

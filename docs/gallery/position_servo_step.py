"""A position servo's step response
=================================

A servo built from components (`examples/position_servo.toml`: a fixed pump into a supply
volume, a 4/3 spool valve, a symmetric cylinder moving a mass, a position sensor and a PI
controller) follows a step of its reference. `hydroarm.load_scenario` reads the file,
`ServoScenario.replace` shortens the run, and `hydroarm.plotting.servo.servo_figure` draws
the position, the spool and the pressures (docs/components.md).

The example's loop has no hydraulic damping at its operating point (docs/linear.md: ζ_h = 0
with the spool in its overlap), so the run limit-cycles by about ±8 mm about the reference
and the chamber pressures swing with it, with peaks at each step.
"""

import matplotlib

matplotlib.use("Agg")

import hydroarm as ha
from hydroarm.io.examples import examples_folder
from hydroarm.plotting.servo import servo_figure

EXAMPLES = examples_folder()  # the example files: examples/ in a checkout, or in the wheel

servo = ha.load_scenario(EXAMPLES / "position_servo.toml").replace(duration=1.5)
result = servo.run()
summary = result.summary()
for key in ("final_position_m", "final_reference_m", "peak_pressure_bar", "peak_speed_m_s"):
    if key in summary:
        print(f"{key:<20} {summary[key]:.4g}")

fig = servo_figure(result)
fig.savefig("position_servo_step.png", dpi=100)

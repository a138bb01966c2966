"""A linear view: the boom servo's Bode plot
==========================================

`hydroarm.linearize` linearises a servo about an operating point (docs/linear.md): here the
boom servo of `examples/boom_servo.toml` at 0.2 m of stroke. Where the valve is closed at
that point, the loop is read at the nearest point with flow. The open-loop and closed-loop
frequency responses are drawn with `LinearModel.bode_figure`, and the margins printed.
"""

import matplotlib

matplotlib.use("Agg")

import hydroarm as ha
from hydroarm.io.examples import examples_folder

EXAMPLES = examples_folder()  # the example files: examples/ in a checkout, or in the wheel

servo = ha.load_scenario(EXAMPLES / "boom_servo.toml")
linear = ha.linearize(servo, at=0.2)
model = linear.nearest or linear
for key in ("gain_margin_db", "phase_margin_deg"):
    print(f"{key:<18} {model.margins()[key]:.3g}")
print(
    f"hydraulic natural frequency {model.quantities['hydraulic_natural_frequency_rad_s']:.4g} rad/s"
)

fig = model.bode_figure()
fig.savefig("boom_servo_bode.png", dpi=100)

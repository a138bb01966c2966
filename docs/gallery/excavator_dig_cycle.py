"""A mechanism: the excavator's dig-and-dump cycle
================================================

`examples/excavator.toml` is a whole machine (docs/mechanism.md): an excavator's boom, stick
and bucket on three revolute joints, each turned by a cylinder through a pivot linkage under
PID control, fed by one pressure-compensated pump. The circuit and its mechanism run as one
system; the joints' angles and torques are drawn with
`hydroarm.plotting.mechanism.fig_joints`, and side views of the machine with
`fig_frames` (the first part of the cycle, to keep the example short; `hydroarm arm
--config examples/excavator.toml` runs all of it).
"""

import matplotlib

matplotlib.use("Agg")

from hydroarm.io.circuit import load_circuit
from hydroarm.io.examples import examples_folder
from hydroarm.model.circuit import build, simulate
from hydroarm.plotting.mechanism import fig_frames, fig_joints, stick_parents, stick_points

EXAMPLES = examples_folder()  # the example files: examples/ in a checkout, or in the wheel

circuit = load_circuit(EXAMPLES / "excavator.toml")
circuit = circuit.replace(duration=6.0)
compiled = build(circuit)
result = simulate(compiled)
columns = result.columns()
t = columns["t_s"]
mechanism = compiled.mechanism
joints = tuple(mechanism.joint_names)
print("joints:", ", ".join(joints))

fig = fig_joints(t, columns, joints)
fig.savefig("excavator_joints.png", dpi=100)

start = len(compiled.hydraulic)
q = result.states[:, start : start + mechanism.n]
frames = fig_frames(t, stick_points(mechanism, q), stick_parents(mechanism), n=8)
frames.savefig("excavator_frames.png", dpi=90)

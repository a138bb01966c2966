"""The compiled net's per-circuit lists that the system kernel's loops take (issue 28 speed):
the ports summed at the nodes (net[26], net[27]) and the tables of the loops over the
components (net[28] to net[30]).

Checks that can fail: every hydraulic and every mechanical port is summed once, at its node,
the lists sorted by node (the kernel sums a node's run of the list in a register) and, within
a node, in the order the laws run (the order of the floating-point sums, which keeps the
results those of summing after each law); each table row holds its component's kind code,
offsets and port count, in the order of its loop.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hydroarm.core.circuit.components import KIND
from hydroarm.core.circuit.system import D_HYDRAULIC, D_MECHANICAL
from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import build

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(
    scope="module",
    params=["circuit_position_servo.toml", "two_actuators.toml", "ucl-arm-mechanism.toml"],
)
def compiled(request):
    return build(load_circuit(EXAMPLES / request.param))


def test_port_lists_cover_each_port_once_by_node_in_law_order(compiled):
    net = compiled.net
    kinds, ports, domains, law_order, nports = net[0], net[3], net[4], net[6], net[10]
    for code, listed in ((D_HYDRAULIC, net[26]), (D_MECHANICAL, net[27])):
        in_law_order = [
            (c, k, ports[c, k])
            for c in law_order
            for k in range(nports[c])
            if domains[c, k] == code
        ]
        expected = sorted(in_law_order, key=lambda e: e[2])  # stable: law order in a node
        assert listed.shape == (len(expected), 3)
        assert [tuple(r) for r in listed.tolist()] == [tuple(map(int, e)) for e in expected]
    assert len(net[26]) > 0 and len(kinds) == len(compiled.circuit.components)


def test_component_tables_follow_their_loops(compiled):
    net = compiled.net
    kinds, poff, soff, nports = net[0], net[1], net[2], net[10]
    for order, table in ((net[6], net[28]), (net[5], net[29]), (net[7], net[30])):
        assert table.shape == (len(order), 5)
        np.testing.assert_array_equal(table[:, 0], order)
        np.testing.assert_array_equal(table[:, 1], kinds[order])
        np.testing.assert_array_equal(table[:, 2], poff[order])
        np.testing.assert_array_equal(table[:, 3], soff[order])
        np.testing.assert_array_equal(table[:, 4], nports[order])
    types = [c.type for c in compiled.circuit.components]
    assert [KIND[types[c]] for c in net[28][:, 0]] == net[28][:, 1].tolist()

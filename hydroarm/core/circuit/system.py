"""The system kernel: one right-hand side over any circuit (issue 28; docs/architecture.md).

A circuit is compiled (:mod:`hydroarm.model.circuit`) into fixed arrays, the *net*::

    kinds[c]        the kind code of component c (:data:`.components.KIND`)
    poff[c]         the offset of its parameter block in the parameter vector P
    soff[c]         the offset of its own states in the state vector s
    ports[c, k]     the node (hydraulic or mechanical) or signal its port k connects to
    domains[c, k]   D_HYDRAULIC, D_MECHANICAL, D_SIGNAL_IN, D_SIGNAL_OUT, D_FLOW_TAP, D_NONE
    sig_order       the components with signal outputs, sources before their readers
    law_order       every component, those that read other components' flows last
    proj_list       the components with a non-smooth part
    fixed[i]        c + 1 where component c prescribes node i's pressure (a tank), else 0
    dims            (hydraulic nodes nh, mechanical nodes nm, signals, components, states)
    nports[c]       how many ports component c declares

and the state vector is ``[p_0 … p_nh-1, x_0 … x_nm-1, v_0 … v_nm-1, component states]``.
The right-hand side evaluates the signals in order, then every component's law, and sums
at the nodes (Kirchhoff's laws for both domains)::

    ṗ_i = Σ_c q_c,i / Σ_c C_c,i          (hydraulic node: flows in, compliances)
    ẋ_m = v_m,   v̇_m = Σ_c F_c,m / Σ_c M_c,m   (mechanical node: forces, masses)

A node at the cavitation floor (``system.cavitation_pressure``) does not fall further; the
step's projection also holds it there. A prescribed node's pressure is its source's.

:func:`port_quantities` gives, at any state, every port's through variable and every
component's absorbed power, so that ``Σ_c P_c = 0`` at every instant: the energy account
closes over all components by construction (docs/components.md "Energy").
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .declare import MAX_PORTS, Component, Param
from .dispatch import follows_components, law_of, project_of, signals_of
from .laws import kernel

D_NONE, D_HYDRAULIC, D_MECHANICAL, D_SIGNAL_IN, D_SIGNAL_OUT, D_FLOW_TAP = range(6)

#: the system's own parameters, the first block of P (``system.<name>`` in files and sweeps)
SYSTEM = Component(
    type="system",
    summary="settings of the whole circuit",
    parameters=(
        Param(
            "cavitation_pressure",
            "Pa",
            0.0,
            ">= 0",
            "lowest absolute node pressure (the oil parts below it)",
        ),
    ),
    states=(),
    ports=(),
)
SYS, _, _ = SYSTEM.indices()
N_SYSTEM_PARAMETERS = len(SYSTEM.parameters)


@njit(cache=True, nogil=True, error_model="numpy")
def make_work(net):
    """The work arrays of one evaluation: (pn, xm, vm, sig, thr, cap, qn, cn, fm, mm)."""
    dims = net[9]
    nh, nm, nsig, nc = dims[0], dims[1], dims[2], dims[3]
    return (
        np.zeros(nh),
        np.zeros(nm),
        np.zeros(nm),
        np.zeros(max(nsig, 1)),
        np.zeros((nc, MAX_PORTS)),
        np.zeros((nc, MAX_PORTS)),
        np.zeros(nh),
        np.zeros(nh),
        np.zeros(nm),
        np.zeros(nm),
    )


@kernel
def evaluate_signals(t, s, P, net, work):
    """Node pressures, mechanical states and every signal at (t, s), in the work arrays."""
    kinds, poff, soff, ports = net[0], net[1], net[2], net[3]
    sig_order = net[5]
    dims = net[9]
    nh, nm = dims[0], dims[1]
    pn, xm, vm, sig = work[0], work[1], work[2], work[3]
    for i in range(nh):
        pn[i] = s[i]
    for m in range(nm):
        xm[m] = s[nh + m]
        vm[m] = s[nh + nm + m]
    for j in range(sig_order.shape[0]):
        c = sig_order[j]
        signals_of(kinds[c], t, P, poff[c], s, soff[c], ports[c], pn, xm, vm, sig)


@kernel
def system_rhs(t, s, P, net, work, d):
    """Write ṡ into d: the circuit's smooth right-hand side at (t, s) (module doc)."""
    kinds, poff, soff, ports, domains = net[0], net[1], net[2], net[3], net[4]
    law_order = net[6]
    fixed = net[8]
    dims = net[9]
    nh, nm = dims[0], dims[1]
    evaluate_signals(t, s, P, net, work)
    pn, xm, vm, sig, thr, cap, qn, cn, fm, mm = work
    qn[:] = 0.0
    cn[:] = 0.0
    fm[:] = 0.0
    mm[:] = 0.0
    nports = net[10]
    for j in range(law_order.shape[0]):
        c = law_order[j]
        for k in range(nports[c]):
            thr[c, k] = 0.0
            cap[c, k] = 0.0
        law_of(kinds[c], t, c, P, poff[c], s, soff[c], d, ports[c], pn, xm, vm, sig, thr, cap)
        for k in range(nports[c]):
            dom = domains[c, k]
            if dom == D_HYDRAULIC:
                qn[ports[c, k]] += thr[c, k]
                cn[ports[c, k]] += cap[c, k]
            elif dom == D_MECHANICAL:
                fm[ports[c, k]] += thr[c, k]
                mm[ports[c, k]] += cap[c, k]
    floor = P[SYS.cavitation_pressure]
    for i in range(nh):
        if fixed[i] != 0:
            d[i] = 0.0
        else:
            r = qn[i] / cn[i]
            if pn[i] <= floor and r < 0.0:
                r = 0.0
            d[i] = r
    for m in range(nm):
        d[nh + m] = vm[m]
        d[nh + nm + m] = fm[m] / mm[m]


@kernel
def system_project(t, h, s_old, s, P, net, work):
    """The non-smooth part of a step to (t, s), in place: the cavitation floor and the
    prescribed nodes, then every component's projection (stops, dry friction, latches), which
    sees the signals at the new state."""
    kinds, poff, soff, ports = net[0], net[1], net[2], net[3]
    proj_list = net[7]
    fixed = net[8]
    dims = net[9]
    nh, nm = dims[0], dims[1]
    mm = work[9]
    floor = P[SYS.cavitation_pressure]
    for i in range(nh):
        if fixed[i] == 0 and s[i] < floor:
            s[i] = floor
    evaluate_signals(t, s, P, net, work)  # the signals at the new state
    pn, sig = work[0], work[3]
    for i in range(nh):
        if fixed[i] != 0:
            s[i] = pn[i]
    for j in range(proj_list.shape[0]):
        c = proj_list[j]
        project_of(kinds[c], t, h, P, poff[c], s_old, s, soff[c], ports[c], nh, nh + nm, mm, sig)


@kernel
def port_quantities(t, s, P, net, work, d, flow, power):
    """At (t, s): ``flow[c, k]`` the flow [m³/s] into component c at hydraulic port k (its
    through variable, sign reversed; a prescribing source takes its node's balance) or the
    force [N, N m] it exerts on a mechanical node, and ``power[c]`` the power [W] component c
    absorbs from the network (stored or dissipated; negative: delivered), compliance and
    inertia included. Σ power = 0 but for a node held at the cavitation floor."""
    system_rhs(t, s, P, net, work, d)
    ports, domains = net[3], net[4]
    fixed = net[8]
    dims = net[9]
    nh, nm, nc = dims[0], dims[1], dims[3]
    pn, vm, thr, cap, qn = work[0], work[2], work[4], work[5], work[6]
    for c in range(nc):
        pw = 0.0
        for k in range(MAX_PORTS):
            dom = domains[c, k]
            i = ports[c, k]
            if dom == D_HYDRAULIC:
                q = thr[c, k] - cap[c, k] * d[i]  # into the node, compliance included
                if fixed[i] == c + 1:  # the node's source takes the node's balance
                    q = -(qn[i] - thr[c, k])
                flow[c, k] = -q
                pw -= pn[i] * q
            elif dom == D_MECHANICAL:
                f = thr[c, k] - cap[c, k] * d[nh + nm + i]
                flow[c, k] = thr[c, k]
                pw -= f * vm[i]
            else:
                flow[c, k] = 0.0
        power[c] = pw


@njit(cache=True, nogil=True, error_model="numpy")
def record_outputs(t, S, P, net, flows, power, sigs):
    """:func:`port_quantities` and the signals at every recorded state S[r] (time t[r])."""
    work = make_work(net)
    d = np.empty(S.shape[1])
    for r in range(S.shape[0]):
        port_quantities(t[r], S[r], P, net, work, d, flows[r], power[r])
        sig = work[3]
        for i in range(sigs.shape[1]):
            sigs[r, i] = sig[i]


follows_components(evaluate_signals, system_rhs, system_project, port_quantities, record_outputs)

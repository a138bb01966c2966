"""The system kernel: one right-hand side over any circuit (issue 28; docs/architecture.md).

A circuit is compiled (`hydroarm.model.circuit`) into fixed arrays, the *net*::

    kinds[c]        the kind code of component c (`components.KIND`)
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
    tree            the fields of the mechanism's `TreeModel`,
                    net[11:21] (a tree of no joints without one; `tree_of`)
    tree_nodes[j]   the mechanical node of the tree's joint j (its angle or position)
    joint_limits    (joints × 4): each joint's damping, dry friction, lower and upper limit
    slaves[k]       (slave node, master node, linkage component): a node a linkage positions
    couplings[k]    (coupled joint, its free master joint), net[24]; coupling_laws[k] its
                    (ratio, offset), net[25]: q_s = ratio·q_m + offset
    hyd, mech       (component, port, node) of every hydraulic and every mechanical port,
                    sorted by node and in law order within a node, net[26] and net[27]:
                    the order of the sums at the nodes (each law adds its own ports to
                    them, `law_of`)
    tables          net[28], net[29], net[30]: the components of law_order, sig_order and
                    proj_list, a row each: (component, kind, poff, soff, nports), what the
                    loops over the components take
    energy          net[31]: the energy account, a row a component (component, kind, poff,
                    soff, nports, eo: its first energy state, terms), and a last row
                    (−1, …, eo, 1) for a mechanism's; no rows: no account (the default)
    reference       net[32]: [p_ref], the pressure [Pa] the account measures pressures from

and the state vector is ``[p_0 … p_nh-1, x_0 … x_nm-1, v_0 … v_nm-1, component states]``.
The right-hand side evaluates the signals in order, then every component's law, and sums
at the nodes (Kirchhoff's laws for both domains)::

    ṗ_i = Σ_c q_c,i / Σ_c C_c,i          (hydraulic node: flows in, compliances)
    ẋ_m = v_m,   v̇_m = Σ_c F_c,m / Σ_c M_c,m   (mechanical node: forces, masses)

A *linkage* (a component with a ``transmit`` law: a crank, a cylinder between two pivots)
positions one mechanical node, its slave, from another, its master: x_s = g(x_m). The slave
has no state of its own; before the laws it is set from its master (x_s = g, v_s = g'·v_m),
and after them its force and mass are carried to the master by virtual work::

    F_m += g'·(F_s − M_s·g''·v_m²),   M_m += g'²·M_s,   v̇_s = g'·v̇_m + g''·v_m²

The joints of a mechanism are mechanical nodes too, but their masses are coupled: their
accelerations come from the tree's articulated-body algorithm
(`hydroarm.core.tree.forward_dynamics`) under the forces the components put on them,
less each joint's viscous damping, with the components' own masses at the joint (pistons,
rotors, folded through linkages) as the joint's armature. A *coupled* joint (a kinematic
coupling, URDF's mimic) is no free coordinate: like a linkage's slave, it is set from its
master before the laws (q_s = r·q_m + o, q̇_s = r·q̇_m), and the joints' accelerations come
from the tree's equations reduced to the free joints, Gᵀ·M·G·q̈_f = Gᵀ·(τ − bias)
(`hydroarm.core.tree.forward_dynamics_coupled`), so its torque, damping and armature
act on the master through the coupling; its dry friction and limits act through the master
(`hydroarm.model.mechanism.CompiledMechanism.kernel_limits`).

A node at the cavitation floor (``system.cavitation_pressure``) does not fall further; the
step's projection also holds it there. A prescribed node's pressure is its source's.

`port_quantities` gives, at any state, every port's through variable and every
component's absorbed power, so that ``Σ_c P_c = 0`` at every instant: the energy account
closes over all components by construction (docs/components.md "Energy").

A circuit built with an energy account (`CompiledCircuit`,
``energy=True``) has one more state a declared energy term (``<component>.<term>_energy``
[J], after every other state) whose rate is that share of the component's absorbed power
(`energy_rates`, at the end of `system_rhs`), so the stepper integrates the
account exactly as it integrates the pressures, stage by stage. No other state reads them.
Pressures count from the reference p_ref: Σ_c P_c = 0 whatever p_ref (the flows into the
components at each node add up to nothing), but each term's value depends on it (a tank at
p_ref absorbs nothing; the servo's account is measured from its tank).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..tree import TreeModel, TreeWork, _forward_dynamics, _forward_dynamics_coupled
from .declare import MAX_PORTS, Component, Param
from .dispatch import (
    derive_of,
    energy_of,
    follows_components,
    law_of,
    project_of,
    signals_of,
    transmit_of,
)
from .laws import dry_friction, end_stop, inlined_kernel, kernel

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
    """The work arrays of one evaluation: (pn, xm, vm, sig, thr, cap, qn, cn, fm, mm, tree
    work, joint positions, velocities, forces, accelerations, external link forces, each
    slave's g' and g''·v², the transmission's (g, g', g'', force lever), each slave's force
    lever)."""
    dims = net[9]
    nh, nm, nsig, nc = dims[0], dims[1], dims[2], dims[3]
    nt = net[21].shape[0]
    ns = net[23].shape[0]
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
        TreeWork(
            np.zeros((nt, 3, 3)),
            np.zeros((nt, 3)),
            np.zeros((nt, 6)),
            np.zeros((nt, 6)),
            np.zeros((nt, 6)),
            np.zeros((nt, 6)),
            np.zeros((nt, 6)),
            np.zeros((nt, 6, 6)),
            np.zeros((nt, 6)),
            np.zeros((nt, 6)),
            np.zeros(nt),
            np.zeros(nt),
            np.zeros((nt, nt)),
            np.zeros(nt),
            np.zeros((4, 6)),
            np.zeros((3, 6, 6)),
            np.full(nt, -1, np.int64),
            np.full(nt, -1, np.int64),
        ),
        np.zeros(nt),
        np.zeros(nt),
        np.zeros(nt),
        np.zeros(nt),
        np.zeros((nt, 6)),
        np.zeros(ns),
        np.zeros(ns),
        np.zeros(4),
        np.zeros(ns),
    )


@njit(cache=True, nogil=True, error_model="numpy")
def with_derived(P, net):
    """A copy of P with every component's derived quantities (`Derived`)
    computed from its parameters, in the slots after them: what the laws read. Every entry
    of the kernel that runs from a P (`hydroarm.integrators.system`,
    `record_outputs`) takes its copy, once per run (a batch's row), so that whoever
    changed a parameter in P (a sweep's column, a fit's trial, a co-simulation input)
    changed its derived quantities too."""
    Q = P.copy()
    table = net[28]
    for j in range(table.shape[0]):
        derive_of(table[j, 1], Q, table[j, 2])
    return Q


@kernel
def tree_of(net):
    """The mechanism's tree from its fields in the net (kept flat there: numba's parallel
    loops take tuples of arrays, not named tuples inside them)."""
    return TreeModel(
        net[11],
        net[12],
        net[13],
        net[14],
        net[15],
        net[16],
        net[17],
        net[18],
        net[19],
        net[20],
    )


@inlined_kernel
def position_slaves(P, net, work):
    """Each coupled joint from its master, then each linkage's slave node from its master
    (module doc), masters first."""
    kinds, poff = net[0], net[1]
    slaves = net[23]
    xm, vm = work[1], work[2]
    if net[24].shape[0] > 0:  # (a call copies its arrays' fields: none made without work)
        couple_joints(net[21], net[24], net[25], xm, vm)
    gj, gc, g, gf = work[16], work[17], work[18], work[19]
    for k in range(slaves.shape[0]):
        sl, ma, c = slaves[k, 0], slaves[k, 1], slaves[k, 2]
        transmit_of(kinds[c], P, poff[c], xm[ma], g)
        v = vm[ma]
        xm[sl] = g[0]
        vm[sl] = g[1] * v
        gj[k] = g[1]
        gc[k] = g[2] * v * v
        gf[k] = g[3]


@kernel
def couple_joints(nodes, couplings, laws, xm, vm):
    """Each coupled joint's position and velocity from its (free) master's:
    q_s = ratio·q_m + offset, q̇_s = ratio·q̇_m."""
    for k in range(couplings.shape[0]):
        sl, ma = nodes[couplings[k, 0]], nodes[couplings[k, 1]]
        xm[sl] = laws[k, 0] * xm[ma] + laws[k, 1]
        vm[sl] = laws[k, 0] * vm[ma]


@inlined_kernel
def evaluate_signals(t, s, P, net, work):
    """Node pressures, mechanical states and every signal at (t, s), in the work arrays."""
    ports = net[3]
    dims = net[9]
    nh, nm = dims[0], dims[1]
    pn, xm, vm, sig = work[0], work[1], work[2], work[3]
    for i in range(nh):
        pn[i] = s[i]
    for m in range(nm):
        xm[m] = s[nh + m]
        vm[m] = s[nh + nm + m]
    position_slaves(P, net, work)
    all_signals(t, s, P, net[29], ports, pn, xm, vm, sig)


@kernel
def all_signals(t, s, P, table, ports, pn, xm, vm, sig):
    """Every signal output in order (`evaluate_signals`; ``table``: net[29], the
    components with signals as in `all_laws`). The loops over the components are
    functions of their own, with the dispatcher compiled into them: a law's call copies its
    arrays' fields (some 70 words), a loop's call once per evaluation."""
    for j in range(table.shape[0]):
        c = table[j, 0]
        signals_of(table[j, 1], t, P, table[j, 2], s, table[j, 3], ports[c], pn, xm, vm, sig)


@inlined_kernel
def system_rhs(t, s, P, net, work, d):
    """Write ṡ into d: the circuit's smooth right-hand side at (t, s) (module doc)."""
    ports = net[3]
    fixed = net[8]
    dims = net[9]
    nh = dims[0]
    evaluate_signals(t, s, P, net, work)
    pn, xm, vm, sig, thr, cap, qn, cn, fm, mm = work[:10]
    # the sums at the nodes, which each component's law adds its ports to (`law_of`): in
    # law order, then port order, each from 0 (net[26], net[27] list them in that order)
    for i in range(nh):
        qn[i] = 0.0
        cn[i] = 0.0
    for m in range(fm.shape[0]):
        fm[m] = 0.0
        mm[m] = 0.0
    all_laws(t, s, P, d, net[28], ports, pn, xm, vm, sig, thr, cap, qn, cn, fm, mm)
    floor = P[SYS.cavitation_pressure]
    for i in range(nh):
        if fixed[i] != 0:
            d[i] = 0.0
        else:
            r = qn[i] / cn[i]
            if pn[i] <= floor and r < 0.0:
                r = 0.0
            d[i] = r
    mechanical_accelerations(P, net, work, nh, d)
    if net[31].shape[0] > 0:
        energy_rates(
            t, s, P, d, net[31], net[32][0], ports, net[4], fixed, nh, net[21], net[23],
            pn, xm, vm, sig, thr, cap, qn, work[8], work[10].armature, work[16], work[19],
        )  # fmt: skip


@inlined_kernel
def energy_rates(
    t, s, P, d, table, pref, ports, domains, fixed, nh, nodes, slaves,
    pn, xm, vm, sig, thr, cap, qn, fm, armature, gj, gf,
):  # fmt: skip
    """The rates [W] of the energy states into d (module doc; ``table``: net[31]): each
    component's absorbed power as `port_quantities` computes it, pressures from
    ``pref``, the power a linkage with a force lever other than its ratio makes (its
    ``(g_f − g')·F_s·v_m``), split into its declared terms (its ``energy`` law gives all but
    the last, the last the rest), and a mechanism's, Σ_j (τ_j − A_j·q̈_j)·q̇_j. Compiled
    into `system_rhs`: a call copied its twenty-odd arrays' fields at each evaluation, about
    a fifth of the account's cost on the servo (benchmarks/servo_throughput.py); the
    functions that have numba's reference counting call the right-hand side through a
    function without it (`hydroarm.integrators.system.rhs_into`)."""
    nm = vm.shape[0]
    iv = nh + nm
    for j in range(table.shape[0]):
        c, eo, n = table[j, 0], table[j, 5], table[j, 6]
        pw = 0.0
        if c < 0:  # the mechanism's joints
            for jj in range(nodes.shape[0]):
                m = nodes[jj]
                pw += (fm[m] - armature[jj] * d[iv + m]) * vm[m]
            d[eo] = pw
            continue
        for k in range(table[j, 4]):
            dom = domains[c, k]
            i = ports[c, k]
            if dom == D_HYDRAULIC:
                q = thr[c, k] - cap[c, k] * d[i]
                if fixed[i] == c + 1:
                    q = -(qn[i] - thr[c, k])
                pw -= (pn[i] - pref) * q
            elif dom == D_MECHANICAL:
                pw -= (thr[c, k] - cap[c, k] * d[iv + i]) * vm[i]
        for k in range(slaves.shape[0]):
            if slaves[k, 2] == c:
                pw -= (gf[k] - gj[k]) * fm[slaves[k, 0]] * vm[slaves[k, 1]]
        rest = pw
        if n > 1:
            energy_of(table[j, 1], t, c, P, table[j, 2], s, table[j, 3], d, eo, ports[c],
                      pn, xm, vm, sig, thr, cap, pref)  # fmt: skip
            for i in range(n - 1):
                rest -= d[eo + i]
        d[eo + n - 1] = rest


@kernel
def all_laws(t, s, P, d, table, ports, pn, xm, vm, sig, thr, cap, qn, cn, fm, mm):
    """Every component's law in order, each adding its ports' through variables and
    storages to their nodes' sums (``qn``, ``cn``, ``fm``, ``mm``, cleared by the caller;
    `law_of`) (`system_rhs`; ``table``: net[28], a row a component in law order:
    (component, kind code, parameter offset, state offset, ports)). The loop takes few
    arguments, the net's component fields as one table: a call passes every field of every
    array argument (seven words a vector), and the five arrays it took before were an
    eighth of a step's time on the position servo (benchmarks/circuit_throughput.py)."""
    for j in range(table.shape[0]):
        c = table[j, 0]
        law_of(table[j, 1], t, c, P, table[j, 2], s, table[j, 3], d, ports[c], pn, xm, vm,
               sig, thr, cap, qn, cn, fm, mm)  # fmt: skip


@inlined_kernel
def mechanical_accelerations(P, net, work, nh, d):
    """ẋ and v̇ of every mechanical node into d, from the forces and masses the laws summed
    in the work arrays: slaves folded into their masters, the tree's joints by the
    articulated-body algorithm, every other node by F/M (module doc). Afterwards ``mm`` holds
    each node's effective mass for the projections (a joint's articulated inertia D_j, a
    slave's its master's over g'²). The arrays go to the parts by name, the tree's only to
    a circuit with a mechanism: every call copies its arguments, and the whole net and work
    tuples are some 500 words (benchmarks/circuit_throughput.py)."""
    slaves = net[23]
    vm, fm, mm, gj, gc, gf = work[2], work[8], work[9], work[16], work[17], work[19]
    # the parts' calls made only where there is work for them: a call copies its arrays'
    # fields, some 40 words a call, four times a step (benchmarks/servo_throughput.py)
    if slaves.shape[0] > 0:
        fold_slaves(slaves, fm, mm, gj, gc, gf)
    nm = vm.shape[0]
    for m in range(nm):
        d[nh + m] = vm[m]
        d[nh + nm + m] = fm[m] / mm[m] if mm[m] > 0.0 else 0.0
    if net[21].shape[0] > 0:
        joint_accelerations(
            net[11:21],
            net[24],
            net[25],
            net[21],
            net[22],
            work[1],
            vm,
            fm,
            mm,
            work[10],
            work[11],
            work[12],
            work[13],
            work[14],
            work[15],
            nh + nm,
            d,
        )
    if slaves.shape[0] > 0:
        slave_accelerations(slaves, mm, gj, gc, nh + nm, d)


@kernel
def fold_slaves(slaves, fm, mm, gj, gc, gf):
    """Each slave's force and mass carried to its master by virtual work, last slaves
    first (module doc); a linkage whose force lever differs from its ratio (the paper's
    crank with the torque arm r/n printed in its eq. (3)) carries the force by that lever
    (``gf``; not energy-conserving: the difference is that linkage's)."""
    for k in range(slaves.shape[0] - 1, -1, -1):
        sl, ma = slaves[k, 0], slaves[k, 1]
        fm[ma] += gj[k] * (fm[sl] - mm[sl] * gc[k]) + (gf[k] - gj[k]) * fm[sl]
        mm[ma] += gj[k] * gj[k] * mm[sl]


@kernel
def joint_accelerations(
    tf, cpl, cpl_laws, nodes, limits, xm, vm, fm, mm, tw, q, qd, tau, qdd, fext, iv, d
):
    """The tree's joints' accelerations into ``d[iv + node]`` by the articulated-body
    algorithm (with couplings: the reduced equations of the free joints), each joint's
    articulated inertia into ``mm`` (`mechanical_accelerations`; ``tf``: the tree's
    fields, net[11:21]). A call that takes only the arrays it uses: a call passes every field
    of every array argument, and the whole net and work (some 500 words) were 12 % of a step
    of the UCL arm as a mechanism; compiled into its callers instead, it took numba's
    reference counting in those that have it
    (`derivatives_at`), and the process aborted there."""
    for j in range(nodes.shape[0]):
        m = nodes[j]
        q[j] = xm[m]
        qd[j] = vm[m]
        tau[j] = fm[m] - limits[j, 0] * vm[m]
        tw.armature[j] = mm[m]
    tree = TreeModel(tf[0], tf[1], tf[2], tf[3], tf[4], tf[5], tf[6], tf[7], tf[8], tf[9])
    if cpl.shape[0] > 0:  # (the tree's algorithms compiled in: one call, not two)
        _forward_dynamics_coupled(tree, cpl, cpl_laws, q, qd, tau, fext, tw, qdd)
    else:
        _forward_dynamics(tree, q, qd, tau, fext, tw, qdd)
    for j in range(nodes.shape[0]):
        m = nodes[j]
        d[iv + m] = qdd[j]
        mm[m] = tw.D[j]


@kernel
def slave_accelerations(slaves, mm, gj, gc, iv, d):
    """Each slave's acceleration from its master's, v̇_s = g'·v̇_m + g''·v_m² (d[iv + node]:
    the nodes' accelerations), and its effective mass, its master's over g'²."""
    for k in range(slaves.shape[0]):
        sl, ma = slaves[k, 0], slaves[k, 1]
        d[iv + sl] = gj[k] * d[iv + ma] + gc[k]
        mm[sl] = mm[ma] / (gj[k] * gj[k]) if gj[k] != 0.0 else mm[sl]


@inlined_kernel
def system_project(t, h, s_old, s, P, net, work, share):
    """The non-smooth part of a step to (t, s), in place: the cavitation floor and the
    prescribed nodes, then every component's projection (stops, dry friction, latches), which
    sees the signals at the new state. ``share``: how the stepper moves positions with
    velocities (`POSITION_SHARE_EULER`, `dry_friction`)."""
    ports = net[3]
    fixed = net[8]
    dims = net[9]
    nh, nm = dims[0], dims[1]
    mm = work[9]
    floor = P[SYS.cavitation_pressure]
    for i in range(nh):
        if fixed[i] == 0 and s[i] < floor:
            s[i] = floor
    nodes, limits = net[21], net[22]
    # the mechanism's joints: dry friction, then limits (a coupled joint has neither: its
    # own act through its master's, net[22])
    for j in range(nodes.shape[0]):
        ix = nh + nodes[j]
        iv = ix + nm
        dry_friction(s_old, s, ix, iv, h, limits[j, 1], limits[j, 1], mm[nodes[j]], share)
        end_stop(s, ix, iv, limits[j, 2], limits[j, 3])
    evaluate_signals(t, s, P, net, work)  # the signals at the new state
    pn, xm, vm, sig = work[0], work[1], work[2], work[3]
    slaves = net[23]
    couplings, laws = net[24], net[25]
    for k in range(couplings.shape[0]):  # the coupled joints where their masters put them
        sl = nodes[couplings[k, 0]]
        s[nh + sl] = xm[sl]
        s[nh + nm + sl] = vm[sl]
    for k in range(slaves.shape[0]):  # the slaves where their linkages put them
        sl = slaves[k, 0]
        s[nh + sl] = xm[sl]
        s[nh + nm + sl] = vm[sl]
    for i in range(nh):
        if fixed[i] != 0:
            s[i] = pn[i]
    all_projections(t, h, s_old, s, P, net[30], ports, nh, nm, mm, sig, share)
    gj = work[16]
    for k in range(slaves.shape[0] - 1, -1, -1):
        # a projection that moved a slave (a cylinder at its stop) moves its master with it:
        # one Newton step through the linkage, Δx_m = Δx_s/g', Δv_m = Δv_s/g'
        sl, ma = slaves[k, 0], slaves[k, 1]
        dx = s[nh + sl] - xm[sl]
        dv = s[nh + nm + sl] - vm[sl]
        if (dx != 0.0 or dv != 0.0) and gj[k] != 0.0:
            s[nh + ma] += dx / gj[k]
            s[nh + nm + ma] += dv / gj[k]
    for k in range(couplings.shape[0]):
        # and one that moved a coupled joint (directly or through a linkage) moves its
        # master, Δq_m = Δq_s/ratio; the coupled joint then follows the master exactly
        sl, ma, r = nodes[couplings[k, 0]], nodes[couplings[k, 1]], laws[k, 0]
        dx = s[nh + sl] - xm[sl]
        dv = s[nh + nm + sl] - vm[sl]
        if (dx != 0.0 or dv != 0.0) and r != 0.0:
            s[nh + ma] += dx / r
            s[nh + nm + ma] += dv / r
    for k in range(couplings.shape[0]):
        sl, ma = nodes[couplings[k, 0]], nodes[couplings[k, 1]]
        s[nh + sl] = laws[k, 0] * s[nh + ma] + laws[k, 1]
        s[nh + nm + sl] = laws[k, 0] * s[nh + nm + ma]


@kernel
def all_projections(t, h, s_old, s, P, table, ports, nh, nm, mm, sig, share):
    """Every component's projection in order (`system_project`; ``table``: net[30],
    the components with a projection as in `all_laws`)."""
    for j in range(table.shape[0]):
        c = table[j, 0]
        project_of(
            table[j, 1],
            t,
            h,
            P,
            table[j, 2],
            s_old,
            s,
            table[j, 3],
            ports[c],
            nh,
            nh + nm,
            mm,
            sig,
            share,
        )


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


@kernel
def outputs_at(t, s, P, net, work, d, flows, power, sig, mech):
    """Every output quantity at one state (t, s): `port_quantities` into ``flows``
    (components × ports) and ``power``, the signals into ``sig``, and into ``mech`` the force
    [N or N m] the components put on each mechanical node (a joint's torque, slaves folded
    in), each linkage's g' (its moment arm [m] or ratio), and the power [W] the mechanism
    absorbs, Σ_j (τ_j − A_j·q̈_j)·q̇_j (τ_j: the components' torque at joint j, A_j its
    armature), which closes the energy account: what the components deliver to the
    mechanism is its kinetic and potential energy and its joints' damping. What
    `record_outputs` gives at each record and the observers
    (`hydroarm.integrators.observers`) at each step: one evaluation of the outputs."""
    dims = net[9]
    nh, nm = dims[0], dims[1]
    nodes = net[21]
    ns = net[23].shape[0]
    port_quantities(t, s, P, net, work, d, flows, power)
    ws = work[3]
    for i in range(sig.shape[0]):
        sig[i] = ws[i]
    fm, vm, tw, gj = work[8], work[2], work[10], work[16]
    for m in range(nm):
        mech[m] = fm[m]
    for k in range(ns):
        mech[nm + k] = gj[k]
    pw = 0.0
    for j in range(nodes.shape[0]):
        m = nodes[j]
        pw += (fm[m] - tw.armature[j] * d[nh + nm + m]) * vm[m]
    mech[nm + ns] = pw


@njit(cache=True, nogil=True, error_model="numpy")
def record_outputs(t, S, P, net, flows, power, sigs, mech):
    """`outputs_at` at every recorded state S[r] (time t[r]), into ``flows[r]``,
    ``power[r]``, ``sigs[r]`` and ``mech[r]``."""
    work = make_work(net)
    P = with_derived(P, net)
    d = np.empty(S.shape[1])
    for r in range(S.shape[0]):
        outputs_at(t[r], S[r], P, net, work, d, flows[r], power[r], sigs[r], mech[r])


follows_components(
    with_derived,
    tree_of,
    position_slaves,
    mechanical_accelerations,
    energy_rates,
    fold_slaves,
    joint_accelerations,
    slave_accelerations,
    evaluate_signals,
    all_signals,
    all_laws,
    all_projections,
    system_rhs,
    system_project,
    port_quantities,
    outputs_at,
    record_outputs,
)

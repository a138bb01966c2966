"""The decoupled arm model's own loop, held apart as a reference (`hydroarm.reference`).

The arm runs on the system kernel (`hydroarm.arm.expand.simulate_arm`: the scenario written
as one mechanism). This loop (`arm_integrate`, `simulate_decoupled`) is no product path's
physics: the benchmarks and tests compare with it (it is the model the arm ran on before
issue 28). What follows describes it.

Every articulation is a [`ServoJoint`][hydroarm.ServoJoint] (valve, jack, crank,
gearbox, physics options) advanced by the single-joint step kernel
(`hydroarm.integrators.fixed.step_once`), so that one joint alone is the single-joint
model; a joint built from components by the servo kernel's step
(`hydroarm.reference.servo_kernel.step`). What the arm adds (docs/arm.md): the pose-dependent
loads (the diagonal mass-matrix term and the gravity torque, at the start of each Euler
step and at every stage of the coupled RK4) and the shared power pack (the supply pressure
at which the valves together draw the pump's flow, solved each step).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..arm.model import ArmScenario, kernel_inputs
from ..arm.result import ArmResult
from ..core.arm_kinematics import (
    ELEVATION,
    REACH,
    ROTATION,
    WRIST,
    pose_terms,
)
from ..core.components import spool_valve_flows
from ..core.equations import (
    crank_reach,
    derivatives,
    jack_position,
    pressure_bound,
    supply_flow,
    valve_opening,
)
from ..core.params import (
    J_SUPPLY,
    L_INERTIA,
    L_TORQUE,
    joint_at,
    load_at,
)
from ..core.servo import N_STATES as N_SERVO_STATES
from ..core.servo import (
    P_AREA_A,
    P_AREA_B,
    P_FLOW_GAIN,
    P_FORCE,
    P_K_AT,
    P_K_BT,
    P_K_PA,
    P_K_PB,
    P_LAP_AT,
    P_LAP_BT,
    P_LAP_PA,
    P_LAP_PB,
    P_MASS,
    P_P_TANK,
    P_P_TRANS,
    P_SPOOL_ORDER,
    P_VALVE,
    S_E_SUPPLY,
    S_PA,
    S_PB,
    S_PS,
    S_Q,
    S_V,
    S_XV,
    VALVE_LINEARISED,
)
from ..errors import HydroarmError
from ..integrators import registry
from ..integrators.fixed import EULER, in_bounds, rk4_projections, step_once
from ..model.lever import LeverInput
from .servo_kernel import actuator_motion, servo_rhs, spool_demand
from .servo_kernel import project as servo_project
from .servo_kernel import step as servo_step


# ---------------------------------------------------------------------- kernel ---
@njit(cache=True, nogil=True)
def _demand(ps, es, PP, PM, comp, CS, CP):
    """Σ_i |Q_i| [m³/s]: the flow the valves draw from the supply at pressure ``ps`` (the
    supply-edge flows of `supply_flow`), PM's supply set to ps.
    A component joint (``comp``) draws its valve's supply flow Q_P
    (`valve_flows`) at spool position ``es`` and state ``CS``,
    whose supply (absolute) is set to ps above its tank."""
    s = 0.0
    for j in range(es.shape[0]):
        PM[j, J_SUPPLY] = ps
        if comp[j]:
            CS[j, S_PS] = ps + CP[j, P_P_TANK]
            s += _component_supply_flow(es[j], CS, CP, j)
            continue
        s += supply_flow(es[j], PP[j], joint_at(PM, j))
    return s


@njit(cache=True, nogil=True)
def _component_supply_flow(x_v, CS, CP, j):
    """The supply flow Q_P [m³/s] of `valve_flows` of component
    joint ``j`` at spool position x_v, read from the rows of ``CS`` and ``CP`` in place (the
    same operations; a row view would cost an atomic reference-count pair per call)."""
    if CP[j, P_VALVE] == VALVE_LINEARISED:
        q = CP[j, P_FLOW_GAIN] * x_v
        if q >= 0.0:
            return q
        return -(q * (CP[j, P_AREA_B] / CP[j, P_AREA_A]))
    return spool_valve_flows(
        x_v,
        CS[j, S_PS],
        CP[j, P_P_TANK],
        CS[j, S_PA],
        CS[j, S_PB],
        CP[j, P_K_PA],
        CP[j, P_K_AT],
        CP[j, P_K_PB],
        CP[j, P_K_BT],
        CP[j, P_LAP_PA],
        CP[j, P_LAP_AT],
        CP[j, P_LAP_PB],
        CP[j, P_LAP_BT],
        CP[j, P_P_TRANS],
    )[2]


@njit(cache=True, nogil=True)
def _lever(t, TT, TY, NT, SINE, j):
    """`evaluate` of joint ``j``'s lever (row j of the tables,
    its first NT[j] points), read in place: the same operations (the interval found by the
    same bisection as ``np.searchsorted(side="right")``), no row views."""
    n = NT[j]
    if t >= TT[j, n - 1]:
        y = TY[j, n - 1]
    elif t < TT[j, 0]:
        y = TY[j, 0]
    else:
        lo, hi = 0, n  # the first index whose time is > t, minus one
        while lo < hi:
            mid = (lo + hi) >> 1
            if TT[j, mid] <= t:
                lo = mid + 1
            else:
                hi = mid
        i = lo - 1
        dt = TT[j, i + 1] - TT[j, i]
        if dt > 0.0:
            y = TY[j, i] + (TY[j, i + 1] - TY[j, i]) * (t - TT[j, i]) / dt
        else:
            y = TY[j, i + 1]
    if SINE[j, 0] != 0.0 and t >= SINE[j, 2]:
        y += SINE[j, 0] * np.sin(2.0 * np.pi * SINE[j, 1] * (t - SINE[j, 2]))
    return y


@njit(cache=True, nogil=True)
def _component_spool(y, s, P):
    """Spool position [m] of a component joint at lever ``y`` and state ``s``: the feedback's
    demand for a spool without dynamics (as `servo_rhs` takes it),
    else the spool state."""
    if P[P_SPOOL_ORDER] == 0:
        x, v_x, _ = actuator_motion(s[S_Q], s[S_V], P)
        return spool_demand(y, s, x, v_x, P)[0]
    return s[S_XV]


@njit(cache=True, nogil=True)
def _supply(t, TH, PP, TT, TY, NT, SINE, PM, es, pump_flow, p_relief, comp, CS, CP):
    """Supply pressure from the flow balance of the pump and the valves (module doc), the
    valves' openings taken from the lever at time ``t`` and the angles ``TH`` (component
    joints: their spool at state ``CS``); PM's supply column set to it. ``es`` is scratch
    for the valve openings."""
    for j in range(TH.shape[0]):
        y = _lever(t, TT, TY, NT, SINE, j)
        if comp[j]:
            es[j] = _component_spool(y, CS[j], CP[j])
            continue
        J = joint_at(PM, j)
        es[j] = valve_opening(y, jack_position(TH[j], J), J)
    return _supply_pressure(PP, PM, es, pump_flow, p_relief, p_relief, comp, CS, CP)


@njit(cache=True, nogil=True)
def _supply_pressure(PP, PM, es, pump_flow, p_relief, guess, comp, CS, CP):
    """Supply pressure at the valve openings ``es`` and load pressures ``PP``; PM's supply
    column set to it.

    The demand D rises monotonically with the supply pressure; the root of D·|D| = Q_p² (nearly
    linear in p_s: each valve draws ∝ √(p_s ∓ p)) in [0, p_r] is found by the Illinois
    variant of false position (superlinear; a bisection step whenever the bracket does not
    halve), to a bracket of 1e-12·p_r. A ``guess`` strictly inside (0, p_r) (the last
    solution, in the coupled RK4) narrows the starting bracket to about it: a bracket of
    ±10⁻³·p_r widened fourfold until it holds the root; otherwise it is [0, p_r].
    """
    nj = PP.shape[0]
    q2 = pump_flow * pump_flow
    d = _demand(p_relief, es, PP, PM, comp, CS, CP)
    if d <= pump_flow:
        return p_relief
    f_hi = d * abs(d) - q2
    lo, hi = 0.0, p_relief
    if 0.0 < guess < p_relief:
        d = _demand(guess, es, PP, PM, comp, CS, CP)
        fg = d * abs(d) - q2
        step = 1e-3 * p_relief
        if fg > 0.0:  # the root is below the guess
            hi, f_hi = guess, fg
            while True:
                x = hi - step
                if x <= 0.0:
                    break
                d = _demand(x, es, PP, PM, comp, CS, CP)
                fx = d * abs(d) - q2
                if fx <= 0.0:
                    lo = x
                    break
                hi, f_hi = x, fx
                step *= 4.0
        else:
            lo = guess
            while True:
                x = lo + step
                if x >= p_relief:
                    break
                d = _demand(x, es, PP, PM, comp, CS, CP)
                fx = d * abs(d) - q2
                if fx > 0.0:
                    hi, f_hi = x, fx
                    break
                lo = x
                step *= 4.0
    d = _demand(lo, es, PP, PM, comp, CS, CP)
    f_lo = d * abs(d) - q2
    ps = p_relief
    if f_lo >= 0.0:
        ps = lo
    else:
        side = 0
        tol = 1e-12 * p_relief
        for _ in range(100):
            width = hi - lo
            if width <= tol:
                break
            x = hi - f_hi * (hi - lo) / (f_hi - f_lo)
            if not (lo < x < hi):
                x = 0.5 * (lo + hi)
            d = _demand(x, es, PP, PM, comp, CS, CP)
            fx = d * abs(d) - q2
            if fx == 0.0:
                lo = hi = x
                break
            if fx > 0.0:
                hi, f_hi = x, fx
                if side == 1:  # the same end moved twice: halve the other end's value
                    f_lo *= 0.5
                side = 1
            else:
                lo, f_lo = x, fx
                if side == -1:
                    f_hi *= 0.5
                side = -1
            if hi - lo > 0.5 * width:  # no halving: bisect once
                x = 0.5 * (lo + hi)
                d = _demand(x, es, PP, PM, comp, CS, CP)
                fx = d * abs(d) - q2
                if fx > 0.0:
                    hi, f_hi = x, fx
                else:
                    lo, f_lo = x, fx
                side = 0
        ps = 0.5 * (lo + hi)
    for j in range(nj):
        PM[j, J_SUPPLY] = ps
        if comp[j]:
            CS[j, S_PS] = ps + CP[j, P_P_TANK]
    return ps


@njit(cache=True, nogil=True)
def _pose_loads(TH, PM, kinds, pose, offsets, own_inertia, G):
    """Set the gravity torque (as the load torque T, W = X = 0) and the inertia of every
    pose-loaded joint from the articulation angles of the servo angles ``TH`` (closed form)."""
    nj = TH.shape[0]
    qa = qp = qe = 0.0  # articulation angles α, ψ, ε (0 for a joint not in the arm)
    for j in range(nj):
        if kinds[j] == ELEVATION:
            qa = TH[j] + offsets[j]
        elif kinds[j] == ROTATION:
            qp = TH[j] + offsets[j]
        elif kinds[j] == REACH:
            qe = TH[j] + offsets[j]
    ta, tp, te, maa, mpp, mee, _, _, _ = pose_terms(qa, qp, qe, G)
    for j in range(nj):
        if pose[j] and kinds[j] != WRIST:
            kj = kinds[j]
            tg = ta if kj == ELEVATION else (tp if kj == ROTATION else te)
            inert = maa if kj == ELEVATION else (mpp if kj == ROTATION else mee)
            PM[j, L_TORQUE] = tg
            PM[j, L_INERTIA] = inert + own_inertia[j]


@njit(cache=True, nogil=True)
def _component_loads(PM, CP, comp, pose):
    """Copy the pose load (torque, inertia) of every pose-loaded component joint from its PM
    row into its servo parameters (the servo's external torque and mass entries)."""
    for j in range(PM.shape[0]):
        if comp[j] and pose[j]:
            CP[j, P_FORCE] = PM[j, L_TORQUE]
            CP[j, P_MASS] = PM[j, L_INERTIA]


@njit(cache=True, nogil=True)
def _rates(
    t, TH, OM, PP, TT, TY, NT, SINE, PM, kinds, pose, offsets, own, G, any_pose, pump_flow,
    p_relief, es, KA, KB, KC, comp, CS, CP, CK,
):  # fmt: skip
    """The coupled right-hand side of the whole arm at (t, θ, ω, p): pose loads and the
    supply pressure at that state, then every joint's smooth (θ̇, θ̈, ṗ) into KA, KB, KC (dry
    friction excluded: it is the step's projection, as in the single joint). A component
    joint's state is its row of ``CS`` (θ, ω its position and velocity), its rates
    `servo_rhs` into its row of ``CK``. Returns the supply
    pressure."""
    nj = TH.shape[0]
    if any_pose:
        _pose_loads(TH, PM, kinds, pose, offsets, own, G)
        _component_loads(PM, CP, comp, pose)
    for j in range(nj):
        KC[j] = _lever(t, TT, TY, NT, SINE, j)  # the lever, for now
        if comp[j]:
            es[j] = _component_spool(KC[j], CS[j], CP[j])
            continue
        J = joint_at(PM, j)
        es[j] = valve_opening(KC[j], jack_position(TH[j], J), J)
    ps = p_relief
    if np.isfinite(pump_flow):
        ps = _supply_pressure(PP, PM, es, pump_flow, p_relief, PM[0, J_SUPPLY], comp, CS, CP)
    for j in range(nj):
        if comp[j]:
            CS[j, S_PS] = ps + CP[j, P_P_TANK]
            servo_rhs(KC[j], CS[j], CP[j], CK[j])
            KA[j], KB[j], KC[j] = CK[j, S_Q], CK[j, S_V], 0.0
            continue
        J = joint_at(PM, j)
        L = load_at(PM, j)
        KA[j], KB[j], KC[j] = derivatives(TH[j], OM[j], PP[j], KC[j], J, L)
    return ps


@njit(cache=True, nogil=True)
def _component_pressure(s, P):
    """The force-equivalent load pressure (A_A·p_A − A_B·p_B)/A_A [Pa] of a component joint
    (the jack force over the piston area: the arm's recorded load pressure)."""
    return (P[P_AREA_A] * s[S_PA] - P[P_AREA_B] * s[S_PB]) / P[P_AREA_A]


@njit(cache=True, nogil=True)
def _component_in_bounds(s, reach):
    """A component joint's state is finite and short of the crank's dead centre."""
    for i in range(s.shape[0]):
        if not np.isfinite(s[i]):
            return False
    return abs(s[S_Q]) < reach


@njit(cache=True, nogil=True)
def arm_integrate(
    method,
    TH0,
    OM0,
    PP0,
    t0,
    h,
    nsteps,
    record_every,
    TT,
    TY,
    NT,
    SINE,
    PM,
    kinds,
    pose,
    offsets,
    own_inertia,
    G,
    pump_flow,
    p_relief,
    comp,
    CS0,
    CP,
    stop_joint=-1,
    stop_offset=0.0,
    stop_angle=0.0,
    settle_t=np.inf,
    resume=False,
    PB=None,
):
    """Advance all joints together; returns (t, θ, ω, p, y, supply pressure, bad step,
    component states): the bad step is the first step at which a joint's state left the
    physical bounds (non-finite, past the crank's dead centre or above
    `pressure_bound`), or −1.

    ``euler``: each joint takes the single-joint step (`step_once`) with the pose loads
    and the supply pressure of the start of the step. ``rk4``: the classical RK4 of the
    coupled system (pose loads and supply pressure evaluated at every stage, so fourth order
    where the motion is smooth; dry friction is not in the stages), then each joint's
    non-smooth physics (`rk4_projections`: dry friction's
    stick or slide, the single joint's projection) with its start-of-step load.

    A joint built from components (``comp[j]``; docs/arm.md) has the state ``CS0[j]`` and
    the parameters ``CP[j]`` of the component servo (`hydroarm.core.servo`, its
    external torque, mass and supply set here each step or stage): ``euler`` takes the
    servo's own step (`hydroarm.reference.servo_kernel.step`), ``rk4`` its right-hand side
    in the coupled stages and its projections (`hydroarm.reference.servo_kernel.project`)
    with the start-of-step load. Its recorded p is the force-equivalent load pressure, its
    full state is recorded too (the last output; one row when no joint is a component).

    A probe (``stop_joint`` ≥ 0; `probe_reaches`) stops once its answer is decided:
    at the first recorded state whose articulation angle θ + ``stop_offset`` of joint
    ``stop_joint`` is above ``stop_angle``, or (``euler``) at an exact fixed point of the
    step after ``settle_t`` (every lever settled: from there every state repeats, the
    energies aside), with that state recorded once more when a later record would have kept
    it. The recorded angles then have the same maximum above ``stop_angle`` or not as the
    full run's.

    A run advanced piece by piece (`ArmStepper`) calls the
    kernel for each piece with ``resume`` True: the state (TH0, OM0, PP0, CS0) is where the
    last piece ended, PM's supply and pose columns and CP's load entries are as the last
    piece left them (the coupled RK4 starts its supply solve from the last root), not set
    to the start's; ``PB`` are the start pressures of the whole run (its pressure bounds;
    None: PP0). From the same state and inputs the pieces' steps are the whole run's, bit
    for bit.
    """
    nj = TH0.shape[0]
    ns = N_SERVO_STATES
    P_B = PP0 if PB is None else PB
    nrec = nsteps // record_every + 1
    T = np.empty(nrec)
    TH = np.empty((nrec, nj))
    OM = np.empty((nrec, nj))
    PPr = np.empty((nrec, nj))
    Y = np.empty((nrec, nj))
    PS = np.empty(nrec)
    th = TH0.copy()
    om = OM0.copy()
    pp = PP0.copy()
    any_comp = False
    for j in range(nj):
        if comp[j]:
            any_comp = True
    CSR = np.zeros((nrec if any_comp else 1, nj, ns))
    cs = CS0.copy()  # component states (rows of non-component joints unused)
    cst = np.empty((nj, ns))  # component stage states
    CK = np.empty((4, nj, ns))  # component stage rates
    cout = np.empty(ns)
    w1 = np.empty(ns)
    w2 = np.empty(ns)
    w3 = np.empty(ns)
    w4 = np.empty(ns)
    w5 = np.empty(ns)
    cheld = np.empty((nj, 2))
    es = np.empty(nj)  # scratch of the supply solve
    # RK4 scratch: stage rates and states, the start-of-step load and supply of each joint
    K = np.empty((4, 3, nj))
    ths = np.empty(nj)
    oms = np.empty(nj)
    pps = np.empty(nj)
    held = np.empty((nj, 3))
    finite_pump = np.isfinite(pump_flow)
    any_pose = False
    for j in range(nj):
        if pose[j]:
            any_pose = True
        if resume:
            continue
        PM[j, J_SUPPLY] = p_relief
        if comp[j]:
            cs[j, S_PS] = p_relief + CP[j, P_P_TANK]
        if pose[j]:
            # the wrist's pose load is zero and stays so (ρ moves no point)
            PM[j, L_TORQUE] = 0.0
            PM[j, L_INERTIA] = own_inertia[j]
            if comp[j]:
                CP[j, P_FORCE] = 0.0
                CP[j, P_MASS] = own_inertia[j]
    T[0] = t0
    for j in range(nj):
        TH[0, j] = th[j]
        OM[0, j] = om[j]
        PPr[0, j] = pp[j]
        Y[0, j] = _lever(t0, TT, TY, NT, SINE, j)
        if comp[j]:
            CSR[0, j] = cs[j]
    PS[0] = p_relief
    rec = 1
    bad = -1
    probe = stop_joint >= 0
    last_record = (nsteps // record_every) * record_every
    ps_prev = np.nan
    for k in range(1, nsteps + 1):
        t = t0 + (k - 1) * h
        fixed = probe and t > settle_t  # an exact fixed point of this step, so far
        if method == EULER:
            if any_pose:
                _pose_loads(th, PM, kinds, pose, offsets, own_inertia, G)
                if any_comp:
                    _component_loads(PM, CP, comp, pose)
            ps = p_relief
            if finite_pump:
                ps = _supply(t, th, pp, TT, TY, NT, SINE, PM, es, pump_flow, p_relief, comp, cs, CP)
            for j in range(nj):
                if comp[j]:
                    cs[j, S_PS] = ps + CP[j, P_P_TANK]
                    servo_step(
                        method, t, h, cs[j], cout, TT[j, : NT[j]], TY[j, : NT[j]], SINE[j],
                        CP[j], w1, w2, w3, w4, w5,
                    )  # fmt: skip
                    if fixed:
                        for i in range(S_E_SUPPLY):  # the energies are integrals only
                            if cout[i] != cs[j, i]:
                                fixed = False
                                break
                    cs[j] = cout
                    th[j], om[j], pp[j] = cout[S_Q], cout[S_V], _component_pressure(cout, CP[j])
                    if not _component_in_bounds(cout, crank_reach(joint_at(PM, j))):
                        bad = k
                    continue
                Jj = joint_at(PM, j)
                Lj = load_at(PM, j)
                a, b, c = step_once(
                    method,
                    t,
                    h,
                    th[j],
                    om[j],
                    pp[j],
                    TT[j, : NT[j]],
                    TY[j, : NT[j]],
                    SINE[j],
                    Jj,
                    Lj,
                )
                if fixed and (a != th[j] or b != om[j] or c != pp[j]):
                    fixed = False
                th[j], om[j], pp[j] = a, b, c
                # finite, short of the crank's dead centre, below the pressure bound
                if not in_bounds(a, b, c, crank_reach(Jj), pressure_bound(P_B[j], Jj, Lj)):
                    bad = k
            if fixed and ps != ps_prev:
                fixed = False
            ps_prev = ps
        else:
            fixed = False
            ps = _rates(
                t, th, om, pp, TT, TY, NT, SINE, PM, kinds, pose, offsets, own_inertia, G,
                any_pose, pump_flow, p_relief, es, K[0, 0], K[0, 1], K[0, 2], comp, cs, CP,
                CK[0],
            )  # fmt: skip
            for j in range(nj):
                held[j, 0] = PM[j, J_SUPPLY]
                held[j, 1] = PM[j, L_TORQUE]
                held[j, 2] = PM[j, L_INERTIA]
                if comp[j]:
                    cheld[j, 0] = CP[j, P_FORCE]
                    cheld[j, 1] = CP[j, P_MASS]
            for s in range(1, 4):
                c = 0.5 * h if s < 3 else h
                for j in range(nj):
                    if comp[j]:
                        for i in range(ns):
                            cst[j, i] = cs[j, i] + c * CK[s - 1, j, i]
                        ths[j] = cst[j, S_Q]
                        oms[j] = cst[j, S_V]
                        pps[j] = pp[j]
                        continue
                    ths[j] = th[j] + c * K[s - 1, 0, j]
                    oms[j] = om[j] + c * K[s - 1, 1, j]
                    pps[j] = pp[j] + c * K[s - 1, 2, j]
                _rates(
                    t + c, ths, oms, pps, TT, TY, NT, SINE, PM, kinds, pose, offsets,
                    own_inertia, G, any_pose, pump_flow, p_relief, es, K[s, 0], K[s, 1], K[s, 2],
                    comp, cst, CP, CK[s],
                )  # fmt: skip
            w = h / 6.0
            for j in range(nj):
                PM[j, J_SUPPLY] = held[j, 0]
                PM[j, L_TORQUE] = held[j, 1]
                PM[j, L_INERTIA] = held[j, 2]
                Jj = joint_at(PM, j)
                if comp[j]:
                    CP[j, P_FORCE] = cheld[j, 0]
                    CP[j, P_MASS] = cheld[j, 1]
                    for i in range(ns):
                        cout[i] = cs[j, i] + w * (
                            CK[0, j, i] + 2.0 * CK[1, j, i] + 2.0 * CK[2, j, i] + CK[3, j, i]
                        )
                    cout[S_PS] = held[j, 0] + CP[j, P_P_TANK]
                    cs[j, S_PS] = cout[S_PS]
                    tr = _lever(t + h, TT, TY, NT, SINE, j)
                    servo_project(method, cs[j], cout, h, tr, CP[j])
                    cs[j] = cout
                    th[j], om[j], pp[j] = cout[S_Q], cout[S_V], _component_pressure(cout, CP[j])
                    if not _component_in_bounds(cout, crank_reach(Jj)):
                        bad = k
                    continue
                Lj = load_at(PM, j)
                a = th[j] + w * (K[0, 0, j] + 2.0 * K[1, 0, j] + 2.0 * K[2, 0, j] + K[3, 0, j])
                b = om[j] + w * (K[0, 1, j] + 2.0 * K[1, 1, j] + 2.0 * K[2, 1, j] + K[3, 1, j])
                c = pp[j] + w * (K[0, 2, j] + 2.0 * K[1, 2, j] + 2.0 * K[2, 2, j] + K[3, 2, j])
                # the single joint's projections after its smooth RK4 update (dry friction's
                # stick or slide, cavitation floor, end stops): one rule for both
                a, b, c = rk4_projections(h, th[j], om[j], a, b, c, Jj, Lj)
                th[j], om[j], pp[j] = a, b, c
                if not in_bounds(a, b, c, crank_reach(Jj), pressure_bound(P_B[j], Jj, Lj)):
                    bad = k
        if bad >= 0:
            break
        above = probe and th[stop_joint] + stop_offset > stop_angle
        # a probe at a fixed point: its later records would all repeat this state
        if k % record_every == 0 or (fixed and above and k <= last_record):
            tk = t0 + k * h
            T[rec] = tk
            for j in range(nj):
                TH[rec, j] = th[j]
                OM[rec, j] = om[j]
                PPr[rec, j] = pp[j]
                Y[rec, j] = _lever(tk, TT, TY, NT, SINE, j)
                if comp[j]:
                    CSR[rec, j] = cs[j]
            PS[rec] = ps
            rec += 1
            if above or fixed:
                break
        elif fixed:
            break
    nc = rec if any_comp else 1
    return T[:rec], TH[:rec], OM[:rec], PPr[:rec], Y[:rec], PS[:rec], bad, CSR[:nc]


def simulate_decoupled(
    sc: ArmScenario, *, check_stability: bool = True, probe: tuple[str, float] | None = None
):
    """Run an `ArmScenario` on the decoupled arm model's own loop (`arm_integrate`: the
    diagonal pose inertia, the algebraic power pack); returns an `ArmResult`. No product
    path runs it: the arm runs on the system kernel
    (`hydroarm.arm.simulate_arm`); it stays, with `arm_integrate`, as
    the reference of `hydroarm.arm.stepper.ArmStepper` until that moves to the system
    kernel too.

    ``probe`` (joint name, articulation angle): the run stops once it is decided whether a
    recorded angle of that joint is above the angle (`arm_integrate`); the result then
    holds the records up to there only, with the full run's answer to that question."""
    if check_stability:
        sc.check_step()
    nj = len(sc.joints)
    k = kernel_inputs(sc)
    levers: list[LeverInput] = [sc.inputs[j.name] for j in sc.joints]
    for j in np.flatnonzero(k["comp"]):
        # the servo kernel's start: its projection of the state at rest (the spool at its
        # demand for the lever, the load in its stops)
        s0 = k["CS0"][j].copy()
        servo_project(EULER, s0, k["CS0"][j], 0.0, float(levers[j](0.0)[0]), k["CP"][j])
    code = registry.method(sc.method).code
    nsteps = int(round(sc.duration / sc.step))
    stop = (-1, 0.0, 0.0, math.inf)
    if probe is not None:
        settle = max(float(lv.times[-1]) for lv in levers)
        if any(float(lv.sine[0]) != 0.0 for lv in levers):
            settle = math.inf
        i = [aj.name for aj in sc.joints].index(probe[0])
        stop = (i, float(sc.joints[i].angle_offset), float(probe[1]), settle)
    t, th, om, pp, y, ps, bad, cstates = arm_integrate(
        code,
        k["TH0"],
        np.zeros(nj),
        k["PP0"],
        0.0,
        sc.step,
        nsteps,
        sc.record_every,
        k["TT"],
        k["TY"],
        k["NT"],
        k["SINE"],
        k["PM"],
        k["kinds"],
        k["pose"],
        k["offsets"],
        k["own_inertia"],
        k["G"],
        float(sc.power_pack.pump_flow),
        float(sc.power_pack.supply_pressure),
        k["comp"],
        k["CS0"],
        k["CP"],
        *stop,
    )
    if bad >= 0:
        raise HydroarmError(
            "solver.step",
            f"the run left the physical bounds at t = {bad * sc.step:.6g} s (a state non-finite, "
            "past a crank's dead centre or beyond the pressure bound): reduce the step",
        )
    return ArmResult(
        t=t,
        theta=th,
        omega=om,
        p=pp,
        y=y,
        supply_pressure=ps,
        scenario=sc,
        component_states=cstates if k["comp"].any() else None,
    )

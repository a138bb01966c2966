"""Single-input single-output LTI quantities in numpy alone (docs/linear.md, "Cost").

Margins, bandwidth and the small-signal step of a state-space (A, b, c, d), the same
definitions as python-control's ``stability_margins``, ``bandwidth`` and ``step_info``,
without importing it (python-control pulls in ``scipy.signal``: about 0.6 s, more than the
rest of a linearisation). Crossings are found on a dense logarithmic grid and refined by
bisection to machine precision; the step response is exact (modal form) on a fine grid, its
10 %, 90 % and settling crossings interpolated. tests/test_linear.py checks each against
python-control.
"""

from __future__ import annotations

import math

import numpy as np

# every frequency search spans these decades [rad/s]
W_LO, W_HI, W_POINTS = 1e-3, 1e6, 2000
SETTLING = 0.02
RISE = (0.1, 0.9)


def freqresp(A, b, c, d, w) -> np.ndarray:
    """G(jω) = c·(jω·I − A)⁻¹·b + d at the frequencies ``w`` [rad/s]."""
    A = np.asarray(A, float)
    w = np.atleast_1d(np.asarray(w, float))
    n = A.shape[0]
    M = 1j * w[:, None, None] * np.eye(n) - A
    rhs = np.broadcast_to(np.asarray(b, float).reshape(n), (w.size, n))[..., None]
    x = np.linalg.solve(M, rhs.astype(complex))[..., 0]
    return x @ np.asarray(c, float).reshape(n) + float(d)


def _bisect(f, lo, hi, iterations=80):
    """A root of f (a sign change between lo and hi), bisecting in log ω."""
    flo = f(lo)
    for _ in range(iterations):
        mid = math.sqrt(lo * hi)
        fm = f(mid)
        if fm == 0.0:
            return mid
        if (fm > 0) == (flo > 0):
            lo, flo = mid, fm
        else:
            hi = mid
        if hi - lo <= 4e-16 * hi:
            break
    return math.sqrt(lo * hi)


def _crossings(f, w, values):
    idx = np.nonzero(np.diff(np.sign(values)) != 0)[0]
    return np.array([_bisect(f, w[i], w[i + 1]) for i in idx])


def margins(A, b, c, d=0.0) -> dict:
    """Gain margin [dB], phase margin [deg] and their crossovers [rad/s] of the loop G
    (negative unity feedback), chosen as python-control's ``stability_margins`` does: the
    gain margin nearest 0 dB among the negative-real-axis crossings, the phase margin of
    least magnitude among the unit-gain crossings (inf / nan: no crossing)."""

    def g(w):
        return freqresp(A, b, c, d, w)

    w = np.logspace(math.log10(W_LO), math.log10(W_HI), W_POINTS)
    G = g(w)
    # phase crossings: Im G changes sign where Re G < 0
    w180 = _crossings(lambda x: float(g(x)[0].imag), w, G.imag)
    w180 = np.array([x for x in w180 if g(x)[0].real <= 0.0])
    # gain crossings: |G| − 1 changes sign
    wc = _crossings(lambda x: float(abs(g(x)[0]) - 1.0), w, np.abs(G) - 1.0)
    out = {
        "gain_margin_db": math.inf,
        "phase_margin_deg": math.inf,
        "phase_crossover_rad_s": math.nan,
        "gain_crossover_rad_s": math.nan,
    }
    if w180.size:
        gm = 1.0 / np.abs(g(w180))
        i = int(np.argmin(np.abs(np.log(gm))))
        out["gain_margin_db"] = float(20 * math.log10(gm[i]))
        out["phase_crossover_rad_s"] = float(w180[i])
    if wc.size:
        pm = np.remainder(np.angle(g(wc), deg=True), 360.0) - 180.0
        i = int(np.argmin(np.abs(pm)))
        out["phase_margin_deg"] = float(pm[i])
        out["gain_crossover_rad_s"] = float(wc[i])
    return out


def dc_gain(A, b, c, d=0.0) -> float:
    A = np.asarray(A, float)
    n = A.shape[0]
    try:
        x = np.linalg.solve(A, np.asarray(b, float).reshape(n))
    except np.linalg.LinAlgError:
        return math.inf
    return float(float(d) - np.asarray(c, float).reshape(n) @ x)


def bandwidth(A, b, c, d=0.0, dbdrop=-3.0) -> float:
    """The first frequency [rad/s] where |G| falls ``dbdrop`` dB below its DC gain (nan: none
    below 10⁶ rad/s, or no finite DC gain)."""
    g0 = abs(dc_gain(A, b, c, d))
    if not math.isfinite(g0) or g0 == 0.0:
        return math.nan
    level = g0 * 10 ** (dbdrop / 20)
    w = np.logspace(math.log10(W_LO), math.log10(W_HI), W_POINTS)
    mag = np.abs(freqresp(A, b, c, d, w))
    below = np.nonzero(mag < level)[0]
    if not below.size:
        return math.nan
    i = int(below[0])
    if i == 0:
        return float(w[0])
    return _bisect(lambda x: float(abs(freqresp(A, b, c, d, x)[0]) - level), w[i - 1], w[i])


def step_horizon(A) -> float:
    """A time [s] by which a stable system's step has settled: 10 of its slowest time
    constants (and at least 3 periods of its slowest oscillation)."""
    lam = np.linalg.eigvals(np.asarray(A, float))
    slow = float(np.min(np.abs(lam.real)))
    periods = [2 * math.pi / abs(x.imag) for x in lam if abs(x.imag) > 0]
    return max(10.0 / slow, 3 * max(periods, default=0.0))


def balance(A) -> np.ndarray:
    """Diagonal scaling s (powers of 2) with diag(s)⁻¹·A·diag(s) balanced (Osborne: each
    state's row and column of comparable norm; states in Pa beside states in rad)."""
    A = np.abs(np.asarray(A, float))
    n = A.shape[0]
    s = np.ones(n)
    for _ in range(100):
        done = True
        for i in range(n):
            M = A * np.outer(1.0 / s, s)
            col = M[:, i].sum() - M[i, i]
            row = M[i, :].sum() - M[i, i]
            if col == 0.0 or row == 0.0:
                continue
            f = 2.0 ** round(0.5 * math.log2(row / col))
            if f != 1.0:
                s[i] *= f
                done = False
        if done:
            break
    return s


def step(A, b, c, d, t) -> np.ndarray:
    """Unit-step response y(t) = d + c·A⁻¹·(e^{At} − I)·b of a stable system (modal form of
    the balanced system; python-control's ``step_response`` when its eigenvectors are
    ill-conditioned)."""
    A = np.asarray(A, float)
    n = A.shape[0]
    sc = balance(A)
    A = A * np.outer(1.0 / sc, sc)
    b = np.asarray(b, float).reshape(n) / sc
    c = np.asarray(c, float).reshape(n) * sc
    t = np.asarray(t, float)
    lam, V = np.linalg.eig(A)
    if np.linalg.cond(V) > 1e8 or np.any(lam == 0):
        import control

        r = control.step_response(control.ss(A, b[:, None], c[None, :], float(d)), T=t)
        return np.asarray(r.outputs, float).reshape(t.shape)
    beta = np.linalg.solve(V, b.astype(complex))
    gamma = c @ V
    modes = (gamma * beta / lam)[None, :] * (np.exp(np.outer(t, lam)) - 1.0)
    return float(d) + modes.sum(axis=1).real


def step_info(A, b, c, d=0.0, points=20001) -> dict:
    """Rise time (10–90 % of the final value), settling time (last leaving the 2 % band),
    overshoot [% of the final value], peak and its time, of a stable system's unit step
    (python-control's ``step_info`` definitions; crossings interpolated on a grid of
    ``points`` over `step_horizon`)."""
    nan = {k: math.nan for k in ("RiseTime", "SettlingTime", "Overshoot", "Peak", "PeakTime")}
    if np.max(np.linalg.eigvals(np.asarray(A, float)).real) >= 0:
        return nan
    final = dc_gain(A, b, c, d)
    if not math.isfinite(final) or final == 0.0:
        return nan
    t = np.linspace(0.0, step_horizon(A), points)
    y = step(A, b, c, d, t) / final

    def first_above(level):
        i = int(np.nonzero(y >= level)[0][0])
        if i == 0:
            return 0.0
        return float(t[i - 1] + (level - y[i - 1]) / (y[i] - y[i - 1]) * (t[i] - t[i - 1]))

    rise = first_above(RISE[1]) - first_above(RISE[0])
    out = np.nonzero(np.abs(y - 1.0) >= SETTLING)[0]
    if out.size == 0:
        settle = 0.0
    elif out[-1] + 1 >= t.size:
        settle = math.nan
    else:
        i = int(out[-1])
        level = 1.0 + math.copysign(SETTLING, y[i] - 1.0)
        settle = float(t[i] + (level - y[i]) / (y[i + 1] - y[i]) * (t[i + 1] - t[i]))
    k = int(np.argmax(np.abs(y)))
    return {
        "RiseTime": rise,
        "SettlingTime": settle,
        "Overshoot": float(max(0.0, 100.0 * (np.max(y) - 1.0))),
        "Peak": float(abs(y[k] * final)),
        "PeakTime": float(t[k]),
    }


# ------------------------------------------------- floating levels, modes ---
def reduce_levels(J, B, C, keep: np.ndarray, floating: list[np.ndarray]):
    """The model (J, B, C) on the states ``keep`` (indices into the full state) reduced to
    the states complementary to the floating levels ``floating`` (vectors over the full
    state; docs/linear.md "floating levels"): each level's pivot state (its largest entry)
    dropped, A_r = W_Q·J·Q, B_r = W_Q·B, C_r = C·Q, whose eigenvalues are J's less the
    levels' zeros. Returns (A, B, C, kept positions, pivots)."""
    n = J.shape[0]
    if not floating:
        return J, B, C, np.arange(n), []
    N = np.array([v[keep] for v in floating]).T  # n × k
    pivots: list[int] = []
    for j in range(N.shape[1]):
        order = np.argsort(-np.abs(N[:, j]))
        pivots.append(int(next(i for i in order if i not in pivots)))
    rest = np.array([i for i in range(n) if i not in pivots], np.int64)
    Q = np.eye(n)[:, rest]
    T = np.hstack([N, Q])
    W = np.linalg.inv(T)[N.shape[1] :, :]
    return W @ J @ Q, W @ B, C @ Q, rest, pivots


def participation_mode(A, rows) -> tuple[float | None, float | None]:
    """(ω [rad/s], ζ) of the mode of A in which the states ``rows`` (a load's velocity)
    take the largest part (participation |v_k·w_k| summed over ``rows``): the oscillatory
    pair with the most, else the two real poles with the most as the roots of
    s² + 2ζω s + ω²; (None, None) where no such mode is identifiable."""
    A = np.asarray(A, float)
    if A.size == 0 or not len(rows):
        return None, None
    lam, V = np.linalg.eig(A)
    W = np.linalg.inv(V)
    part = np.array([sum(abs(V[r, k] * W[k, r]) for r in rows) for k in range(lam.size)])
    order = np.argsort(-part)
    pairs = [int(i) for i in order if abs(lam[i].imag) > 1e-9 * abs(lam[i])]
    if pairs:  # the oscillatory mode the load's velocity takes the largest part in
        k = pairs[0]
        w = float(abs(lam[k]))
        return w, float(-lam[k].real / w)
    reals = [int(i) for i in order if abs(lam[i].imag) <= 1e-9 * abs(lam[i])][:2]
    if len(reals) < 2 or lam[reals[0]].real * lam[reals[1]].real <= 0:
        return None, None
    a, b = float(lam[reals[0]].real), float(lam[reals[1]].real)
    w = math.sqrt(a * b)
    return w, float(-(a + b) / (2 * w))


#: a pole whose real part is above this fraction of the largest pole's magnitude (and above
#: 1e-9 1/s) is right of the imaginary axis; below, on it to rounding (an undamped pair, a
#: zero of an integrator): the central differences' relative error is about 1e-10
UNSTABLE_TOL = 1e-7


def unstable_poles(poles) -> np.ndarray:
    """The poles truly right of the imaginary axis (beyond `UNSTABLE_TOL`)."""
    p = np.asarray(poles, complex)
    if p.size == 0:
        return p
    tol = max(UNSTABLE_TOL * float(np.max(np.abs(p))), 1e-9)
    return p[p.real > tol]

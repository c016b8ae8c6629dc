"""A chain of fixed length between a hook and a seabed anchor at a given span: its state and its
horizontal stiffness (the dock model's line, the core's problem 5 with an optional EA).

Notation as in :mod:`catenary_monitor.core.physics.catenary`: ``w`` submerged weight per
unstretched metre [N/m], ``h`` depth anchor -> hook [m], ``L`` unstretched chain length hook ->
anchor [m],
``s`` horizontal span hook -> anchor [m], ``EA`` axial stiffness [N] (``inf``: inextensible).
R is the horizontal tension, V the vertical force at the hook, V_A the vertical pull on the
anchor (the uplift), T and T_A the tensions at hook and anchor.

The chain is stepped by its hook tension T: for a given T the span is a closed form
(:func:`span_from_tension`), with ``D = T - T_A`` from :func:`elastic.anchor_end_tension`
(``D = w h`` for the inextensible chain)::

    V_A = (D (T + T_A) / (w L) - w L) / 2
    grounded (V_A <= 0): R = T_A,  V = sqrt(D (T + R)),  s = (L - V/w) + (R/w) asinh(V/R) + R L/EA
    lifted   (V_A > 0):  R = sqrt((T_A - V_A)(T_A + V_A)),  V = V_A + w L,
                         s = (R/w) asinh((w L T_A - V_A D) / R^2) + R L/EA

(no seabed friction; the grounded chain is stretched by R). The span grows with T from the slack
span ``s_slack = L - D0/w`` (R = 0: the chain hangs vertically to the seabed, ``D0 = w h`` when
inextensible) to ``sqrt(L^2 - h^2)`` (inextensible, taut) or without bound (elastic).

:func:`statics_at_span` inverts it: the inextensible chain by the core's problem-5 kernels
(``catenary.grounded_parameter_from_length``, ``catenary.taut_parameter_from_length``), the
elastic one by Newton in T, safeguarded by the bracket every residual tightens, started from the
inextensible answer (or a warm start).  The stiffness comes from the Jacobian of (span, depth)
with respect to (R, V), which is symmetric (the line is conservative)::

    J_sR = (asinh(V/R) - asinh(V_A/R) - V/T + V_A/T_A) / w + L/EA
    J_sV = J_hR = -R (T - T_A) / (T T_A w)
    J_hV = (w L T_A - V_A D) / (T T_A w) + min(V/w, L)/EA        (V_A = 0, T_A = R if grounded)

so at fixed depth ``dR/ds = J_hV / det J`` and ``dV/ds = -J_sV / det J``.  Differences that
cancel for nearly straight chains are written as sums of positive terms or series.
"""

from __future__ import annotations

import math
from enum import IntEnum
from typing import Any, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics.elastic import anchor_end_tension

__all__ = [
    'LineRegime',
    'LineStatics',
    'span_from_tension',
    'slack_span',
    'taut_span',
    'statics_at_span',
    'lift_depth',
]

#: Newton in T stops after a step of at most this relative size: convergence is quadratic, so
#: the error left after that step is ~T_STEP_TOL**2, below rounding.
T_STEP_TOL = 1e-9
#: Iteration cap of the elastic solve (never reached on the physical domain: tests).
MAXITER = 60
_EPS4 = 4.0 * float(np.finfo(float).eps)


class LineRegime(IntEnum):
    """Where a fixed-length chain is at a given span."""

    SLACK = 0  # no horizontal tension: the chain hangs to the seabed and lies there
    GROUNDED = 1  # part of the chain on the seabed, anchor not lifted
    LIFTED = 2  # the whole chain in the water column, anchor pulled up
    TAUT = 3  # inextensible chain cannot span that far (no state)
    INVALID = 4  # impossible input (NaN, w <= 0, h <= 0, L <= h, s < 0, EA <= 0)
    NO_CONVERGENCE = 5  # the elastic solve did not converge (report the inputs)


class LineStatics(NamedTuple):
    """State of fixed-length chains at their spans (arrays of one shape, SI units).

    NaN where the regime is TAUT, INVALID or NO_CONVERGENCE (``horizontal_tension`` is ``inf``
    for TAUT: an inextensible chain held beyond its reach).
    """

    horizontal_tension: np.ndarray  # N, R
    top_tension: np.ndarray  # N, T at the hook
    top_vertical: np.ndarray  # N, V at the hook
    uplift_force: np.ndarray  # N, V_A on the anchor
    grounded_length: np.ndarray  # m, unstretched chain lying on the seabed
    suspended_length: np.ndarray  # m, unstretched chain in the water column
    dr_ds: np.ndarray  # N/m, horizontal stiffness dR/ds at fixed depth
    dt_ds: np.ndarray  # N/m, dT/ds at fixed depth
    regime: np.ndarray  # int, LineRegime
    iterations: np.ndarray  # int, Newton residuals of the elastic solve (0: inextensible)


def _arrays(*args: Any) -> list[np.ndarray]:
    return [np.array(a, dtype=float) for a in np.broadcast_arrays(*args)]


def slack_span(w: Any, h: Any, length: Any, ea: Any) -> np.ndarray:
    """Span [m] below which the chain is slack (R = 0): ``L - D0/w``, ``h w = D0 (1 + D0/2EA)``."""
    w, h, length, ea = _arrays(w, h, length, ea)
    d0 = 2.0 * h * w / (1.0 + np.sqrt(1.0 + 2.0 * h * w / ea))
    return length - d0 / w


def taut_span(h: Any, length: Any) -> np.ndarray:
    """Largest span [m] an inextensible chain of length L reaches at depth h."""
    h, length = _arrays(h, length)
    return np.sqrt((length - h) * (length + h))


class _State(NamedTuple):
    span: np.ndarray
    r: np.ndarray
    v: np.ndarray
    va: np.ndarray
    ta: np.ndarray  # tension at the anchor end of the suspended part (R when grounded)
    d: np.ndarray  # T - T_A
    grounded: np.ndarray  # unstretched grounded length
    lifted: np.ndarray  # bool


def _from_tension(w: Any, h: Any, length: Any, t: Any, ea: Any) -> _State:
    """Closed-form state of the chain of length L whose hook tension is T (T above slack)."""
    ta, d = anchor_end_tension(w, h, t, ea)
    wl = w * length
    va = 0.5 * (d * (t + ta) / wl - wl)
    lifted = va > 0.0
    inv_ea = 1.0 / ea
    # grounded branch
    r_g = ta
    v_g = np.sqrt(d * (t + r_g))
    ground = length - v_g / w
    s_g = ground + r_g / w * np.arcsinh(v_g / r_g) + r_g * length * inv_ea
    # lifted branch (evaluated everywhere, selected below)
    va_l = np.maximum(va, 0.0)
    r_l = np.sqrt(np.maximum((ta - va_l) * (ta + va_l), 0.0))
    s_l = r_l / w * np.arcsinh((wl * ta - va_l * d) / (r_l * r_l)) + r_l * length * inv_ea
    return _State(
        span=np.where(lifted, s_l, s_g),
        r=np.where(lifted, r_l, r_g),
        v=np.where(lifted, va_l + wl, v_g),
        va=va_l,
        ta=ta,
        d=d,
        grounded=np.where(lifted, 0.0, ground),
        lifted=lifted,
    )


def span_from_tension(w: Any, h: Any, length: Any, tension: Any, ea: Any = math.inf) -> Any:
    """Span [m] of a chain of length L at depth h whose hook tension is T (closed form).

    ``ea = inf`` is the inextensible chain.  T must exceed the slack tension (``w h`` when
    inextensible); NaN otherwise.
    """
    w, h, length, tension, ea = _arrays(w, h, length, tension, ea)
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        return _from_tension(w, h, length, tension, ea).span


def _f_asinh(rho: np.ndarray) -> np.ndarray:
    """``asinh(rho) - rho / sqrt(1 + rho^2)``, series below 0.1 (it is ~rho^3/3)."""
    small = rho < 0.1
    if not small.any():
        return np.arcsinh(rho) - rho / np.sqrt(1.0 + rho * rho)
    r2 = rho * rho
    series = (
        rho
        * r2
        * (
            1.0 / 3.0
            - r2 * (3.0 / 10.0 - r2 * (15.0 / 56.0 - r2 * (35.0 / 144.0 - r2 * (315.0 / 1408.0))))
        )
    )
    direct = np.arcsinh(rho) - rho / np.sqrt(1.0 + r2)
    return np.where(rho < 0.1, series, direct)


def _f_asinh_diff(rho: np.ndarray, rho_a: np.ndarray) -> np.ndarray:
    """``f(rho) - f(rho_a)`` for :func:`_f_asinh` without cancellation (0 <= rho_a <= rho)."""
    small = rho < 0.1
    direct = _f_asinh(rho) - _f_asinh(rho_a)
    if not small.any():
        return direct
    # f = sum c_n rho^n (n = 3, 5, ...): f(p) - f(q) = (p - q) sum c_n (p^n - q^n)/(p - q).
    p, q = rho, rho_a
    p2 = p * p
    qn = q * q * q  # q^n for n = 3
    pn = p * p + p * q + q * q  # (p^3 - q^3) / (p - q)
    total = np.zeros_like(p)
    for coef in (1.0 / 3.0, -3.0 / 10.0, 15.0 / 56.0, -35.0 / 144.0, 315.0 / 1408.0):
        total = total + coef * pn
        pn = p2 * pn + qn * (p + q)
        qn = qn * q * q
    return np.where(small, (p - q) * total, direct)


def _stiffness(
    w: np.ndarray, length: np.ndarray, t: np.ndarray, s: _State, inv_ea: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(dR/ds, dT/ds)`` at fixed depth from the symmetric Jacobian of (span, depth)."""
    r, v, va, ta, d = s.r, s.v, s.va, s.ta, s.d
    lifted = s.lifted
    rho, rho_a = v / r, va / r
    j_sr = np.where(lifted, _f_asinh_diff(rho, rho_a), _f_asinh(rho)) / w + length * inv_ea
    # T - T_A: D when lifted; V^2 / (T + R) when grounded (T_A = R there).
    t_minus = np.where(lifted, d, v * v / (t + r))
    ta_eff = np.where(lifted, ta, r)
    j_sv = -r * t_minus / (t * ta_eff * w)
    num = np.where(lifted, w * length * ta - va * d, v * ta_eff)
    j_hv = num / (t * ta_eff * w) + np.minimum(v / w, length) * inv_ea
    det = j_sr * j_hv - j_sv * j_sv
    dr = j_hv / det
    dv = -j_sv / det
    return dr, (r * dr + v * dv) / t


def statics_at_span(
    w: Any,
    h: Any,
    length: Any,
    span: Any,
    ea: Any = math.inf,
    t_start: Optional[Any] = None,
) -> LineStatics:
    """State and stiffness of fixed-length chains at given spans, vectorized.

    Parameters
    ----------
    w : submerged weight per unstretched metre [N/m].
    h : depth anchor -> hook [m].
    length : unstretched chain length hook -> anchor [m].
    span : horizontal distance hook -> anchor [m].
    ea : axial stiffness [N]; ``inf`` (default) is the inextensible chain.
    t_start : optional hook tensions [N] to start the elastic solve from (a warm start).

    Returns
    -------
    LineStatics (arrays of the broadcast shape).

    Notes
    -----
    Inextensible chains: the core's problem-5 kernels (a bisection-safeguarded Newton to a few
    ulps).  Elastic chains: Newton in T on :func:`span_from_tension` with ``dT/ds`` from the
    Jacobian, every residual tightening a bracket ``[T_slack, T_hi]``; a step leaving it is
    replaced by bisection (or a doubling while no upper bound is known).  Stops after a step
    of at most ``T_STEP_TOL`` relative (the error left is at rounding level) or at an exact
    zero residual; elements still moving after ``MAXITER`` residuals are NO_CONVERGENCE.
    """
    w, h, length, span, ea = _arrays(w, h, length, span, ea)
    shape = w.shape
    w, h, length, span, ea = (a.ravel() for a in (w, h, length, span, ea))
    start = None if t_start is None else np.broadcast_to(np.asarray(t_start, float), shape).ravel()
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        out = _statics(w, h, length, span, ea, start)
    return LineStatics(*(np.reshape(v, shape) for v in out))


def _statics(
    w: np.ndarray,
    h: np.ndarray,
    length: np.ndarray,
    span: np.ndarray,
    ea: np.ndarray,
    start: Optional[np.ndarray],
) -> LineStatics:
    n = w.size
    regime = np.full(n, int(LineRegime.INVALID), np.int64)
    valid = (
        np.isfinite(w)
        & np.isfinite(h)
        & np.isfinite(length)
        & np.isfinite(span)
        & ~np.isnan(ea)
        & (w > 0)
        & (h > 0)
        & (length > h)
        & (span >= 0)
        & (ea > 0)
    )
    t = np.full(n, np.nan)
    iters = np.zeros(n, np.int64)
    rigid = valid & np.isinf(ea)
    elastic = valid & ~np.isinf(ea)
    s_slack = np.where(valid, slack_span(w, h, length, ea), np.nan)
    slack = valid & (span <= s_slack)
    regime[slack] = LineRegime.SLACK
    s_taut = taut_span(h, length)
    taut = rigid & ~slack & (span >= s_taut)
    regime[taut] = LineRegime.TAUT
    # Newton in T: elastic chains, and inextensible ones given a warm start; the others by the
    # core's problem-5 kernels (and any inextensible one whose Newton did not converge).
    warm = np.zeros(n, bool) if start is None else np.isfinite(start) & (start > 0)
    newton = (elastic | (rigid & warm)) & ~slack & ~taut
    if newton.any():
        t0 = _elastic_start(w, h, length, span, ea, start, newton)
        t[newton], iters[newton], ok = _newton_tension(
            w[newton], h[newton], length[newton], span[newton], ea[newton], t0
        )
        idx = np.flatnonzero(newton)
        failed = idx[~ok]
        t[failed] = np.nan
        retry = failed[rigid[failed]]
        newton[retry] = False
        regime[failed[~rigid[failed]]] = LineRegime.NO_CONVERGENCE
    kernel = rigid & ~slack & ~taut & ~newton
    if kernel.any():
        t[kernel] = _rigid_tension(w[kernel], h[kernel], length[kernel], span[kernel])
    live = kernel
    todo = newton
    solved = (live | todo) & np.isfinite(t)
    return _assemble(w, h, length, ea, t, solved, slack, taut, regime, iters)


def _rigid_tension(
    w: np.ndarray, h: np.ndarray, length: np.ndarray, span: np.ndarray
) -> np.ndarray:
    """Hook tension of inextensible chains (slack and taut excluded) by the problem-5 kernels."""
    a_lift = (length - h) * (length + h) / (2.0 * h)
    s_lift = a_lift * cat.acosh1p(h / a_lift)
    t = np.empty(w.size)
    ground = span <= s_lift
    if ground.any():
        a, _ = cat.grounded_parameter_from_length(h[ground], length[ground] - span[ground])
        t[ground] = w[ground] * (a + h[ground])
    lift = ~ground
    if lift.any():
        a, _ = cat.taut_parameter_from_length(h[lift], span[lift], length[lift])
        state = cat.lifted_from_horizontal(w[lift], h[lift], a, span[lift])
        t[lift] = state.top_tension
    return t


def _elastic_start(
    w: np.ndarray,
    h: np.ndarray,
    length: np.ndarray,
    span: np.ndarray,
    ea: np.ndarray,
    start: Optional[np.ndarray],
    todo: np.ndarray,
) -> np.ndarray:
    """Start of the elastic Newton: the warm start, else the inextensible chain, else a
    straight chain stretched to the chord."""
    idx = np.flatnonzero(todo)
    t0 = np.full(idx.size, np.nan)
    if start is not None:
        t0 = start[idx].copy()
    need = ~np.isfinite(t0)
    if need.any():
        j = idx[need]
        chord = np.hypot(span[j], h[j])
        reach = chord < 0.999 * length[j]
        guess = np.full(j.size, np.nan)
        if reach.any():
            k = j[reach]
            rigid_slack = span[k] <= length[k] - h[k]
            r_ok = ~rigid_slack
            if r_ok.any():
                kk = k[r_ok]
                sub = np.full(k.size, np.nan)
                sub[r_ok] = _rigid_tension(w[kk], h[kk], length[kk], span[kk])
                guess[reach] = sub
        # Straight, stretched chain: T ~ EA (chord / L - 1) + w h, at least above slack.
        straight = ea[j] * np.maximum(chord / length[j] - 1.0, 0.0) + w[j] * (h[j] + length[j])
        guess = np.where(np.isfinite(guess), guess, straight)
        t0[need] = guess
    return t0


def _newton_tension(
    w: np.ndarray,
    h: np.ndarray,
    length: np.ndarray,
    span: np.ndarray,
    ea: np.ndarray,
    t: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Safeguarded Newton in T on ``span_from_tension(T) = span`` (chains not slack or taut).

    Converged at a relative step below ``T_STEP_TOL``, a residual at the span's rounding level
    (``4 eps s``: near taut dT/ds is so large that T's last digits are not determined), or a
    bracket ``4 eps`` wide."""
    d0 = 2.0 * h * w / (1.0 + np.sqrt(1.0 + 2.0 * h * w / ea))  # slack tension: T_A = 0
    lo = d0.copy()
    hi = np.full(t.size, np.inf)
    t = np.where(t > lo, t, 2.0 * lo)
    inv_ea = 1.0 / ea
    iters = np.zeros(t.size, np.int64)
    done = np.zeros(t.size, bool)
    idx = np.arange(t.size)
    for it in range(1, MAXITER + 1):
        if idx.size == 0:
            break
        cur = t[idx]
        st = _from_tension(w[idx], h[idx], length[idx], cur, ea[idx])
        f = st.span - span[idx]
        lo_i = np.where(f < 0.0, np.maximum(lo[idx], cur), lo[idx])
        hi_i = np.where(f > 0.0, np.minimum(hi[idx], cur), hi[idx])
        _, dt_ds = _stiffness(w[idx], length[idx], cur, st, inv_ea[idx])
        step = -f * dt_ds
        new = cur + step
        at_root = np.abs(f) <= _EPS4 * span[idx]
        conv = (np.abs(step) <= T_STEP_TOL * cur) | at_root
        bad = ~((new > lo_i) & (new < hi_i)) & ~at_root
        new = np.where(bad, np.where(np.isfinite(hi_i), 0.5 * (lo_i + hi_i), 2.0 * cur), new)
        conv |= np.isfinite(hi_i) & ((hi_i - lo_i) <= 4e-16 * hi_i)
        t[idx] = np.where(at_root, cur, np.where(bad & conv, cur, new))
        lo[idx], hi[idx] = lo_i, hi_i
        iters[idx] = it
        done[idx[conv]] = True
        idx = idx[~conv]
    return t, iters, done


def _assemble(
    w: np.ndarray,
    h: np.ndarray,
    length: np.ndarray,
    ea: np.ndarray,
    t: np.ndarray,
    solved: np.ndarray,
    slack: np.ndarray,
    taut: np.ndarray,
    regime: np.ndarray,
    iters: np.ndarray,
) -> LineStatics:
    """Every output from the hook tensions (closed forms at the solved T)."""
    n = w.size
    out = {k: np.full(n, np.nan) for k in LineStatics._fields[:8]}
    if solved.any():
        i = solved
        st = _from_tension(w[i], h[i], length[i], t[i], ea[i])
        dr, dt = _stiffness(w[i], length[i], t[i], st, 1.0 / ea[i])
        out['horizontal_tension'][i] = st.r
        out['top_tension'][i] = t[i]
        out['top_vertical'][i] = st.v
        out['uplift_force'][i] = st.va
        out['grounded_length'][i] = st.grounded
        out['suspended_length'][i] = length[i] - st.grounded
        out['dr_ds'][i] = dr
        out['dt_ds'][i] = dt
        regime[i] = np.where(st.lifted, LineRegime.LIFTED, LineRegime.GROUNDED)
    if slack.any():
        d0 = (
            2.0
            * h[slack]
            * w[slack]
            / (1.0 + np.sqrt(1.0 + 2.0 * h[slack] * w[slack] / ea[slack]))
        )
        for key, value in (
            ('horizontal_tension', 0.0),
            ('top_tension', d0),
            ('top_vertical', d0),
            ('uplift_force', 0.0),
            ('grounded_length', length[slack] - d0 / w[slack]),
            ('suspended_length', d0 / w[slack]),
            ('dr_ds', 0.0),
            ('dt_ds', 0.0),
        ):
            out[key][slack] = value
    if taut.any():
        out['horizontal_tension'][taut] = np.inf
        out['top_tension'][taut] = np.inf
    return LineStatics(**out, regime=regime, iterations=iters)


def solve_chain_length(
    weight: Any,
    depth: Any,
    chain_length: Any,
    anchor_distance: Any,
    ea: Any,
    mbl: Optional[Any] = None,
) -> Any:
    """Problem 5 for an elastic chain: ``solve(w, h, chain_length=Lm, anchor_distance=x, ea=EA)``.

    The hook tension of the fixed-length elastic chain (:func:`statics_at_span`) is handed to
    the elastic problems 3 and 4 (:func:`elastic.solve_with_correction`, whose rule names the
    model), which give the uplift state and the margins for that tension at ``x``;
    ``grounded_length`` is the unstretched chain on the seabed.  Statuses as the inextensible
    problem 5: CHAIN_SLACK when ``x`` is at most the slack span ``Lm - D0/w``, CHAIN_TOO_SHORT
    when ``Lm <= h`` (an elastic chain shorter than the depth is not a mooring).
    """
    from catenary_monitor.core.physics.elastic import solve_with_correction
    from catenary_monitor.core.physics.inextensible import result_keys
    from catenary_monitor.core.physics.result import ALL_KEYS, SolveResult, Status

    inputs = [weight, depth, chain_length, anchor_distance, ea] + ([] if mbl is None else [mbl])
    scalar = all(np.ndim(v) == 0 for v in inputs)
    try:
        arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in inputs))
    except ValueError as exc:
        raise ValueError(f'inputs do not broadcast together: {exc}') from None
    w, h, lm, x, ea_a = (np.array(a, dtype=float).ravel() for a in arrays[:5])
    shape = arrays[0].shape
    m = None if mbl is None else np.array(arrays[5], dtype=float).ravel()
    if np.any(~(ea_a > 0)):
        raise ValueError('ea (axial stiffness) must be > 0 N')
    status = np.zeros(w.size, np.int64)

    def flag(cond: np.ndarray, code: Status) -> None:
        status[(status == 0) & cond] = code

    finite = np.isfinite(w) & np.isfinite(h) & np.isfinite(lm) & np.isfinite(x)
    if m is not None:
        finite &= np.isfinite(m)
    flag(~finite, Status.NON_FINITE)
    flag(~(w > 0), Status.WEIGHT)
    flag(~(h > 0), Status.DEPTH)
    flag(~(x > 0), Status.DISTANCE)
    flag(~(lm > h), Status.CHAIN_TOO_SHORT)
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        flag(~(x > slack_span(w, h, lm, ea_a)), Status.CHAIN_SLACK)
    if m is not None:
        flag(~(m > 0), Status.MBL)
    ok = status == 0
    out = {k: np.full(w.size, np.nan) for k in ALL_KEYS}
    model = np.full(w.size, 'elastic catenary', dtype=object)
    if ok.any():
        st = statics_at_span(w[ok], h[ok], lm[ok], x[ok], ea_a[ok])
        conv = st.regime != LineRegime.NO_CONVERGENCE
        sub = status[ok]
        sub[~conv] = Status.NO_CONVERGENCE
        status[ok] = sub
        good = np.flatnonzero(ok)[conv]
        if good.size:
            res = solve_with_correction(
                w[good],
                h[good],
                st.top_tension[conv],
                anchor_distance=x[good],
                ea=ea_a[good],
                mbl=None if m is None else m[good],
            )[0]
            for k in ALL_KEYS:
                if k != 'grounded_length':
                    out[k][good] = getattr(res, k)
            out['grounded_length'][good] = st.grounded_length[conv]
            model[good] = np.asarray(res.model, dtype=object)
            status[good] = np.asarray(res.status)
    keys = result_keys('chain_length', True, m is not None)
    fields: dict[str, Any] = {}
    for k in ALL_KEYS:
        flat = out[k] if k in keys else np.full(w.size, np.nan)
        v = np.where(status == 0, flat, np.nan).reshape(shape)
        fields[k] = float(v) if scalar else v
    stat = status.reshape(shape)
    return SolveResult(
        **fields,
        status=int(stat) if scalar else stat,
        problem='chain_length',
        keys=keys,
        model=str(model[0]) if scalar else model.reshape(shape),
        method=(
            'fixed-length elastic chain: safeguarded Newton in T '
            '(catenary_monitor.core.physics.fixed_length)'
        ),
    )


def span_and_sensitivity(
    w: Any, h: Any, length: Any, tension: Any, ea: Any = math.inf
) -> tuple[np.ndarray, np.ndarray]:
    """The span [m] a hook tension T implies for a chain of length L at depth h, and
    ``dT/ds`` [N/m] there (closed forms); NaN where T is at or below the slack tension."""
    w, h, length, tension, ea = _arrays(w, h, length, tension, ea)
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        st = _from_tension(w, h, length, tension, ea)
        _, dt_ds = _stiffness(w, length, tension, st, 1.0 / ea)
        slack = ~(st.r > 0.0)
    return np.where(slack, np.nan, st.span), np.where(slack, np.nan, dt_ds)


def lift_depth(w: Any, length: Any, span: Any, ea: Any = math.inf) -> np.ndarray:
    """Depth [m] at which a chain of unstretched length L [m], its hook at horizontal span s [m]
    from the anchor, lifts the anchor: the whole chain hangs, horizontal at the anchor.

    Inextensible, the lifting chain is half of a chain of length 2L hung between two level
    points 2s apart (its vertex at the anchor): ``a`` from
    :func:`catenary.taut_parameter_from_length`, ``theta = s/a`` and
    ``h* = 2 a sinh(theta/2)^2``; it needs ``s < L``.  Elastic, R solves
    ``s = (R/w) asinh(wL/R) + R L/EA`` (increasing in R, below the inextensible R: stretch
    adds span) by safeguarded Newton, and ``h* = (R/w) (sqrt(1 + (wL/R)^2) - 1) + w L^2/(2 EA)``.
    NaN where there is no such depth (``s >= L`` inextensible, NaN or non-positive inputs).
    """
    w, length, span, ea = _arrays(w, length, span, ea)
    out = np.full(span.shape, np.nan)
    ok = (w > 0.0) & (span > 0.0) & (span < length) & (ea > 0.0)
    if not ok.any():
        return out
    w, length, span, ea = w[ok], length[ok], span[ok], ea[ok]
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        a, _ = cat.taut_parameter_from_length(np.zeros_like(span), 2.0 * span, 2.0 * length)
        half = np.sinh(0.5 * span / a)
        depth = 2.0 * a * half * half
        elastic = np.isfinite(ea)
        if elastic.any():
            depth[elastic] = _elastic_lift_depth(
                w[elastic], length[elastic], span[elastic], ea[elastic], w[elastic] * a[elastic]
            )
    out[ok] = depth
    return out


def _elastic_lift_depth(
    w: np.ndarray, length: np.ndarray, span: np.ndarray, ea: np.ndarray, r_rigid: np.ndarray
) -> np.ndarray:
    """:func:`lift_depth` of elastic chains, from the inextensible R (an upper bound)."""
    q = w * length
    lo, hi = np.zeros_like(span), r_rigid.copy()
    r = r_rigid * (1.0 - 0.5 * r_rigid * length / (ea * span))  # first-order stretch
    r = np.where((r > lo) & (r < hi), r, 0.5 * hi)
    for _ in range(MAXITER):
        z = q / r
        f = r / w * np.arcsinh(z) + r * length / ea - span
        lo, hi = np.where(f < 0.0, r, lo), np.where(f > 0.0, r, hi)
        fp = (np.arcsinh(z) - z / np.sqrt(1.0 + z * z)) / w + length / ea
        new = r - f / fp
        new = np.where((new > lo) & (new < hi), new, 0.5 * (lo + hi))
        done = np.abs(new - r) <= T_STEP_TOL * r
        r = new
        if done.all():
            break
    z = q / r
    return r / w * (z * z / (np.sqrt(1.0 + z * z) + 1.0)) + q * length / (2.0 * ea)


def span_from_tension_scalar(w: float, h: float, length: float, t: float, ea: float) -> float:
    """:func:`span_from_tension` of one chain in plain floats (the same closed forms in the same
    order, the branch taken instead of both evaluated). Raises what :mod:`math` raises where
    numpy gives NaN or inf (the caller then uses the array path)."""
    sqrt, asinh = math.sqrt, math.asinh
    ta, d = anchor_end_tension(w, h, t, ea, cat._MATH)
    wl = w * length
    va = 0.5 * (d * (t + ta) / wl - wl)
    inv_ea = 1.0 / ea
    if va > 0.0:  # lifted
        r = sqrt(cat._maximum((ta - va) * (ta + va), 0.0))
        return float(r / w * asinh((wl * ta - va * d) / (r * r)) + r * length * inv_ea)
    v = sqrt(d * (t + ta))
    return float((length - v / w) + ta / w * asinh(v / ta) + ta * length * inv_ea)


def lift_depth_scalar(w: float, length: float, span: float, ea: float = math.inf) -> float:
    """:func:`lift_depth` of one chain in plain floats (the monitor's per-sample path: the same
    iterations, start and stopping tests). Raises what :mod:`math` raises where numpy gives NaN
    or inf."""
    if not (w > 0.0 and span > 0.0 and span < length and ea > 0.0):
        return math.nan
    a, _ = cat.taut_parameter_from_length_scalar(0.0, 2.0 * span, 2.0 * length)
    if math.isfinite(ea):
        return _elastic_lift_depth_scalar(w, length, span, ea, w * a)
    half = math.sinh(0.5 * span / a)
    return 2.0 * a * half * half


def _elastic_lift_depth_scalar(
    w: float, length: float, span: float, ea: float, r_rigid: float
) -> float:
    """:func:`_elastic_lift_depth` of one chain (it stops at this element's own convergence,
    where the array path goes on until every element has: a few ulps apart)."""
    asinh, sqrt = math.asinh, math.sqrt
    q = w * length
    lo, hi = 0.0, r_rigid
    r = r_rigid * (1.0 - 0.5 * r_rigid * length / (ea * span))
    r = r if lo < r < hi else 0.5 * hi
    for _ in range(MAXITER):
        z = q / r
        f = r / w * asinh(z) + r * length / ea - span
        lo, hi = (r if f < 0.0 else lo), (r if f > 0.0 else hi)
        fp = (asinh(z) - z / sqrt(1.0 + z * z)) / w + length / ea
        new = r - f / fp
        new = new if lo < new < hi else 0.5 * (lo + hi)
        done = abs(new - r) <= T_STEP_TOL * r
        r = new
        if done:
            break
    z = q / r
    return r / w * (z * z / (sqrt(1.0 + z * z) + 1.0)) + q * length / (2.0 * ea)


class _StateF(NamedTuple):
    """:class:`_State` of one chain in plain floats (the branch taken, not both)."""

    span: float
    r: float
    v: float
    va: float
    ta: float
    d: float
    lifted: bool


def _from_tension_scalar(w: float, h: float, length: float, t: float, ea: float) -> _StateF:
    """:func:`_from_tension` of one chain (the same closed forms in the same order). Raises
    what :mod:`math` raises where numpy gives NaN or inf."""
    sqrt, asinh = math.sqrt, math.asinh
    if ea == math.inf:  # what anchor_end_tension gives there, exactly
        ta, d = cat.two_prod_diff(t, w, h) + 0.0, w * h
    else:
        ta, d = anchor_end_tension(w, h, t, ea, cat._MATH)
    inv_ea = 1.0 / ea
    wl = w * length
    va = 0.5 * (d * (t + ta) / wl - wl)
    if va > 0.0:  # lifted
        r = sqrt(cat._maximum((ta - va) * (ta + va), 0.0))
        s = r / w * asinh((wl * ta - va * d) / (r * r)) + r * length * inv_ea
        return _StateF(s, r, va + wl, va, ta, d, True)
    v = sqrt(d * (t + ta))
    s = (length - v / w) + ta / w * asinh(v / ta) + ta * length * inv_ea
    return _StateF(s, ta, v, cat._maximum(va, 0.0), ta, d, False)


def _f_asinh_scalar(rho: float) -> float:
    """:func:`_f_asinh` of one float."""
    if rho < 0.1:
        r2 = rho * rho
        return (
            rho
            * r2
            * (
                1.0 / 3.0
                - r2
                * (3.0 / 10.0 - r2 * (15.0 / 56.0 - r2 * (35.0 / 144.0 - r2 * (315.0 / 1408.0))))
            )
        )
    return math.asinh(rho) - rho / math.sqrt(1.0 + rho * rho)


def _f_asinh_diff_scalar(p: float, q: float) -> float:
    """:func:`_f_asinh_diff` of one pair."""
    if not p < 0.1:
        return _f_asinh_scalar(p) - _f_asinh_scalar(q)
    p2 = p * p
    qn = q * q * q
    pn = p * p + p * q + q * q
    total = 0.0
    for coef in (1.0 / 3.0, -3.0 / 10.0, 15.0 / 56.0, -35.0 / 144.0, 315.0 / 1408.0):
        total = total + coef * pn
        pn = p2 * pn + qn * (p + q)
        qn = qn * q * q
    return (p - q) * total


def _dt_ds_scalar(w: float, length: float, t: float, s: _StateF, inv_ea: float) -> float:
    """``dT/ds`` of :func:`_stiffness` for one chain."""
    r, v, va, ta, d = s.r, s.v, s.va, s.ta, s.d
    rho, rho_a = v / r, va / r
    if s.lifted:
        j_sr = _f_asinh_diff_scalar(rho, rho_a) / w + length * inv_ea
        t_minus, ta_eff, num = d, ta, w * length * ta - va * d
    else:
        j_sr = _f_asinh_scalar(rho) / w + length * inv_ea
        t_minus, ta_eff = v * v / (t + r), r
        num = v * ta_eff
    j_sv = -r * t_minus / (t * ta_eff * w)
    j_hv = num / (t * ta_eff * w) + min(v / w, length) * inv_ea
    det = j_sr * j_hv - j_sv * j_sv
    dr = j_hv / det
    dv = -j_sv / det
    return (r * dr + v * dv) / t


def span_and_sensitivity_scalar(
    w: float, h: float, length: float, tension: float, ea: float
) -> tuple[float, float]:
    """:func:`span_and_sensitivity` of one chain in plain floats (the same closed forms; NaN at
    or below the slack tension). Raises what :mod:`math` raises where numpy gives NaN or inf
    (the caller then uses the array path)."""
    st = _from_tension_scalar(w, h, length, tension, ea)
    if not st.r > 0.0:
        return math.nan, math.nan
    return st.span, _dt_ds_scalar(w, length, tension, st, 1.0 / ea)


def tension_at_span_scalar(
    w: float, h: float, length: float, span: float, ea: float, t_start: float
) -> tuple[float, float]:
    """``(T, R)`` [N] of :func:`statics_at_span` for one chain started from ``t_start`` (finite,
    > 0): slack (``D0``, 0), taut (inf, inf), else the same safeguarded Newton in plain floats,
    each chain stopping at its own convergence. Raises ValueError where the array path is
    needed (an invalid input, an inextensible chain whose Newton did not converge: the
    problem-5 kernels) and what :mod:`math` raises where numpy gives NaN or inf."""
    if not (
        w > 0.0 and h > 0.0 and length > h and span >= 0.0 and ea > 0.0 and t_start > 0.0
    ) or not (math.isfinite(w) and math.isfinite(length) and math.isfinite(span)):
        raise ValueError('outside the scalar path')
    d0 = 2.0 * h * w / (1.0 + math.sqrt(1.0 + 2.0 * h * w / ea))
    if span <= length - d0 / w:
        return d0, 0.0
    rigid = math.isinf(ea)
    if rigid and span >= math.sqrt((length - h) * (length + h)):
        return math.inf, math.inf
    t, ok = _newton_tension_scalar(w, h, length, span, ea, t_start, d0)
    if not ok:
        if rigid:
            raise ValueError('no convergence: the problem-5 kernels')
        return math.nan, math.nan
    return t, _from_tension_scalar(w, h, length, t, ea).r


def _newton_tension_scalar(
    w: float, h: float, length: float, span: float, ea: float, t: float, d0: float
) -> tuple[float, bool]:
    """:func:`_newton_tension` of one chain: (T, converged)."""
    lo, hi = d0, math.inf
    t = t if t > lo else 2.0 * lo
    inv_ea = 1.0 / ea
    tol = _EPS4 * span
    for _ in range(MAXITER):
        st = _from_tension_scalar(w, h, length, t, ea)
        f = st.span - span
        if f < 0.0:
            lo = cat._maximum(lo, t)
        elif f > 0.0:
            hi = min(hi, t)
        step = -f * _dt_ds_scalar(w, length, t, st, inv_ea)
        new = t + step
        at_root = abs(f) <= tol
        conv = abs(step) <= T_STEP_TOL * t or at_root
        bad = not (lo < new < hi) and not at_root
        if bad:
            new = 0.5 * (lo + hi) if math.isfinite(hi) else 2.0 * t
        conv = conv or (math.isfinite(hi) and (hi - lo) <= 4e-16 * hi)
        if not (at_root or (bad and conv)):
            t = new
        if conv:
            return t, True
    return t, False

"""Margins with the waves and the sensors' accuracy: the worst case over the box of true readings.

The tension the bounds start from is the line's *dynamic tension* ``T_dyn = peak_tension +
wave_allowance x wave_tension`` (:mod:`catenary_monitor.core.rules.wave_window`: the largest
reading of the last ``wave_window`` seconds plus an allowance for the anchor's dynamic force
beyond the quasi-static; 0.3 covers every MoorDyn scene of docs/dynamics.md), not the one
reading: the quasi-static solve at ``T_dyn`` is the ``dynamic_uplift`` (:func:`dynamic_uplift`),
which the uplift ERROR takes, and the box below is built around ``T_dyn``.

A tension reading is within ``+- tension_accuracy`` (N, per line) of the true hook tension and
a depth reading within ``+- depth_accuracy`` (m) of the true depth: both are taken as bounds
(the sensor's stated accuracy), not as standard deviations. Over the box ``[T - dT, T + dT] x
[h - dh, h + dh]`` each bound is the worst value of the same solve the monitor makes:

``uplift_force_upper`` (N), ``anchor_margin_lower`` (m), ``tide_margin_lower`` (m).

The worst case from the analysis (:func:`bounds`, :func:`bounds_one`; inextensible closed forms
of :mod:`catenary_monitor.core.physics.catenary`, ``a = T/w - h`` for a grounded chain, ``t =
acosh(1 + h/a)``, ``X = x/a``):

* in ``T`` at fixed ``h``: ``x_min = a acosh(1 + h/a)`` grows with ``a`` (its derivative is
  ``t - tanh(t/2) > 0``), so the anchor margin falls with ``T``; the tide margin
  ``a (cosh X - 1) - h`` falls with ``a`` (derivative ``cosh X - 1 - X sinh X < 0``); the
  uplift force grows with ``T`` (tested). Every bound is taken at ``T + dT``.
* the anchor margin in ``h`` at fixed ``T``: ``dx_min/dh = coth t - t`` changes sign once, at
  ``t* = 1.19968`` (the root of ``t tanh t = 1``), so ``x_min`` peaks at ``h_a = k T / (w (1 +
  k))``, ``k = cosh t* - 1``: the lower bound is the margin at ``h_a`` clipped to ``[h - dh, h +
  dh]``, in closed form. The anchor lifts somewhere in the box exactly when it is negative.
* a chain grounded over the whole box: no uplift; ``d(tide margin)/dh = cosh X (X tanh X - 1)``
  makes the tide margin lowest at ``X = t*``, ``h = T/w - x/t*``: the lower bound is the closed
  form at that depth clipped. No solve.
* a chain lifted somewhere in the box: at fixed ``T`` and ``x`` the lifted chains are one family,
  ``X = x/a`` its parameter (anchor at ``u = v - X``, hook at ``v = acosh(c X)``, ``c = T/(w
  x)``): ``h/x = c - cosh(u)/X``, ``F/(w x) = sinh(u)/X``. On the interval of depths where it is
  lifted the uplift force is concave in ``h`` with its peak where ``coth v - tanh u = X``, and the
  tide margin convex with its trough where ``X sinh X + sinh u (coth v - X) = cosh X - 1 + cosh
  u`` (tested); both roots depend on ``c`` alone, so their depths over ``x`` are tabulated in
  ``log c`` once (:func:`lifted_critical_depths`). Each bound is one solve at its critical depth
  clipped to the box (one solve for both where they clip to the same end, the usual case) plus
  the tangent's rise across the box, ``max(0, F'(h_F) (h - h_F))`` with ``F'`` from the solved
  state: for a concave force that is an upper bound whatever the table's error, and the tangent
  is flat where the table is right (a peak inside the box) or points out of it (a peak beyond),
  so the bound is the exact maximum to about ``F'' e dh`` (``e`` the table's error in depth:
  below 1e-9 relative, tested against a dense sampling and mpmath).

Where the analysis does not apply (an elastic chain, a box reaching impossible readings, ``T +
dT <= w (h + dh)``, or ``h - dh <= 0``) the box is sampled (:func:`sampled_bounds`): the solve at
``T + dT`` and the depths ``h - dh``, ``h``, ``h + dh`` and the two critical depths above clipped
to the interval, the uplift's parabola vertex where it is concave over the three; impossible
corners are left out.

A chain with clump weights and buoys (:func:`loaded_bounds`) has no such closed forms: its
bounds are taken at ``T + dT`` too (the uplift grows and both margins fall with the hook
tension, as for the plain chain: tested) and the worst over five depths evenly spread over
``[h - dh, h + dh]`` (``dh`` is centimetres: a value turning inside the interval between two of
them is missed by ``f'' (dh/4)^2 / 2``, far below the sensors' accuracy).

The bounds are NaN only while the nominal solve has none: every line has a tension accuracy (by
default 0.5 % of its MBL) and the depth one (``depth_accuracy``, 0.02 m by default).
"""

from __future__ import annotations

import functools
import math
from types import SimpleNamespace
from typing import Any

import numpy as np

from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics.solve import solve

__all__ = [
    'FIELDS',
    'T_STAR',
    'depth_candidates',
    'bounds',
    'bounds_one',
    'sampled_bounds',
    'lifted_critical_depths',
    'dynamic_tension',
    'dynamic_uplift',
    'dynamic_uplift_one',
    'loaded_bounds',
]

#: The bounds' names (per-line outputs, /diagnostics values, replay CSV), in output order.
FIELDS = ('uplift_force_upper', 'anchor_margin_lower', 'tide_margin_lower')
#: Root of ``t tanh t = 1``: where ``x_min`` (fixed T) and the tide margin turn in depth.
T_STAR = 1.1996786402577338
_K = math.cosh(T_STAR) - 1.0
_KA = _K / (1.0 + _K)  # h_a = _KA T / w
#: ``c = T/(w x)`` below which no depth lifts the anchor: ``cosh(t*)/t*``.
C_MIN = math.cosh(T_STAR) / T_STAR
#: The lifted chain's critical depths over its span at ``C_MIN`` (``c - 1/t*``), the least
#: they take: both grow with ``c`` (tested), so a box below ``_ETA0 x`` needs no table.
_ETA0 = C_MIN - 1.0 / T_STAR
_NAN = math.nan
_INF = math.inf
_SPARE = 1.0 + 1e-15  # t > w h (1 + 1e-15): t > w h exactly, whatever the product's rounding


def dynamic_tension(peak: Any, wave: Any, allowance: float) -> np.ndarray:
    """The tension [N] the dynamic uplift and the bounds take: the window's ``peak`` plus
    ``allowance`` times its ``wave`` tension (N, :mod:`.wave_window`)."""
    return np.asarray(peak, dtype=float) + allowance * np.asarray(wave, dtype=float)


# --------------------------------------------------------------------------------------------
# The dynamic uplift: a solve only where the anchor lifts (x < x_min, closed form).
# --------------------------------------------------------------------------------------------
def dynamic_uplift(
    w: Any, x: Any, mbl: Any, ea: Any, tension: Any, depth: Any, nominal_uplift: Any
) -> np.ndarray:
    """The uplift force [N] at the dynamic ``tension`` (:func:`dynamic_tension`) and the
    measured ``depth`` (hook height added): at least the nominal (NaN where that is). An
    inextensible chain whose span reaches its ``x_min`` there has none: no solve."""
    given = (w, x, mbl, ea, tension, depth, nominal_uplift)
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in given))
    w, x, mbl, ea, t, h, f0 = (a.ravel() for a in arrays)
    out = np.full(len(t), np.nan)
    want = ~np.isnan(f0) & ~np.isnan(t)
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        grounded = want & np.isinf(ea) & _valid(w, x, t, h, h) & ~(x < _x_min(w, t, h))
        out[grounded] = np.fmax(0.0, f0[grounded])
        k = np.flatnonzero(want & ~grounded)
        if k.size:
            r = solve(
                w[k],
                h[k],
                tension=t[k],
                anchor_distance=x[k],
                mbl=mbl[k],
                ea=None if np.all(np.isinf(ea[k])) else ea[k],
            )
            out[k] = np.fmax(np.asarray(r.uplift_force, dtype=float), f0[k])
    out[np.isnan(f0)] = np.nan
    return out.reshape(arrays[0].shape)


def dynamic_uplift_one(
    w: float, x: float, mbl: float, ea: float, tension: float, depth: float, nominal: float
) -> float:
    """:func:`dynamic_uplift` of one line in plain floats (``ea`` inf: inextensible)."""
    if nominal != nominal or tension != tension:
        return _NAN
    if ea == _INF and _valid_one(w, x, tension, depth, depth):
        try:
            if not x < _x_min_one(w, tension, depth):
                return _fmax(0.0, nominal)
        except (ValueError, OverflowError, ZeroDivisionError):
            pass
    r = solve(w, depth, tension=tension, anchor_distance=x, mbl=mbl, ea=None if ea == _INF else ea)
    return _fmax(float(r.uplift_force), nominal)


def _valid(w: Any, x: Any, t: Any, lo: Any, hi: Any) -> Any:
    """Where every depth of ``[lo, hi]`` is a possible reading of hook tension ``t`` (arrays;
    ``t > w hi`` with the product's rounding to spare, finite: NaN and inf fail one of
    these)."""
    inf = np.inf
    return (w > 0.0) & (w < inf) & (x > 0.0) & (x < inf) & (lo > 0.0) & (t < inf) & (
        t > w * hi * _SPARE
    )


def _valid_one(w: float, x: float, t: float, lo: float, hi: float) -> bool:
    """:func:`_valid` of plain floats."""
    inf = math.inf
    return 0.0 < w < inf and 0.0 < x < inf and lo > 0.0 and t < inf and t > w * hi * _SPARE


def _x_min(w: Any, t: Any, h: Any) -> Any:
    """``x_min`` [m] of a grounded chain of hook tension ``t`` at depth ``h`` (the solve's
    closed form, arrays)."""
    b = cat.two_prod_diff(t, w, h) / w
    return b * cat.acosh1p(h / b)


def _x_min_one(w: float, t: float, h: float) -> float:
    """:func:`_x_min` of plain floats."""
    b = cat.two_prod_diff(t, w, h) / w
    z = h / b
    return b * math.log1p(z + math.sqrt(z * (2.0 + z)))


# --------------------------------------------------------------------------------------------
# The lifted chain's critical depths: a table in log c, c = T / (w x).
# --------------------------------------------------------------------------------------------
#: The table's nodes: ``log c`` from ``log C_MIN`` in steps of ``1/128`` up to ``c = 1e4``
#: (beyond, the last node's depths: the tangent keeps the bound an upper bound).
_S0, _DS = math.log(C_MIN), 1.0 / 128.0
_N = int(math.ceil((math.log(1e4) - _S0) / _DS))
_MATH_XP = SimpleNamespace(
    acosh=math.acosh, sinh=math.sinh, cosh=math.cosh, tanh=math.tanh, sqrt=math.sqrt
)
_NUMPY_XP = SimpleNamespace(
    acosh=np.arccosh, sinh=np.sinh, cosh=np.cosh, tanh=np.tanh, sqrt=np.sqrt
)


def _turn(c: Any, big_x: Any, tide: bool, xp: Any = _NUMPY_XP) -> tuple[Any, Any, Any]:
    """``(turn, d turn / dX, u)`` of the lifted family's member ``X`` at ``c = T/(w x)``: the
    uplift's turn ``coth v - tanh u - X`` or (``tide``) the tide margin's ``X sinh X + sinh u
    (coth v - X) - (cosh X - 1) - cosh u``, each of the sign of the value's slope in depth
    (``v = acosh(c X)``, ``u = v - X``)."""
    cx = c * big_x
    v = xp.acosh(cx)
    sinh_v = xp.sqrt((cx - 1.0) * (cx + 1.0))
    dv = c / sinh_v
    u = v - big_x
    du = dv - 1.0
    coth_v = cx / sinh_v
    dcoth = -dv / (sinh_v * sinh_v)
    cosh_u, sinh_u = xp.cosh(u), xp.sinh(u)
    if not tide:
        return coth_v - sinh_u / cosh_u - big_x, dcoth - du / (cosh_u * cosh_u) - 1.0, u
    half = xp.sinh(0.5 * big_x)
    arm = coth_v - big_x
    turn = big_x * xp.sinh(big_x) + sinh_u * arm - 2.0 * half * half - cosh_u
    slope = big_x * xp.cosh(big_x) + cosh_u * du * arm + sinh_u * (dcoth - 1.0) - sinh_u * du
    return turn, slope, u


def _bisect(c: np.ndarray, lo: np.ndarray, hi: np.ndarray, tide: bool) -> np.ndarray:
    """The sign change of :func:`_turn` in ``X`` between ``lo`` and ``hi`` (to rounding)."""
    f_lo = np.sign(_turn(c, lo, tide)[0])
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        left = np.sign(_turn(c, mid, tide)[0]) == f_lo
        lo, hi = np.where(left, mid, lo), np.where(left, hi, mid)
    return 0.5 * (lo + hi)


@functools.lru_cache(maxsize=None)
def _critical_table() -> tuple[list[float], list[float]]:
    """At each node ``log c``: ``log X`` of the uplift's peak and of the tide margin's trough,
    by bisection (built on first use, about 15 ms). The peak lies in ``(1/c, sqrt(1 +
    1/c^2)]`` (where ``u`` peaks), the trough between it and the deeper lift-off (``cosh X =
    c X``); at ``C_MIN`` both are ``X = t*``."""
    c = np.exp(_S0 + _DS * np.arange(1, _N + 1))
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        lo = np.nextafter(1.0 / c, np.inf) * (1.0 + 1e-15)
        peak = _bisect(c, lo, np.sqrt(1.0 + 1.0 / (c * c)), tide=False)
        x_off = np.full_like(c, T_STAR)
        hi = 2.0 + 2.0 * np.log(2.0 * c)
        for _ in range(80):  # the deeper lift-off: cosh X = c X, X > t*
            mid = 0.5 * (x_off + hi)
            below = np.cosh(mid) < c * mid
            x_off, hi = np.where(below, mid, x_off), np.where(below, hi, mid)
        trough = _bisect(c, peak, hi, tide=True)
    first = [math.log(T_STAR)]
    return first + np.log(peak).tolist(), first + np.log(trough).tolist()


def lifted_critical_depths(w: Any, x: Any, t: Any) -> tuple[np.ndarray, np.ndarray]:
    """The depths [m] at which a lifted chain of hook tension ``t`` (N) over span ``x`` (m)
    has its largest uplift force and its lowest tide margin (module docstring; arrays): the
    table's ``X`` (:func:`_critical_table`, linear in ``log c``) and one Newton step on the
    turn, ``h = x (c - cosh(u) / X)``."""
    peak, trough = (np.asarray(v) for v in _critical_table())
    c = np.maximum(t / (w * x), C_MIN)
    pos = np.minimum((np.log(c) - _S0) * (1.0 / _DS), float(_N))
    i = np.minimum(pos.astype(np.intp), _N - 1)
    f = pos - i
    out = []
    for table, tide in ((peak, False), (trough, True)):
        big_x = np.exp(table[i] + f * (table[i + 1] - table[i]))
        with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
            turn, slope, _ = _turn(c, big_x, tide)
            step = turn / slope
            big_x = np.where(np.abs(step) < 0.5 * big_x, big_x - step, big_x)
            u = np.arccosh(c * big_x) - big_x
        out.append(x * (c - np.cosh(u) / big_x))
    return out[0], out[1]


def lifted_critical_depths_one(w: float, x: float, t: float) -> tuple[float, float]:
    """:func:`lifted_critical_depths` of plain floats (raises what :mod:`math` raises)."""
    peak, trough = _critical_table()
    c = t / (w * x)
    c = c if c >= C_MIN else C_MIN
    pos = min((math.log(c) - _S0) * (1.0 / _DS), float(_N))
    i = min(int(pos), _N - 1)
    f = pos - i
    out = []
    for table, tide in ((peak, False), (trough, True)):
        big_x = math.exp(table[i] + f * (table[i + 1] - table[i]))
        turn, slope, _ = _turn(c, big_x, tide, _MATH_XP)
        step = turn / slope
        big_x = big_x - step if abs(step) < 0.5 * big_x else big_x
        u = math.acosh(c * big_x) - big_x
        out.append(x * (c - math.cosh(u) / big_x))
    return out[0], out[1]


def _slopes(w: Any, x: Any, t: Any, r: Any, v: Any, xp: Any = np) -> tuple[Any, Any]:
    """``(dF/dh, d(tide margin)/dh)`` of a lifted chain at fixed hook tension ``t`` from its
    solved horizontal tension ``r`` and uplift force ``v`` (N; module docstring's family:
    ``X = w x / r``, ``tanh u = v / hypot(r, v)``, ``coth v = t / sqrt(t^2 - r^2)``)."""
    big_x = w * x / r
    hyp = xp.sqrt(r * r + v * v)
    tanh_u, cosh_u, sinh_u = v / hyp, hyp / r, v / r
    coth_v = t / xp.sqrt((t - r) * (t + r))
    d = 1.0 - tanh_u * (coth_v - big_x)
    half = xp.sinh(0.5 * big_x)
    turn = big_x * xp.sinh(big_x) + sinh_u * (coth_v - big_x) - 2.0 * half * half - cosh_u
    return w * (coth_v - big_x - tanh_u) / d, turn / (cosh_u * d)


# --------------------------------------------------------------------------------------------
# The bounds.
# --------------------------------------------------------------------------------------------
def bounds(
    w: Any,
    x: Any,
    mbl: Any,
    ea: Any,
    tension: Any,
    depth: Any,
    tension_accuracy: Any,
    d_h: Any,
    nominal_uplift: Any,
    dynamic: bool = False,
) -> dict[str, np.ndarray]:
    """:data:`FIELDS` -> arrays for readings ``tension`` (N) and ``depth`` (m, hook height
    added), per-element line constants (``ea`` inf: inextensible) and accuracies
    ``tension_accuracy`` (N, NaN: not given) and ``d_h`` (m, 0: exact); ``nominal_uplift``
    (N) is the nominal solve's uplift force (NaN: no solve, no bounds). The worst case from
    the analysis where it applies, else the sampled box (module docstring). ``dynamic``: also
    ``dynamic_uplift`` (:func:`dynamic_uplift` at ``tension``: 0 N without a solve where the
    whole box is grounded, the uplift growing with the tension)."""
    given = (w, x, mbl, ea, tension, depth, tension_accuracy, d_h, nominal_uplift)
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in given))
    shape, n = arrays[0].shape, arrays[0].size
    w, x, mbl, ea, t, h, accuracy, dh, f0 = (_lean(a) for a in arrays)
    out = {key: np.full(n, np.nan) for key in FIELDS + (('dynamic_uplift',) if dynamic else ())}
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        keep = ((accuracy == accuracy) | (dh > 0.0)) & (f0 == f0)
        t_up = t + np.where(accuracy == accuracy, accuracy, 0.0)
        lo, hi = h - dh, h + dh
        analytic = keep & (ea == np.inf) & _valid(w, x, t_up, lo, hi)
        k = np.flatnonzero(analytic)
        if k.size:
            columns = _analytic(*(_at(v, k, n) for v in (w, x, t_up, lo, hi, f0)))
            for key, column in zip(FIELDS, columns):
                out[key][k] = column
            if dynamic:  # a grounded box (clear of rounding): no uplift at its tension or below
                g = k[columns[1] > 1e-9 * _at(x, k, n)]
                out['dynamic_uplift'][g] = np.fmax(0.0, _at(f0, g, n))
    k = np.flatnonzero(keep & ~analytic)
    if k.size:
        given = (w, x, mbl, ea, t, h, accuracy, dh, f0)
        sampled = sampled_bounds(*(_at(v, k, n) for v in given))
        for key in FIELDS:
            out[key][k] = sampled[key]
    if dynamic:
        k = np.flatnonzero(np.isnan(out['dynamic_uplift']) & ~np.isnan(f0))
        if k.size:
            line = (w, x, mbl, ea, t, h, f0)
            out['dynamic_uplift'][k] = dynamic_uplift(*(_at(v, k, n) for v in line))
    return {key: v.reshape(shape) for key, v in out.items()}


def _lean(a: np.ndarray) -> Any:
    """A broadcast input as computed on: its one value where it is one value repeated (a
    line's constant), else flat."""
    if a.ndim and a.size > 1 and not any(a.strides):
        return a.flat[0]
    return a.ravel()


def _at(v: Any, k: np.ndarray, n: int) -> Any:
    """``v`` at the elements ``k`` of ``n`` (a constant as it is; all of them: no copy)."""
    if np.ndim(v) == 0 or k.size == n:
        return v
    return v[k]


def _analytic(
    w: Any, x: Any, t: np.ndarray, lo: np.ndarray, hi: np.ndarray, f0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(uplift upper, anchor lower, tide lower) over ``[lo, hi]`` at hook tension ``t``, every
    depth possible, inextensible (module docstring)."""
    c = t / w
    h_a = np.minimum(np.maximum(_KA * c, lo), hi)
    b = cat.two_prod_diff(t, w, h_a) / w
    anchor = x - b * cat.acosh1p(h_a / b)
    h_t = np.minimum(np.maximum(c - x / T_STAR, lo), hi)
    other = np.flatnonzero(h_t != h_a)  # usually none: both at the deeper end
    if other.size:
        b = b.copy()
        b[other] = cat.two_prod_diff(t[other], _at(w, other, 0), h_t[other]) / _at(w, other, 0)
    half = np.sinh(0.5 * x / b)
    tide = 2.0 * b * half * half - h_t
    upper = np.fmax(0.0, f0)
    k = np.flatnonzero(anchor < 0.0)
    if k.size:
        w, x = np.broadcast_to(w, t.shape), np.broadcast_to(x, t.shape)
        up, tide[k] = _lifted(w[k], x[k], t[k], lo[k], hi[k], h_a[k])
        upper[k] = np.fmax(up, f0[k])
    return upper, anchor, tide


def _lifted(
    w: np.ndarray, x: np.ndarray, t: np.ndarray, lo: np.ndarray, hi: np.ndarray, h_a: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(uplift upper, tide lower) of chains lifted somewhere in ``[lo, hi]`` (at ``h_a``): one
    solve at each clipped critical depth (one where both clip to the same; ``h_a`` where the
    table's depth is not lifted) plus the tangent's rise across the box."""
    h_f, h_t = hi.copy(), hi.copy()
    deep = np.flatnonzero(hi > _ETA0 * x)  # else both critical depths are below the box
    if deep.size:
        c_f, c_t = lifted_critical_depths(w[deep], x[deep], t[deep])
        h_f[deep] = np.minimum(np.maximum(c_f, lo[deep]), hi[deep])
        h_t[deep] = np.minimum(np.maximum(c_t, lo[deep]), hi[deep])
    at_f, rh_f, f, tide_f = _solve_lifted(w, x, t, h_f, h_a)
    upper = f + np.where(f > 0.0, _rise(_slopes(w, x, t, rh_f, f)[0], at_f, lo, hi), 0.0)
    tide = tide_f.copy()
    at_t, rh_t, f_t = at_f, rh_f, f
    two = np.flatnonzero(h_t != h_f)
    if two.size:
        at_t, rh_t, f_t = at_f.copy(), rh_f.copy(), f.copy()
        sub = _solve_lifted(w[two], x[two], t[two], h_t[two], h_a[two])
        at_t[two], rh_t[two], f_t[two], tide[two] = sub
    d_t = _slopes(w, x, t, rh_t, f_t)[1]
    fall = -_rise(-d_t, at_t, lo, hi)
    return upper, tide + np.where(f_t > 0.0, fall, 0.0)


def _rise(slope: Any, at: Any, lo: Any, hi: Any) -> Any:
    """``max(0, slope (h - at))`` over ``h`` in ``[lo, hi]`` (arrays)."""
    return np.maximum(np.maximum(slope * (hi - at), slope * (lo - at)), 0.0)


def _solve_lifted(
    w: np.ndarray, x: np.ndarray, t: np.ndarray, at: np.ndarray, h_a: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(depth, horizontal tension, uplift force, tide margin) of the solve at ``(t, at)``, at
    ``h_a`` where ``at`` is not lifted (arrays)."""
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        r = solve(w, at, tension=t, anchor_distance=x)
    rh, f, tide = (np.array(getattr(r, k), dtype=float) for k in _LIFTED_KEYS)
    miss = np.flatnonzero(~(f > 0.0))
    if miss.size:  # the table's depth beside a narrow lifted interval: h_a (lifted)
        at = at.copy()
        at[miss] = h_a[miss]
        with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
            again = solve(w[miss], at[miss], tension=t[miss], anchor_distance=x[miss])
        for column, key in zip((rh, f, tide), _LIFTED_KEYS):
            column[miss] = np.asarray(getattr(again, key), dtype=float)
    return at, rh, f, tide


_LIFTED_KEYS = ('horizontal_tension', 'uplift_force', 'tide_margin')


def bounds_one(
    w: float,
    x: float,
    mbl: float,
    ea: float,
    tension: float,
    depth: float,
    tension_accuracy: float,
    d_h: float,
    nominal_uplift: float,
) -> tuple[float, float, float]:
    """:func:`bounds` of one line in plain floats: the :data:`FIELDS` values (the monitor's
    per-sample path, the same formulas; the sampled box through :func:`bounds` on one
    element where the analysis does not apply)."""
    if nominal_uplift != nominal_uplift or (tension_accuracy != tension_accuracy and not d_h > 0):
        return _NAN, _NAN, _NAN
    t = tension + (0.0 if tension_accuracy != tension_accuracy else tension_accuracy)
    lo, hi = depth - d_h, depth + d_h
    if ea == _INF and _valid_one(w, x, t, lo, hi):
        try:
            return _analytic_one(w, x, t, lo, hi, nominal_uplift)
        except (ValueError, OverflowError, ZeroDivisionError):
            pass  # beyond float range in plain math: numpy gives inf instead
    b = bounds(w, x, mbl, ea, tension, depth, tension_accuracy, d_h, nominal_uplift)
    return tuple(float(b[key]) for key in FIELDS)  # type: ignore[return-value]


def _clip(v: float, lo: float, hi: float) -> float:
    """``np.minimum(np.maximum(v, lo), hi)`` of floats (NaN stays NaN)."""
    v = v if (v != v or v >= lo) else lo
    return v if (v != v or v <= hi) else hi


def _analytic_one(
    w: float, x: float, t: float, lo: float, hi: float, f0: float
) -> tuple[float, float, float]:
    """:func:`_analytic` of plain floats."""
    c = t / w
    h_a = _clip(_KA * c, lo, hi)
    b = cat.two_prod_diff(t, w, h_a) / w
    z = h_a / b
    anchor = x - b * math.log1p(z + math.sqrt(z * (2.0 + z)))
    if not anchor < 0.0:  # grounded over the whole box
        h_t = _clip(c - x / T_STAR, lo, hi)
        b = b if h_t == h_a else cat.two_prod_diff(t, w, h_t) / w
        half = math.sinh(0.5 * x / b)
        return _fmax(0.0, f0), anchor, 2.0 * b * half * half - h_t
    if hi > _ETA0 * x:
        h_f, h_t = lifted_critical_depths_one(w, x, t)
        h_f, h_t = _clip(h_f, lo, hi), _clip(h_t, lo, hi)
    else:  # both critical depths below the box (a span longer than 1.48 depths)
        h_f = h_t = hi
    upper, tide = _lifted_one(w, x, t, lo, hi, h_f, h_t, h_a)
    return _fmax(upper, f0), anchor, tide


def _lifted_one(
    w: float, x: float, t: float, lo: float, hi: float, h_f: float, h_t: float, h_a: float
) -> tuple[float, float]:
    """:func:`_lifted` of one chain: one solve where both critical depths clip to the same."""
    at_f, rh, f, _ = _solve_lifted_one(w, x, t, h_f, h_a)
    upper = f
    if f > 0.0:
        d_f = _slopes(w, x, t, rh, f, cat._MATH)[0]
        upper = f + max(d_f * (hi - at_f), d_f * (lo - at_f), 0.0)
    at_t, rh, f, tide = (at_f, rh, f, _) if h_t == h_f else _solve_lifted_one(w, x, t, h_t, h_a)
    if f > 0.0:
        d_t = _slopes(w, x, t, rh, f, cat._MATH)[1]
        tide = tide + min(d_t * (hi - at_t), d_t * (lo - at_t), 0.0)
    return upper, tide


def _solve_lifted_one(
    w: float, x: float, t: float, at: float, h_a: float
) -> tuple[float, ...]:
    """(depth, horizontal tension, uplift force, tide margin) of the solve at ``(t, at)``, or
    at ``h_a`` where ``at`` is not lifted."""
    r = solve(w, at, tension=t, anchor_distance=x)
    if not r.uplift_force > 0.0:
        at = h_a
        r = solve(w, at, tension=t, anchor_distance=x)
    return at, float(r.horizontal_tension), float(r.uplift_force), float(r.tide_margin)


# --------------------------------------------------------------------------------------------
# The sampled box: elastic chains, boxes reaching impossible readings.
# --------------------------------------------------------------------------------------------
def depth_candidates(w: Any, x: Any, tension: Any, depth: Any, d_h: Any) -> np.ndarray:
    """The five depths (m, shape ``(5, n)``) the bounds are evaluated at for hook tension
    ``tension`` (N, already ``T + dT``): ``h - dh``, ``h``, ``h + dh`` and the two critical
    depths (module docstring) clipped to ``[h - dh, h + dh]``."""
    given = (w, x, tension, depth, d_h)
    w, x, t, h, dh = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in given))
    lo, hi = h - dh, h + dh
    h_anchor = np.clip(_K * t / (w * (1.0 + _K)), lo, hi)
    h_tide = np.clip(t / w - x / T_STAR, lo, hi)
    return np.stack([lo, h, hi, h_anchor, h_tide])


def sampled_bounds(
    w: Any,
    x: Any,
    mbl: Any,
    ea: Any,
    tension: Any,
    depth: Any,
    tension_accuracy: Any,
    d_h: Any,
    nominal_uplift: Any,
) -> dict[str, np.ndarray]:
    """:func:`bounds` by sampling the box (module docstring): the solve at ``T + dT`` and the
    five depths of :func:`depth_candidates`, and the uplift's parabola vertex where it is
    concave over ``h - dh``, ``h``, ``h + dh`` (an elastic chain's bounds, and the reference
    the analysis was checked against)."""
    given = (w, x, mbl, ea, tension, depth, tension_accuracy, d_h, nominal_uplift)
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in given))
    w, x, mbl, ea, t, h, tension_accuracy, dh, f0 = (a.ravel() for a in arrays)
    keep = (~np.isnan(tension_accuracy) | (dh > 0.0)) & ~np.isnan(f0)
    shape = arrays[0].shape
    out = {key: np.full(len(t), np.nan) for key in FIELDS}
    k = np.flatnonzero(keep)
    if k.size:
        upper, anchor, tide = _worst(
            w[k], x[k], mbl[k], ea[k], t[k], h[k], tension_accuracy[k], dh[k]
        )
        out['uplift_force_upper'][k] = np.fmax(upper, f0[k])
        out['anchor_margin_lower'][k] = anchor
        out['tide_margin_lower'][k] = tide
    return {key: v.reshape(shape) for key, v in out.items()}


def _worst(
    w: np.ndarray,
    x: np.ndarray,
    mbl: np.ndarray,
    ea: np.ndarray,
    t: np.ndarray,
    h: np.ndarray,
    tension_accuracy: np.ndarray,
    dh: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(largest uplift force, smallest anchor margin, smallest tide margin) over the five
    candidate depths at ``T + dT`` (NaN where every candidate is impossible)."""
    t_up = t + np.where(np.isnan(tension_accuracy), 0.0, tension_accuracy)
    hs = depth_candidates(w, x, t_up, h, dh)
    n = len(t)
    rep = [np.broadcast_to(v, (5, n)).ravel() for v in (w, x, mbl, ea, t_up)]
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        r = solve(
            rep[0],
            hs.ravel(),
            tension=rep[4],
            anchor_distance=rep[1],
            mbl=rep[2],
            ea=None if np.all(np.isinf(ea)) else rep[3],
        )

    def pick(key: str, big: bool) -> np.ndarray:
        v = np.asarray(getattr(r, key), dtype=float).reshape(5, n)
        v = np.where(np.isnan(v), -np.inf if big else np.inf, v)
        best = v.max(axis=0) if big else v.min(axis=0)
        return np.where(np.isinf(best), np.nan, best)

    upper = _peak(pick('uplift_force', True), r, w, x, mbl, ea, t_up, h, dh)
    return upper, pick('anchor_margin', False), pick('tide_margin', False)


def _peak(
    upper: np.ndarray,
    r: Any,
    w: np.ndarray,
    x: np.ndarray,
    mbl: np.ndarray,
    ea: np.ndarray,
    t_up: np.ndarray,
    h: np.ndarray,
    dh: np.ndarray,
) -> np.ndarray:
    """The uplift bound with its peak in depth refined: where the uplift force is concave over
    ``h - dh``, ``h``, ``h + dh`` (a peak may lie inside: the force is unimodal in depth), also
    the vertex of the parabola through the three, clipped (one more solve for those)."""
    n = len(h)
    v = np.asarray(r.uplift_force, dtype=float).reshape(5, n)[:3]
    lo, mid, hi = v
    with np.errstate(invalid='ignore', divide='ignore'):
        curve = hi - 2.0 * mid + lo
        inside = (np.fmax(lo, hi) > 0.0) & (curve < 0.0) & (dh > 0.0)
    k = np.flatnonzero(inside)
    if not k.size:
        return upper
    vertex = h[k] - dh[k] * (hi[k] - lo[k]) / (2.0 * curve[k])
    vertex = np.clip(vertex, h[k] - dh[k], h[k] + dh[k])
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        peak = solve(
            w[k],
            vertex,
            tension=t_up[k],
            anchor_distance=x[k],
            mbl=mbl[k],
            ea=None if np.all(np.isinf(ea[k])) else ea[k],
        )
    out = upper.copy()
    out[k] = np.fmax(upper[k], np.asarray(peak.uplift_force, dtype=float))
    return out


def loaded_bounds(
    w: float,
    x: float,
    mbl: float,
    loads: Any,
    tension: float,
    depth: float,
    tension_accuracy: float,
    d_h: float,
    nominal_uplift: float,
) -> dict[str, float]:
    """``dynamic_uplift`` and :data:`FIELDS` of one chain with point ``loads`` (``(positions,
    weights)``), as :func:`dynamic_uplift` and :func:`bounds` in plain floats (module
    docstring: five depths at ``T + dT``)."""
    nan = math.nan
    out = dict.fromkeys(('dynamic_uplift', *FIELDS), nan)
    if nominal_uplift != nominal_uplift or tension != tension:
        return out

    def at(t: float, h: float) -> Any:
        return solve(w, h, tension=t, anchor_distance=x, mbl=mbl, point_loads=loads)

    out['dynamic_uplift'] = _fmax(float(at(tension, depth).uplift_force), nominal_uplift)
    if tension_accuracy != tension_accuracy and not d_h > 0.0:
        return out
    t_up = tension + (0.0 if tension_accuracy != tension_accuracy else tension_accuracy)
    spread = (-1.0, -0.5, 0.0, 0.5, 1.0) if d_h > 0.0 else (0.0,)
    rs = [at(t_up, depth + f * d_h) for f in spread]
    ups = [float(r.uplift_force) for r in rs if r.uplift_force == r.uplift_force]
    anchor = [float(r.anchor_margin) for r in rs if r.anchor_margin == r.anchor_margin]
    tide = [float(r.tide_margin) for r in rs if r.tide_margin == r.tide_margin]
    out['uplift_force_upper'] = _fmax(max(ups) if ups else nan, nominal_uplift)
    out['anchor_margin_lower'] = min(anchor) if anchor else nan
    out['tide_margin_lower'] = min(tide) if tide else nan
    return out


def _fmax(a: float, b: float) -> float:
    """``np.fmax`` of two floats (NaN only where both are)."""
    if a != a:
        return b
    return a if b != b or a >= b else b

"""One tick's dock estimate in plain floats: :func:`~catenary_monitor.core.body.estimate.
estimate_dock`'s steps for one row of readings (the live core estimates one tick at a time:
numpy on twelve-element arrays costs ~2 ms a tick, these loops ~0.3 ms).

The same estimate as the array formulation (:func:`~catenary_monitor.core.body.estimate.
estimate_dock_arrays`, kept as the reference: ``test/test_dock_estimate_tick.py`` compares them
to rounding): the implied spans (closed forms, the point-load tables' plain-float queries),
the Gauss-Newton fit with its 3 x 3 normal equations solved by cofactors, the normalized
residuals and the drops, and each line's tension at its fitted span (the same safeguarded
Newton, started from the measured tension moved along ``dT/ds`` to the fitted span: one or two
steps instead of six). A chain the plain-float path cannot take (a line without a reading, an
input where :mod:`math` raises where numpy gives NaN) goes through the array functions, one
element. The live core and its twin both estimate tick by tick through here: the same bits.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Optional

import numpy as np

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.physics import point_loads
from catenary_monitor.core.physics.fixed_length import (
    span_and_sensitivity,
    span_and_sensitivity_scalar,
    statics_at_span,
    tension_at_span_scalar,
)
from catenary_monitor.core.physics.point_load_table import PointLoadTable

__all__ = ['TickEstimate', 'estimate_tick', 'exact_spans', 'exact_states', 'loaded_lines']

#: Gauss-Newton steps at most; stops when the step is below STEP_TOL of the dock's size (yaw:
#: in rad). Spans are nearly linear in the offset: 3-5 steps.
MAXITER = 20
STEP_TOL = 1e-10
#: At most this many lines flagged (and dropped) per estimate.
MAX_FLAGS = 3
#: A line is flagged only if at least this many readings remain in the fit (redundancy >= 2).
MIN_REDUNDANT = 5
#: Readings needed for an estimate (3 unknowns).
MIN_LINES = 3

_NAN = math.nan
_MATH_ERRORS = (ValueError, ZeroDivisionError, OverflowError)


class TickEstimate(NamedTuple):
    """One estimate of ``m`` lines (the fields of a DockEstimate row, plain Python values)."""

    valid: bool
    offset: tuple[float, float, float]
    load: tuple[float, float, float]
    expected: list[float]
    residual: list[float]
    normalized: list[float]
    dropped: list[bool]
    used: list[bool]
    readings: int
    span: list[float]


class _Lines(NamedTuple):
    """A model's per-line constants as lists (built once per model)."""

    hx: list[float]
    hy: list[float]
    ax: list[float]
    ay: list[float]
    w: list[float]
    length: list[float]
    ea: list[float]
    hook_height: list[float]
    accuracy: list[float]  # the default where not given
    given: list[bool]
    tables: list[Optional[PointLoadTable]]
    loaded: list[bool]
    size: float


_VIEWS: dict[int, tuple[DockModel, _Lines]] = {}


def _lines(model: DockModel) -> _Lines:
    """The model's constants as lists (cached by identity)."""
    hit = _VIEWS.get(id(model))
    if hit is not None and hit[0] is model:
        return hit[1]
    m = len(model.names)
    given = np.isfinite(model.tension_accuracy)
    default = float(np.max(model.tension_accuracy[given])) if given.any() else 1.0
    accuracy = np.where(given, model.tension_accuracy, default)
    tables: list[Optional[PointLoadTable]] = list(model.tables) if model.tables else [None] * m
    loaded = [loads is not None for loads in model.loads] if model.loads else [False] * m
    view = _Lines(
        model.hook[:, 0].tolist(),
        model.hook[:, 1].tolist(),
        model.anchor[:, 0].tolist(),
        model.anchor[:, 1].tolist(),
        model.weight.tolist(),
        model.chain_length.tolist(),
        model.ea.tolist(),
        model.hook_height.tolist(),
        accuracy.tolist(),
        given.tolist(),
        tables,
        loaded,
        model.size,
    )
    if len(_VIEWS) > 32:
        _VIEWS.clear()
    _VIEWS[id(model)] = (model, view)
    return view


def loaded_lines(model: DockModel) -> list[int]:
    """The lines with point loads."""
    return [i for i, loads in enumerate(model.loads) if loads is not None]


def exact_spans(
    model: DockModel, i: int, h: np.ndarray, tension: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Line ``i``'s spans from its tensions by the exact chain-length solve (its roots, about
    15 ms each; a model without tables: the surrogate's baseline)."""
    loads = model.loads[i]
    assert loads is not None
    w, length = float(model.weight[i]), float(model.chain_length[i])
    start = float(np.hypot(*(model.anchor[i] - model.hook[i])))
    spans, slopes = np.full(h.shape, math.nan), np.full(h.shape, math.nan)
    for k, (hk, tk) in enumerate(zip(h.tolist(), tension.tolist())):
        if tk == tk:
            s = point_loads.span_at_tension(w, hk, length, tk, loads, start)
            if s == s:
                spans[k], slopes[k] = s, point_loads.line_statics(w, hk, length, s, loads)[7]
    return spans, slopes


def exact_states(
    model: DockModel, i: int, h: np.ndarray, span: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Line ``i``'s hook and horizontal tension at the spans, exactly."""
    loads = model.loads[i]
    assert loads is not None
    w, length = float(model.weight[i]), float(model.chain_length[i])
    top, horizontal = np.full(h.shape, math.nan), np.full(h.shape, math.nan)
    for k, (hk, sk) in enumerate(zip(h.tolist(), span.tolist())):
        if sk == sk:
            values = point_loads.line_statics(w, hk, length, sk, loads)
            horizontal[k], top[k] = values[0], values[1]
    return top, horizontal


def _span_of(model: DockModel, v: _Lines, k: int, h: float, t: float) -> tuple[float, float]:
    """Line k's implied span and dT/ds from its tension ``t`` (NaN: none)."""
    if t != t:
        return _NAN, _NAN
    if v.loaded[k]:
        table = v.tables[k]
        if table is not None:
            return table.span_at_tension_one(h, t)
        s, d = exact_spans(model, k, np.array([h]), np.array([t]))
        return float(s[0]), float(d[0])
    try:
        return span_and_sensitivity_scalar(v.w[k], h, v.length[k], t, v.ea[k])
    except _MATH_ERRORS:
        s, d = span_and_sensitivity(v.w[k], h, v.length[k], t, v.ea[k])
        return float(s), float(d)


def _state_of(
    model: DockModel, v: _Lines, k: int, h: float, span: float, start: float
) -> tuple[float, float]:
    """Line k's hook and horizontal tension at ``span``, the Newton started from ``start``
    (NaN: the array path's own start)."""
    if v.loaded[k]:
        table = v.tables[k]
        if table is not None:
            return table.state_at_span_one(h, span)
        top, hor = exact_states(model, k, np.array([h]), np.array([span]))
        return float(top[0]), float(hor[0])
    if start == start and start > 0.0:
        try:
            return tension_at_span_scalar(v.w[k], h, v.length[k], span, v.ea[k], start)
        except _MATH_ERRORS:
            pass
    st = statics_at_span(
        v.w[k], h, v.length[k], span, v.ea[k], None if start != start else start
    )
    return float(st.top_tension), float(st.horizontal_tension)


class _Geometry(NamedTuple):
    span: list[float]
    jac: list[tuple[float, float, float]]
    ux: list[float]
    uy: list[float]
    arm_x: list[float]
    arm_y: list[float]


def _geometry(v: _Lines, q: list[float]) -> _Geometry:
    """Spans, their Jacobian d s / d q and the unit vectors at offset ``q``."""
    c, s = math.cos(q[2]), math.sin(q[2])
    x, y = q[0], q[1]
    hypot = math.hypot
    spans, jac, uxs, uys, arm_x, arm_y = [], [], [], [], [], []
    for px, py, ax, ay in zip(v.hx, v.hy, v.ax, v.ay):
        rx, ry = c * px - s * py, s * px + c * py
        dx, dy = ax - x - rx, ay - y - ry
        span = hypot(dx, dy)
        ux, uy = (dx / span, dy / span) if span > 0.0 else (_NAN, _NAN)
        spans.append(span)
        uxs.append(ux)
        uys.append(uy)
        arm_x.append(rx)
        arm_y.append(ry)
        jac.append((-ux, -uy, ux * ry - uy * rx))
    return _Geometry(spans, jac, uxs, uys, arm_x, arm_y)


def _normal(jac: list[tuple[float, float, float]], weight: list[float]) -> list[float]:
    """``J^T W J``'s six entries (00, 01, 02, 11, 12, 22) over the lines with weight."""
    a00 = a01 = a02 = a11 = a12 = a22 = 0.0
    for (j0, j1, j2), wk in zip(jac, weight):
        if wk > 0.0:
            w0, w1, w2 = wk * j0, wk * j1, wk * j2
            a00 += w0 * j0
            a01 += w0 * j1
            a02 += w0 * j2
            a11 += w1 * j1
            a12 += w1 * j2
            a22 += w2 * j2
    return [a00, a01, a02, a11, a12, a22]


def _inverse(a: list[float]) -> Optional[list[float]]:
    """The symmetric inverse's six entries, None where the matrix is not finite or far from
    regular (the array path's test: ``|det| > 1e-10 |a00 a11 a22|``, a positive diagonal)."""
    a00, a01, a02, a11, a12, a22 = a
    if not all(math.isfinite(x) for x in a):
        return None
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    det = a00 * c00 + a01 * c01 + a02 * c02
    diag = abs(a00 * a11 * a22)
    if not (abs(det) > 1e-10 * diag and diag > 0.0):
        return None
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    return [c00 / det, c01 / det, c02 / det, c11 / det, c12 / det, c22 / det]


def _fit(
    v: _Lines, s_meas: list[float], weight: list[float]
) -> tuple[list[float], Optional[list[float]], _Geometry]:
    """Weighted Gauss-Newton fit of q to the implied spans from the reference position:
    q, its covariance (None: no fit) and the geometry at q."""
    q = [0.0, 0.0, 0.0]
    tol = v.size * STEP_TOL
    converged = False
    for _ in range(MAXITER):
        g = _geometry(v, q)
        a = _normal(g.jac, weight)
        inv = _inverse(a)
        if inv is None:
            return q, None, g
        b0 = b1 = b2 = 0.0
        for (j0, j1, j2), wk, sk, span in zip(g.jac, weight, s_meas, g.span):
            if wk > 0.0:
                we = wk * (sk - span)
                b0 += we * j0
                b1 += we * j1
                b2 += we * j2
        i00, i01, i02, i11, i12, i22 = inv
        d0 = i00 * b0 + i01 * b1 + i02 * b2
        d1 = i01 * b0 + i11 * b1 + i12 * b2
        d2 = i02 * b0 + i12 * b1 + i22 * b2
        q = [q[0] + d0, q[1] + d1, q[2] + d2]
        if not (math.isfinite(q[0]) and math.isfinite(q[1]) and math.isfinite(q[2])):
            return q, None, _geometry(v, [_NAN, _NAN, _NAN])  # as numpy: no fit
        if math.hypot(d0, d1) <= tol and abs(d2) <= STEP_TOL:
            converged = True
            break
    g = _geometry(v, q)
    if not converged:
        return q, None, g
    return q, _inverse(_normal(g.jac, weight)), g


def _normalized(
    g: _Geometry,
    cov: list[float],
    s_meas: list[float],
    weight: list[float],
    flagged: list[bool],
    testable: list[bool],
) -> list[float]:
    """Span residual over its standard deviation: ``sigma_s^2 - J C J^T`` for a reading in the
    fit, ``sigma_s^2 + J C J^T`` for one left out (a prediction); NaN where not testable."""
    c00, c01, c02, c11, c12, c22 = cov
    out = []
    for k, (j0, j1, j2) in enumerate(g.jac):
        if not testable[k]:
            out.append(_NAN)
            continue
        lev = (
            j0 * (c00 * j0 + c01 * j1 + c02 * j2)
            + j1 * (c01 * j0 + c11 * j1 + c12 * j2)
            + j2 * (c02 * j0 + c12 * j1 + c22 * j2)
        )
        var_s = 1.0 / weight[k]
        var = var_s + lev if flagged[k] else var_s - lev
        out.append((s_meas[k] - g.span[k]) / math.sqrt(var) if var > 0.0 else _NAN)
    return out


def _worst(z: list[float], candidate: list[bool]) -> tuple[int, float]:
    """The candidate with the largest ``|z|`` (the first; a NaN wins, as numpy's argmax)."""
    best, top = 0, -1.0
    for k, (zk, c) in enumerate(zip(z, candidate)):
        value = abs(zk) if c else -1.0
        if value != value:
            return k, value
        if value > top:
            best, top = k, value
    return best, top


def _refit(
    v: _Lines, s_meas: list[float], weight: list[float], flagged: list[bool]
) -> tuple[list[float], Optional[list[float]], _Geometry]:
    return _fit(v, s_meas, [0.0 if f else wk for wk, f in zip(weight, flagged)])


def estimate_tick(
    model: DockModel,
    depth: float,
    tensions: list[float],
    usable: list[bool],
    exclude: Optional[list[bool]],
    remove: float,
) -> TickEstimate:
    """One estimate (see :func:`~catenary_monitor.core.body.estimate.estimate_dock`): tide
    ``depth`` [m], the lines' ``tensions`` [N], which are ``usable``, which are excluded from
    the fit from the start, and the normalized residual above which the largest is dropped."""
    v = _lines(model)
    m = len(tensions)
    h = [depth + hh for hh in v.hook_height]
    s_meas, dt_ds, weight = [_NAN] * m, [_NAN] * m, [0.0] * m
    for k in range(m):
        if usable[k]:
            s, d = _span_of(model, v, k, h[k], tensions[k])
            s_meas[k], dt_ds[k] = s, d
            if s == s and d > 0.0:
                wk = d / v.accuracy[k] if v.accuracy[k] != 0.0 else math.inf
                wk = wk * wk
                weight[k] = wk if math.isfinite(wk) else 0.0
    readings = sum(1 for wk in weight if wk > 0.0)
    q, cov, g = _fit(v, s_meas, weight)
    flagged = [False] * m
    if exclude is not None:
        flagged = [e and wk > 0.0 for e, wk in zip(exclude, weight)]
        if any(flagged):
            q, cov, g = _refit(v, s_meas, weight, flagged)
    testable = [gk and wk > 0.0 for gk, wk in zip(v.given, weight)]
    z = [_NAN] * m
    if cov is not None:
        for _ in range(MAX_FLAGS):
            z = _normalized(g, cov, s_meas, weight, flagged, testable)
            worst, top = _worst(z, [t and not f for t, f in zip(testable, flagged)])
            left = sum(1 for wk, f in zip(weight, flagged) if wk > 0.0 and not f)
            if not (top > remove and left - 1 >= MIN_REDUNDANT):
                break
            flagged[worst] = True
            q, cov, g = _refit(v, s_meas, weight, flagged)
            if cov is None:
                break
        if cov is not None:
            z = _normalized(g, cov, s_meas, weight, flagged, testable)
    valid = readings >= MIN_LINES and cov is not None
    if not valid:
        nans, no = [_NAN] * m, [False] * m
        none = (_NAN, _NAN, _NAN)
        return TickEstimate(False, none, none, nans, nans, nans, no, no, readings, nans)
    expected, residual = [_NAN] * m, [_NAN] * m
    fx = fy = mz = 0.0
    for k in range(m):
        t = tensions[k] if usable[k] else _NAN
        start = t
        if t == t and dt_ds[k] == dt_ds[k]:
            moved = t + dt_ds[k] * (g.span[k] - s_meas[k])  # the measured state moved
            start = moved if math.isfinite(moved) and moved > 0.0 else t
        top, hor = _state_of(model, v, k, h[k], g.span[k], start)
        expected[k] = top
        residual[k] = t - top
        fxk, fyk = hor * g.ux[k], hor * g.uy[k]
        fx += fxk
        fy += fyk
        mz += g.arm_x[k] * fyk - g.arm_y[k] * fxk
    load = tuple(-f if math.isfinite(f) else _NAN for f in (fx, fy, mz))
    normalized = [zk if tk else _NAN for zk, tk in zip(z, testable)]
    return TickEstimate(
        True,
        (q[0], q[1], q[2]),
        (load[0], load[1], load[2]),
        expected,
        residual,
        normalized,
        list(flagged),
        [wk > 0.0 and not f for wk, f in zip(weight, flagged)],
        readings,
        g.span,
    )

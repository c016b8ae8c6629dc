"""The dock's offset and environmental load from the measured tensions of all its lines, and
the lines that disagree with the rest (the live consistency check; pure). :func:`estimate_dock`
makes each estimate in plain floats (:mod:`.estimate_tick`: the live core one tick at a time,
replay tick by tick, the same bits); :func:`estimate_dock_arrays` is the same estimate
vectorized over estimates in numpy, its reference (equal to rounding).

Each measured hook tension T_i implies a span ``s_i`` (closed form for the fixed-length chain,
:func:`catenary_monitor.core.physics.fixed_length.span_and_sensitivity`) with the standard
deviation ``sigma_s = sigma_T / (dT/ds)``. ``sigma_T`` is the sensor's ``tension_accuracy``: that
parameter is a bound (a reading within +- it of the true tension), taken here as the reading's
standard deviation, which no error within the bound exceeds, so the normalized residuals are
never overstated. A slack reading says nothing about the span and gets no weight. The offset
``q = (X, Y, psi)`` minimizes

    sum_i (s_i - |A_i - (X, Y) - R(psi) p_i|)^2 / sigma_s,i^2

(Gauss-Newton from the reference position: spans are nearly linear in q, 3-4 steps). The
residuals are normalized by their standard deviation ``sqrt(sigma_s^2 - J C J^T)`` (C the
covariance of q); the largest-normalized-residual test (Schweppe; the bad-data test of power
system state estimation) drops the line with the largest ``|z|`` above ``REMOVE_Z`` and refits,
up to ``MAX_FLAGS`` times, as long as at least ``MIN_REDUNDANT`` readings remain (fewer cannot
say which line is wrong); a dropped line's z is then its prediction residual. Whether a line is
inconsistent is decided over time from these z (:mod:`catenary_monitor.core.rules.dock_watch`).
Every line is tested at its sensor's accuracy (``tension_accuracy``, by default 0.5 % of its
MBL: :attr:`~catenary_monitor.core.config.parameters.LineConfig.tension_accuracy_or_default`);
a model built with NaN accuracies tests none and weights them with the largest accuracy given (or
equally).

The environmental load is minus the restoring force and moment of every line at the fitted
offset (the dock at rest: static equilibrium), and each line's expected tension is its model
tension at its fitted span (``span``, the hook's distance to its anchor at the fitted offset,
which the monitor solves the line's uplift at: :mod:`catenary_monitor.core.rules.dock_watch`):
``residual = measured - expected`` (an expected tension of ``inf``
means the other lines put this hook beyond its chain's reach).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.estimate_tick import (
    MAX_FLAGS,
    MAXITER,
    MIN_LINES,
    MIN_REDUNDANT,
    STEP_TOL,
    TickEstimate,
    estimate_tick,
    exact_spans,
    exact_states,
    loaded_lines,
)
from catenary_monitor.core.physics.fixed_length import span_and_sensitivity, statics_at_span

__all__ = [
    'DockEstimate',
    'estimate_dock',
    'estimate_dock_arrays',
    'stack_ticks',
    'REMOVE_Z',
    'MAX_FLAGS',
    'MIN_REDUNDANT',
    'MIN_LINES',
]

#: The largest normalized residual above this is dropped from this estimate's fit (a good
#: line is dropped now and then at little cost; a bad one stops biasing the others).
REMOVE_Z = 3.0


class DockEstimate(NamedTuple):
    """``n`` estimates of ``m`` lines (arrays; SI units, yaw in rad)."""

    valid: np.ndarray  # (n,) bool: an offset was estimated
    offset: np.ndarray  # (n, 3): X m, Y m, psi rad
    load: np.ndarray  # (n, 3): Fx N, Fy N, Mz N m (minus the restoring force at the offset)
    expected: np.ndarray  # (n, m) N, model hook tension at the fitted span
    residual: np.ndarray  # (n, m) N, measured - expected (NaN: no reading)
    normalized: np.ndarray  # (n, m), residual over its standard deviation (NaN: not tested)
    dropped: np.ndarray  # (n, m) bool: dropped from this estimate's fit
    used: np.ndarray  # (n, m) bool: in the final fit
    readings: np.ndarray  # (n,) int: readings with weight
    span: np.ndarray  # (n, m) m, each hook's horizontal distance to its anchor at the offset


def _rotation_arm(model: DockModel, psi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hook positions relative to the reference point after yaw psi: (x, y), each (n, m)."""
    c, s = np.cos(psi)[:, None], np.sin(psi)[:, None]
    px, py = model.hook[:, 0], model.hook[:, 1]
    return c * px - s * py, s * px + c * py


def _geometry(
    model: DockModel, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """Spans (n, m), their Jacobian d s / d q (n, m, 3), and the unit vectors ((n, m) x 2)."""
    ax, ay = _rotation_arm(model, q[:, 2])
    dx = model.anchor[:, 0] - q[:, 0:1] - ax
    dy = model.anchor[:, 1] - q[:, 1:2] - ay
    span = np.hypot(dx, dy)
    ux, uy = dx / span, dy / span
    jac = np.empty(span.shape + (3,))
    jac[..., 0] = -ux
    jac[..., 1] = -uy
    jac[..., 2] = ux * ay - uy * ax  # -u . (J r), J r = (-r_y, r_x)
    return span, jac, (ux, uy)


def _fit(
    model: DockModel, s_meas: np.ndarray, weight: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Weighted Gauss-Newton fit of q to the implied spans, per estimate (rows frozen once
    converged). Returns q (n, 3), covariance C (n, 3, 3), Jacobian (n, m, 3), ok (n,)."""
    n = s_meas.shape[0]
    q = np.zeros((n, 3))
    active = np.arange(n)
    ok = np.ones(n, bool)
    tol = STEP_TOL * model.size
    target = np.where(weight > 0, s_meas, 0.0)
    for _ in range(MAXITER):
        if active.size == 0:
            break
        span, jac, _ = _geometry(model, q[active])
        wa = weight[active]
        e = np.where(wa > 0, target[active] - span, 0.0)
        a = _normal(jac, wa)
        b = np.sum((wa * e)[..., None] * jac, axis=1)
        good = _regular(a)
        a = np.where(good[:, None, None], a, np.eye(3))
        step = np.linalg.solve(a, b[..., None])[..., 0]
        step = np.where(good[:, None], step, 0.0)
        q[active] += step
        ok[active[~good]] = False
        done = ~good | (
            (np.hypot(step[:, 0], step[:, 1]) <= tol) & (np.abs(step[:, 2]) <= STEP_TOL)
        )
        active = active[~done]
    ok[active] = False  # still moving after MAXITER steps
    _, jac, _ = _geometry(model, q)
    a = _normal(jac, weight)
    cov = np.full((n, 3, 3), np.nan)
    good = ok & _regular(a)
    ok &= good
    if good.any():
        cov[good] = np.linalg.inv(a[good])
    return q, cov, jac, ok


def _regular(a: np.ndarray) -> np.ndarray:
    """(n,) bool: the normal matrices are finite and far from singular."""
    diag = np.abs(a[:, 0, 0] * a[:, 1, 1] * a[:, 2, 2])
    det = np.linalg.det(np.where(np.isfinite(a), a, 0.0))
    return np.isfinite(a).all(axis=(1, 2)) & (np.abs(det) > 1e-10 * diag) & (diag > 0)


def _normal(jac: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """``J^T W J`` per estimate (n, 3, 3), summed over the lines in line order."""
    return np.sum(weight[..., None, None] * jac[..., :, None] * jac[..., None, :], axis=1)


def _leverage(jac: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """``J_i C J_i^T`` per estimate and line (n, m)."""
    return np.sum(jac[..., :, None] * cov[:, None, :, :] * jac[..., None, :], axis=(2, 3))


def estimate_dock(
    model: DockModel,
    depth: np.ndarray,
    tensions: np.ndarray,
    usable: np.ndarray,
    exclude: Optional[np.ndarray] = None,
    remove: float = REMOVE_Z,
) -> DockEstimate:
    """Offsets, loads, residuals and flags of ``n`` estimates, one at a time in plain floats
    (:func:`~catenary_monitor.core.body.estimate_tick.estimate_tick`; parameters as
    :func:`estimate_dock_arrays`): each row the same bits whichever rows it comes with."""
    depth = np.asarray(depth, dtype=float)
    n, m = tensions.shape
    ex = None if exclude is None else np.broadcast_to(exclude, (n, m)).tolist()
    rows = [
        estimate_tick(model, d, t, u, None if ex is None else ex[i], remove)
        for i, (d, t, u) in enumerate(
            zip(depth.tolist(), np.asarray(tensions, float).tolist(), usable.tolist())
        )
    ]
    return stack_ticks(rows, n, m)


def stack_ticks(rows: list[TickEstimate], n: int, m: int) -> DockEstimate:
    """``n`` ticks' estimates of ``m`` lines as one DockEstimate."""
    cols: list[Any] = list(zip(*rows)) if rows else [()] * len(DockEstimate._fields)
    return DockEstimate(
        valid=np.array(cols[0], bool),
        offset=np.array(cols[1], float).reshape(n, 3),
        load=np.array(cols[2], float).reshape(n, 3),
        expected=np.array(cols[3], float).reshape(n, m),
        residual=np.array(cols[4], float).reshape(n, m),
        normalized=np.array(cols[5], float).reshape(n, m),
        dropped=np.array(cols[6], bool).reshape(n, m),
        used=np.array(cols[7], bool).reshape(n, m),
        readings=np.array(cols[8], np.int64),
        span=np.array(cols[9], float).reshape(n, m),
    )


def estimate_dock_arrays(
    model: DockModel,
    depth: np.ndarray,
    tensions: np.ndarray,
    usable: np.ndarray,
    exclude: Optional[np.ndarray] = None,
    remove: float = REMOVE_Z,
) -> DockEstimate:
    """Offsets, loads, residuals and flags of ``n`` estimates, vectorized over them (the
    reference formulation of :func:`estimate_dock`, equal to it to rounding).

    Parameters
    ----------
    model : the dock.
    depth : (n,) tide depth at the hooks [m] (each line adds its hook height).
    tensions : (n, m) newest measured hook tensions [N].
    usable : (n, m) bool, the readings to use (recent, finite, the depth known).
    exclude : (n, m) or (m,) bool, readings left out of the fit from the start (lines already
        found inconsistent); their z is a prediction residual.
    remove : normalized residual above which the largest is dropped from the fit.
    """
    depth = np.asarray(depth, dtype=float)
    n, m = tensions.shape
    h = depth[:, None] + model.hook_height[None, :]
    given = np.isfinite(model.tension_accuracy)
    default = float(np.max(model.tension_accuracy[given])) if given.any() else 1.0
    tension_accuracy = np.where(given, model.tension_accuracy, default)[None, :]
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        s_meas, dt_ds = _spans(model, h, np.where(usable, tensions, np.nan))
        fits = usable & np.isfinite(s_meas) & (dt_ds > 0)
        weight = np.where(fits, (dt_ds / tension_accuracy) ** 2, 0.0)
        weight = np.where(np.isfinite(weight), weight, 0.0)
        readings = np.sum(weight > 0, axis=1)
        enough = readings >= MIN_LINES
        q, cov, jac, ok = _fit(model, s_meas, weight)
        flagged = np.zeros((n, m), bool)
        if exclude is not None:
            flagged |= np.broadcast_to(exclude, (n, m)) & (weight > 0)
            if flagged.any():
                rows = np.flatnonzero(flagged.any(axis=1))
                w_sub = np.where(flagged[rows], 0.0, weight[rows])
                q[rows], cov[rows], jac[rows], ok[rows] = _fit(model, s_meas[rows], w_sub)
        testable = given[None, :] & (weight > 0)
        for _ in range(MAX_FLAGS):
            z = _normalized(model, q, cov, jac, s_meas, weight, flagged, testable)
            z_abs = np.where(testable & ~flagged & (weight > 0), np.abs(z), -1.0)
            worst = np.argmax(z_abs, axis=1)
            top = z_abs[np.arange(n), worst]
            left = np.sum((weight > 0) & ~flagged, axis=1)
            drop = ok & (top > remove) & (left - 1 >= MIN_REDUNDANT)
            if not drop.any():
                break
            rows = np.flatnonzero(drop)
            flagged[rows, worst[rows]] = True
            w_sub = np.where(flagged[rows], 0.0, weight[rows])
            q[rows], cov[rows], jac[rows], ok[rows] = _fit(model, s_meas[rows], w_sub)
        z = _normalized(model, q, cov, jac, s_meas, weight, flagged, testable)
        valid = enough & ok
        span, _, unit = _geometry(model, q)
        start = np.where(usable, tensions, np.nan)  # the measured tension: a close start
        expected, horizontal = _at_spans(model, h, span, start)
        residual = np.where(usable, tensions - expected, np.nan)
        load = _load(model, q, horizontal, unit)
    nan = np.nan
    return DockEstimate(
        valid=valid,
        offset=np.where(valid[:, None], q, nan),
        load=np.where(valid[:, None], load, nan),
        expected=np.where(valid[:, None], expected, nan),
        residual=np.where(valid[:, None], residual, nan),
        normalized=np.where(valid[:, None] & testable, z, nan),
        dropped=flagged & valid[:, None],
        used=(weight > 0) & ~flagged & valid[:, None],
        readings=readings,
        span=np.where(valid[:, None], span, nan),
    )


def _spans(model: DockModel, h: np.ndarray, tensions: np.ndarray) -> tuple[np.ndarray, ...]:
    """The span each tension implies and ``dT/ds`` there, (n, m) each: closed forms for a
    plain chain, the table of a line with point loads (its exact solve where it has none)."""
    loaded = loaded_lines(model)
    plain = np.array(tensions, copy=True)
    plain[:, loaded] = math.nan  # (their own answers below)
    s_meas, dt_ds = span_and_sensitivity(model.weight, h, model.chain_length, plain, model.ea)
    for i in loaded:
        table = model.tables[i] if model.tables else None
        if table is not None:
            s_meas[:, i], dt_ds[:, i] = table.span_at_tension(h[:, i], tensions[:, i])
        else:
            s_meas[:, i], dt_ds[:, i] = exact_spans(model, i, h[:, i], tensions[:, i])
    return s_meas, dt_ds


def _at_spans(
    model: DockModel, h: np.ndarray, span: np.ndarray, start: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Hook and horizontal tension at the spans, (n, m) each (as :func:`_spans` solves)."""
    loaded = loaded_lines(model)
    plain = np.array(span, copy=True)
    plain[:, loaded] = math.nan  # not the plain chain's Newton: their own answers below
    st = statics_at_span(model.weight, h, model.chain_length, plain, model.ea, start)
    top, horizontal = np.array(st.top_tension), np.array(st.horizontal_tension)
    for i in loaded:
        table = model.tables[i] if model.tables else None
        if table is not None:
            top[:, i], horizontal[:, i] = table.state_at_span(h[:, i], span[:, i])
        else:
            top[:, i], horizontal[:, i] = exact_states(model, i, h[:, i], span[:, i])
    return top, horizontal


def _normalized(
    model: DockModel,
    q: np.ndarray,
    cov: np.ndarray,
    jac: np.ndarray,
    s_meas: np.ndarray,
    weight: np.ndarray,
    flagged: np.ndarray,
    testable: np.ndarray,
) -> np.ndarray:
    """Span residual over its standard deviation: ``sigma_s^2 - J C J^T`` for a reading in
    the fit, ``sigma_s^2 + J C J^T`` for one left out (a prediction)."""
    span, _, _ = _geometry(model, q)
    e = s_meas - span
    var_s = np.where(weight > 0, 1.0 / np.where(weight > 0, weight, 1.0), np.nan)
    lev = _leverage(jac, cov)
    in_fit = (weight > 0) & ~flagged
    var = np.where(in_fit, var_s - lev, var_s + lev)
    return np.where(testable & (var > 0), e / np.sqrt(np.where(var > 0, var, 1.0)), np.nan)


def _load(
    model: DockModel, q: np.ndarray, r: np.ndarray, unit: tuple[np.ndarray, np.ndarray]
) -> np.ndarray:
    """Minus the restoring force and yaw moment at q (NaN if a line would be taut)."""
    ax, ay = _rotation_arm(model, q[:, 2])
    fx, fy = r * unit[0], r * unit[1]
    moment = ax * fy - ay * fx
    out = -np.stack([np.sum(fx, axis=1), np.sum(fy, axis=1), np.sum(moment, axis=1)], axis=1)
    return np.where(np.isfinite(out), out, math.nan)

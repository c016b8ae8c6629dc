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

Monotonicity (inextensible closed forms of :mod:`catenary_monitor.core.physics.catenary`, ``a = T/w
- h`` for a grounded chain, ``t = acosh(1 + h/a)``, ``X = x/a``):

* in ``T`` at fixed ``h``: ``x_min = a acosh(1 + h/a)`` grows with ``a`` (its derivative is
  ``t - tanh(t/2) > 0``), so the anchor margin falls with ``T``; the tide margin
  ``a (cosh X - 1) - h`` falls with ``a`` (derivative ``cosh X - 1 - X sinh X < 0``); the
  uplift force grows with ``T`` (tested). Every bound is taken at ``T + dT``.
* in ``h`` at fixed ``T`` none is monotone: ``dx_min/dh = coth t - t`` changes sign at ``t* =
  1.19968`` (the root of ``t tanh t = 1``), so ``x_min`` peaks at ``h = k T / (w (1 + k))``,
  ``k = cosh t* - 1``; ``d(tide margin)/dh = cosh X (X tanh X - 1)`` makes the tide margin lowest
  at ``X = t*``, ``h = T/w - x/t*``; the uplift force rises with depth and then falls.
  The solve is therefore evaluated at ``T + dT`` and the depths ``h - dh``, ``h``, ``h + dh``
  and the two critical depths clipped to the interval: exact for the anchor and tide margins
  of a grounded inextensible chain. The uplift force has no closed-form peak: where it is
  concave over the interval, the vertex of the parabola through ``h - dh``, ``h``, ``h + dh``
  (clipped) is solved too, which finds its peak to about 1e-7 relative (tested). For a lifted
  tide margin and an elastic chain the bounds are the worst of these values (the tests check
  that the bounds contain the solve at random readings within the accuracy).

A chain with clump weights and buoys (:func:`loaded_bounds`) has no such closed forms: its
bounds are taken at ``T + dT`` too (the uplift grows and both margins fall with the hook
tension, as for the plain chain: tested) and the worst over five depths evenly spread over
``[h - dh, h + dh]`` (``dh`` is centimetres: a value turning inside the interval between two of
them is missed by ``f'' (dh/4)^2 / 2``, far below the sensors' accuracy).

A corner whose readings are impossible (e.g. ``T + dT <= w (h + dh)``) is left out. The bounds
are NaN only while the nominal solve has none: every line has a tension accuracy (by default
0.5 % of its MBL) and the depth one (``depth_accuracy``, 0.02 m by default).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from catenary_monitor.core.physics.solve import solve

__all__ = [
    'FIELDS',
    'T_STAR',
    'depth_candidates',
    'bounds',
    'dynamic_tension',
    'dynamic_uplift',
    'loaded_bounds',
]

#: The bounds' names (per-line outputs, /diagnostics values, replay CSV), in output order.
FIELDS = ('uplift_force_upper', 'anchor_margin_lower', 'tide_margin_lower')
#: Root of ``t tanh t = 1``: where ``x_min`` (fixed T) and the tide margin turn in depth.
T_STAR = 1.1996786402577338
_K = math.cosh(T_STAR) - 1.0


def dynamic_tension(peak: Any, wave: Any, allowance: float) -> np.ndarray:
    """The tension [N] the dynamic uplift and the bounds take: the window's ``peak`` plus
    ``allowance`` times its ``wave`` tension (N, :mod:`.wave_window`)."""
    return np.asarray(peak, dtype=float) + allowance * np.asarray(wave, dtype=float)


def dynamic_uplift(
    w: Any, x: Any, mbl: Any, ea: Any, tension: Any, depth: Any, nominal_uplift: Any
) -> np.ndarray:
    """The uplift force [N] at the dynamic ``tension`` (:func:`dynamic_tension`) and the
    measured ``depth`` (hook height added): at least the nominal (NaN where that is)."""
    given = (w, x, mbl, ea, tension, depth, nominal_uplift)
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in given))
    w, x, mbl, ea, t, h, f0 = (a.ravel() for a in arrays)
    out = np.full(len(t), np.nan)
    k = np.flatnonzero(~np.isnan(f0) & ~np.isnan(t))
    if k.size:
        with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
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
) -> dict[str, np.ndarray]:
    """:data:`FIELDS` -> arrays for readings ``tension`` (N) and ``depth`` (m, hook height
    added), per-element line constants (``ea`` inf: inextensible) and accuracies
    ``tension_accuracy`` (N, NaN: not given) and ``d_h`` (m, 0: exact); ``nominal_uplift``
    (N) is the nominal solve's uplift force (NaN: no solve, no bounds)."""
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

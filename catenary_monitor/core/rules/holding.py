"""Holding: will the anchor drag? Seed 001's rule and the anchor distance the chain implies.

The holding of an anchor and its chain (seed 001: ``P = Wa la + Wc lc L1``) is the anchor's
(or sinker's) own part, ``anchor_holding`` (N, its weight in water times its holding
coefficient), plus the chain lying on the seabed: ``weight x chain_friction x
grounded_length``. Per line (SI):

``grounded_length`` (m)
    ``chain_length - suspended_length`` (not below 0); 0 while the anchor is lifted (the
    whole chain hangs). Needs ``chain_length``.
``holding_capacity`` (N)
    ``anchor part + weight x chain_friction x grounded_length`` (the chain's part only with
    ``chain_friction``). The anchor part is ``anchor_holding`` while the anchor is down; with
    an uplift ``V`` it is ``anchor_holding x max(0, 1 - V / anchor_weight)`` when the sinker's
    weight in water ``anchor_weight`` is given (a sinker holds by friction ``mu (W - V)``), and
    0 otherwise (a drag anchor pulled upward loses its grip: the conservative choice). Needs
    ``anchor_holding``.
``drag_margin`` (N)
    ``holding_capacity - horizontal_tension``: the horizontal load the anchor and grounded chain
    must hold is the chain's horizontal tension (the same all along a catenary).
``implied_anchor_distance`` (m)
    With ``chain_length`` the geometry is over-determined: the span at which a chain of that
    length, at this depth, has this hook tension
    (:func:`catenary_monitor.core.physics.fixed_length.span_from_tension`: grounded length plus the
    suspended part's span, lifted or not, elastic with ``ea``). Compared with the installed
    ``anchor_distance`` it shows a dragged anchor (or a wrong chain length).
``drag_state`` (code)
    Hou et al. 2005's third regime, the anchor dragging (seed 001), by this rule: ``2``
    (:data:`DRAGGING`) when the horizontal load exceeds the holding capacity (``drag_margin <
    0``) **and** the chain puts the anchor more than ``drag_tolerance`` beyond its installed
    ``anchor_distance`` (``implied_anchor_distance - anchor_distance > drag_tolerance``): the
    load is more than the anchor holds and the hook-anchor span has opened, so either the
    anchor is moving or only an anchor holding more than its configured capacity stops it.
    ``1`` (:data:`OVERLOADED`) when the load exceeds the holding but the span has not opened
    beyond the tolerance (a steady overload of an anchor that has not moved: the capacity is
    conservative); ``0`` (:data:`HOLDING`) otherwise. NaN without ``anchor_holding``; never 2
    without ``chain_length`` (the span is not known).
``tide_margin_at_length`` (m)
    The depth rise at which that chain, its length and its span held (the hook stays where it
    is installed, ``anchor_distance``), lifts its anchor
    (:func:`catenary_monitor.core.physics.fixed_length.lift_depth`) minus the depth now;
    negative while the anchor is lifted. ``tide_margin`` holds the horizontal tension instead;
    a chain of fixed length gains pretension as the tide rises, so this one is usually the
    nearer, and the time to uplift counts down to the nearer of the two. The lift depth is a
    property of the geometry, not of one reading: the gauge's noise enters only as the depth
    subtracted (and cancels in the forecast). Needs ``chain_length``.

NaN where the data are not given or the line has no solve.

A chain with clump weights and buoys (:func:`holding_loaded`): the same values with its point
loads: the implied anchor distance and the lift depth by
:func:`~catenary_monitor.core.physics.point_loads.span_at_tension` and
:func:`~catenary_monitor.core.physics.point_loads.lift_depth`, and a clump lying on the
grounded chain (its place below the grounded length) adds ``chain_friction`` times its weight
to the holding (one settling at the touchdown is left out: the seabed carries an unknown part
of it).
"""

from __future__ import annotations

import functools
import math
from typing import Any, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.physics import fixed_length, point_loads

__all__ = [
    'FIELDS',
    'LENGTH_FIELDS',
    'DRAG_FIELDS',
    'HOLDING',
    'OVERLOADED',
    'DRAGGING',
    'DRAG_STATES',
    'HoldingInputs',
    'holding',
    'holding_scalar',
    'holding_loaded',
    'drag_word',
]

#: The holding values' names (per-line outputs, /diagnostics values, replay CSV), in order.
FIELDS = ('grounded_length', 'holding_capacity', 'drag_margin', 'implied_anchor_distance')
#: Appended after them (the per-line outputs end with it, after ``sensor_state``).
LENGTH_FIELDS = ('tide_margin_at_length',)
#: Appended at the end of the per-line outputs: the anchor's drag state (:data:`DRAG_STATES`).
DRAG_FIELDS = ('drag_state',)
#: ``drag_state`` codes and their words (``/diagnostics`` and the console show the word).
HOLDING, OVERLOADED, DRAGGING = 0, 1, 2
DRAG_STATES = ('holding', 'overloaded', 'dragging')


class HoldingInputs(NamedTuple):
    """A line's holding data and its nominal solve, arrays or plain floats (NaN: not given;
    ``ea`` inf: inextensible): chain ``weight`` in water (N/m), ``ea`` (N), ``chain_length``
    (m), ``anchor_holding``, ``anchor_weight`` (N), ``chain_friction`` (-); hook ``tension``
    (N), ``depth`` (m, hook height added), ``horizontal`` tension (N), ``suspended`` length (m),
    ``uplift`` force (N); the installed ``anchor_distance`` (m)."""

    weight: Any
    ea: Any
    chain_length: Any
    anchor_holding: Any
    anchor_weight: Any
    chain_friction: Any
    tension: Any
    depth: Any
    horizontal: Any
    suspended: Any
    uplift: Any
    anchor_distance: Any = math.nan


def holding(line: HoldingInputs, tolerance: float = np.inf) -> dict[str, np.ndarray]:
    """:data:`FIELDS`, :data:`LENGTH_FIELDS` and :data:`DRAG_FIELDS` -> arrays from the line
    data and the nominal solve (:class:`HoldingInputs`); the installed ``anchor_distance`` (m)
    and ``drag_tolerance`` (m) decide ``drag_state``."""
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in line))
    w, ea, length, a_hold, a_weight, mu, t, h, r, s, v, x0 = arrays
    if np.isnan(length).all() and np.isnan(a_hold).all():  # nothing configured: all NaN
        return {key: np.full(t.shape, np.nan) for key in FIELDS + LENGTH_FIELDS + DRAG_FIELDS}
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        solved = ~np.isnan(r)
        lifted = v > 0.0
        grounded = np.where(lifted, 0.0, np.maximum(length - s, 0.0))
        grounded = np.where(solved & ~np.isnan(length), grounded, np.nan)
        sinker = a_hold * np.maximum(1.0 - v / a_weight, 0.0)
        anchor = np.where(lifted, np.where(np.isnan(a_weight), 0.0, sinker), a_hold)
        chain = np.where(np.isnan(mu) | np.isnan(grounded), 0.0, w * mu * grounded)
        capacity = np.where(solved & ~np.isnan(a_hold), anchor + chain, np.nan)
        implied, lift = np.full(t.shape, np.nan), np.full(t.shape, np.nan)
        need = solved & ~np.isnan(length)
        if need.any():  # only where a chain length is given (the span solve is the cost)
            implied[need] = fixed_length.span_from_tension(
                w[need], h[need], length[need], t[need], ea[need]
            )
            span = np.where(np.isnan(x0), implied, x0)  # the hook where it is installed
            lift[need] = fixed_length.lift_depth(w[need], length[need], span[need], ea[need])
        margin = capacity - r
        over = margin < 0.0
        state = np.where(over, np.where(implied - x0 > tolerance, DRAGGING, OVERLOADED), HOLDING)
        state = np.where(np.isnan(margin), np.nan, state.astype(float))
    return {
        'grounded_length': grounded,
        'holding_capacity': capacity,
        'drag_margin': margin,
        'implied_anchor_distance': implied,
        'tide_margin_at_length': lift - h,
        'drag_state': state,
    }


def drag_word(code: float) -> str:
    """The word of a ``drag_state`` code (``unknown`` for NaN)."""
    return DRAG_STATES[int(code)] if code == code else 'unknown'


def holding_scalar(line: HoldingInputs, tolerance: float = math.inf) -> dict[str, float]:
    """:func:`holding` of one line in plain floats (the monitor's per-sample path, an order of
    magnitude faster on one element): the same formulas in the same order, the fixed-length
    chain by :func:`~catenary_monitor.core.physics.fixed_length.span_from_tension_scalar` and
    :func:`~catenary_monitor.core.physics.fixed_length.lift_depth_scalar`. Where plain floats
    raise (an overflow, a root of a negative number) the array path answers instead, so the
    numbers are the array path's to rounding (test_holding)."""
    floats = HoldingInputs(*(float(v) for v in line))
    try:
        return _holding_floats(floats, float(tolerance))
    except (ValueError, OverflowError, ZeroDivisionError):
        array_path: Any = holding
        arrays = array_path(HoldingInputs(*([v] for v in floats)), float(tolerance))
        return {key: float(v[0]) for key, v in arrays.items()}


def holding_loaded(
    loads: point_loads.PointLoads, line: HoldingInputs, tolerance: float = math.inf
) -> dict[str, float]:
    """:func:`holding_scalar` of a chain with point ``loads`` (inextensible: ``line.ea`` is not
    taken; module docstring), the nominal solve's values with those loads."""
    floats = HoldingInputs(*(float(v) for v in line))._replace(ea=math.inf)
    try:
        return _holding_floats(floats, float(tolerance), loads=loads)
    except (ValueError, OverflowError, ZeroDivisionError):
        return dict.fromkeys(FIELDS + LENGTH_FIELDS + DRAG_FIELDS, math.nan)


def _holding_floats(
    line: HoldingInputs,
    tolerance: float,
    *,
    loads: Optional[point_loads.PointLoads] = None,
) -> dict[str, float]:
    """:func:`holding_scalar` itself (raises where :mod:`math` does); ``loads``: the chain's
    point loads (:func:`holding_loaded`)."""
    nan = math.nan
    w, ea, length, a_hold, a_weight, mu, t, h, r, s, v, x0 = line
    if length != length and a_hold != a_hold:  # nothing configured: all NaN
        return dict.fromkeys(FIELDS + LENGTH_FIELDS + DRAG_FIELDS, nan)
    solved = r == r
    lifted = v > 0.0
    grounded = 0.0 if lifted else _maximum0(length - s)
    grounded = grounded if solved and length == length else nan
    if lifted:
        anchor = 0.0 if a_weight != a_weight else a_hold * _maximum0(1.0 - v / a_weight)
    else:
        anchor = a_hold
    chain = 0.0 if (mu != mu or grounded != grounded) else w * mu * grounded
    if loads is not None and chain and grounded > 0.0:  # clumps lying on the grounded chain
        chain += mu * sum(wk for p, wk in zip(*loads) if wk > 0.0 and p < grounded)
    capacity = anchor + chain if solved and a_hold == a_hold else nan
    implied = lift = nan
    if solved and length == length and loads is not None:
        start = 0.5 * (length - h + math.sqrt((length - h) * (length + h))) if x0 != x0 else x0
        implied = point_loads.span_at_tension(w, h, length, t, loads, start)
        lift = point_loads.lift_depth(w, length, implied if x0 != x0 else x0, loads)
    elif solved and length == length:
        implied = fixed_length.span_from_tension_scalar(w, h, length, t, ea)
        span = implied if x0 != x0 else x0  # the hook where it is installed
        lift = _lift_depth(w, length, span, ea)
    margin = capacity - r
    state = float(DRAGGING if implied - x0 > tolerance else OVERLOADED) if margin < 0.0 else 0.0
    return {
        'grounded_length': grounded,
        'holding_capacity': capacity,
        'drag_margin': margin,
        'implied_anchor_distance': implied,
        'tide_margin_at_length': lift - h,
        'drag_state': nan if margin != margin else state,
    }


#: :func:`~catenary_monitor.core.physics.fixed_length.lift_depth_scalar` remembered: the lift
#: depth is the line's geometry (its weight, chain length and span), not the sample's, so a
#: line's samples between two span updates take one Newton iteration, not one each (the same
#: bits: a pure function of four floats).
_lift_depth = functools.lru_cache(maxsize=256)(fixed_length.lift_depth_scalar)


def _maximum0(x: float) -> float:
    """``np.maximum(x, 0.0)`` of one float (NaN stays NaN)."""
    return x if (x != x or x >= 0.0) else 0.0

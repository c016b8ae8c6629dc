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
``tide_margin_at_length`` (m)
    The depth rise at which that chain, its length and its span held (the hook stays where it
    is: the installed ``anchor_distance``, or where the params give the dock's geometry the
    span of the live dock estimate), lifts its anchor
    (:func:`catenary_monitor.core.physics.fixed_length.lift_depth`) minus the depth now;
    negative while the anchor is lifted. ``tide_margin`` holds the horizontal tension instead;
    a chain of fixed length gains pretension as the tide rises, so this one is usually the
    nearer, and the time to uplift counts down to the nearer of the two. The lift depth is a
    property of the geometry, not of one reading: the gauge's noise enters only as the depth
    subtracted (and cancels in the forecast). Needs ``chain_length``.

NaN where the data are not given or the line has no solve.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from catenary_monitor.core.physics import fixed_length

__all__ = ['FIELDS', 'LENGTH_FIELDS', 'holding']

#: The holding values' names (per-line outputs, /diagnostics values, replay CSV), in order.
FIELDS = ('grounded_length', 'holding_capacity', 'drag_margin', 'implied_anchor_distance')
#: Appended after them (the per-line outputs end with it, after ``sensor_state``).
LENGTH_FIELDS = ('tide_margin_at_length',)


def holding(
    w: Any,
    ea: Any,
    chain_length: Any,
    anchor_holding: Any,
    anchor_weight: Any,
    chain_friction: Any,
    tension: Any,
    depth: Any,
    horizontal: Any,
    suspended: Any,
    uplift: Any,
    span: Any = np.nan,
) -> dict[str, np.ndarray]:
    """:data:`FIELDS` and :data:`LENGTH_FIELDS` -> arrays from the line data (NaN: not given;
    ``ea`` inf: inextensible) and the nominal solve: hook ``tension`` (N), ``depth`` (m, hook
    height added), ``horizontal`` tension (N), ``suspended`` length (m) and ``uplift`` force
    (N); ``span`` (m) the hook's horizontal distance to the anchor (NaN: the implied one)."""
    arrays = np.broadcast_arrays(
        *(
            np.asarray(v, dtype=float)
            for v in (
                w,
                ea,
                chain_length,
                anchor_holding,
                anchor_weight,
                chain_friction,
                tension,
                depth,
                horizontal,
                suspended,
                uplift,
                span,
            )
        )
    )
    w, ea, length, a_hold, a_weight, mu, t, h, r, s, v, x = arrays
    if np.isnan(length).all() and np.isnan(a_hold).all():  # nothing configured: all NaN
        return {key: np.full(t.shape, np.nan) for key in FIELDS + LENGTH_FIELDS}
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
            x = np.where(np.isnan(x), implied, x)
            lift[need] = fixed_length.lift_depth(w[need], length[need], x[need], ea[need])
    return {
        'grounded_length': grounded,
        'holding_capacity': capacity,
        'drag_margin': capacity - r,
        'implied_anchor_distance': implied,
        'tide_margin_at_length': lift - h,
    }

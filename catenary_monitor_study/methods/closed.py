"""Closed forms (problems 1-3) and the project's default, the one the node uses (problem 4).

* ``closed form (textbook)``: ``R = T - w h``, ``x_min = a acosh(1 + h/a)`` as written in any
  handbook.  ``1 + h/a`` rounds away ``h/a`` below 1e-16 and ``acosh`` of a number just above 1
  loses half the digits (a cancelling formula); ``T - w h`` cancels when ``h >> a``.
* ``closed form (stable)``: the core's kernels (``catenary.grounded`` with the compensated
  ``T - w h``); this is the floor of the benchmark: one catenary evaluation.
* ``default``: ``catenary_monitor.solve`` itself (scalar: its plain-float path; vectorized:
arrays).
* ``default kernel``: the numpy problem-4 kernel alone (``catenary.lifted_from_tension``): what
  ``solve()`` falls back to where its C kernel is not built, without validation or margins.
"""

from __future__ import annotations

import math

import numpy as np

from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics.solve import solve

from .base import Method

# ---------------------------------------------------------------- problem 3: T -> (R, x_min)


def p3_textbook(w: float, h: float, t: float) -> tuple[float, float]:
    r = t - w * h
    a = r / w
    return r, a * math.acosh(1.0 + h / a)


def p3_textbook_vec(w: np.ndarray, h: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r = t - w * h
    a = r / w
    return r, a * np.arccosh(1.0 + h / a)


def p3_stable(w: float, h: float, t: float) -> tuple[float, float]:
    b = cat.two_prod_diff(t, w, h) / w
    return w * b, cat.grounded(b, h, cat._MATH).min_anchor_distance


def p3_stable_vec(w: np.ndarray, h: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    b = cat.two_prod_diff(t, w, h) / w
    return w * b, cat.grounded(b, h).min_anchor_distance


def p3_default(w: float, h: float, t: float) -> tuple[float, float]:
    r = solve(w, h, tension=t)
    return r.horizontal_tension, r.min_anchor_distance


def p3_default_vec(w: np.ndarray, h: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r = solve(w, h, tension=t)
    return r.horizontal_tension, r.min_anchor_distance


# ---------------------------------------------------------------- problem 4: T, x -> (R, F)


def p4_default(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    r = solve(w, h, tension=t, anchor_distance=x)
    return r.horizontal_tension, r.uplift_force


def p4_default_vec(
    w: np.ndarray, h: np.ndarray, t: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    r = solve(w, h, tension=t, anchor_distance=x)
    return r.horizontal_tension, r.uplift_force


def p4_kernel(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    b = cat.two_prod_diff(t, w, h) / w
    z = h / b
    if x >= b * math.log1p(z + math.sqrt(z * (2.0 + z))):  # x_min, as in cat.grounded
        return w * b, 0.0
    s, _, ok = cat.lifted_from_tension_scalar(w, b, h, x)
    return (s.horizontal_tension, s.uplift_force) if ok else (math.nan, math.nan)


def p4_kernel_vec(
    w: np.ndarray, h: np.ndarray, t: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    b = cat.two_prod_diff(t, w, h) / w
    r = w * b
    f = np.zeros_like(r)
    lift = x < cat.grounded(b, h).min_anchor_distance
    s, _, ok = cat.lifted_from_tension(w[lift], b[lift], h[lift], x[lift])
    r[lift] = np.where(ok, s.horizontal_tension, np.nan)
    f[lift] = np.where(ok, s.uplift_force, np.nan)
    return r, f


# ---------------------------------------------------------------- problem 2: R, x -> (alpha, F)


def p2_textbook(w: float, h: float, r: float, x: float) -> tuple[float, float]:
    """Equation (1) solved for the anchor angle: ``u = asinh(h / (2 a sinh(X/2))) - X/2``.

    With ``tan(alpha) = sinh(u)`` and ``X = x/a``, equation (1) is the depth of the catenary from
    ``u`` to ``u + X``: ``a (cosh(u + X) - cosh u) = 2 a sinh(X/2) sinh(u + X/2) = h``.  The
    subtraction loses digits as x -> x_min (u -> 0), but no more than the problem's own
    conditioning there.
    """
    a = r / w
    big = x / a
    u = math.asinh(h / (2.0 * a * math.sinh(0.5 * big))) - 0.5 * big
    u = max(u, 0.0)
    return math.atan(math.sinh(u)), r * math.sinh(u)


def p2_default(w: float, h: float, r: float, x: float) -> tuple[float, float]:
    s = solve(w, h, horizontal=r, anchor_distance=x)
    return math.radians(s.anchor_angle_deg), s.uplift_force


METHODS = [
    Method(
        'closed form (textbook)',
        3,
        p3_textbook,
        p3_textbook_vec,
        'closed',
        why='cancelling formula: acosh(1 + h/a) loses half its digits for h/a << 1 and all '
        'of them '
        'below 1e-16; T - w h cancels for h >> a',
    ),
    Method(
        'closed form (stable)',
        3,
        p3_stable,
        p3_stable_vec,
        'closed',
        why='never fails: acosh(1+z) as log1p(z + sqrt(z(2+z))), compensated T - w h',
    ),
    Method(
        'default',
        3,
        p3_default,
        p3_default_vec,
        'closed',
        default=True,
        why='solve(): the stable closed form behind validation and status codes',
    ),
    Method(
        'default',
        4,
        p4_default,
        p4_default_vec,
        'closed',
        default=True,
        why='never fails: Newton in log d with a bracket, no cancellation at either end',
    ),
    Method(
        'default kernel',
        4,
        p4_kernel,
        p4_kernel_vec,
        'closed',
        why="the numpy uplift kernel alone: solve()'s fallback where the C kernel is not built "
        '(no validation, no margins)',
    ),
    Method(
        'closed form (textbook)',
        2,
        p2_textbook,
        None,
        'closed',
        why='never fails: its subtraction asinh(...) - X/2 near x_min costs no more digits than '
        'the problem itself loses there',
    ),
    Method(
        'default',
        2,
        p2_default,
        None,
        'closed',
        default=True,
        why='closed form with the subtraction rewritten as the depth deficit; solve() adds '
        'validation and the margins (a second solve) around it',
    ),
]

"""Textbook root finders on the textbook unknowns: bisection, Newton, safeguarded Newton, brentq,
and the two-unknown formulation a newcomer writes with ``scipy.optimize.root`` / ``fsolve``.

Problem 4 (T, x given) in the unknown ``a = R/w`` reads, with ``A = T/w`` and ``B = A - h``
(anchor-end tension over w),

    f(a) = a [acosh(A/a) - acosh(B/a)] - x = 0,      0 < a <= B,

with f(0+) = -x < 0, f(B) = x_min - x > 0 and one root; f has an infinite slope at a = B.
``acosh(B/a)`` near
``a = B`` is ``acosh`` of a number just above 1 (half the digits lost), and for ``h << B`` the
two ``acosh`` are nearly equal and cancel: the formula, not the root finder, limits accuracy.
Problem 3 in the unknown x: ``a (cosh(x/a) - 1) = h`` with ``a = (T - w h)/w``, root in
``(0, a + h]``; ``cosh(x/a) - 1`` cancels for ``x << a`` (``h << a``) and overflows for
``x/a > 710``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from catenary_monitor.core.physics import catenary as cat

from .base import Method, NoConvergence

EPS = np.finfo(float).eps
MAXITER = 200

# ------------------------------------------------------------------ problem 4: textbook f(a)


def _f4(a: float, big_a: float, b: float, x: float) -> float:
    return a * (math.acosh(big_a / a) - math.acosh(b / a)) - x


def _df4(a: float, big_a: float, b: float) -> float:
    # d/da [a acosh(c/a)] = acosh(c/a) - c / sqrt(c^2 - a^2)
    return (
        math.acosh(big_a / a)
        - big_a / math.sqrt(big_a * big_a - a * a)
        - math.acosh(b / a)
        + b / math.sqrt(b * b - a * a)
    )


def _state4(w: float, b: float, a: float) -> tuple[float, float]:
    # anchor-end tension R sec(alpha) = w B  ->  F = R tan(alpha) = w sqrt(B^2 - a^2)
    return w * a, w * math.sqrt((b - a) * (b + a))


def _setup4(w: float, h: float, t: float) -> tuple[float, float]:
    big_a = t / w
    return big_a, big_a - h


def p4_bisect(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    big_a, b = _setup4(w, h, t)
    lo, hi = 0.0, b
    for _ in range(MAXITER):
        mid = 0.5 * (lo + hi)
        if _f4(mid, big_a, b, x) < 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 2.0 * EPS * hi:
            return _state4(w, b, 0.5 * (lo + hi))
    raise NoConvergence('bisection: iteration cap')


def p4_bisect_vec(
    w: np.ndarray, h: np.ndarray, t: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    big_a = t / w
    b = big_a - h
    lo, hi = np.zeros_like(b), b.copy()
    with np.errstate(all='ignore'):
        for _ in range(MAXITER):
            mid = 0.5 * (lo + hi)
            neg = mid * (np.arccosh(big_a / mid) - np.arccosh(b / mid)) - x < 0.0
            lo = np.where(neg, mid, lo)
            hi = np.where(neg, hi, mid)
            if np.all(hi - lo <= 2.0 * EPS * hi):
                break
        a = 0.5 * (lo + hi)
        return w * a, w * np.sqrt((b - a) * (b + a))


def _newton_start(big_a: float, b: float, h: float, x: float) -> float:
    # Hou's first iterate: a0 = B x / x_min (exact at x = x_min)
    return b * x / (b * math.acosh(big_a / b))


def p4_newton(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    big_a, b = _setup4(w, h, t)
    a = _newton_start(big_a, b, h, x)
    for _ in range(MAXITER):
        step = _f4(a, big_a, b, x) / _df4(a, big_a, b)
        a -= step
        if not 0.0 < a <= b:
            raise NoConvergence(f'Newton left the domain 0 < a <= B (a = {a:g})')
        if abs(step) <= 4.0 * EPS * a:
            return _state4(w, b, a)
    raise NoConvergence('Newton: iteration cap')


def p4_newton_vec(
    w: np.ndarray, h: np.ndarray, t: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    big_a = t / w
    b = big_a - h
    a = x / np.arccosh(big_a / b)
    with np.errstate(all='ignore'):
        for _ in range(MAXITER):
            f = a * (np.arccosh(big_a / a) - np.arccosh(b / a)) - x
            df = (
                np.arccosh(big_a / a)
                - big_a / np.sqrt(big_a**2 - a * a)
                - np.arccosh(b / a)
                + b / np.sqrt(b * b - a * a)
            )
            step = f / df
            a = np.where((a - step > 0) & (a - step <= b), a - step, np.nan)
            if not np.any(np.abs(step) > 4.0 * EPS * a):  # NaN compares False: dropped
                break
        return w * a, w * np.sqrt((b - a) * (b + a))


def p4_safe_newton(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    """Newton on a inside a bracket [lo, hi] that every residual tightens; bisection fallback."""
    big_a, b = _setup4(w, h, t)
    lo, hi = 0.0, b
    a = _newton_start(big_a, b, h, x)
    for _ in range(MAXITER):
        f = _f4(a, big_a, b, x)
        if f < 0.0:
            lo = a
        else:
            hi = a
        new = a - f / _df4(a, big_a, b) if a < b else 0.5 * (lo + hi)
        if not lo < new < hi:
            new = 0.5 * (lo + hi)
        if abs(new - a) <= 4.0 * EPS * a or hi - lo <= 2.0 * EPS * hi:
            return _state4(w, b, new)
        a = new
    raise NoConvergence('safeguarded Newton: iteration cap')


def _brentq4(w: float, h: float, t: float, x: float, **kw: float) -> tuple[float, float]:
    big_a, b = _setup4(w, h, t)
    a, res = optimize.brentq(
        _f4, 1e-12 * b, b, args=(big_a, b, x), full_output=True, disp=False, **kw
    )
    if not res.converged:
        raise NoConvergence(res.flag)
    return _state4(w, b, a)


def p4_brentq(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    """scipy's brentq as called by most users: default ``xtol = 2e-12`` (absolute)."""
    return _brentq4(w, h, t, x)


def p4_brentq_rel(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    """brentq with a relative-safe ``xtol`` (scipy's Notes: 5e-324): the formula still cancels."""
    return _brentq4(w, h, t, x, xtol=5e-324)


def p4_brentq_logd(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    """brentq on the default's unknown and residual (eta = log d): right unknown, generic."""
    b = cat.two_prod_diff(t, w, h) / w
    e, r02, xlo, m, eta0, eta_hi = cat._uplift_setup(b, h, x, cat._MATH)

    def f(eta: float) -> float:
        return cat._uplift_residual(eta, e, r02, xlo, m, cat._MATH)[0]

    eta_lo = min(eta0, eta_hi) - 1.0
    while f(eta_lo) > 0.0:
        eta_lo -= 4.0
    if f(eta_hi) <= 0.0:
        return w * b, 0.0
    eta = optimize.brentq(f, eta_lo, eta_hi, xtol=1e-15, rtol=4 * EPS)
    s = cat._lifted_from_d(w, b, e, xlo, m, math.exp(eta), cat._MATH)
    return s.horizontal_tension, s.uplift_force


def p4_fsolve(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    """Two unknowns (R, alpha) on the paper's equations (1), (2) and T, ``scipy.optimize.root``."""

    def fun(v: np.ndarray) -> list[float]:
        r, alpha = v
        a = r / w
        big = x / a
        sec, tan = 1.0 / math.cos(alpha), math.tan(alpha)
        y = a * (sec * (math.cosh(big) - 1.0) + tan * math.sinh(big))
        length = a * (tan * (math.cosh(big) - 1.0) + sec * math.sinh(big))
        return [y - h, math.hypot(r, r * tan + w * length) - t]

    with np.errstate(all='ignore'):
        sol = optimize.root(fun, [t - w * h, 0.1], method='hybr')
    if not sol.success:
        raise NoConvergence(sol.message)
    r, alpha = sol.x
    return r, r * math.tan(alpha)


# ------------------------------------------------------------------ problem 3: unknown x


def _setup3(w: float, h: float, t: float) -> float:
    return (t - w * h) / w


def p3_bisect(w: float, h: float, t: float) -> tuple[float, float]:
    a = _setup3(w, h, t)
    lo, hi = 0.0, a + h
    for _ in range(MAXITER):
        mid = 0.5 * (lo + hi)
        if a * (math.cosh(mid / a) - 1.0) < h:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 2.0 * EPS * hi:
            return w * a, 0.5 * (lo + hi)
    raise NoConvergence('bisection: iteration cap')


def p3_bisect_vec(w: np.ndarray, h: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = (t - w * h) / w
    lo, hi = np.zeros_like(a), a + h
    with np.errstate(all='ignore'):
        for _ in range(MAXITER):
            mid = 0.5 * (lo + hi)
            neg = a * (np.cosh(mid / a) - 1.0) < h
            lo = np.where(neg, mid, lo)
            hi = np.where(neg, hi, mid)
            if np.all(hi - lo <= 2.0 * EPS * hi):
                break
    return w * a, 0.5 * (lo + hi)


def p3_newton(w: float, h: float, t: float) -> tuple[float, float]:
    a = _setup3(w, h, t)
    x = math.sqrt(2.0 * a * h)  # the parabola's span: exact as h/a -> 0
    for _ in range(MAXITER):
        step = (a * (math.cosh(x / a) - 1.0) - h) / math.sinh(x / a)
        x -= step
        if not x > 0.0:
            raise NoConvergence(f'Newton left the domain x > 0 (x = {x:g})')
        if abs(step) <= 4.0 * EPS * x:
            return w * a, x
    raise NoConvergence('Newton: iteration cap')


def p3_brentq(w: float, h: float, t: float) -> tuple[float, float]:
    a = _setup3(w, h, t)
    x, res = optimize.brentq(
        lambda x: a * (math.cosh(x / a) - 1.0) - h, 0.0, a + h, full_output=True, disp=False
    )
    if not res.converged:
        raise NoConvergence(res.flag)
    return w * a, x


def p3_fsolve(w: float, h: float, t: float) -> tuple[float, float]:
    """Two unknowns (x, R), equations (1) with alpha = 0 and T = sqrt(R^2 + (w L)^2)."""

    def fun(v: np.ndarray) -> list[float]:
        x, r = v
        a = r / w
        return [a * (math.cosh(x / a) - 1.0) - h, math.hypot(r, w * a * math.sinh(x / a)) - t]

    r0 = t - w * h
    with np.errstate(all='ignore'):
        sol = optimize.root(fun, [math.sqrt(2.0 * r0 / w * h), t], method='hybr')
    if not sol.success:
        raise NoConvergence(sol.message)
    return sol.x[1], sol.x[0]


_CANCEL4 = (
    'cancelling formula: acosh(B/a) near a = B, and acosh(A/a) - acosh(B/a) for h << B, '
    'lose digits whatever the root finder'
)
METHODS = [
    Method('bisection', 4, p4_bisect, p4_bisect_vec, 'roots', why=_CANCEL4),
    Method(
        'Newton',
        4,
        p4_newton,
        p4_newton_vec,
        'roots',
        why='wrong unknown: f(a) is flat at small a and infinitely steep at a = B, so from below '
        'the root Newton steps past B (out of the domain) or cycles; plus the cancelling '
        'formula',
    ),
    Method('safeguarded Newton', 4, p4_safe_newton, None, 'roots', why=_CANCEL4),
    Method(
        'brentq',
        4,
        p4_brentq,
        None,
        'roots',
        why='absolute tolerance: xtol = 2e-12 m is coarse when a is micrometres '
        '(h >> B, x << x_min); '
        'plus the cancelling formula',
    ),
    Method('brentq (xtol=5e-324)', 4, p4_brentq_rel, None, 'roots', why=_CANCEL4),
    Method(
        'brentq on log d',
        4,
        p4_brentq_logd,
        None,
        'roots',
        why="the default's unknown and residual under a generic solver: accurate, slower",
    ),
    Method(
        'root/fsolve (R, alpha)',
        4,
        p4_fsolve,
        None,
        'roots',
        why='two badly scaled unknowns (N and rad) from a fixed start: hybr stalls ("not making '
        'good progress") away from the dock scale, and stops at a relative xtol of 1.5e-8',
    ),
    Method(
        'bisection',
        3,
        p3_bisect,
        p3_bisect_vec,
        'roots',
        why='cancelling formula: cosh(x/a) - 1 for h << a; cosh(x/a) overflows at the bracket end '
        'a + h when h/a > 710',
    ),
    Method(
        'Newton',
        3,
        p3_newton,
        None,
        'roots',
        why='cancelling formula: cosh(x/a) - 1 for h << a is rounding noise at the root, so the '
        'relative step test is never met (iteration cap)',
    ),
    Method(
        'brentq',
        3,
        p3_brentq,
        None,
        'roots',
        why='cosh(x/a) overflows at the bracket end a + h when h >> a; cancelling formula '
        'for h << a',
    ),
    Method(
        'root/fsolve (x, R)',
        3,
        p3_fsolve,
        None,
        'roots',
        why='two badly scaled unknowns; hybr stops at a relative xtol of 1.5e-8; cosh overflows '
        'on its trial steps for h >> a',
    ),
]

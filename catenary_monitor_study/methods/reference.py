"""The accuracy reference: the paper's own equations solved in 50-digit arithmetic (mpmath).

Equations of Hu & Tang (2004), with ``a = R/w``, anchor angle ``alpha`` and span ``x``:

    (1)  y = a [sec(alpha) (cosh(x/a) - 1) + tan(alpha) sinh(x/a)]      depth reached
    (2)  L = a [tan(alpha) (cosh(x/a) - 1) + sec(alpha) sinh(x/a)]      suspended length
         T = sqrt(R^2 + (R tan(alpha) + w L)^2)                          hook tension

Nothing here is stored: every answer is computed from the float inputs, read as exact numbers,
with ``mp.dps = 50``, and each solution is checked by putting it back into all the equations
(residual below 1e-40 relative).  With ``tan(alpha) = sinh(u)`` the anchor-end tension of the
solution is ``R sec(alpha) = T - w y``, so problem 4 is a one-unknown bracketed solve in u.

``condition`` numbers (``|p/f df/dp|`` for the continuous input p: x for problem 4, L for the
length-given problem) come from a 1e-25 relative perturbation of the same 50-digit solve.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import mpmath as mp

DPS = 50
_CHECK = mp.mpf(10) ** -40


class Ref(NamedTuple):
    """Reference answer, floats rounded from 50 digits (c1, c2: condition numbers of v1, v2)."""

    v1: float
    v2: float
    c1: float
    c2: float
    length: float  # suspended length L [m]


def _y_and_l(a: mp.mpf, u: mp.mpf, x: mp.mpf) -> tuple[mp.mpf, mp.mpf]:
    sec, tan = mp.cosh(u), mp.sinh(u)
    big = x / a
    y = a * (sec * (mp.cosh(big) - 1) + tan * mp.sinh(big))  # equation (1)
    length = a * (tan * (mp.cosh(big) - 1) + sec * mp.sinh(big))  # equation (2)
    return y, length


def _p3(w: mp.mpf, h: mp.mpf, t: mp.mpf) -> tuple[mp.mpf, mp.mpf, mp.mpf]:
    def top(r: mp.mpf) -> mp.mpf:
        a = r / w
        x = a * mp.acosh(1 + h / a)  # equation (1) with alpha = 0, inverted
        length = a * mp.sinh(x / a)  # equation (2) with alpha = 0
        return mp.sqrt(r * r + (w * length) ** 2) - t

    r = mp.findroot(top, t - w * h, tol=mp.mpf(10) ** (-2 * DPS + 10), verify=False)
    a = r / w
    x = a * mp.acosh(1 + h / a)
    y, length = _y_and_l(a, mp.mpf(0), x)
    assert abs(y - h) <= _CHECK * h and abs(top(r)) <= _CHECK * t
    return r, x, length


def problem3(w: float, h: float, t: float) -> Ref:
    """Problem 3: hook tension T, no uplift -> (R, x_min); condition numbers 1 (closed form)."""
    with mp.workdps(DPS):
        r, x, length = _p3(mp.mpf(w), mp.mpf(h), mp.mpf(t))
        return Ref(float(r), float(x), 1.0, 1.0, float(length))


def _p4(w: mp.mpf, h: mp.mpf, t: mp.mpf, x: mp.mpf) -> tuple[mp.mpf, mp.mpf, mp.mpf]:
    b = t / w - h  # anchor-end tension over w (exact identity of the equations)

    def resid(u: mp.mpf) -> mp.mpf:
        a = b / mp.cosh(u)
        return _y_and_l(a, u, x)[0] - h

    lo, hi = mp.mpf(0), mp.mpf(1)
    if resid(lo) >= 0:
        raise ValueError('x >= x_min: the anchor is not lifted')
    while resid(hi) <= 0:
        lo, hi = hi, 2 * hi
    u = mp.findroot(
        resid,
        (lo, hi),
        solver='anderson',
        tol=mp.mpf(10) ** (-2 * DPS + 10),
        verify=False,
        maxsteps=400,
    )
    if not (
        lo <= u <= hi and abs(resid(u)) <= _CHECK * h
    ):  # plain bisection, 2^-240 of the bracket
        for _ in range(240):
            mid = (lo + hi) / 2
            if resid(mid) < 0:
                lo = mid
            else:
                hi = mid
        u = (lo + hi) / 2
    a = b / mp.cosh(u)
    r = w * a
    y, length = _y_and_l(a, u, x)
    f = r * mp.sinh(u)
    assert abs(y - h) <= _CHECK * h, 'reference did not converge'
    assert abs(mp.sqrt(r * r + (f + w * length) ** 2) - t) <= _CHECK * t
    return r, f, length


def problem4(w: float, h: float, t: float, x: float) -> Ref:
    """Problem 4: hook tension T, span x < x_min -> (R, uplift F) with their condition numbers."""
    with mp.workdps(DPS):
        wm, hm, tm, xm = (mp.mpf(v) for v in (w, h, t, x))
        r, f, length = _p4(wm, hm, tm, xm)
        d = mp.mpf(10) ** -25
        r2, f2, _ = _p4(wm, hm, tm, xm * (1 + d))
        return Ref(
            float(r),
            float(f),
            float(abs((r2 - r) / r / d)),
            float(abs((f2 - f) / f / d)),
            float(length),
        )


def _pl(w: mp.mpf, h: mp.mpf, x: mp.mpf, length: mp.mpf, a0: mp.mpf) -> tuple[mp.mpf, mp.mpf]:
    # chord = 2 a sinh(x / 2a): in D = x / 2a, sinh(D) = k D with k = chord / x > 1, one root
    k = mp.sqrt(length * length - h * h) / x
    lo, hi = mp.mpf(0), mp.mpf(1)
    while mp.sinh(hi) - k * hi <= 0:
        lo, hi = hi, 2 * hi
    lo = max(lo, hi / 4) if lo == 0 else lo
    while mp.sinh(lo) - k * lo >= 0:
        lo /= 2
    d = mp.findroot(
        lambda d: mp.sinh(d) - k * d,
        (lo, hi),
        solver='anderson',
        tol=mp.mpf(10) ** (-2 * DPS + 10),
        verify=False,
        maxsteps=400,
    )
    a = x / (2 * d)
    u = mp.atanh(h / length) - x / (2 * a)
    if u < 0:
        raise ValueError('chain long enough to lie on the seabed')
    y, l2 = _y_and_l(a, u, x)
    assert abs(y - h) <= _CHECK * h and abs(l2 - length) <= _CHECK * length
    return w * a, w * a * mp.sinh(u)


def given_length(w: float, h: float, x: float, length: float, a0: float) -> Ref:
    """Fully suspended chain of given length L between anchor and hook -> (R, F).

    The form in which MoorPy and pycatenary state the problem; ``a0`` is a start for the root.
    """
    with mp.workdps(DPS):
        wm, hm, xm, lm = (mp.mpf(v) for v in (w, h, x, length))
        r, f = _pl(wm, hm, xm, lm, mp.mpf(a0))
        d = mp.mpf(10) ** -25
        r2, f2 = _pl(wm, hm, xm, lm * (1 + d), r / wm)
        return Ref(
            float(r), float(f), float(abs((r2 - r) / r / d)), float(abs((f2 - f) / f / d)), length
        )


def _p2(w: mp.mpf, h: mp.mpf, r: mp.mpf, x: mp.mpf) -> tuple[mp.mpf, mp.mpf]:
    a = r / w

    def resid(u: mp.mpf) -> mp.mpf:
        return _y_and_l(a, u, x)[0] - h  # increases with u

    lo, hi = mp.mpf(0), mp.mpf(1)
    if resid(lo) >= 0:
        raise ValueError('x >= x_min: the anchor is not lifted')
    while resid(hi) <= 0:
        lo, hi = hi, 2 * hi
    u = mp.findroot(
        resid,
        (lo, hi),
        solver='anderson',
        tol=mp.mpf(10) ** (-2 * DPS + 10),
        verify=False,
        maxsteps=400,
    )
    if not (lo <= u <= hi and abs(resid(u)) <= _CHECK * h):
        for _ in range(240):
            mid = (lo + hi) / 2
            if resid(mid) < 0:
                lo = mid
            else:
                hi = mid
        u = (lo + hi) / 2
    assert abs(resid(u)) <= _CHECK * h, 'reference did not converge'
    return mp.atan(mp.sinh(u)), r * mp.sinh(u)


def problem2(w: float, h: float, r: float, x: float) -> Ref:
    """Problem 2 (table 3): horizontal tension R and span x < x_min -> (anchor angle [rad], F)."""
    with mp.workdps(DPS):
        wm, hm, rm, xm = (mp.mpf(v) for v in (w, h, r, x))
        alpha, f = _p2(wm, hm, rm, xm)
        d = mp.mpf(10) ** -25
        alpha2, f2 = _p2(wm, hm, rm, xm * (1 + d))
        return Ref(
            float(alpha),
            float(f),
            float(abs((alpha2 - alpha) / alpha / d)),
            float(abs((f2 - f) / f / d)),
            math.nan,
        )

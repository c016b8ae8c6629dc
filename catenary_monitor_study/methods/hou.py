"""Hou, Dong, Shi & Yin (2005), J. Dalian Maritime Univ. 31(4): the fixed-point iteration and
the 0.618 (golden-section) search for the catenary parameter a (seed 001).

Native problem (5): chain of paid-out length ``Lm`` with the hawse ``dm`` from the anchor and
part of the chain on the seabed.  With ``L = sqrt(2 a h + h^2)`` (suspended length) and
``d = dm - (Lm - L)`` (suspended span), the iteration is ``a <- d / ln((a + h + L) / a)``,
started from the straight-line guess ``L0^2 = h^2 + d0^2``, ``Lm - L0 + d0 = dm``, stopped when
``|a1 - a0| < eps``.  The 0.618 search narrows ``[a1, a2]`` on ``|dm - (Lm - L' + d')|``.

Adapted to problem 4 (the same idea on its equation): ``a <- x / (acosh(A/a) - acosh(B/a))``
from ``a0 = B``, and the 0.618 search of ``|a (acosh(A/a) - acosh(B/a)) - x|`` on ``(0, B]``.
"""

from __future__ import annotations

import math

from .base import Method, NoConvergence

MAXITER = 2000
GOLD = 0.5 * (math.sqrt(5.0) - 1.0)  # 0.618...


def _hou5_state(w: float, h: float, lm: float, a: float) -> tuple[float, float]:
    length = math.sqrt(2.0 * a * h + h * h)
    return w * a, lm - length


def p5_fixed_point(
    w: float, h: float, lm: float, dm: float, eps: float = 1e-13
) -> tuple[float, float]:
    """Hou's iteration as printed (relative stop ``|a1 - a0| < eps a1``)."""
    c = dm - lm
    l0 = -(h * h + c * c) / (2.0 * c)
    d0 = dm - lm + l0
    a0 = (l0 * l0 - h * h) / (2.0 * h)
    for _ in range(MAXITER):
        a1 = d0 / math.log((a0 + h + l0) / a0)
        if abs(a1 - a0) < eps * a1:
            return _hou5_state(w, h, lm, a1)
        a0 = a1
        l0 = math.sqrt(2.0 * a0 * h + h * h)
        d0 = dm - (lm - l0)
        if not (d0 > 0.0 and a0 > 0.0):
            raise NoConvergence('fixed point left the domain')
    raise NoConvergence('fixed point: iteration cap')


def p5_golden(
    w: float, h: float, lm: float, dm: float, a_max: float, eps: float = 1e-13
) -> tuple[float, float]:
    """Hou's 0.618 search on ``[0, a_max]`` (``a_max`` from the dragging-anchor load)."""

    def miss(a: float) -> float:
        length = math.sqrt(2.0 * a * h + h * h)
        d = a * math.log((a + h + length) / a)
        return abs(dm - (lm - length + d))

    lo, hi = 0.0, a_max
    for _ in range(MAXITER):
        a1 = lo + (1.0 - GOLD) * (hi - lo)
        a2 = lo + GOLD * (hi - lo)
        m1, m2 = miss(a1), miss(a2)
        if m1 < eps * dm or m2 < eps * dm or hi - lo <= 4e-16 * hi:
            return _hou5_state(w, h, lm, a1 if m1 <= m2 else a2)
        if m2 < m1:
            lo = a1
        else:
            hi = a2
    raise NoConvergence('0.618 search: iteration cap')


def _d4(a: float, big_a: float, b: float) -> float:
    return math.acosh(big_a / a) - math.acosh(b / a)


def p4_fixed_point(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    big_a = t / w
    b = big_a - h
    a0 = b
    for _ in range(MAXITER):
        a1 = x / _d4(a0, big_a, b)
        if not 0.0 < a1 <= b:
            raise NoConvergence(f'fixed point left 0 < a <= B (a = {a1:g})')
        if abs(a1 - a0) <= 4e-16 * a1:
            return w * a1, w * math.sqrt((b - a1) * (b + a1))
        a0 = a1
    raise NoConvergence(
        'fixed point: iteration cap (|g\'(a)| close to 1: linear convergence stalls)'
    )


def p4_golden(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    big_a = t / w
    b = big_a - h

    def miss(a: float) -> float:
        return abs(a * _d4(a, big_a, b) - x)

    lo, hi = 0.0, b
    a1, a2 = lo + (1.0 - GOLD) * (hi - lo), lo + GOLD * (hi - lo)
    m1, m2 = miss(a1), miss(a2)
    for _ in range(MAXITER):
        if hi - lo <= 4e-16 * hi:
            a = a1 if m1 <= m2 else a2
            return w * a, w * math.sqrt((b - a) * (b + a))
        if m2 < m1:
            lo, a1, m1 = a1, a2, m2
            a2 = lo + GOLD * (hi - lo)
            m2 = miss(a2)
        else:
            hi, a2, m2 = a2, a1, m1
            a1 = lo + (1.0 - GOLD) * (hi - lo)
            m1 = miss(a1)
    raise NoConvergence('0.618 search: iteration cap')


_WHY = (
    "wrong unknown: a <- x / (acosh(A/a) - acosh(B/a)) is not a contraction (|g'(a)| > 1) "
    'except for steep chains (h >> B), so the iterates leave 0 < a <= B'
)
METHODS = [
    Method('Hou fixed point', 4, p4_fixed_point, None, 'hou', why=_WHY),
    Method(
        'Hou 0.618 search',
        4,
        p4_golden,
        None,
        'hou',
        why='cancelling formula; the search compares |f| values that are rounding noise near '
        'the root',
    ),
]

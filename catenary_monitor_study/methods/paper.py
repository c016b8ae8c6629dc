"""The seed paper's own method (Hu & Tang 2004, Fig. 2), as printed: a stepping search.

The paper has no inverse.  It steps the unknown down from a hand-picked start and refines the
step until the equation is met to the precision its tables print:

* span x (problems 1 and 3): from 1000 m down in steps of 10 m;
* anchor angle alpha (problems 2 and 4): from 44 deg down in steps of 1 deg;
* horizontal tension R (problems 3 and 4, measured T): from ``T - 2.0 kN`` down in steps of
  0.1 kN, running the inner search at each R until the hook tension ``T1`` computed from
  equations (1), (2) equals the measured T.

On each step that overshoots (``y < h``, or ``T1 < T``) the search goes back and divides the step
by 10, and it stops when ``|y - h| <= 1e-5 m`` and ``|T1 - T| <= 1 N``: the five decimals of y and
the 0.001 kN of T1 printed in tables 2-4.  Those are our reading of Fig. 2 (the flow chart itself
is an image the OCR did not keep), checked against the sequences of tables 1-4: x = 1000, 990,
980, ..., 108.5849, 108.5839; alpha = 44, 43, 42, ..., 6.9538, 6.9537; R = 1621.5 ... 1596.4.

Fails, by construction, where the start is on the wrong side of the root (x_min > 1000 m,
alpha > 44 deg, ``w h < 2 kN``: the search only goes down), where the absolute steps need more
than ``MAX_EVALS`` evaluations (R of many MN), and its answers carry the absolute tolerances
above, far coarser than 1e-6 relative on small or large scenes.
"""

from __future__ import annotations

import math
from typing import Callable

from .base import Method, NoConvergence

Y_TOL = 1e-5  # m, y printed with five decimals
T_TOL = 1.0  # N, T1 printed to 0.001 kN
X_START, X_STEP = 1000.0, 10.0  # m
ALPHA_START, ALPHA_STEP = math.radians(44.0), math.radians(1.0)
R_OFFSET, R_STEP = 2000.0, 100.0  # N: R starts at T - 2.0 kN, steps of 0.1 kN
MAX_EVALS = 100_000


class _Budget:
    def __init__(self) -> None:
        self.left = MAX_EVALS

    def spend(self) -> None:
        self.left -= 1
        if self.left < 0:
            raise NoConvergence(f'stepping search: more than {MAX_EVALS} evaluations')


def _search_down(
    f: Callable[[float], float], v: float, step: float, tol: float, budget: _Budget, what: str
) -> float:
    """Step v down until ``|f(v)| <= tol``; f > 0 above the root. Back up, step/10 on overshoot."""
    budget.spend()
    fv = f(v)
    if fv < -tol:
        raise NoConvergence(f'stepping search: the start {what} is already below the root')
    while abs(fv) > tol:
        new = v - step
        if new > 0.0:
            budget.spend()
            fn = f(new)
        else:
            fn = -math.inf  # out of the domain: treat as an overshoot
        if fn >= -tol:
            v, fv = new, fn
        else:
            step /= 10.0
            if v - step == v:
                raise NoConvergence(f'stepping search: step below the resolution of {what}')
    return v


def _y_and_l(a: float, alpha: float, x: float) -> tuple[float, float]:
    big = x / a
    sec, tan = 1.0 / math.cos(alpha), math.tan(alpha)
    ch = math.cosh(big) if big < 710.0 else math.inf
    sh = math.sinh(big) if big < 710.0 else math.inf
    return a * (sec * (ch - 1.0) + tan * sh), a * (tan * (ch - 1.0) + sec * sh)  # (1), (2)


def _span(w: float, h: float, r: float, budget: _Budget) -> float:
    a = r / w
    return _search_down(
        lambda x: _y_and_l(a, 0.0, x)[0] - h, X_START, X_STEP, Y_TOL, budget, 'x = 1000 m'
    )


def _angle(w: float, h: float, r: float, x: float, budget: _Budget) -> float:
    a = r / w
    return _search_down(
        lambda al: _y_and_l(a, al, x)[0] - h,
        ALPHA_START,
        ALPHA_STEP,
        Y_TOL,
        budget,
        'alpha = 44 deg',
    )


def p1_stepping(w: float, h: float, r: float) -> float:
    """Problem 1 (tables 1, 2): x_min for a given R."""
    return _span(w, h, r, _Budget())


def p2_stepping(w: float, h: float, r: float, x: float) -> tuple[float, float]:
    """Problem 2 (table 3): anchor angle and uplift for given R and x."""
    alpha = _angle(w, h, r, x, _Budget())
    return alpha, r * math.tan(alpha)


def p3_stepping(w: float, h: float, t: float) -> tuple[float, float]:
    """Problem 3 (table 4): R and x_min for a measured T (nested search on R, then x)."""
    budget = _Budget()
    found = {}

    def excess(r: float) -> float:
        x = _span(w, h, r, budget)
        found[r] = x
        length = _y_and_l(r / w, 0.0, x)[1]
        return math.hypot(r, w * length) - t

    r = _search_down(excess, t - R_OFFSET, R_STEP, T_TOL, budget, 'R = T - 2 kN')
    return r, found[r]


def p4_stepping(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    """Problem 4: R and uplift for a measured T at span x (nested search on R, then alpha)."""
    budget = _Budget()
    found = {}

    def excess(r: float) -> float:
        alpha = _angle(w, h, r, x, budget)
        found[r] = alpha
        length = _y_and_l(r / w, alpha, x)[1]
        return math.hypot(r, r * math.tan(alpha) + w * length) - t

    r = _search_down(excess, t - R_OFFSET, R_STEP, T_TOL, budget, 'R = T - 2 kN')
    return r, r * math.tan(found[r])


_WHY = (
    'bracket missing the root (it only steps down from x = 1000 m, alpha = 44 deg, R = T - 2 kN) '
    'and absolute tolerances (1e-5 m in y, 1 N in T, 0.1 kN steps) where relative ones were needed'
)
METHODS = [
    Method('paper stepping (Fig. 2)', 3, p3_stepping, None, 'paper', why=_WHY, slow=True),
    Method('paper stepping (Fig. 2)', 4, p4_stepping, None, 'paper', why=_WHY, slow=True),
    Method('paper stepping (Fig. 2)', 2, p2_stepping, None, 'paper', why=_WHY, slow=True),
]

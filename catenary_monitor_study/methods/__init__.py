"""Alternative catenary solvers, side by side behind one interface.

Every method is a :class:`~catenary_monitor_study.methods.base.Method`: a name, the problem it
solves and a scalar function (plus a vectorized one where the method allows).  Signatures, all SI:

* problem 3 (hook tension T -> minimum anchor distance): ``fn(w, h, T) -> (R, x_min)``;
* problem 4 (T and anchor distance x -> uplift state):  ``fn(w, h, T, x) -> (R, F)``;
* problem 2 (horizontal tension R and x -> uplift):     ``fn(w, h, R, x) -> (alpha_rad, F)``;
* problem 5 (paid-out length Lm and x, chain on the seabed): ``fn(w, h, Lm, x) -> (R, grounded)``.

A method signals failure by raising (``NoConvergence`` for an iteration that gives up) or by
returning NaN; the benchmark also counts an error above ``FAIL_RTOL`` as a failure.

Modules, one per family: ``closed`` (closed forms and the project's default), ``roots``
(bisection, Newton, safeguarded Newton, brentq, the two-unknown fsolve/root formulation),
``paper`` (the seed paper's Fig. 2 stepping search, as printed), ``hou`` (Hou 2005's fixed-point
iteration and 0.618 search), ``peers`` (MoorPy, pycatenary; optional), ``reference`` (the
50-digit mpmath solution of the paper's own equations).
"""

from __future__ import annotations

from typing import Optional

from .base import FAIL_RTOL, Method, NoConvergence

__all__ = ['Method', 'NoConvergence', 'FAIL_RTOL', 'all_methods']


def all_methods(problem: Optional[int] = None, peers: bool = True) -> list[Method]:
    """Every registered method (optionally of one problem); peers only if importable."""
    from . import closed, hou, paper, roots

    out: list[Method] = []
    for mod in (closed, roots, hou, paper):
        out.extend(mod.METHODS)
    if peers:
        from . import peers as peer_mod

        out.extend(peer_mod.available_methods())
    return [m for m in out if problem is None or m.problem == problem]

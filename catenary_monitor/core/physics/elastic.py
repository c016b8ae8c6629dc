"""The elastic chain (axial stiffness EA) and the rule that picks the inextensible model.

Model (Irvine's elastic catenary; weight ``w`` per unstretched metre, strain ``T/EA``).  With
horizontal tension R, vertical tension ``V_A`` at the anchor and ``V_B`` at the hook, tensions
``T_A = sqrt(R^2 + V_A^2)`` and ``T = sqrt(R^2 + V_B^2)``, unstretched suspended length
``L0 = (V_B - V_A)/w``:

    x = (R/w) [asinh(V_B/R) - asinh(V_A/R)] + R L0 / EA
    h = (T - T_A)/w + (T^2 - T_A^2) / (2 EA w)

The second equation gives the anchor-end tension in closed form whatever the uplift:
``T - T_A = D`` with ``h w = D (1 + (2T - D)/(2 EA))``, solved without cancellation.  Then

* no uplift (``V_A = 0``, problem 3): ``R = T - D``, ``V_B = sqrt(D (T + R))``, and
  ``x_min = (R/w) asinh(V_B/R) + R V_B / (w EA)`` (closed form);
* uplift (problem 4, x < x_min): with ``R = T_A sech u``, ``V_A = T_A tanh u`` the span
  ``x(u) = (T_A/w) sech u [acosh((T/T_A) cosh u) - u] + R (V_B - V_A)/(w EA)`` decreases with
  u; both terms are written as sums of positive parts and x(u) = x is solved in ``log u`` by
  Illinois regula falsi with a bisection every third step (vectorized, to a 4 eps bracket or a
  residual below 4 eps x), started from the rigid chain with the same end tensions (the core's
  uplift kernel).

The load margin needs the hook tension at which ``x_min = x``: Newton in ``log T_A`` (T from T_A
in closed form, ``d x_min / d T_A`` too), started from the rigid critical chain.  The elastic
critical tension may be below ``w h`` (the stretched chain reaches the depth with less).

``EA -> inf`` gives back the inextensible formulas exactly.

The rule (``solve``): the inextensible answer is kept where the elastic correction, the largest of
``|dx_min|/x_min``, ``|dR|/R``, ``|dF|/T`` and ``|dL|/L`` (elastic minus inextensible; F relative
to the hook tension since it may be 0), is at most ``tol`` (default ``ELASTIC_TOL = 1e-6``: below
what a load cell or a tide gauge resolves, so the extra model changes nothing a user can see);
elsewhere the elastic answer is returned.  ``SolveResult.model`` says which, element by element.
Near the lift-off distance the uplift correction grows like the square root of the strain, so
even stiff chains need the elastic model there.
"""

from __future__ import annotations

import math
from typing import Any, Optional, Protocol

import numpy as np

from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics.inextensible import solve_inextensible as solve_rigid
from catenary_monitor.core.physics.result import SolveResult

#: Keep the inextensible answer when the elastic correction is at most this (relative).
ELASTIC_TOL = 1e-6
INEXTENSIBLE = 'inextensible catenary'
ELASTIC = 'elastic catenary'
_EPS = float(np.finfo(float).eps)
_ETA_MAX = math.log(700.0)  # u <= 700: sech(700) underflows, so no span is shorter


def anchor_end_tension(w: Any, h: Any, t: Any, ea: Any, xp: Any = np) -> tuple[Any, Any]:
    """``(T_A, D)``: ``T_A = T - D`` with ``h w = D (1 + (2T - D)/(2EA))``, no cancellation.

    ``D = h w k`` with ``k = 2 / ((1+s) + sqrt((1+s)^2 - q))``, ``s = T/EA``, ``q = 2hw/EA``, and
    ``T_A = (T - w h) + w h (1 - k)`` where ``1 - k`` is a ratio of positive terms.  Both are
    returned: ``T - T_A`` recomputed from a rounded T_A would cancel when T_A ~ T.
    """
    s = t / ea
    q = 2.0 * h * w / ea
    root = xp.sqrt((1.0 + s) ** 2 - q)
    den = (1.0 + s) + root
    one_minus_k = (s + (2.0 * s + s * s - q) / (root + 1.0)) / den
    return cat.two_prod_diff(t, w, h) + w * h * one_minus_k, 2.0 * w * h / den


def _x_over_b(u: Any, e: Any, xp: Any = np) -> Any:
    """``sech(u) [acosh((1+e) cosh u) - u]`` as one log1p of positive terms."""
    c, s = xp.cosh(u), xp.sinh(u)
    p = (1.0 + e) * c
    pm1 = 2.0 * xp.sinh(0.5 * u) ** 2 + e * c
    sp = xp.sqrt(pm1 * (p + 1.0))
    num = e * c + e * c * c * (2.0 + e) / (sp + s)
    return xp.log1p(num / (c + s)) / c


def _top_vertical(u: Any, t: Any, ta: Any, d: Any, xp: Any = np) -> tuple[Any, Any]:
    """``R = T_A sech u``, ``V_B = sqrt(T^2 - R^2)`` [N], ``T - R = D + T_A (1 - sech u)``."""
    c = xp.cosh(u)
    r = ta / c
    t_minus_r = d + ta * 2.0 * xp.sinh(0.5 * u) ** 2 / c
    return r, xp.sqrt(t_minus_r * (t + r))


def _span(u: Any, w: Any, t: Any, ta: Any, d: Any, ea: Any, xp: Any = np) -> Any:
    """Elastic span x(u) [m] for hook tension T, anchor-end tension T_A = T - D."""
    r, vb = _top_vertical(u, t, ta, d, xp)
    va = ta * xp.tanh(u)
    return ta / w * _x_over_b(u, d / ta, xp) + r * d * (t + ta) / ((vb + va) * w * ea)


def _stretch(
    w: Any, t: Any, ta: Any, d: Any, r: Any, va: Any, vb: Any, l0: Any, ea: Any, xp: Any = np
) -> Any:
    """Elastic stretch [m]: the integral of T/EA along the chain (Irvine), a sum of positive terms.

    ``[V T + R^2 asinh(V/R)]`` from V_A to V_B over ``2 EA w``, with ``V_B T - V_A T_A = w L0 T +
    V_A D``
    and ``asinh(V_B/R) - asinh(V_A/R) = asinh(D (T + T_A) / (V_B T_A + V_A T))`` (no cancellation
    when the chain is nearly straight).
    """
    return (w * l0 * t + va * d + r * r * xp.arcsinh(d * (t + ta) / (vb * ta + va * t))) / (
        2.0 * ea * w
    )


def _illinois(
    fun: Any,
    lo: np.ndarray,
    hi: np.ndarray,
    flo: np.ndarray,
    fhi: np.ndarray,
    maxiter: int = 200,
    ftol: Any = 0.0,
) -> np.ndarray:
    """Root of a decreasing ``fun`` in ``[lo, hi]`` (``flo > 0 > fhi``), vectorized.

    Illinois regula falsi, with a plain bisection every third step so the bracket at least
    halves every three evaluations.  A regula falsi point is kept ``2 eps`` inside the bracket
    (relative, or absolute below 1): once the iterates reach the root from one side, the next one
    lands on the other side and closes the bracket (without this, ~40 bisections follow).  Stops
    when the bracket is ``4 eps`` wide (same scale), returning its midpoint, or when a residual is
    at most ``ftol`` in size (per element: the rounding level of ``fun``; 0, the default, stops
    only on an exact zero), returning that point.  Each iteration evaluates only the elements
    still active.
    """
    lo, hi, flo, fhi = (np.array(v, dtype=float) for v in (lo, hi, flo, fhi))
    side = np.zeros(lo.shape, dtype=np.int8)
    root = 0.5 * (lo + hi)
    idx = np.arange(lo.size)
    for k in range(maxiter):
        if idx.size == 0:
            break
        a, b, fa, fb = lo[idx], hi[idx], flo[idx], fhi[idx]
        if k % 3 != 2:
            mid = (a * fb - b * fa) / (fb - fa)
            near = 2.0 * _EPS * np.maximum(1.0, np.abs(mid))  # kept this far inside
            mid = np.minimum(np.maximum(mid, a + near), b - near)
        else:
            mid = 0.5 * (a + b)
        mid = np.where((mid > a) & (mid < b), mid, 0.5 * (a + b))
        fm = fun(mid, idx)
        pos = fm > 0.0
        # Illinois: halve the residual kept at the end that did not move twice in a row
        fb = np.where(pos & (side[idx] == 1), 0.5 * fb, fb)
        fa = np.where(~pos & (side[idx] == -1), 0.5 * fa, fa)
        lo[idx] = np.where(pos, mid, a)
        flo[idx] = np.where(pos, fm, fa)
        hi[idx] = np.where(pos, b, mid)
        fhi[idx] = np.where(pos, fb, fm)
        side[idx] = np.where(pos, 1, -1)
        root[idx] = mid
        width = hi[idx] - lo[idx]
        small = np.abs(fm) <= (ftol[idx] if np.ndim(ftol) else ftol)
        done = small | (width <= 4.0 * _EPS * np.maximum(1.0, np.abs(mid)))
        root[idx[done]] = np.where(small[done], mid[done], 0.5 * (lo[idx[done]] + hi[idx[done]]))
        idx = idx[~done]
    return root


def _illinois_scalar(
    fun: Any, lo: float, hi: float, flo: float, fhi: float, maxiter: int = 200, ftol: float = 0.0
) -> float:
    """Scalar twin of :func:`_illinois` (same steps and stopping test), plain-float ``fun``."""
    side = 0
    mid = 0.5 * (lo + hi)
    tiny = 4.0 * _EPS
    for k in range(maxiter):
        a, b, fa, fb = lo, hi, flo, fhi
        mid = (a * fb - b * fa) / (fb - fa) if k % 3 != 2 and fb != fa else 0.5 * (a + b)
        if k % 3 != 2:
            near = 2.0 * _EPS * max(1.0, abs(mid))
            if mid < a + near:
                mid = a + near
            if mid > b - near:
                mid = b - near
        if not a < mid < b:  # also NaN
            mid = 0.5 * (a + b)
        fm = fun(mid)
        if fm > 0.0:
            if side == 1:  # Illinois: halve the residual kept at the end that did not move twice
                fb = 0.5 * fb
            lo, flo, hi, fhi, side = mid, fm, b, fb, 1
        else:
            if side == -1:
                fa = 0.5 * fa
            lo, flo, hi, fhi, side = a, fa, mid, fm, -1
        if abs(fm) <= ftol:
            return mid
        if hi - lo <= tiny * max(1.0, abs(mid)):
            return 0.5 * (lo + hi)
    return mid


def elastic_state(w: Any, h: Any, t: Any, x: Optional[Any], ea: Any) -> dict[str, np.ndarray]:
    """Elastic solution (vectorized): R, x_min, F, stretched and unstretched suspended length.

    ``x`` may be None (problem 3).  Where ``x >= x_min`` the anchor is not lifted (F = 0).
    """
    with np.errstate(over='ignore', invalid='ignore', divide='ignore'):
        return _elastic_state(w, h, t, x, ea)


def _elastic_state(w: Any, h: Any, t: Any, x: Optional[Any], ea: Any) -> dict[str, np.ndarray]:
    w, h, t, ea = (np.asarray(v, dtype=float) for v in (w, h, t, ea))
    shape = np.broadcast(w, h, t, ea, *(() if x is None else (np.asarray(x, dtype=float),))).shape
    w, h, t, ea = (np.broadcast_to(v, shape).astype(float).ravel() for v in (w, h, t, ea))
    out_shape, shape = shape, w.shape
    ta, d = (np.asarray(v, dtype=float) for v in anchor_end_tension(w, h, t, ea))
    # no uplift: V_A = 0, R = T_A
    r = ta.copy()
    vb = np.sqrt(d * (t + ta))
    x_min = r / w * np.arcsinh(vb / r) + r * vb / (w * ea)
    va = np.zeros(shape)
    u = np.zeros(shape)
    if x is not None:
        x = np.broadcast_to(np.asarray(x, dtype=float), out_shape).ravel()
        lift = x < x_min
        if lift.any():
            args = [v[lift] for v in (w, t, ta, d, ea)]
            target = x[lift]

            def f(eta: np.ndarray, sel: np.ndarray) -> np.ndarray:
                return _span(np.exp(eta), *(v[sel] for v in args)) - target[sel]

            # start from the rigid chain with the same end tensions: the rigid span is exact there
            # and the elastic term is positive, so f > 0 (a lower bound on u) where it is lifted
            wl, tal, dl = args[0], args[2], args[3]
            rigid_lift = target < tal / wl * np.arcsinh(np.sqrt(dl * (args[1] + tal)) / tal)
            lo = np.full(target.shape, -200.0)  # log u: u = e^-200 is x_min to rounding
            if rigid_lift.any():
                s_r, _, ok_r = cat.lifted_from_tension(
                    wl[rigid_lift],
                    tal[rigid_lift] / wl[rigid_lift],
                    dl[rigid_lift] / wl[rigid_lift],
                    target[rigid_lift],
                )
                u_r = np.arcsinh(s_r.uplift_force / s_r.horizontal_tension)
                lo[rigid_lift] = np.where(
                    ok_r & (u_r > 0), np.log(np.maximum(u_r, 1e-300)), -200.0
                )
            all_idx = np.arange(target.size)
            flo = f(lo, all_idx)
            bad = ~(flo > 0.0)  # rounding at the start point: fall back to the far end
            lo[bad] = -200.0
            flo[bad] = f(lo[bad], all_idx[bad])
            step = np.full(target.shape, 1e-3)
            hi = lo + step
            fhi = f(hi, all_idx)
            grow = fhi >= 0.0
            while grow.any():  # ... up to where x(u) < x
                lo = np.where(grow, hi, lo)
                flo = np.where(grow, fhi, flo)
                step = np.where(grow, 4.0 * step, step)
                hi = np.where(grow, np.minimum(hi + step, _ETA_MAX), hi)
                sel = all_idx[grow]
                fhi[grow] = f(hi[grow], sel)
                grow = (fhi >= 0.0) & (hi < _ETA_MAX)
            ul = np.exp(_illinois(f, lo, hi, flo, fhi, ftol=4.0 * _EPS * target))  # x to rounding
            u[lift] = ul
            r[lift], vb[lift] = _top_vertical(ul, t[lift], ta[lift], d[lift])
            va[lift] = ta[lift] * np.tanh(ul)
    l0 = d * (t + ta) / ((vb + va) * w)  # (V_B - V_A)/w without the cancellation
    stretch = _stretch(w, t, ta, d, r, va, vb, l0, ea, np)
    out = {
        'horizontal_tension': r,
        'min_anchor_distance': x_min,
        'uplift_force': va,
        'unstretched_length': l0,
        'suspended_length': l0 + stretch,
        'top_vertical': vb,
        'anchor_tension': ta,
    }
    return {k: v.reshape(out_shape) for k, v in out.items()}


def _elastic_state_scalar(
    w: float, h: float, t: float, x: Optional[float], ea: float
) -> tuple[float, float, float, float, float, float]:
    """Plain-float twin of :func:`_elastic_state` (same formulas, start and iteration), one scene.

    Returns ``(R, x_min, V_A, L, V_B, T_A)`` [N, m, N, m, N, N] (L the stretched suspended length).
    May raise OverflowError, ZeroDivisionError or ValueError where numpy would give inf or NaN.
    """
    xm = cat._MATH
    sqrt, asinh, exp, log = math.sqrt, math.asinh, math.exp, math.log
    ta, d = anchor_end_tension(w, h, t, ea, xm)
    r = ta
    vb = sqrt(d * (t + ta))
    x_min = r / w * asinh(vb / r) + r * vb / (w * ea)
    va = 0.0
    if x is not None and x < x_min:

        def f(eta: float) -> float:
            return _span(exp(eta), w, t, ta, d, ea, xm) - x

        lo = -200.0
        if x < ta / w * asinh(
            sqrt(d * (t + ta)) / ta
        ):  # rigid chain with the same end tensions lifted
            s_r, _, ok_r = cat.lifted_from_tension_scalar(w, ta / w, d / w, x)
            u_r = asinh(s_r.uplift_force / s_r.horizontal_tension)
            if ok_r and u_r > 0:
                lo = log(max(u_r, 1e-300))
        flo = f(lo)
        if not flo > 0.0:
            lo = -200.0
            flo = f(lo)
        step = 1e-3
        hi = lo + step
        fhi = f(hi)
        grow = fhi >= 0.0
        while grow:
            lo, flo = hi, fhi
            step *= 4.0
            hi = min(hi + step, _ETA_MAX)
            fhi = f(hi)
            grow = fhi >= 0.0 and hi < _ETA_MAX
        u = exp(_illinois_scalar(f, lo, hi, flo, fhi, ftol=4.0 * _EPS * x))
        r, vb = _top_vertical(u, t, ta, d, xm)
        va = ta * math.tanh(u)
    l0 = d * (t + ta) / ((vb + va) * w)
    return r, x_min, va, l0 + _stretch(w, t, ta, d, r, va, vb, l0, ea, xm), vb, ta


def _critical_residual(rho: Any, w: Any, h: Any, x: Any, ea: Any, xp: Any = np) -> tuple[Any, Any]:
    """``log(x_min / x)`` and its derivative in ``rho = log R``, no-uplift chain with R = T_A.

    With R given, ``D = T - R`` solves ``h w = D (1 + (2R + D)/(2EA))`` in closed form (a sum of
    positive terms), ``V = sqrt(D (2R + D))`` and ``x_min = (R/w) asinh(V/R) + R V/(w EA)``, whose
    derivative is ``w dx_min/dR = asinh(V/R) - D/V + V/EA``.
    """
    r = xp.exp(rho)
    s = 1.0 + r / ea
    d = 2.0 * h * w / (s + xp.sqrt(s * s + 2.0 * h * w / ea))
    v = xp.sqrt(d * (2.0 * r + d))
    y = xp.arcsinh(v / r)
    x_min = r / w * y + r * v / (w * ea)
    return xp.log(x_min / x), r * (y - d / v + v / ea) / (w * x_min)


def _critical_tension_from(rho: Any, w: Any, h: Any, ea: Any, xp: Any = np) -> Any:
    """Hook tension ``T = R + D`` [N] of the no-uplift chain, anchor-end tension ``R = e^rho``."""
    r = xp.exp(rho)
    s = 1.0 + r / ea
    return r + 2.0 * h * w / (s + xp.sqrt(s * s + 2.0 * h * w / ea))


def _elastic_critical_tension(
    w: np.ndarray, h: np.ndarray, x: np.ndarray, ea: np.ndarray, a_rigid: np.ndarray
) -> np.ndarray:
    """Hook tension [N] at which the elastic chain's x_min equals x (x_min grows with T).

    Unknown ``rho = log R`` (anchor-end tension R at lift-off), in which ``log x_min`` is smooth
    and nearly linear (slope 1/2 for shallow chains, ~1 for steep ones), from the rigid critical
    parameter ``a_rigid`` [m] (``R = w a``: off by about the strain).  Newton on
    :func:`_critical_residual`, safeguarded by the bracket its residuals give (a step leaving it
    is replaced by bisection, or by a step of 4 toward the root while one side is unknown), steps
    clipped to +-4.  Stops after a step of at most ``STEP_TOL`` (applied): the convergence is
    quadratic, so the error left is ~STEP_TOL^2, below rounding.  Each iteration evaluates only
    the active elements; the result is never NaN for a finite start.
    """
    rho = np.log(w * a_rigid)
    lo = np.full(rho.shape, -np.inf)
    hi = np.full(rho.shape, np.inf)
    idx = np.arange(rho.size)
    for _ in range(cat.MAXITER):
        if idx.size == 0:
            break
        cur = rho[idx]
        f, fp = _critical_residual(cur, w[idx], h[idx], x[idx], ea[idx])
        lo_i = np.where(f < 0.0, np.maximum(lo[idx], cur), lo[idx])
        hi_i = np.where(f > 0.0, np.minimum(hi[idx], cur), hi[idx])
        step = np.clip(-f / fp, -4.0, 4.0)
        new = cur + step
        converged = (np.abs(step) <= cat.STEP_TOL) | (f == 0.0)
        bad = ~((new >= lo_i) & (new <= hi_i) | converged)  # also catches NaN
        bracketed = np.isfinite(lo_i) & np.isfinite(hi_i)
        middle = 0.5 * (np.where(bracketed, lo_i, 0.0) + np.where(bracketed, hi_i, 0.0))
        new = np.where(
            bad,
            np.where(bracketed, middle, np.where(f > 0.0, cur - 4.0, cur + 4.0)),
            new,
        )
        rho[idx], lo[idx], hi[idx] = np.where(f == 0.0, cur, new), lo_i, hi_i
        idx = idx[~converged]
    return _critical_tension_from(rho, w, h, ea)


def _elastic_depth_reach(
    w: np.ndarray, r: np.ndarray, x: np.ndarray, ea: np.ndarray
) -> np.ndarray:
    """Depth a no-uplift elastic chain of horizontal tension R spans over x (the tide margin).

    In ``nu = asinh(V/R)``: ``x = a nu + a k sinh(nu)`` (``a = R/w``, ``k = R/EA``), increasing
    and convex, so Newton from a point right of the root decreases monotonically.  Both terms
    bound it: the start is the smaller of the rigid ``x/a`` and ``asinh(x/(a k))``, the close one
    for a nearly slack chain (from ``x/a`` ~ 500 Newton crept down by ~1 a step and stopped at
    100 steps far off, where sinh^2 overflowed: a +inf tide margin for a finite one).
    Then ``h = 2 a sinh(nu/2)^2 + a k sinh(nu)^2 / 2`` [m], +inf only beyond float64.
    """
    a = r / w
    k = r / ea
    with np.errstate(divide='ignore'):  # a k = 0 (EA infinite): no stretch bound, asinh(inf)
        nu = np.minimum(np.minimum(x / a, np.arcsinh(x / (a * k))), 700.0)
    for _ in range(100):
        g = a * nu + a * k * np.sinh(nu) - x
        step = g / (a + a * k * np.cosh(nu))
        nu = nu - step
        if np.all(np.abs(step) <= 4.0 * np.finfo(float).eps * nu):
            break
    sn = np.sinh(nu)
    with np.errstate(over='ignore'):  # a depth beyond float64: +inf, a real margin
        return 2.0 * a * np.sinh(0.5 * nu) ** 2 + 0.5 * (a * k * sn) * sn


def _elastic_critical_tension_scalar(
    w: float, h: float, x: float, ea: float, a_rigid: float
) -> float:
    """Plain-float twin of :func:`_elastic_critical_tension` (same start, safeguard, stop) [N]."""
    xm = cat._MATH
    rho = math.log(w * a_rigid)
    lo, hi = -math.inf, math.inf
    for _ in range(cat.MAXITER):
        f, fp = _critical_residual(rho, w, h, x, ea, xm)
        if f < 0.0:
            lo = max(lo, rho)
        elif f > 0.0:
            hi = min(hi, rho)
        elif f == 0.0:
            break
        step = -f / fp
        if step > 4.0:
            step = 4.0
        elif step < -4.0:
            step = -4.0
        new = rho + step
        if -cat.STEP_TOL <= step <= cat.STEP_TOL:
            rho = new
            break
        if not lo <= new <= hi:  # also NaN
            new = (
                0.5 * (lo + hi)
                if -math.inf < lo and hi < math.inf
                else (rho - 4.0 if f > 0.0 else rho + 4.0)
            )
        rho = new
    return _critical_tension_from(rho, w, h, ea, xm)


def _elastic_depth_reach_scalar(w: float, r: float, x: float, ea: float) -> float:
    """Plain-float twin of :func:`_elastic_depth_reach` [m]."""
    sinh, cosh = math.sinh, math.cosh
    a = r / w
    k = r / ea
    ak = a * k
    nu = min(x / a, math.asinh(x / ak) if ak > 0.0 else math.inf, 700.0)
    tiny = 4.0 * _EPS
    for _ in range(100):
        g = a * nu + a * k * sinh(nu) - x
        step = g / (a + a * k * cosh(nu))
        nu = nu - step
        if abs(step) <= tiny * nu:
            break
    s = sinh(0.5 * nu)
    sn = sinh(nu)
    return 2.0 * a * (s * s) + 0.5 * (a * k * sn) * sn


class RigidValues(Protocol):
    """What :func:`elastic_correction` reads of the inextensible answer (a
    :class:`SolveResult` or a :class:`SimpleRigid`)."""

    @property
    def min_anchor_distance(self) -> Any: ...

    @property
    def horizontal_tension(self) -> Any: ...

    @property
    def uplift_force(self) -> Any: ...

    @property
    def suspended_length(self) -> Any: ...

    @property
    def top_tension(self) -> Any: ...


def elastic_correction(rigid: RigidValues, el: dict[str, np.ndarray]) -> np.ndarray:
    """Largest relative change the elastic model makes to the reported quantities."""
    t = np.asarray(rigid.top_tension, dtype=float)
    parts = [
        np.abs(el['min_anchor_distance'] - rigid.min_anchor_distance) / rigid.min_anchor_distance,
        np.abs(el['horizontal_tension'] - rigid.horizontal_tension) / rigid.horizontal_tension,
        np.abs(el['uplift_force'] - rigid.uplift_force) / t,
        np.abs(el['suspended_length'] - rigid.suspended_length) / rigid.suspended_length,
    ]
    return np.max(parts, axis=0)


def solve_with_correction(
    weight: Any,
    depth: Any,
    tension: Any,
    anchor_distance: Any = None,
    ea: Any = None,
    mbl: Any = None,
    tol: float = ELASTIC_TOL,
) -> tuple[SolveResult, Any]:
    """Problems 3 and 4 with an optional axial stiffness ``ea`` [N]; the model chosen by the rule.

    Returns ``(result, correction)``: a :class:`SolveResult` whose ``model`` names the model used
    (per element for arrays) and the elastic correction that decided it (0 without ``ea``).
    With ``ea=None`` this is exactly the inextensible solve. ``catenary_monitor.solve(..., ea=EA)``
    returns the result alone.
    """
    if tol < 0:
        raise ValueError(f'tol must be >= 0 (got {tol})')
    rigid = solve_rigid(weight, depth, tension=tension, anchor_distance=anchor_distance, mbl=mbl)
    scalar = np.ndim(rigid.status) == 0
    if ea is None:
        return rigid, 0.0 if scalar else np.zeros(np.shape(rigid.status))
    if scalar and type(ea) in _PLAIN:  # the node's case: plain floats, no arrays
        ea_f = float(ea)
        if not ea_f > 0:
            raise ValueError('ea (axial stiffness) must be > 0 N')
        if rigid.status != 0:
            return rigid, 0.0
        try:
            return _solve_scalar(
                rigid,
                float(weight),
                float(depth),
                float(tension),
                None if anchor_distance is None else float(anchor_distance),
                ea_f,
                tol,
            )
        except (OverflowError, ZeroDivisionError, ValueError):
            pass  # beyond float range in plain math: the arrays below give inf / NaN instead
    ea_arr = np.asarray(ea, dtype=float)
    if np.any(~(ea_arr > 0)):
        raise ValueError('ea (axial stiffness) must be > 0 N')
    status = np.asarray(rigid.status)
    shape = status.shape
    ok = status == 0
    bc = lambda v: np.broadcast_to(np.asarray(v, dtype=float), shape)  # noqa: E731
    w, h, t, ea_b = bc(weight)[ok], bc(depth)[ok], bc(tension)[ok], bc(ea_arr)[ok]
    x = None if anchor_distance is None else bc(anchor_distance)[ok]
    el = elastic_state(w, h, t, x, ea_b)
    rig = {
        k: (
            np.atleast_1d(np.asarray(getattr(rigid, k), dtype=float))[ok.ravel()]
            if scalar
            else np.asarray(getattr(rigid, k), dtype=float)[ok]
        )
        for k in (
            'min_anchor_distance',
            'horizontal_tension',
            'uplift_force',
            'suspended_length',
            'top_tension',
            'top_angle_deg',
            'anchor_angle_deg',
            'anchor_margin',
            'tide_margin',
            'load_margin',
        )
    }
    corr = elastic_correction(SimpleRigid(rig), el)
    use = corr > tol
    out = {k: v.copy() for k, v in rig.items()}
    if use.any():
        r, vb, va = el['horizontal_tension'], el['top_vertical'], el['uplift_force']
        new = {
            'min_anchor_distance': el['min_anchor_distance'],
            'horizontal_tension': r,
            'uplift_force': va,
            'suspended_length': el['suspended_length'],
            'top_angle_deg': np.degrees(np.arctan2(vb, r)),
            'anchor_angle_deg': np.degrees(np.arctan2(va, r)),
        }
        if x is not None:
            new['anchor_margin'] = x - el['min_anchor_distance']
            new['tide_margin'] = _elastic_depth_reach(w, r, x, ea_b) - h
            a_rigid, _ = cat.critical_parameter(h, x)  # converged: else the status is not 0
            new['load_margin'] = _elastic_critical_tension(w, h, x, ea_b, a_rigid) - t
        for k, v in new.items():
            out[k] = np.where(use, v, out[k])
    fields: dict[str, Any] = {}
    for k, v in out.items():
        if k not in rigid.keys and k != 'top_tension':
            continue
        full = np.full(shape, np.nan)
        full[ok] = v
        fields[k] = float(full) if scalar else full
    model = np.full(shape, INEXTENSIBLE, dtype=object)
    model[ok] = np.where(use, f'{ELASTIC}', INEXTENSIBLE)
    corr_full = np.zeros(shape)
    corr_full[ok] = corr
    res = rigid._replace(**fields, model=str(model) if scalar else model)
    return res, (float(corr_full) if scalar else corr_full)


_PLAIN = (float, int, np.float64)


def _solve_scalar(
    rigid: SolveResult, w: float, h: float, t: float, x: Optional[float], ea: float, tol: float
) -> tuple[SolveResult, float]:
    """:func:`solve` for one valid scene in plain floats (same formulas and rule as the arrays).

    ``rigid`` is the scalar inextensible result (status 0).  May raise OverflowError,
    ZeroDivisionError or ValueError where numpy would give inf or NaN (the caller falls back).
    """
    r, x_min, va, length, vb, _ = _elastic_state_scalar(w, h, t, x, ea)
    parts = (
        abs(x_min - rigid.min_anchor_distance) / rigid.min_anchor_distance,
        abs(r - rigid.horizontal_tension) / rigid.horizontal_tension,
        abs(va - rigid.uplift_force) / t,
        abs(length - rigid.suspended_length) / rigid.suspended_length,
    )
    corr = math.nan if any(p != p for p in parts) else max(parts)  # NaN propagates, as np.max
    if not corr > tol:
        return rigid, corr
    new: dict[str, Any] = {  # float fields of SolveResult
        'min_anchor_distance': x_min,
        'horizontal_tension': r,
        'uplift_force': va,
        'suspended_length': length,
        'top_angle_deg': math.degrees(math.atan2(vb, r)),
        'anchor_angle_deg': math.degrees(math.atan2(va, r)),
    }
    if x is not None:
        new['anchor_margin'] = x - x_min
        new['tide_margin'] = _elastic_depth_reach_scalar(w, r, x, ea) - h
        a_rigid = cat.critical_parameter_scalar(h, x)
        new['load_margin'] = _elastic_critical_tension_scalar(w, h, x, ea, a_rigid) - t
    return rigid._replace(model=ELASTIC, **new), corr


class SimpleRigid:
    """Attribute view of a dict (the rigid values of the valid elements)."""

    # The attributes elastic_correction reads (RigidValues); the dict has them all.
    min_anchor_distance: np.ndarray
    horizontal_tension: np.ndarray
    uplift_force: np.ndarray
    suspended_length: np.ndarray
    top_tension: np.ndarray

    def __init__(self, d: dict[str, np.ndarray]) -> None:
        self.__dict__.update(d)


#: Lines of the report (docs/elastic.md): submerged weight [N/m] and axial stiffness EA [N].
#: U3 studlink chain 81 mm: EA ~ 1.01e8 d^2 kN (d in m), the usual studlink estimate; the
#: paper's w = 1.3 kN/m.  Steel wire of similar strength (six-strand 76 mm): metallic area
#: ~0.58 pi d^2/4, effective modulus ~90 GPa, ~0.25 kN/m in water.  Polyester 160 mm:
#: quasi-static EA ~ 15 x MBL (MBL ~ 5 MN), nearly neutrally buoyant, ~30 N/m in water.
REPORT_LINES = (
    ('U3 studlink chain, 81 mm (the paper\'s dock)', 1300.0, 1.01e8 * 0.081**2 * 1e3),
    ('six-strand steel wire, 76 mm', 250.0, 90e9 * 0.58 * np.pi / 4 * 0.076**2),
    ('polyester rope, 160 mm', 30.0, 15 * 5.0e6),
)


def report(
    depth: float = 20.85, tension: float = 1623.5e3, anchor_distance: float = 121.06
) -> list[dict[str, Any]]:
    """How much elasticity changes x_min and the uplift, per line, at one dock scene."""
    rows = []
    for name, w, ea in REPORT_LINES:
        rigid = solve_rigid(w, depth, tension=tension, anchor_distance=anchor_distance)
        el = {
            k: float(v) for k, v in elastic_state(w, depth, tension, anchor_distance, ea).items()
        }
        rows.append(
            {
                'line': name,
                'w': w,
                'ea': ea,
                'strain': tension / ea,
                'x_min_rigid': rigid.min_anchor_distance,
                'x_min_elastic': el['min_anchor_distance'],
                'uplift_rigid': rigid.uplift_force,
                'uplift_elastic': el['uplift_force'],
                'dx_min_rel': (el['min_anchor_distance'] - rigid.min_anchor_distance)
                / rigid.min_anchor_distance,
                'duplift_over_t': (el['uplift_force'] - rigid.uplift_force) / tension,
            }
        )
    return rows

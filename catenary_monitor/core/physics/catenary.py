"""Numerically stable catenary kernels for a chain from a hook point down to a seabed anchor.

Notation (SI units throughout): ``w`` submerged weight per metre [N/m], ``h`` vertical distance
anchor -> hook [m], ``x`` horizontal distance hook -> anchor [m], ``R`` horizontal tension [N],
``T`` hook (top) tension [N], ``a = R / w`` the catenary parameter [m].

The chain is a catenary ``y = a cosh(xi)`` in its own parameter ``xi``; the anchor sits at ``xi =
u``
(``u = 0``: the chain meets the seabed tangentially, no uplift) and the hook at ``xi = u + X`` with
``X = x / a``.  Every kernel below is written so that nothing cancels that the problem itself does
not make ill-conditioned: ``cosh(z) - 1`` is evaluated as ``2 sinh(z/2)**2``, ``acosh(1 + z)`` as
``log1p(z + sqrt(z (2 + z)))``, and the uplift solve iterates on ``log(X - log1p(h/B))`` so that
both of its ends (``x -> 0`` and ``x -> x_min``) keep full relative accuracy.

Each closed form takes an array namespace ``xp`` (``numpy`` or :mod:`math` through ``_MATH``) so
the
same formula serves the vectorized path and the fast scalar path.  Inputs here are assumed valid:
validation lives in :mod:`catenary_monitor.solve`.
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any, NamedTuple

import numpy as np

#: Newton stops after a step of at most this size in its log variable (relative size of the
#: unknown): convergence is quadratic, so the error left is ~STEP_TOL**2, far below rounding.
STEP_TOL = 1e-9
#: Plain Newton steps taken on whole arrays before the safeguarded active-set loop (problem 4;
#: from its model-based start most elements have converged after 2).
FAST_STEPS = 2
# : Iteration cap; never reached on the physical domain (residual counts:
# test/test_methods_scalar.py).
MAXITER = 60
_EPS = float(np.finfo(float).eps)

_MATH = SimpleNamespace(
    sqrt=math.sqrt,
    log=math.log,
    maximum=max,
    minimum=min,
    log1p=math.log1p,
    exp=math.exp,
    expm1=math.expm1,
    sinh=math.sinh,
    cosh=math.cosh,
    tanh=math.tanh,
    asinh=math.asinh,
    arctan2=math.atan2,
    arcsinh=math.asinh,
    arctan=math.atan,
    frexp=math.frexp,
    ldexp=math.ldexp,
)


def acosh1p(z: Any, xp: Any = np) -> Any:
    """``acosh(1 + z)`` for ``z >= 0`` without the cancellation of ``acosh(1 + tiny)``."""
    return xp.log1p(z + xp.sqrt(z * (2.0 + z)))


def two_prod_diff(t: Any, w: Any, h: Any) -> Any:
    """``t - w*h`` with the product's rounding error compensated (Dekker/Veltkamp split).

    The anchor-end tension ``T - w h`` cancels when the chain is nearly vertical (h/a large);
    computing it in compensated arithmetic keeps it correctly rounded in that regime.
    """
    p = w * h
    split = 134217729.0  # 2**27 + 1
    cw = split * w
    wh = cw - (cw - w)
    wl = w - wh
    ch = split * h
    hh = ch - (ch - h)
    hl = h - hh
    err = ((wh * hh - p) + wh * hl + wl * hh) + wl * hl
    return (t - p) - err


# --------------------------------------------------------------------------------------------
# Problems 1 and 3: anchor tangent to the seabed (no uplift), closed forms.
# --------------------------------------------------------------------------------------------
class Grounded(NamedTuple):
    """Chain meeting the seabed tangentially: the minimum anchor distance for its load."""

    min_anchor_distance: Any  # m, horizontal span of the suspended chain
    suspended_length: Any  # m
    top_angle: Any  # rad, from the horizontal at the hook


def grounded(a: Any, h: Any, xp: Any = np) -> Grounded:
    """Suspended span, length and top angle of a catenary with its vertex at the anchor.

    ``x_min = a acosh(1 + h/a)``, ``L = sqrt(h (h + 2a))``, ``tan(beta) = L / a``.  ``L`` is
    taken as ``sqrt(h) sqrt(h + 2a)``: ``h (h + 2a)`` underflowed to 0 for h < ~1e-154 m.
    """
    x_min = a * acosh1p(h / a, xp)
    length = xp.sqrt(h) * xp.sqrt(h + 2.0 * a)
    return Grounded(x_min, length, xp.arctan2(length, a))


def depth_reached(a: Any, x: Any, xp: Any = np) -> Any:
    """Depth ``a (cosh(x/a) - 1)`` [m] a no-uplift catenary spans over horizontal distance x."""
    s = xp.sinh(0.5 * x / a)
    return 2.0 * a * s * s


# --------------------------------------------------------------------------------------------
# Lifted anchor: a catenary whose anchor end leaves the seabed at angle alpha.
# --------------------------------------------------------------------------------------------
class Lifted(NamedTuple):
    """State of a chain whose anchor end is lifted (all in SI; zero uplift when t == 0)."""

    horizontal_tension: Any  # N
    uplift_force: Any  # N, vertical pull on the anchor
    anchor_angle: Any  # rad
    top_tension: Any  # N
    top_angle: Any  # rad
    suspended_length: Any  # m


_new_tuple = tuple.__new__  # builds a NamedTuple from a tuple without its keyword handling


def _lifted_state(w: Any, a: Any, u_sinh: Any, u_cosh: Any, big_x: Any, xp: Any) -> Lifted:
    """Quantities of the catenary with anchor at ``xi = u`` and hook at ``xi = u + X``.

    ``u_sinh = sinh(u)``, ``u_cosh = cosh(u)`` (given separately to keep their accuracy).
    """
    sx = xp.sinh(big_x)
    half = xp.sinh(0.5 * big_x)
    cm1 = 2.0 * half * half  # cosh(X) - 1
    top_sinh = u_sinh * (1.0 + cm1) + u_cosh * sx  # sinh(u + X)
    top_cosh = u_cosh * (1.0 + cm1) + u_sinh * sx  # cosh(u + X)
    r = w * a
    return Lifted(
        horizontal_tension=r,
        uplift_force=r * u_sinh,
        anchor_angle=xp.arctan2(u_sinh, 1.0),
        top_tension=r * top_cosh,
        top_angle=xp.arctan2(top_sinh, 1.0),
        suspended_length=a * (u_sinh * cm1 + u_cosh * sx),
    )


def lifted_from_horizontal(w: Any, h: Any, a: Any, x: Any, xp: Any = np) -> Lifted:
    """Problem 2: horizontal tension (``a = R/w``) and span x given, anchor closer than x_min.

    Closed form: with ``p = sinh(X/2)`` and ``q = h / (2 a p)``, the anchor parameter is
    ``u = asinh(q) - asinh(p)``, evaluated as ``asinh((q - p)(q + p) / (q sqrt(1+p^2) + p
    sqrt(1+q^2)))``
    where ``q - p = (h/a - 2 p^2) / (2p)``: the only subtraction left is the problem's own
    (depth minus the depth a no-uplift chain reaches).  Negative ``u`` is clipped to 0 (grounded).
    """
    big_x = x / a
    p = xp.sinh(0.5 * big_x)
    q = h / (2.0 * a * p)
    q_minus_p = (h / a - 2.0 * p * p) / (2.0 * p)
    # sinh(u) = sinh(asinh(q) - asinh(p)) = tan(alpha), the anchor-end slope.
    u_sinh = q_minus_p * (q + p) / (q * xp.sqrt(1.0 + p * p) + p * xp.sqrt(1.0 + q * q))
    u_sinh = xp.maximum(u_sinh, 0.0)
    return _lifted_state(w, a, u_sinh, xp.sqrt(1.0 + u_sinh * u_sinh), big_x, xp)


# --------------------------------------------------------------------------------------------
# Problem 4: hook tension T and span x given, anchor closer than x_min -> uplift state.
# --------------------------------------------------------------------------------------------
#
# With B = T/w - h (anchor-end tension over w), e = h / B, the span in catenary units
# X = x / a lies in [log1p(e), acosh(1+e)].  Writing X = log1p(e) + d, the exact relation
#     (x sinh(X) / (B X))**2 = expm1(d) * (e (2 + e) - expm1(-d))
# has no cancellation for any d > 0; we solve it by Newton in eta = log(d) on the log of the
# ratio of both sides, which is close to linear in eta over the whole range.  Then
#     sech(u) = x / (B X),   tanh(u) = (e - 2 sinh(X/2)**2) / sinh(X).


def _uplift_residual(eta: Any, e: Any, r02: Any, xlo: Any, m: Any, xp: Any) -> tuple[Any, Any]:
    """Residual ``log(x(d)^2 / x_t^2)`` and its derivative with respect to ``eta = log(d)``.

    ``r02 = e (2 + e)``, ``xlo = log1p(e)``, ``m = x_t / B``.  The residual is the log of one
    product of well-conditioned factors, so its absolute error is a few ulps.  The factors are
    scaled by ``sc``, the power of 2 nearest ``1/m`` (:func:`_scale`): the same bits wherever
    nothing under- or overflows, and no underflow of ``expm1(d) p ~ m^2`` for tiny ``m = x/B``
    (hook tensions up to float64's limit, T/w ~ 1e300 x).
    """
    d = xp.exp(eta)
    big_x = xlo + d
    em = xp.expm1(d)
    ed = 1.0 + em  # exp(d)
    p = r02 + em / ed  # em / ed = -expm1(-d)
    sc = _scale(m, xp)
    ratio = (em * sc) * (p * sc) * (big_x / ((m * sc) * xp.sinh(big_x))) ** 2
    # d/dd log(sinh X / X) = coth X - 1/X; its cancellation for small X only slows nothing:
    # the 1/d term dominates the derivative there.
    dfdd = ed / em + 1.0 / (ed * p) - 2.0 * (1.0 / xp.tanh(big_x) - 1.0 / big_x)
    return xp.log(ratio), dfdd * d


def _scale(m: Any, xp: Any) -> Any:
    """The power of 2 nearest ``1 / m`` (``m sc`` in [0.5, 1)): scaling by it is exact."""
    return xp.ldexp(1.0, -xp.frexp(m)[1])


def _uplift_setup(b: Any, h: Any, x: Any, xp: Any) -> tuple[Any, Any, Any, Any, Any, Any]:
    """Constants of the uplift solve and the starting point.

    Returns ``e, r02, xlo, m, eta0, eta_max``; ``eta_max = log(d_max)`` is where x = x_min.
    The start solves the model ``m^2 = c d (r02 + d)`` (exact as d -> 0 with ``c = c0``, and at
    d_max with ``c = c1``) twice: first with ``c1``, then with ``log c`` interpolated linearly in
    ``d / d_max`` at the first root.  It is within 1e-3 in eta over most of the domain (within 0.2
    everywhere), so Newton needs 2-3 residuals instead of 3-6.  The model is solved in ``d sc``
    (:func:`_scale`): no underflow of ``m^2`` for tiny ``m``, the same bits elsewhere.
    """
    e = h / b
    r02 = e * (2.0 + e)
    xlo = xp.log1p(e)
    m = x / b
    x0 = xp.log1p(e + xp.sqrt(r02))  # acosh1p(e)
    d_max = x0 - xlo
    eta_max = xp.log(d_max)
    c1 = x0 * x0 / (d_max * (r02 + d_max))
    sc = _scale(m, xp)
    ms, r02s = m * sc, r02 * sc
    q = ms * ms / c1  # (m sc)^2 / c1
    r02_sq = r02s * r02s
    d = _start_root(q, r02s, r02_sq, xp) / sc
    frac = xp.minimum(d / d_max, 1.0)
    c0 = 2.0 * (1.0 + e) * xlo / r02
    d = _start_root(q * xp.exp((frac - 1.0) * xp.log(c0 * c0 / c1)), r02s, r02_sq, xp) / sc
    return e, r02, xlo, m, xp.log(xp.maximum(d, 1e-300)), eta_max


def _start_root(q: Any, r02: Any, r02_sq: Any, xp: Any) -> Any:
    """Positive root of ``d (r02 + d) = q`` (``r02_sq = r02**2``), without cancellation."""
    return 2.0 * q / (r02 + xp.sqrt(r02_sq + 4.0 * q))


def _lifted_from_d(w: Any, b: Any, e: Any, xlo: Any, m: Any, d: Any, xp: Any) -> Lifted:
    """Uplift state from the solved ``d``: ``sech u = m / X``,
    ``tanh u = (e - cosh X + 1)/sinh X``.

    :func:`_lifted_state` with ``a = B sech u`` simplified: ``R = w B sech u``, ``F = w B tanh u``,
    ``T = w B (cosh X + tanh u sinh X)``, ``L = B (tanh u (cosh X - 1) + sinh X)``.
    """
    big_x = xlo + d
    s = m / big_x  # sech u
    half = xp.sinh(0.5 * big_x)
    sx = xp.sinh(big_x)
    cm1 = 2.0 * half * half  # cosh(X) - 1
    t = xp.maximum((e - cm1) / sx, 0.0)  # tanh u
    wb = w * b
    c = 1.0 + cm1
    return Lifted(
        horizontal_tension=wb * s,
        uplift_force=wb * t,
        anchor_angle=xp.arctan(t / s),
        top_tension=wb * (c + t * sx),
        top_angle=xp.arctan((t * c + sx) / s),
        suspended_length=b * (t * cm1 + sx),
    )


def lifted_from_tension(
    w: np.ndarray, b: np.ndarray, h: np.ndarray, x: np.ndarray
) -> tuple[Lifted, np.ndarray, np.ndarray]:
    """Problem 4, vectorized: uplift state for hook tension ``T = w (B + h)`` and span x < x_min.

    All arguments are 1-D float arrays of one length (``b = T/w - h``).  Returns the state, the
    iteration count and a converged flag per element.

    Notes
    -----
    Newton in ``eta``, safeguarded by a bracket that every evaluated residual tightens (the
    residual increases with eta).  A step that leaves the bracket is replaced by bisection, or
    by a step of -4 in eta while no lower bound is known.  Each iteration evaluates only the
    elements still active.  Stopping test: ``|step| <= STEP_TOL`` in eta (relative in d); the
    convergence is quadratic, so the error left after that step is at rounding level.
    """
    e, r02, xlo, m, eta, eta_hi = _uplift_setup(b, h, x, np)
    eta = np.minimum(eta, eta_hi)
    # Fast phase: FAST_STEPS plain Newton steps on the whole arrays (no gather, no bracket
    # bookkeeping; the residual costs little more than one closed-form evaluation).  Elements
    # whose last step was at rounding level are done; the others continue below, safeguarded,
    # from where they are if that is finite and inside (-inf, eta_max], else from the start.
    start = eta.copy()
    step = np.zeros_like(eta)
    for _ in range(FAST_STEPS):
        f, fp = _uplift_residual(eta, e, r02, xlo, m, np)
        step = -f / fp
        eta = np.minimum(eta + step, eta_hi)
    done = np.abs(step) <= STEP_TOL
    iters = np.full(eta.shape, FAST_STEPS, dtype=np.int64)
    restart = ~np.isfinite(eta)
    eta[restart] = start[restart]
    eta_lo = np.full_like(eta, -np.inf)
    idx = np.flatnonzero(~done)
    for it in range(FAST_STEPS + 1, MAXITER + 1):
        if idx.size == 0:
            break
        cur = eta[idx]
        f, fp = _uplift_residual(cur, e[idx], r02[idx], xlo[idx], m[idx], np)
        lo = np.where(f < 0.0, np.maximum(eta_lo[idx], cur), eta_lo[idx])
        hi = np.where(f > 0.0, np.minimum(eta_hi[idx], cur), eta_hi[idx])
        step = -f / fp
        new = cur + step
        converged = (np.abs(step) <= STEP_TOL) | (f == 0.0)
        bad = ~((new >= lo) & (new <= hi) | converged)  # also catches NaN
        new = np.where(bad, np.where(np.isfinite(lo), 0.5 * (lo + hi), cur - 4.0), new)
        eta[idx], eta_lo[idx], eta_hi[idx] = np.where(f == 0.0, cur, new), lo, hi
        iters[idx] = it
        done[idx[converged]] = True
        idx = idx[~converged]
    return _lifted_from_d(w, b, e, xlo, m, np.exp(eta), np), iters, done


def lifted_from_tension_scalar(w: float, b: float, h: float, x: float) -> tuple[Lifted, int, bool]:
    """Problem 4 for one element in plain floats (the node's and the CLI's fast path).

    Same formulas, start, safeguard and stopping test as :func:`lifted_from_tension`, written out
    inline with local ``math`` functions (``_uplift_setup``, ``_uplift_residual``,
    ``_lifted_from_d`` in the same operation order): about twice as fast
    as calling those helpers through the ``_MATH`` namespace, same results.
    """
    log, log1p, exp, expm1, sinh, tanh = (
        math.log,
        math.log1p,
        math.exp,
        math.expm1,
        math.sinh,
        math.tanh,
    )
    sqrt = math.sqrt
    e = h / b
    r02 = e * (2.0 + e)
    xlo = log1p(e)
    m = x / b
    x0 = log1p(e + sqrt(r02))  # acosh1p(e)
    d_max = x0 - xlo
    eta_hi = log(d_max)
    c1 = x0 * x0 / (d_max * (r02 + d_max))
    sc = math.ldexp(1.0, -math.frexp(m)[1])  # _scale: the model and residual in d sc
    ms, r02s = m * sc, r02 * sc
    q = ms * ms / c1
    r02_sq = r02s * r02s
    d = 2.0 * q / (r02s + sqrt(r02_sq + 4.0 * q)) / sc
    frac = d / d_max
    if frac < 1.0:  # else the second model solve gives the same d
        c0 = 2.0 * (1.0 + e) * xlo / r02
        q = q * exp((frac - 1.0) * log(c0 * c0 / c1))
        d = 2.0 * q / (r02s + sqrt(r02_sq + 4.0 * q)) / sc
    eta = log(d if d > 1e-300 else 1e-300)
    if eta > eta_hi:
        eta = eta_hi
    neg_inf = -math.inf
    eta_lo = neg_inf
    tol = STEP_TOL
    it = 0
    converged = False
    while it < MAXITER:
        it += 1
        d = exp(eta)
        big_x = xlo + d
        em = expm1(d)
        ed = 1.0 + em
        p = r02 + em / ed
        q = big_x / (ms * sinh(big_x))
        f = log((em * sc) * (p * sc) * (q * q))  # numpy's ** 2 on arrays is this product
        if f < 0.0:
            if eta > eta_lo:
                eta_lo = eta
        else:
            if f == 0.0:
                converged = True
                break
            if eta < eta_hi:  # f > 0 (or NaN, as the scalar code always did)
                eta_hi = eta
        step = -f / ((ed / em + 1.0 / (ed * p) - 2.0 * (1.0 / tanh(big_x) - 1.0 / big_x)) * d)
        if -tol <= step <= tol:
            eta += step
            converged = True
            break
        eta += step
        if not eta_lo <= eta <= eta_hi:
            eta = 0.5 * (eta_lo + eta_hi) if eta_lo > neg_inf else eta - step - 4.0
    # _lifted_from_d, inline
    big_x = xlo + exp(eta)
    s = m / big_x
    half = sinh(0.5 * big_x)
    sx = sinh(big_x)
    cm1 = 2.0 * half * half
    t = (e - cm1) / sx
    if t <= 0.0:  # max(t, 0), NaN kept
        t = 0.0
    wb = w * b
    c = 1.0 + cm1
    atan = math.atan
    # Lifted(horizontal_tension, uplift_force, anchor_angle, top_tension, top_angle,
    # suspended_length)
    return (
        _new_tuple(
            Lifted,
            (
                wb * s,
                wb * t,
                atan(t / s),
                wb * (c + t * sx),
                atan((t * c + sx) / s),
                b * (t * cm1 + sx),
            ),
        ),
        it,
        converged,
    )


# --------------------------------------------------------------------------------------------
# Load margin: the hook tension at which a no-uplift chain just reaches the anchor at x.
# --------------------------------------------------------------------------------------------
def critical_parameter(h: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Catenary parameter ``a`` [m] of the no-uplift chain spanning (x, h); vectorized.

    Solves ``2 a sinh(x/2a)**2 = h``, i.e. ``sinh(D)**2 / D = h / x`` with ``D = x / (2a)``, by
    safeguarded Newton in ``log D`` (the left side is increasing in D).  The critical hook
    tension is ``w (a + h)``.  Returns ``a`` and a converged flag.
    """
    c = h / x
    log_c = np.log(c)
    pos = (log_c - _CRIT_Y0) * _CRIT_INV_DY
    outside = ~((pos >= 0.0) & (pos < _CRIT_N))
    k = np.where(outside, 0.0, pos).astype(np.intp)
    eta = _hermite(pos - k, *(tab[k] for tab in _CRIT_TABLE))
    if outside.any():
        eta[outside] = _critical_series_start(c[outside])
    eta = _critical_newton(eta, log_c, fast_steps=1)  # one residual converges from the table
    return x / (2.0 * np.exp(eta)), np.isfinite(eta)


def _critical_newton(
    eta: np.ndarray, log_c: np.ndarray, fast_steps: int = FAST_STEPS
) -> np.ndarray:
    """Newton in ``eta = log D`` from ``eta`` (updated in place), steps clipped to +-4.

    The first ``fast_steps`` steps run on the whole arrays; then only on the moving elements.
    """
    idx = np.arange(eta.size)
    for it in range(MAXITER):
        if idx.size == 0:
            break
        if it < fast_steps:  # whole arrays: no gather while most elements are still moving
            f, fp = _critical_residual(eta, log_c, np)
            step = np.clip(-f / fp, -4.0, 4.0)
            eta += step
            if it == fast_steps - 1:
                idx = np.flatnonzero(~(np.abs(step) <= STEP_TOL))
            continue
        f, fp = _critical_residual(eta[idx], log_c[idx], np)
        step = np.clip(-f / fp, -4.0, 4.0)
        eta[idx] += step
        idx = idx[~(np.abs(step) <= STEP_TOL)]
    eta[idx] = np.nan  # not converged within MAXITER
    return eta


def _critical_residual(eta: Any, log_c: Any, xp: Any) -> tuple[Any, Any]:
    """``log(sinh(D)^2 / (D c))`` and its derivative in ``eta = log D`` (``D coth D`` terms)."""
    d = xp.exp(eta)
    # log sinh D = D + log1p(-exp(-2D)) - log 2: no overflow for large D.
    log_sinh = d + xp.log(-xp.expm1(-2.0 * d)) - _LOG_2
    f = 2.0 * log_sinh - eta - log_c
    fp = 2.0 * d / xp.tanh(d) - 1.0
    return f, fp


def _critical_series_start(c: np.ndarray) -> np.ndarray:
    """Start ``log D`` outside the table: the series inverse ``D = c - c^3/3 + 13 c^5/45`` for
    small c (``sinh(D)^2/D = D + D^3/3 + 2 D^5/45 + ...``), ``~ e^{2D}/(4D)`` for large D."""
    big = np.log(4.0 * np.maximum(c, 1.0))
    c2 = c * c
    d0 = np.where(
        c < 0.5,
        c * (1.0 - c2 * (1.0 / 3.0 - c2 * (13.0 / 45.0))),
        np.where(c < 1.0, c, 0.5 * (big + np.log(np.maximum(0.5 * big, 1.0)))),
    )
    return np.log(np.maximum(d0, 1e-300))


def _hermite(t: Any, y0: Any, y1: Any, s0: Any, s1: Any) -> Any:
    """Cubic Hermite interpolation on [0, 1] from end values y0, y1 and end slopes s0, s1."""
    return y0 + t * (
        s0 + t * ((3.0 * (y1 - y0) - 2.0 * s0 - s1) + t * (2.0 * (y0 - y1) + s0 + s1))
    )


def critical_parameter_scalar(h: float, x: float) -> float:
    """Scalar twin of :func:`critical_parameter` (same start and stopping test), inline ``math``.

    Returns NaN if Newton has not converged after MAXITER residuals (never on the physical domain).
    """
    log, exp, expm1, tanh = math.log, math.exp, math.expm1, math.tanh
    c = h / x
    log_c = log(c)
    pos = (log_c - _CRIT_Y0) * _CRIT_INV_DY
    if 0.0 <= pos < _CRIT_N:  # _hermite, inline
        k = int(pos)
        t = pos - k
        y0, y1, s0, s1 = _CRIT_ETA[k], _CRIT_ETA[k + 1], _CRIT_SLOPE[k], _CRIT_SLOPE[k + 1]
        eta = y0 + t * (
            s0 + t * ((3.0 * (y1 - y0) - 2.0 * s0 - s1) + t * (2.0 * (y0 - y1) + s0 + s1))
        )
    elif c < 0.5:  # _critical_series_start, inline
        c2 = c * c
        eta = log(c * (1.0 - c2 * (1.0 / 3.0 - c2 * (13.0 / 45.0))))
    else:
        big = log(4.0 * c)
        eta = log(0.5 * (big + log(max(0.5 * big, 1.0))))
    log_2 = _LOG_2
    tol = STEP_TOL
    for _ in range(MAXITER):
        d = exp(eta)
        f = 2.0 * (d + log(-expm1(-2.0 * d)) - log_2) - eta - log_c  # _critical_residual
        step = -f / (2.0 * d / tanh(d) - 1.0)
        if step > 4.0:  # the clip of the vectorized path
            step = 4.0
        elif step < -4.0:
            step = -4.0
        eta += step
        if -tol <= step <= tol:
            return x / (2.0 * exp(eta))
    return math.nan


_LOG_2 = math.log(2.0)
# Start of the load-margin solve: ``eta = log D`` tabulated against ``log c`` on a uniform grid
# (c = h/x from 0.02 to 7e9, 1066 nodes), interpolated by cubic Hermite with the exact slopes
# ``d eta / d log c = 1 / (2 D coth D - 1)``.  The start is within ~2e-10 of the root, so the
# first Newton step is already below STEP_TOL: one residual, against 2-4 from the series start
# (which stays below c = 0.02, where it is within 1e-10).  The table is solved at import by the
# vectorized Newton from the series start (about 1 ms).
_CRIT_Y0, _CRIT_DY = math.log(0.02), 0.025
_CRIT_INV_DY = 1.0 / _CRIT_DY
_CRIT_N = 0  # no table while it is being built


def _critical_table(
    n: int, y0: float = _CRIT_Y0, dy: float = _CRIT_DY
) -> tuple[list[float], list[float]]:
    """``eta = log D`` at ``log c = y0 + k dy`` (k = 0..n), solved by Newton, and the slopes
    ``d eta / dk`` of the Hermite interpolation."""
    log_c = y0 + dy * np.arange(n + 1)
    eta = _critical_newton(_critical_series_start(np.exp(log_c)), log_c)
    d = np.exp(eta)
    slope = dy / (2.0 * d / np.tanh(d) - 1.0)
    return eta.tolist(), slope.tolist()


_CRIT_ETA, _CRIT_SLOPE = _critical_table(1065)
_CRIT_N = 1065
_CRIT_TABLE = (
    np.array(_CRIT_ETA[:-1]),
    np.array(_CRIT_ETA[1:]),
    np.array(_CRIT_SLOPE[:-1]),
    np.array(_CRIT_SLOPE[1:]),
)


# --------------------------------------------------------------------------------------------
# Problem 5: paid-out chain length Lm and span x given (Hou et al. 2005).
# --------------------------------------------------------------------------------------------
def grounded_parameter_from_length(
    h: np.ndarray, excess: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Catenary parameter [m] of a chain lying on the seabed, from ``excess = Lm - x``.

    With ``theta = acosh(1 + h/a)`` (the suspended span over a), suspended length minus span is
    ``a (sinh(theta) - theta)`` and ``h = a (cosh(theta) - 1)``, so theta solves
    ``(sinh(theta) - theta) / (2 sinh(theta/2)**2) = excess / h``, left side increasing from 0
    to 1; requires ``0 < excess < h``.  ``sinh(theta) - theta`` uses its series below 0.5.
    Bisection-safeguarded Newton in theta.  Returns ``a`` and a converged flag.
    """
    target = excess / h
    lo = np.zeros_like(target)
    hi = np.full_like(target, 2.0)
    while True:  # widen the upper bound until it brackets (the ratio tends to 1)
        grow = _excess_ratio(hi) < target
        if not grow.any():
            break
        hi = np.where(grow, 2.0 * hi, hi)
    theta = np.minimum(3.0 * target, 0.5 * hi)  # ratio ~ theta/3 for small theta
    done = np.zeros(theta.shape, dtype=bool)
    for _ in range(4 * MAXITER):
        r = _excess_ratio(theta)
        f = r - target
        lo = np.where(f < 0.0, theta, lo)
        hi = np.where(f > 0.0, theta, hi)
        dr = _excess_ratio_derivative(theta, r)
        new = theta - f / dr
        new = np.where((new > lo) & (new < hi), new, 0.5 * (lo + hi))
        step = np.abs(new - theta)
        theta = np.where(done, theta, new)
        done |= (step <= 4.0 * np.finfo(float).eps * theta) | (f == 0.0)
        if done.all():
            break
    half = np.sinh(0.5 * theta)
    return h / (2.0 * half * half), done


def _sinh_minus_x(z: np.ndarray) -> np.ndarray:
    """``sinh(z) - z`` without cancellation (series for |z| < 0.5)."""
    z2 = z * z
    series = (
        z
        * z2
        / 6.0
        * (
            1.0
            + z2
            / 20.0
            * (
                1.0
                + z2
                / 42.0
                * (1.0 + z2 / 72.0 * (1.0 + z2 / 110.0 * (1.0 + z2 / 156.0 * (1.0 + z2 / 210.0))))
            )
        )
    )
    return np.where(np.abs(z) < 0.5, series, np.sinh(z) - z)


def _excess_ratio(theta: np.ndarray) -> np.ndarray:
    half = np.sinh(0.5 * theta)
    return _sinh_minus_x(theta) / (2.0 * half * half)


def _excess_ratio_derivative(theta: np.ndarray, ratio: np.ndarray) -> np.ndarray:
    # d/dtheta [(sinh t - t)/(cosh t - 1)] = (cosh t - 1 - ratio sinh t)/(cosh t - 1)
    half = np.sinh(0.5 * theta)
    cm1 = 2.0 * half * half
    return (cm1 - ratio * np.sinh(theta)) / cm1


def taut_parameter_from_length(
    h: np.ndarray, x: np.ndarray, length: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Catenary parameter of a fully suspended chain of given length between two points.

    Solves ``sqrt(L^2 - h^2) = 2 a sinh(x / 2a)`` (requires ``L^2 > x^2 + h^2``), i.e.
    ``sinh(D)/D - 1 = k - 1`` with ``D = x/(2a)`` and ``k - 1 = (sqrt(L^2 - h^2) - x) / x``, by
    Newton in D from an upper start (the left side is convex, so Newton from above decreases
    monotonically).  ``sinh(D)/D - 1`` and ``D cosh D - sinh D`` use their series for small D,
    so a nearly straight chain (D -> 0, the high tensions of a lifted anchor) keeps full
    relative accuracy.  Stops after a step below ``4 eps D`` or once a step no longer decreases
    D (rounding level: the iterates can only fall while above the root).
    """
    chord = np.sqrt((length - h) * (length + h))
    km1 = (chord - x) / x
    k = 1.0 + km1
    d = np.maximum(
        np.sqrt(6.0 * np.maximum(km1, 0.0)), np.log(2.0 * k) + np.log(np.log(2.0 * k) + 1.0)
    )
    done = np.zeros(d.shape, dtype=bool)
    eps4 = 4.0 * np.finfo(float).eps
    for _ in range(4 * MAXITER):
        f = _sinh_minus_x(d) / d - km1  # sinh(D)/D - k
        fp = _d_cosh_minus_sinh(d) / (d * d)  # d/dD sinh(D)/D
        new = d - f / fp
        stop = (np.abs(new - d) <= eps4 * d) | ~(new < d)
        new = np.where(done | (~(new < d) & ~done), d, new)
        done |= stop
        d = new
        if done.all():
            break
    return x / (2.0 * d), done


def _d_cosh_minus_sinh(z: np.ndarray) -> np.ndarray:
    """``z cosh(z) - sinh(z)`` without cancellation (series ``sum 2n z^(2n+1)/(2n+1)!`` below
    0.5)."""
    z2 = z * z
    series = (
        z
        * z2
        / 3.0
        * (
            1.0
            + z2
            / 10.0
            * (
                1.0
                + z2
                / 28.0
                * (1.0 + z2 / 54.0 * (1.0 + z2 / 88.0 * (1.0 + z2 / 130.0 * (1.0 + z2 / 180.0))))
            )
        )
    )
    return np.where(np.abs(z) < 0.5, series, z * np.cosh(z) - np.sinh(z))


def taut_parameter_from_length_scalar(h: float, x: float, length: float) -> tuple[float, bool]:
    """:func:`taut_parameter_from_length` for one element in plain floats (the monitor's
    per-sample path): the same start, Newton step, stopping test and series, in the same
    operation order. Raises what :mod:`math` raises (ValueError, OverflowError,
    ZeroDivisionError) where numpy would give NaN or inf: the caller hands those to the array
    path."""
    sqrt, log = math.sqrt, math.log
    chord = sqrt((length - h) * (length + h))
    km1 = (chord - x) / x
    k = 1.0 + km1
    d = _maximum(sqrt(6.0 * _maximum(km1, 0.0)), log(2.0 * k) + log(log(2.0 * k) + 1.0))
    eps4 = 4.0 * _EPS
    done = False
    for _ in range(4 * MAXITER):
        f = _sinh_minus_x_scalar(d) / d - km1
        fp = _d_cosh_minus_sinh_scalar(d) / (d * d)
        new = d - f / fp
        falls = new < d
        done = abs(new - d) <= eps4 * d or not falls
        d = new if falls else d
        if done:
            break
    return x / (2.0 * d), done


def _maximum(a: float, b: float) -> float:
    """``np.maximum`` of two floats (NaN if either is)."""
    return a if (a != a or a >= b) else b


def _sinh_minus_x_scalar(z: float) -> float:
    """:func:`_sinh_minus_x` of one float."""
    if not abs(z) < 0.5:
        return math.sinh(z) - z
    z2 = z * z
    return (
        z
        * z2
        / 6.0
        * (
            1.0
            + z2
            / 20.0
            * (
                1.0
                + z2
                / 42.0
                * (1.0 + z2 / 72.0 * (1.0 + z2 / 110.0 * (1.0 + z2 / 156.0 * (1.0 + z2 / 210.0))))
            )
        )
    )


def _d_cosh_minus_sinh_scalar(z: float) -> float:
    """:func:`_d_cosh_minus_sinh` of one float."""
    if not abs(z) < 0.5:
        return z * math.cosh(z) - math.sinh(z)
    z2 = z * z
    return (
        z
        * z2
        / 3.0
        * (
            1.0
            + z2
            / 10.0
            * (
                1.0
                + z2
                / 28.0
                * (1.0 + z2 / 54.0 * (1.0 + z2 / 88.0 * (1.0 + z2 / 130.0 * (1.0 + z2 / 180.0))))
            )
        )
    )

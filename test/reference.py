"""50-digit mpmath reference solutions, written from the seed paper's own equations (1) and (2).

Independent of the project's formulation: the uplift state is found by solving the paper's
equation (1), y(x; alpha) = h, for the anchor angle, with the catenary parameter eliminated
through the anchor-end tension. Used only by the tests.
"""

from __future__ import annotations

import mpmath as mp

DPS = 50  # digits; bisection to 2**-200 of the bracket keeps every result to ~50 digits


def _mp(*values):
    return [v if isinstance(v, mp.mpf) else mp.mpf(float(v)) for v in values]


def _bisect(f, lo, hi, iterations=200):
    """Root of an increasing function on [lo, hi] by bisection (2**-200 of the bracket)."""
    for _ in range(iterations):
        mid = (lo + hi) / 2
        if f(mid) > 0:
            hi = mid
        else:
            lo = mid
    return (lo + hi) / 2


def grounded(w, h, a):
    """Problem 1/3 with a = R/w: x_min, L, top angle (deg) from y(x) = h at alpha = 0."""
    with mp.workdps(DPS):
        w, h, a = _mp(w, h, a)
        x = a * mp.acosh(1 + h / a)
        length = a * mp.sinh(x / a)  # eq. (2), alpha = 0
        beta = mp.degrees(mp.atan(mp.sinh(x / a)))
        return {
            'min_anchor_distance': x,
            'suspended_length': length,
            'top_angle_deg': beta,
            'horizontal_tension': w * a,
            'top_tension': w * (a + h),
        }


def uplift_from_tension(w, t, h, x):
    """Problem 4: hook tension T and span x < x_min -> R, F, alpha, L, beta (paper eqs. 1, 2)."""
    with mp.workdps(DPS):
        w, t, h, x = _mp(w, t, h, x)
        b = t / w - h  # anchor-end tension / w
        # Anchor angle alpha: a = b cos(alpha); equation (1) y(x; alpha) = h.

        def y_minus_h(alpha):
            a = b * mp.cos(alpha)
            return a * (mp.sec(alpha) * (mp.cosh(x / a) - 1) + mp.tan(alpha) * mp.sinh(x / a)) - h

        alpha = _bisect(y_minus_h, mp.mpf(0), mp.pi / 2)
        a = b * mp.cos(alpha)
        length = a * (mp.tan(alpha) * (mp.cosh(x / a) - 1) + mp.sec(alpha) * mp.sinh(x / a))
        top_slope = mp.sinh(mp.asinh(mp.tan(alpha)) + x / a)
        return {
            'horizontal_tension': w * a,
            'uplift_force': w * a * mp.tan(alpha),
            'anchor_angle_deg': mp.degrees(alpha),
            'suspended_length': length,
            'top_angle_deg': mp.degrees(mp.atan(top_slope)),
        }


def uplift_from_horizontal(w, h, r, x):
    """Problem 2: R and x given -> alpha from equation (1), F, T, L."""
    with mp.workdps(DPS):
        w, h, r, x = _mp(w, h, r, x)
        a = r / w

        def y_minus_h(alpha):
            return a * (mp.sec(alpha) * (mp.cosh(x / a) - 1) + mp.tan(alpha) * mp.sinh(x / a)) - h

        alpha = _bisect(y_minus_h, mp.mpf(0), mp.pi / 2)
        length = a * (mp.tan(alpha) * (mp.cosh(x / a) - 1) + mp.sec(alpha) * mp.sinh(x / a))
        v_top = r * mp.tan(alpha) + w * length
        return {
            'anchor_angle_deg': mp.degrees(alpha),
            'uplift_force': r * mp.tan(alpha),
            'top_tension': mp.sqrt(r * r + v_top * v_top),
            'suspended_length': length,
            'top_angle_deg': mp.degrees(mp.atan(v_top / r)),
        }


def critical_tension(w, h, x):
    """Hook tension at which a no-uplift chain just spans (x, h): a (cosh(x/a) - 1) = h."""
    with mp.workdps(DPS):
        w, h, x = _mp(w, h, x)
        # d = x / 2a solves sinh(d)^2 / d = h / x; bracket it on a log scale.
        c = h / x

        def f(ld):
            return 2 * mp.log(mp.sinh(mp.exp(ld))) - ld - mp.log(c)

        ld = _bisect(f, mp.mpf(-80), mp.mpf(8))
        a = x / (2 * mp.exp(ld))
        return w * (a + h)


def grounded_from_length(w, h, length, x):
    """Problem 5 (Hou 2005): chain of length Lm on the seabed, span x -> R, grounded length."""
    with mp.workdps(DPS):
        w, h, length, x = _mp(w, h, length, x)

        def excess(log_a):  # (suspended length - span) - (Lm - x), decreasing in a
            a = mp.exp(log_a)
            return -((mp.sqrt(h * h + 2 * a * h) - a * mp.acosh(1 + h / a)) - (length - x))

        a = mp.exp(_bisect(excess, mp.log(h) - 200, mp.log(h) + 200, iterations=260))
        return {
            'horizontal_tension': w * a,
            'grounded_length': length - mp.sqrt(h * h + 2 * a * h),
        }

"""The uplift envelope: from each direction, the smallest load (and wind) that lifts an anchor.

Along a ray of loads ``lam * pattern`` (a horizontal force of ``lam`` newtons pushing from
direction ``phi``; or the wind load of :func:`~catenary_monitor.core.body.loads.
wind_load_per_speed2` with ``lam = V^2``) the dock is solved in equilibrium, warm-started from
the previous point, and each line's lift indicator

    z = grounded length + (allowed uplift - uplift) / w        [m]

is followed: positive while some chain lies on the seabed, zero when the anchor starts to lift
(or its uplift reaches ``allowed_uplift``), negative beyond. The smallest ``lam`` where the
lowest z reaches 0 is bracketed by steps of ``GROWTH`` from a guess (the previous direction's
answer), then found by Brent's method to ``RTOL``; the line it belongs to is the first to lift.
"""

from __future__ import annotations

import math
from typing import Callable, NamedTuple, Optional

import numpy as np
from scipy.optimize import brentq

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.equilibrium import (
    Equilibrium,
    EquilibriumStatus,
    solve_equilibrium,
)
from catenary_monitor.core.body.loads import push_direction, wind_load_per_speed2

__all__ = ['Lift', 'lift_indicator', 'first_lift', 'EnvelopeRow', 'uplift_envelope']

#: Relative tolerance on the lifting load.
RTOL = 1e-6
#: Bracketing step factor along the ray.
GROWTH = 1.5
#: Largest force [N] and wind speed [m/s] searched.
MAX_FORCE = 1e9
MAX_WIND = 150.0


def lift_indicator(model: DockModel, eq: Equilibrium) -> np.ndarray:
    """Per line: grounded length + (allowed uplift - uplift) / w [m]; <= 0 is lifted."""
    assert eq.lines is not None
    st = eq.lines.statics
    return st.grounded_length + (model.allowed_uplift - st.uplift_force) / model.weight


class Lift(NamedTuple):
    """The first lift along one ray: ``scale`` (N, or (m/s)^2 for wind), the line, the
    equilibrium there; ``status`` ``'lifts'``, ``'lifted at rest'``, ``'none below limit'``
    or the equilibrium status that stopped the search."""

    scale: float
    line: Optional[str]
    equilibrium: Optional[Equilibrium]
    status: str


def first_lift(
    model: DockModel,
    depth: float,
    pattern: np.ndarray,
    guess: float,
    limit: float,
) -> Lift:
    """Smallest ``lam`` in ``[0, limit]`` at which ``lam * pattern`` lifts an anchor."""
    cache: dict[float, Equilibrium] = {}
    starts: list[tuple[float, np.ndarray]] = [(0.0, np.zeros(3))]

    def solve(lam: float) -> Equilibrium:
        if lam not in cache:
            near = min(starts, key=lambda p: abs(p[0] - lam))[1]
            eq = solve_equilibrium(model, depth, lam * pattern, start=near)
            cache[lam] = eq
            if eq.status == EquilibriumStatus.CONVERGED:
                starts.append((lam, eq.offset))
        return cache[lam]

    def z_min(lam: float) -> float:
        return float(np.min(lift_indicator(model, solve(lam))))

    rest = solve(0.0)
    if rest.status != EquilibriumStatus.CONVERGED:
        return Lift(math.nan, None, rest, rest.status.name.lower())
    if z_min(0.0) <= 0.0:
        return Lift(0.0, _lowest(model, rest), rest, 'lifted at rest')
    lo, hi = 0.0, max(guess, limit * 1e-6)
    while True:
        eq = solve(hi)
        if eq.status != EquilibriumStatus.CONVERGED:
            return Lift(math.nan, None, eq, eq.status.name.lower())
        if z_min(hi) <= 0.0:
            break
        if hi >= limit:
            return Lift(math.nan, None, eq, 'none below limit')
        lo, hi = hi, min(hi * GROWTH, limit)
    lam = _root(z_min, lo, hi)
    eq = solve(lam)
    return Lift(lam, _lowest(model, eq), eq, 'lifts')


def _root(fun: Callable[[float], float], lo: float, hi: float) -> float:
    """The lifting scale in ``[lo, hi]`` (``fun(lo) > 0 >= fun(hi)``) by Brent's method."""
    f_hi = fun(hi)
    if f_hi == 0.0:
        return hi
    return float(brentq(fun, lo, hi, xtol=1e-300, rtol=RTOL, maxiter=200))


def _lowest(model: DockModel, eq: Equilibrium) -> str:
    return model.names[int(np.argmin(lift_indicator(model, eq)))]


class EnvelopeRow(NamedTuple):
    """One direction of the envelope (from ``direction_deg``, clockwise from the bow)."""

    direction_deg: float
    force: float  # N, smallest horizontal force from there that lifts an anchor (NaN: none)
    force_line: Optional[str]
    force_status: str
    wind: float  # m/s, smallest wind speed from there that lifts an anchor (NaN: none)
    wind_line: Optional[str]
    wind_status: str
    wind_load: float  # N, |wind load| at that speed


def uplift_envelope(
    model: DockModel,
    depth: float,
    directions: np.ndarray,
    wind: bool = True,
    progress: Optional[Callable[[int, int], None]] = None,
) -> list[EnvelopeRow]:
    """The envelope at ``depth`` [m] over ``directions`` [deg, from, clockwise from the bow].

    ``wind=False`` skips the wind search (no projected areas needed). ``progress(i, n)`` is
    called after each direction.
    """
    rows = []
    g_force, g_wind = 1e5, 100.0
    for i, phi in enumerate(np.asarray(directions, dtype=float).tolist()):
        push = push_direction(phi)
        f = first_lift(model, depth, np.array([push[0], push[1], 0.0]), g_force, MAX_FORCE)
        if math.isfinite(f.scale) and f.scale > 0:
            g_force = f.scale / GROWTH
        w_scale, w_line, w_status, w_load = math.nan, None, 'not computed', math.nan
        if wind:
            pattern = wind_load_per_speed2(model.dock, phi)
            lw = first_lift(model, depth, pattern, g_wind, MAX_WIND**2)
            w_scale, w_line, w_status = lw.scale, lw.line, lw.status
            if math.isfinite(lw.scale):
                w_load = float(math.hypot(*(pattern[:2] * lw.scale)))
                if lw.scale > 0:
                    g_wind = lw.scale / GROWTH
        rows.append(
            EnvelopeRow(
                phi,
                f.scale,
                f.line,
                f.status,
                math.sqrt(w_scale) if math.isfinite(w_scale) else math.nan,
                w_line,
                w_status,
                w_load,
            )
        )
        if progress is not None:
            progress(i + 1, len(directions))
    return rows

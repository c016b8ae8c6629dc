"""Static equilibrium of the dock in surge, sway and yaw under a given load.

Solves ``restoring(q) + load = 0`` (:func:`catenary_monitor.core.body.dock_model.line_states`) for
the offset ``q = (X, Y, psi)`` by Newton with the analytic stiffness, safeguarded:

* the step ``K^-1 G`` (least squares where K is singular, e.g. a yaw nobody resists) is capped
  at ``MAX_STEP`` of the shortest chain in translation and ``MAX_YAW_STEP`` in yaw;
* a backtracking line search on the scaled residual ``|G|^2`` (forces over the force scale,
  the moment over the force scale times the dock's size) halves the step until the residual
  falls by the Armijo fraction and every inextensible chain can still reach its anchor;
* where K is singular and part of the load is resisted by nothing (a slack side), the dock
  moves with it by full steps until a chain takes it up;
* where even a tiny Newton step does not lower the residual, Levenberg-Marquardt steps
  ``(K^T K + mu D) d = K^T G`` with growing ``mu`` take over.

It stops when the scaled residual is below ``FORCE_TOL`` (relative to the load and line
tensions), or when the Newton step is below ``STEP_TOL`` of the dock's size (the offset is
known to rounding; near a taut inextensible chain the force cannot be resolved further).
Never a silent non-convergence: the result has a named :class:`EquilibriumStatus` and message.
``NO_EQUILIBRIUM`` is the dock drifting away (the chains cannot balance the load near the
dock's station: it moved farther than the shortest anchor distance, over an anchor);
``NO_CONVERGENCE`` the iteration cap or a residual no step lowers; ``LINE_FAILED`` a line state
that cannot be computed; ``BAD_INPUT`` a non-finite load or a non-positive depth.
"""

from __future__ import annotations

import math
from enum import IntEnum
from typing import NamedTuple, Optional

import numpy as np

from catenary_monitor.core.body.dock_model import BodyLines, DockModel, line_states
from catenary_monitor.core.physics.fixed_length import LineRegime

__all__ = [
    'EquilibriumStatus',
    'EQUILIBRIUM_MESSAGES',
    'Equilibrium',
    'solve_equilibrium',
    'FORCE_TOL',
    'MAXITER',
    'LINE_KEYS',
    'line_report',
]

#: Converged when |G| (scaled) is below this, relative to the largest of the load, the line
#: tensions and the chains' weight in water.
FORCE_TOL = 1e-11
#: ... or when the Newton step is below this, relative to the dock's size (yaw: in rad).
STEP_TOL = 1e-13
#: ... provided the residual is below this (the force rounding floor next to taut chains).
ROUNDING_TOL = 1e-6
#: Newton iteration cap (a 12-line dock converges in 3-8 from rest, docs/dock_body.md).
MAXITER = 100
#: Largest translation step, as a fraction of the shortest chain, and yaw step [rad].
MAX_STEP = 0.25
MAX_YAW_STEP = 0.05
_ARMIJO = 1e-4
_HALVINGS = 40


class EquilibriumStatus(IntEnum):
    """Outcome of :func:`solve_equilibrium`."""

    CONVERGED = 0
    NO_EQUILIBRIUM = 1
    NO_CONVERGENCE = 2
    LINE_FAILED = 3
    BAD_INPUT = 4


EQUILIBRIUM_MESSAGES = {
    EquilibriumStatus.CONVERGED: 'equilibrium found',
    EquilibriumStatus.NO_EQUILIBRIUM: (
        'no equilibrium: the chains cannot hold this load, the dock drifts away'
    ),
    EquilibriumStatus.NO_CONVERGENCE: 'the equilibrium solve did not converge (please report)',
    EquilibriumStatus.LINE_FAILED: 'a line state cannot be computed at this offset',
    EquilibriumStatus.BAD_INPUT: 'load must be finite and depth > 0',
}


class Equilibrium(NamedTuple):
    """The dock at rest under ``load``: offset, lines, and how the solve went (SI)."""

    status: EquilibriumStatus
    offset: np.ndarray  # (X, Y, psi): m, m, rad
    load: np.ndarray  # (Fx, Fy, Mz): N, N, N m
    depth: float  # m, tide depth at the hooks
    lines: Optional[BodyLines]
    iterations: int
    residual: np.ndarray  # restoring + load at the answer (N, N, N m)

    @property
    def message(self) -> str:
        """One sentence for the status."""
        return EQUILIBRIUM_MESSAGES[self.status]

    @property
    def offset_x(self) -> float:
        """Surge offset [m] (toward the bow)."""
        return float(self.offset[0])

    @property
    def offset_y(self) -> float:
        """Sway offset [m] (to port)."""
        return float(self.offset[1])

    @property
    def yaw_deg(self) -> float:
        """Yaw [deg], counter-clockwise seen from above (bow to port), REP 103."""
        return math.degrees(float(self.offset[2]))


def _scales(model: DockModel, lines: BodyLines, load: np.ndarray) -> tuple[float, float]:
    """(force scale N, length scale m) of the residual."""
    weight = float(np.sum(model.weight * lines.depth))
    tensions = lines.statics.horizontal_tension
    f = max(float(np.hypot(load[0], load[1])), abs(load[2]) / model.size, weight)
    if np.all(np.isfinite(tensions)):
        f = max(f, float(np.sum(tensions)))
    return f, model.size


def _merit(g: np.ndarray, f_scale: float, l_scale: float) -> float:
    if not np.all(np.isfinite(g)):
        return math.inf
    return float((g[0] ** 2 + g[1] ** 2 + (g[2] / l_scale) ** 2) / f_scale**2)


def solve_equilibrium(
    model: DockModel,
    depth: float,
    load: np.ndarray,
    start: Optional[np.ndarray] = None,
) -> Equilibrium:
    """Offset of the dock where its chains balance ``load = (Fx, Fy, Mz)`` [N, N, N m].

    ``depth`` is the tide depth at the hooks [m]; ``start`` an offset to start from (default:
    the reference position). See the module docstring for the method and the statuses.
    """
    load = np.asarray(load, dtype=float)
    q = np.zeros(3) if start is None else np.array(start, dtype=float)
    if not (np.all(np.isfinite(load)) and math.isfinite(depth) and depth > 0):
        return Equilibrium(
            EquilibriumStatus.BAD_INPUT, q, load, depth, None, 0, np.full(3, np.nan)
        )
    lines = line_states(model, depth, q)
    if not lines.feasible and start is not None:
        q = np.zeros(3)
        lines = line_states(model, depth, q)
    bad = (lines.statics.regime == LineRegime.INVALID) | (
        lines.statics.regime == LineRegime.NO_CONVERGENCE
    )
    if bad.any() or not lines.feasible:
        status = EquilibriumStatus.LINE_FAILED
        return Equilibrium(status, q, load, depth, lines, 0, lines.restoring + load)
    f_scale, l_scale = _scales(model, lines, load)
    drift = float(np.min(np.hypot(*(model.anchor - model.hook).T)))
    max_step = MAX_STEP * float(np.min(model.chain_length))
    g = lines.restoring + load
    phi = _merit(g, f_scale, l_scale)
    for it in range(1, MAXITER + 1):
        if phi <= FORCE_TOL**2:
            return Equilibrium(EquilibriumStatus.CONVERGED, q, load, depth, lines, it - 1, g)
        step, drifting = _newton_step(lines.stiffness, g, max_step, l_scale)
        if drifting:  # nothing resists part of the load: move with it (no descent to test)
            trial = q + step
            moved = line_states(model, depth, trial, lines)
            if moved.feasible:
                q, lines = trial, moved
                g = lines.restoring + load
                phi = _merit(g, f_scale, l_scale)
                if math.hypot(q[0], q[1]) > drift:
                    status = EquilibriumStatus.NO_EQUILIBRIUM
                    return Equilibrium(status, q, load, depth, lines, it, g)
                continue
        small = math.hypot(step[0], step[1]) <= STEP_TOL * l_scale and abs(step[2]) <= STEP_TOL
        if small and phi <= ROUNDING_TOL**2:
            # the offset is known to rounding: near taut, |G| cannot fall further
            return Equilibrium(EquilibriumStatus.CONVERGED, q, load, depth, lines, it - 1, g)
        scales = (f_scale, l_scale)
        new = _line_search(model, depth, load, q, step, phi, scales, lines)
        if new is None:
            new = _lm_step(model, depth, load, q, lines, g, phi, scales, max_step)
        if new is None:
            return Equilibrium(EquilibriumStatus.NO_CONVERGENCE, q, load, depth, lines, it, g)
        q, lines = new
        g = lines.restoring + load
        phi = _merit(g, f_scale, l_scale)
        if math.hypot(q[0], q[1]) > drift:
            return Equilibrium(EquilibriumStatus.NO_EQUILIBRIUM, q, load, depth, lines, it, g)
    if phi <= FORCE_TOL**2:
        return Equilibrium(EquilibriumStatus.CONVERGED, q, load, depth, lines, MAXITER, g)
    return Equilibrium(EquilibriumStatus.NO_CONVERGENCE, q, load, depth, lines, MAXITER, g)


def _cap(step: np.ndarray, max_step: float) -> np.ndarray:
    """Scale ``step`` so its translation is at most ``max_step`` and its yaw MAX_YAW_STEP."""
    scale = 1.0
    trans = math.hypot(step[0], step[1])
    if trans > max_step:
        scale = max_step / trans
    if abs(step[2]) * scale > MAX_YAW_STEP:
        scale = MAX_YAW_STEP / abs(step[2])
    return step * scale


def _newton_step(
    k: np.ndarray, g: np.ndarray, max_step: float, l_scale: float
) -> tuple[np.ndarray, bool]:
    """``K^-1 G`` (pseudo-inverse where K is singular), capped; where the residual has a part
    that nothing resists (a slack side), the dock moves that way by a full step instead (it
    drifts until a chain takes the load up, or it has drifted away).

    K is symmetric; it is scaled ``D K D`` with ``D = diag(1, 1, 1/size)`` so that every entry
    is a force per length before its singular values are compared."""
    d = np.array([1.0, 1.0, 1.0 / l_scale])
    ks = k * d[:, None] * d[None, :]
    gs = g * d
    if not np.all(np.isfinite(ks)):
        return np.zeros(3), False
    u, sv, vt = np.linalg.svd(ks)
    tiny = sv <= 1e-12 * max(float(sv[0]), 1e-300)
    free = vt[tiny]
    along = free @ gs
    if tiny.any() and np.linalg.norm(along) > 1e-9 * max(float(np.linalg.norm(gs)), 1e-300):
        move = free.T @ along
        return _cap(move / np.linalg.norm(move) * 1e9 * d, max_step), True
    inv = np.where(tiny, 0.0, 1.0 / np.where(tiny, 1.0, sv))
    return _cap(d * (vt.T @ (inv * (u.T @ gs))), max_step), False


def _line_search(
    model: DockModel,
    depth: float,
    load: np.ndarray,
    q: np.ndarray,
    step: np.ndarray,
    phi: float,
    scales: tuple[float, float],
    lines: BodyLines,
) -> Optional[tuple[np.ndarray, BodyLines]]:
    """Backtrack along ``step`` to an Armijo decrease of the residual (None: none found)."""
    alpha = 1.0
    for _ in range(_HALVINGS):
        trial = q + alpha * step
        new = line_states(model, depth, trial, lines)
        if new.feasible and _merit(new.restoring + load, *scales) <= (1.0 - _ARMIJO * alpha) * phi:
            return trial, new
        alpha *= 0.5
    return None


def _lm_step(
    model: DockModel,
    depth: float,
    load: np.ndarray,
    q: np.ndarray,
    lines: BodyLines,
    g: np.ndarray,
    phi: float,
    scales: tuple[float, float],
    max_step: float,
) -> Optional[tuple[np.ndarray, BodyLines]]:
    """Levenberg-Marquardt steps with growing damping until the residual falls (None: never)."""
    f_scale, l_scale = scales
    w = np.array([1.0, 1.0, 1.0 / l_scale])  # residual weights: moment to force units
    k = lines.stiffness * w[:, None]
    gw = g * w
    a = k.T @ k
    diag = np.maximum(np.diag(a), 1e-300)
    mu = 1e-6
    while mu < 1e12:
        try:
            step = np.linalg.solve(a + mu * np.diag(diag), k.T @ gw)
        except np.linalg.LinAlgError:
            mu *= 10.0
            continue
        trial = q + _cap(step, max_step)
        new = line_states(model, depth, trial, lines)
        if new.feasible and _merit(new.restoring + load, *scales) < phi:
            return trial, new
        mu *= 10.0
    return None


#: Per-line keys of :func:`line_report` (SI; the JSON keys of ``catenary-monitor equilibrium``).
LINE_KEYS = (
    'line',
    'state',
    'anchor_distance',
    'top_tension',
    'horizontal_tension',
    'uplift_force',
    'grounded_length',
    'min_anchor_distance',
    'anchor_margin',
    'tide_margin',
    'load_margin',
    'safety_factor',
    'anchor_angle_deg',
    'top_angle_deg',
)


def line_report(model: DockModel, lines: BodyLines) -> list[dict[str, object]]:
    """Every line's state at an offset, with the monitor's margins for its tension and span.

    ``anchor_distance`` is the span hook -> anchor now; the margins are those the monitor
    computes (``solve(w, h, tension=T, anchor_distance=span, mbl=MBL, ea=EA)``, with the line's
    point loads where it has any), so
    ``anchor_margin`` < 0 is a lifted anchor. A slack line (no horizontal tension) has no
    suspended span: ``min_anchor_distance`` 0, ``anchor_margin`` the span, no ``tide_margin``
    (None: the tide margin holds R, which is 0).
    """
    from catenary_monitor.core.physics import catenary as cat
    from catenary_monitor.core.physics.point_loads import critical
    from catenary_monitor.core.physics.solve import solve

    st = lines.statics
    slack = st.regime == LineRegime.SLACK
    names = {
        int(LineRegime.SLACK): 'slack',
        int(LineRegime.GROUNDED): 'grounded',
        int(LineRegime.LIFTED): 'lifted',
    }
    rows: list[dict[str, object]] = [
        {
            'line': name,
            'state': names.get(int(st.regime[i]), LineRegime(int(st.regime[i])).name.lower()),
        }
        for i, name in enumerate(model.names)
    ]
    loaded = np.array([bool(model.loads) and model.loads[i] is not None for i in range(len(rows))])
    live = np.flatnonzero(~slack & np.isfinite(st.top_tension) & ~loaded)
    if live.size:
        ea = model.ea[live]
        res = solve(
            model.weight[live],
            lines.depth[live],
            tension=st.top_tension[live],
            anchor_distance=lines.span[live],
            mbl=model.mbl[live],
            ea=None if np.all(np.isinf(ea)) else ea,
        )
        for j, i in enumerate(live.tolist()):
            for key in LINE_KEYS[4:]:
                if key != 'grounded_length':
                    rows[i][key] = float(np.asarray(getattr(res, key))[j])
    for i in np.flatnonzero(~slack & np.isfinite(st.top_tension) & loaded).tolist():
        res = solve(
            model.weight[i],
            lines.depth[i],
            tension=st.top_tension[i],
            anchor_distance=lines.span[i],
            mbl=model.mbl[i],
            point_loads=model.loads[i],
        )
        for key in LINE_KEYS[4:]:
            if key != 'grounded_length':
                rows[i][key] = float(getattr(res, key))
    for i in np.flatnonzero(slack).tolist():
        w, h, s, t = model.weight[i], lines.depth[i], lines.span[i], st.top_tension[i]
        a_crit = float(cat.critical_parameter(np.array([h]), np.array([s]))[0][0])
        t_crit = w * (a_crit + h)
        loads = model.loads[i] if model.loads else None
        if loads is not None:  # the tension that lifts the anchor with its clumps and buoys
            h_c, crit = critical(float(w), float(h), float(s), loads)
            t_crit = math.hypot(h_c, crit.v)
        rows[i].update(
            horizontal_tension=0.0,
            uplift_force=0.0,
            min_anchor_distance=0.0,
            anchor_margin=float(s),
            tide_margin=None,
            load_margin=float(t_crit - t),
            safety_factor=float(model.mbl[i] / t),
            anchor_angle_deg=0.0,
            top_angle_deg=90.0,
        )
    for i, row in enumerate(rows):
        row['anchor_distance'] = float(lines.span[i])
        row['top_tension'] = float(st.top_tension[i])
        row['grounded_length'] = float(st.grounded_length[i])
        if 'uplift_force' in row and not slack[i]:
            row['uplift_force'] = float(st.uplift_force[i])
            row['horizontal_tension'] = float(st.horizontal_tension[i])
    return [{k: row.get(k) for k in LINE_KEYS} for row in rows]

"""The dock and its chains as one rigid body in the horizontal plane: geometry, line states and
the restoring force, yaw moment and stiffness at a given offset.

Frames (REP 103): the dock frame has x toward the bow, y to port, z up; the reference frame is
the dock frame with the dock at its reference position (offset 0), fixed to the seabed. The
dock's offset is ``q = (X, Y, psi)``: the translation of its reference point [m] and its yaw
[rad, counter-clockwise seen from above: bow to port]. A line's hook sits at ``p`` on the dock;
its anchor at ``p + x0 e(heading)`` in the reference frame, with ``e(b) = (cos b, -sin b)``
(``heading`` clockwise from the bow) and ``x0`` the installed anchor distance.

At offset q the hook is at ``P = (X, Y) + R(psi) p``; the span is ``s = |A - P|`` and the line
pulls the hook toward its anchor with ``f = R(s) u``, ``u = (A - P)/s``, where R(s) is the
horizontal tension of the fixed-length chain at that span and depth
(:func:`catenary_monitor.core.physics.fixed_length.statics_at_span`). The restoring force is ``sum
f`` and the yaw moment about the reference point ``sum (R(psi) p) x f``. The stiffness ``K = -d(F,
M)/dq`` is analytic: per line ``k = R'(s) u u^T + (R/s)(I - u u^T)`` (axial and geometric), moved
to the body by ``[I | J r]`` with ``r = R(psi) p``, ``J`` the rotation by +90 deg, plus the
moment's own ``-r.f`` term in yaw.

Heave, roll and pitch are not modelled: the dock's waterplane and metacentric stiffness are
orders above what the chains change (docs/dock_body.md gives the numbers), so the hooks stay at
the measured depth and the problem is planar.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple, Optional

import numpy as np

from catenary_monitor.core.config.parameters import DockConfig, MonitorConfig
from catenary_monitor.core.physics.fixed_length import LineRegime, LineStatics, statics_at_span
from catenary_monitor.core.physics.point_load_table import PointLoadTable, table_for
from catenary_monitor.core.physics.point_loads import PointLoads, line_statics

__all__ = ['DockModel', 'BodyLines', 'line_states', 'direction']


def direction(deg: np.ndarray | float) -> np.ndarray:
    """Unit vector(s) in the dock frame (x bow, y port) of a direction clockwise from the bow."""
    b = np.radians(deg)
    return np.stack([np.cos(b), -np.sin(b)], axis=-1)


@dataclass(frozen=True)
class DockModel:
    """The dock's lines as arrays (config order, SI): hooks (m, 2) on the dock, anchors (m, 2)
    in the reference frame, chain constants, and the dock's data for the load formulas."""

    names: tuple[str, ...]
    hook: np.ndarray
    anchor: np.ndarray
    chain_length: np.ndarray
    weight: np.ndarray
    ea: np.ndarray  # N, inf for an inextensible chain
    hook_height: np.ndarray
    mbl: np.ndarray
    allowed_uplift: np.ndarray
    tension_accuracy: np.ndarray  # N, +- bound (the estimate's sigma_T), or its default
    dock: DockConfig
    #: Per line: its clump weights and buoys (None: a plain chain); () when no line has any.
    loads: tuple[Optional[PointLoads], ...] = ()
    #: Per line with point loads: its surrogate for the live estimate (None: none; the exact
    #: solve then), over ``dock_table_depth_min`` - ``_max``; () when no line has one.
    tables: tuple[Optional[PointLoadTable], ...] = ()

    @classmethod
    def from_config(cls, config: MonitorConfig) -> DockModel:
        """The model of a configuration whose lines all have hook_x, hook_y, heading and
        chain_length (``config.has_dock_model``); ValueError naming what is missing otherwise."""
        if not config.has_dock_model:
            missing = [
                f'{line.name}.{key}'
                for line in config.lines
                for key in ('hook_x', 'hook_y', 'heading', 'chain_length')
                if getattr(line, key) is None or getattr(line, key) != getattr(line, key)
            ]
            raise ValueError(
                'the dock model needs hook_x, hook_y, heading and chain_length on every line '
                f'(not set: {", ".join(missing[:4])}{", ..." if len(missing) > 4 else ""})'
            )
        lines = config.lines

        def col(key: str) -> np.ndarray:
            return np.array([getattr(line, key) for line in lines], dtype=float)

        hook = np.stack([col('hook_x'), col('hook_y')], axis=1)
        anchor = hook + col('anchor_distance')[:, None] * direction(col('heading'))
        return cls(
            names=tuple(line.name for line in lines),
            hook=hook,
            anchor=anchor,
            chain_length=col('chain_length'),
            weight=col('weight'),
            ea=np.array([math.inf if line.ea is None else line.ea for line in lines]),
            hook_height=col('hook_height'),
            mbl=col('mbl'),
            allowed_uplift=col('allowed_uplift'),
            tension_accuracy=np.array([line.tension_accuracy_or_default for line in lines]),
            dock=config.dock,
            loads=_point_loads(config),
            tables=_tables(config),
        )

    @property
    def table_span_error(self) -> float:
        """The largest span error [m] of the lines' surrogates as measured when built (NaN:
        no line has one)."""
        errors = [t.span_error for t in self.tables if t is not None]
        return max(errors) if errors else math.nan

    @property
    def size(self) -> float:
        """Largest hook distance from the reference point [m] (1 if every hook is there)."""
        return float(max(np.max(np.hypot(self.hook[:, 0], self.hook[:, 1])), 1.0))


def _point_loads(config: MonitorConfig) -> tuple[Optional[PointLoads], ...]:
    loads = [
        None if line.point_loads is None else PointLoads.of(*line.point_loads)
        for line in config.lines
    ]
    return tuple(loads) if any(p is not None for p in loads) else ()


def _tables(config: MonitorConfig) -> tuple[Optional[PointLoadTable], ...]:
    depths = config.dock.table_depths
    if depths is None:
        return ()
    tables = [
        table_for(
            line.weight,
            float(line.chain_length or 0.0),
            None if line.point_loads is None else PointLoads.of(*line.point_loads),
            line.mbl,
            (depths[0] + line.hook_height, depths[1] + line.hook_height),
        )
        for line in config.lines
    ]
    return tuple(tables) if any(t is not None for t in tables) else ()


class BodyLines(NamedTuple):
    """Every line at one offset: its statics, geometry and pull on the dock (SI)."""

    statics: LineStatics
    depth: np.ndarray  # m, hook to seabed (tide depth + hook height)
    span: np.ndarray  # m, horizontal distance hook -> anchor now
    unit: np.ndarray  # (m, 2), unit vector hook -> anchor, reference frame
    arm: np.ndarray  # (m, 2), hook relative to the dock's reference point, reference frame
    force: np.ndarray  # (m, 2), N, pull of each line on the dock
    restoring: np.ndarray  # (3,), N and N m: sum of the pulls and their yaw moment
    stiffness: np.ndarray  # (3, 3), -d(restoring)/dq, N/m, N/rad, N m/m, N m/rad

    @property
    def feasible(self) -> bool:
        """False when an inextensible chain would have to reach beyond its length."""
        return bool(np.all(np.isfinite(self.restoring)))


def _rotation(psi: float) -> np.ndarray:
    c, s = math.cos(psi), math.sin(psi)
    return np.array([[c, -s], [s, c]])


def line_states(
    model: DockModel, depth: float, q: np.ndarray, near: Optional[BodyLines] = None
) -> BodyLines:
    """The lines, the restoring force and moment, and the stiffness at offset ``q``.

    ``depth`` is the tide depth at the hooks [m] (each line adds its hook height);
    ``q = (X, Y, psi)`` [m, m, rad]; ``near``: the lines at a nearby offset, whose tensions moved
    along their stiffness start each line's solve (a warm start; the answer does not depend on
    it beyond rounding).
    """
    arm = model.hook @ _rotation(float(q[2])).T
    d = model.anchor - (q[:2] + arm)
    span = np.hypot(d[:, 0], d[:, 1])
    with np.errstate(invalid='ignore', divide='ignore'):
        unit = d / span[:, None]
    h = depth + model.hook_height
    t_start = None
    if near is not None:
        with np.errstate(invalid='ignore'):
            t_start = near.statics.top_tension + near.statics.dt_ds * (span - near.span)
    st = statics_at_span(model.weight, h, model.chain_length, span, model.ea, t_start)
    if model.loads:
        st = _with_point_loads(model, h, span, st)
    r = st.horizontal_tension
    with np.errstate(invalid='ignore'):
        force = r[:, None] * unit
        jr = np.stack([-arm[:, 1], arm[:, 0]], axis=1)  # J r: d(arm)/d(psi)
        moment = np.sum(jr * force, axis=1)  # r x f
        restoring = np.array([force[:, 0].sum(), force[:, 1].sum(), moment.sum()])
        stiffness = _stiffness(st, span, unit, force, arm, jr)
    return BodyLines(st, h, span, unit, arm, force, restoring, stiffness)


def _with_point_loads(
    model: DockModel, h: np.ndarray, span: np.ndarray, st: LineStatics
) -> LineStatics:
    """``st`` with the lines that carry point loads solved with them
    (:func:`~catenary_monitor.core.physics.point_loads.line_statics`)."""
    cols = [np.array(c, copy=True) for c in st]
    for i, loads in enumerate(model.loads):
        if loads is None:
            continue
        w, length = float(model.weight[i]), float(model.chain_length[i])
        values = line_statics(w, float(h[i]), length, float(span[i]), loads)
        for c, v in zip(cols, values):
            c[i] = v
        cols[-1][i] = 0  # iterations: none of the elastic solve
    return LineStatics(*cols)


def _stiffness(
    st: LineStatics,
    span: np.ndarray,
    unit: np.ndarray,
    force: np.ndarray,
    arm: np.ndarray,
    jr: np.ndarray,
) -> np.ndarray:
    """``-d(F_x, F_y, M_z)/d(X, Y, psi)`` summed over the lines (see the module docstring)."""
    uu = unit[:, :, None] * unit[:, None, :]
    geometric = np.where(span > 0, st.horizontal_tension / span, 0.0)
    k = st.dr_ds[:, None, None] * uu + geometric[:, None, None] * (np.eye(2) - uu)
    kjr = np.einsum('mij,mj->mi', k, jr)
    out = np.empty((3, 3))
    out[:2, :2] = k.sum(axis=0)
    out[:2, 2] = kjr.sum(axis=0)
    out[2, :2] = kjr.sum(axis=0)  # k is symmetric: (J r)^T k
    out[2, 2] = np.sum(jr * kjr) + np.sum(arm * force)
    # d(moment)/d(psi) = sum[(J J r).f + (J r).df/dpsi] = -sum r.f - sum (J r)^T k (J r)
    return out


def slack_mask(lines: BodyLines) -> np.ndarray:
    """True for the lines that are slack (no horizontal tension)."""
    return lines.statics.regime == LineRegime.SLACK

"""The dock model built in MoorPy (a peer): one free body in surge, sway and yaw, the same lines.

Used by the tests (``test/test_body_moorpy.py``) and by ``catenary-monitor bench-body``. MoorPy
needs a finite axial stiffness: an inextensible line is given ``INEXTENSIBLE_EA``. Its lines get
``d_vol = 0`` and ``m = w / g`` so that MoorPy's submerged weight ``(m - rho pi d^2/4) g`` is ours.
MoorPy calls ``breakpoint()`` on some error paths: ``PYTHONBREAKPOINT=0`` is set here.
A line with point loads is MoorPy lines joined at free points (a clump's mass, a buoy's
volume), started where our chain at its installed span has them; the seabed touches such a
point only when it lies there (:data:`SEABED_TOL`).
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from catenary_monitor.core.body.dock_model import DockModel

os.environ.setdefault('PYTHONBREAKPOINT', '0')

__all__ = ['moorpy_system', 'moorpy_equilibrium', 'moorpy_lines', 'INEXTENSIBLE_EA']

#: EA [N] given to MoorPy for an inextensible chain (stretch ~1e-6 m at a few MN).
INEXTENSIBLE_EA = 1e14
_G = 9.81
_RHO = 1025.0
#: Height [m] above the seabed below which MoorPy lets the seabed carry part of a free point's
#: weight (its ``Point.zTol``, 2 m by default: a clump 1 m above the seabed would weigh half).
SEABED_TOL = 1e-6


def moorpy_system(model: DockModel, depth: float) -> tuple[Any, Any]:
    """A MoorPy ``System`` with the dock as one body free in DOFs 0, 1, 5 and its lines
    (hook at the water line plus its hook height, anchor on the seabed at ``depth``)."""
    import moorpy as mp

    ms = mp.System(depth=float(np.max(depth + model.hook_height)), g=_G, rho=_RHO)
    body = ms.addBody(0, np.zeros(6), DOFs=[0, 1, 5])
    ms.catenary_ends = []  # per line: (its anchor segment, its hook segment) in ms.lineList
    for i, name in enumerate(model.names):
        ea = float(model.ea[i]) if math.isfinite(model.ea[i]) else INEXTENSIBLE_EA
        line_type = {
            'name': name,
            'm': float(model.weight[i]) / _G,
            'd_vol': 0.0,
            'w': float(model.weight[i]),
            'EA': ea,
            'MBL': float(model.mbl[i]),
            'material': 'chain',
            'd_nom': 0.0,
            'input_d': 0.0,
            'Cd': 0.0,
            'CdAx': 0.0,
            'Ca': 0.0,
            'CaAx': 0.0,
            'cost': 0.0,
        }
        h = float(depth + model.hook_height[i])
        anchor = ms.addPoint(1, [model.anchor[i, 0], model.anchor[i, 1], -h + 0.0])
        hook = ms.addPoint(1, [model.hook[i, 0], model.hook[i, 1], 0.0], body=1)
        ends = [anchor.number, *_free_points(ms, model, i, h), hook.number]
        loads = model.loads[i] if model.loads else None
        cuts = [0.0, *(() if loads is None else loads.positions), float(model.chain_length[i])]
        first = len(ms.lineList)
        for k in range(len(ends) - 1):
            ms.addLine(cuts[k + 1] - cuts[k], line_type, pointA=ends[k], pointB=ends[k + 1])
        ms.catenary_ends.append((first, len(ms.lineList) - 1))
    ms.initialize()
    return ms, body


def _free_points(ms: Any, model: DockModel, i: int, h: float) -> list[int]:
    """Line ``i``'s point loads as free MoorPy points, placed where our chain at its
    installed span has them; their numbers, from the anchor."""
    from catenary_monitor.core.physics.point_loads import solve_length

    loads = model.loads[i] if model.loads else None
    if loads is None:
        return []
    span = float(np.hypot(*(model.anchor[i] - model.hook[i])))
    ans = solve_length(float(model.weight[i]), h, float(model.chain_length[i]), span, loads)
    back = (model.hook[i] - model.anchor[i]) / span
    out = []
    for (x, z), wk in zip(ans.points, loads.weights):
        at = model.anchor[i] + x * back
        mass, volume = (wk / _G, 0.0) if wk > 0 else (0.0, -wk / (_RHO * _G))
        point = ms.addPoint(0, [at[0], at[1], -h + z], m=mass, v=volume)
        point.zTol = SEABED_TOL  # MoorPy's default: the seabed holds a point within 2 m of it
        out.append(point.number)
    return out


def moorpy_equilibrium(
    model: DockModel, depth: float, load: np.ndarray, tol: float = 1e-4, system: Any = None
) -> tuple[np.ndarray, np.ndarray, Any]:
    """MoorPy's body equilibrium under ``load = (Fx, Fy, Mz)``: the offset (X, Y, psi [rad]),
    the hook tensions [N], and the system. ``tol`` is MoorPy's position tolerance [m]."""
    ms, body = moorpy_system(model, depth) if system is None else system
    body.setPosition(np.zeros(6))
    body.f6Ext = np.array([load[0], load[1], 0.0, 0.0, 0.0, load[2]], dtype=float)
    converged = ms.solveEquilibrium(tol=tol, maxIter=500)
    if converged is False:
        raise RuntimeError('MoorPy did not converge')
    r6 = np.array(body.r6, dtype=float)
    tensions = np.array([float(ms.lineList[b].TB) for _, b in ms.catenary_ends])
    return np.array([r6[0], r6[1], r6[5]]), tensions, (ms, body)


def moorpy_lines(system: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each line of a solved MoorPy ``System`` (or ``(system, body)``): the hook tension [N],
    the anchor's vertical force (the uplift, >= 0) [N] and the hook's horizontal distance to
    its anchor [m], all as MoorPy has them."""
    ms = system[0] if isinstance(system, tuple) else system
    ends = [(ms.lineList[a], ms.lineList[b]) for a, b in ms.catenary_ends]
    top = np.array([float(hook.TB) for _, hook in ends])
    uplift = np.array([max(float(anchor.fA[2]), 0.0) for anchor, _ in ends])
    span = np.array(
        [math.hypot(*(np.asarray(b.rB)[:2] - np.asarray(a.rA)[:2])) for a, b in ends]
    )
    return top, uplift, span

"""The dock model built in MoorPy (a peer): one free body in surge, sway and yaw, the same lines.

Used by the tests (``test/test_body_moorpy.py``) and by ``catenary-monitor bench-body``. MoorPy
needs a finite axial stiffness: an inextensible line is given ``INEXTENSIBLE_EA``. Its lines get
``d_vol = 0`` and ``m = w / g`` so that MoorPy's submerged weight ``(m - rho pi d^2/4) g`` is ours.
MoorPy calls ``breakpoint()`` on some error paths: ``PYTHONBREAKPOINT=0`` is set here.
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


def moorpy_system(model: DockModel, depth: float) -> tuple[Any, Any]:
    """A MoorPy ``System`` with the dock as one body free in DOFs 0, 1, 5 and its lines
    (hook at the water line plus its hook height, anchor on the seabed at ``depth``)."""
    import moorpy as mp

    ms = mp.System(depth=float(np.max(depth + model.hook_height)), g=_G)
    body = ms.addBody(0, np.zeros(6), DOFs=[0, 1, 5])
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
        ms.addLine(
            float(model.chain_length[i]), line_type, pointA=anchor.number, pointB=hook.number
        )
    ms.initialize()
    return ms, body


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
    tensions = np.array([float(line.TB) for line in ms.lineList])
    return np.array([r6[0], r6[1], r6[5]]), tensions, (ms, body)


def moorpy_lines(system: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each line of a solved MoorPy ``System`` (or ``(system, body)``): the hook tension [N],
    the anchor's vertical force (the uplift, >= 0) [N] and the hook's horizontal distance to
    its anchor [m], all as MoorPy has them."""
    ms = system[0] if isinstance(system, tuple) else system
    top = np.array([float(line.TB) for line in ms.lineList])
    uplift = np.array([max(float(line.fA[2]), 0.0) for line in ms.lineList])
    span = np.array(
        [math.hypot(*(np.asarray(line.rB)[:2] - np.asarray(line.rA)[:2])) for line in ms.lineList]
    )
    return top, uplift, span

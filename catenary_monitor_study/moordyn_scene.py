"""One chain, or a whole dock, in MoorDyn (NREL's lumped-mass mooring model), driven at the
hooks: the dynamic reference the monitor's quasi-static solve, bounds, alarms and dock estimate
are checked against.

The chain hangs from an anchor fixed on a flat seabed to a hook point that MoorDyn is told to
follow (a coupled point): the tide moves the hook up, the dock's slow drift and its
wave-frequency surge move it along the line. Recorded at every output step: the hook tension
(what a load pin reads), the hook's depth above the seabed (what the tide gauge gives, the
hook height taken as 0) and the anchor's vertical reaction (the uplift: the first segment's
vertical tension at the anchor, less the half segment's weight the anchor node carries, plus
the seabed's contact force on it).

:func:`run_dock` does the same for a dock of many chains: the dock is a MoorDyn body whose
motion is prescribed (a coupled body: surge, sway, yaw, and heave for the tide), the hooks
points on it, each anchor a fixed point; recorded per line as for one chain, with the dock's
offset.

MoorDyn prints a line per step on file descriptor 1: it is redirected to /dev/null while it
runs. Units SI; the chain's mass per metre is its submerged weight over g plus the displaced
water of its volume-equivalent diameter (1.8 x the nominal one, studless chain practice).
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import Any, Callable, NamedTuple, Sequence

import numpy as np

from catenary_monitor.sim.moordyn_dock import (
    PAPER_CHAIN,
    SEABED,
    Chain,
    MoorDynDock,
    available,
    line_type,
    line_types_header,
    options,
    quiet,
)

__all__ = [
    'Chain',
    'SEABED',
    'Record',
    'DockRecord',
    'run_line',
    'run_dock',
    'storm_motion',
    'available',
    'PAPER_CHAIN',
]


class Record(NamedTuple):
    """MoorDyn's output at each step: time [s], hook span [m] and depth above the seabed [m],
    hook tension [N], the anchor's vertical reaction (uplift, >= 0) and horizontal pull [N]."""

    t: np.ndarray
    span: np.ndarray
    depth: np.ndarray
    tension: np.ndarray
    uplift: np.ndarray
    anchor_horizontal: np.ndarray


class DockRecord(NamedTuple):
    """MoorDyn's output for a dock at each step: time [s], the dock's offset (X, Y [m], yaw
    [rad], as prescribed), the hooks' depth above the seabed [m], and per line (columns in the
    model's order) the hook tension, the anchor's vertical reaction (>= 0) [N] and the hook's
    horizontal distance to its anchor [m]."""

    t: np.ndarray
    offset: np.ndarray  # (n, 3)
    depth: np.ndarray  # (n,)
    tension: np.ndarray  # (n, m)
    uplift: np.ndarray  # (n, m)
    span: np.ndarray  # (n, m)


def _input_file(chain: Chain, span: float, depth: float, dt: float) -> str:
    return f"""--------------------- MoorDyn Input File ------------------------------------
catenary_monitor: one chain, hook driven
{line_types_header()}{line_type(chain)}\
---------------------------- POINTS -----------------------------------------------
ID   Attachment  X       Y     Z      Mass  Volume  CdA    Ca
(#)   (-)        (m)     (m)   (m)    (kg)  (m^3)  (m^2)  (-)
1     Fixed      0       0     {-SEABED}  0     0       0      0
2     Coupled    {span:.6f}     0     {-SEABED + depth:.6f}       0     0       0      0
---------------------- LINES ----------------------------------------
ID    LineType   AttachA  AttachB  UnstrLen  NumSegs  LineOutputs
(#)   (name)     (#)      (#)      (m)       (-)      (-)
1     chain      1        2        {chain.length:.6f}  {chain.segments}       -
{options(dt)}"""


def run_line(
    chain: Chain,
    span: Callable[[float], tuple[float, float]],
    depth: Callable[[float], tuple[float, float]],
    duration: float,
    dt_out: float = 0.1,
    dt: float = 5e-4,
) -> Record:
    """Drive the chain's hook for ``duration`` s: ``span(t)`` and ``depth(t)`` give the hook's
    horizontal distance from the anchor and its height above the seabed [m] with their rates
    [m/s]; MoorDyn integrates at ``dt`` and is sampled every ``dt_out`` s (from the static
    state at t = 0)."""
    import moordyn

    x0, z0 = span(0.0)[0], depth(0.0)[0]
    seg = chain.length / chain.segments
    rows = []
    with tempfile.TemporaryDirectory() as tmp, quiet():
        path = Path(tmp) / 'line.txt'
        path.write_text(_input_file(chain, x0, z0, dt))
        system = moordyn.Create(str(path))
        moordyn.Init(system, [x0, 0.0, -SEABED + z0], [span(0.0)[1], 0.0, depth(0.0)[1]])
        line = moordyn.GetLine(system, 1)
        n = moordyn.GetLineN(line)
        t = 0.0
        steps = int(round(duration / dt_out))
        for k in range(1, steps + 1):
            t_new = k * dt_out
            (x, vx), (z, vz) = span(t_new), depth(t_new)
            moordyn.Step(system, [x, 0.0, -SEABED + z], [vx, 0.0, vz], t, t_new - t)
            t = t_new
            anchor = moordyn.GetLineNodeTen(line, 0)
            bed = moordyn.GetLineNodeSeabedForce(line, 0)
            top = moordyn.GetLineNodeTen(line, n)
            lift = anchor[2] - chain.weight * seg / 2.0 + bed[2]
            rows.append((t, x, z, math.sqrt(sum(c * c for c in top)), lift, anchor[0]))
        moordyn.Close(system)
    a = np.array(rows)
    return Record(a[:, 0], a[:, 1], a[:, 2], a[:, 3], np.maximum(a[:, 4], 0.0), a[:, 5])


#: A dock's motion at time t [s]: ``(X, Y, yaw, depth)`` [m, m, rad, m] and their rates.
Motion = Callable[[float], tuple[Sequence[float], Sequence[float]]]


def run_dock(
    model: Any,
    motion: Motion,
    duration: float,
    chain: Chain = PAPER_CHAIN,
    dt_out: float = 0.1,
    dt: float = 1e-3,
) -> DockRecord:
    """Drive a dock (a :class:`~catenary_monitor.core.body.dock_model.DockModel`: hooks,
    anchors, chain lengths and weights) through ``motion`` for ``duration`` s, each line a
    ``chain`` of its own length and weight (``chain``'s EA, diameter, drag, segments); sampled
    every ``dt_out`` s from the static state at t = 0 (REP 103 frames: the body's yaw is the
    dock's, counter-clockwise seen from above)."""
    q0, v0 = motion(0.0)
    times, qs, tensions, uplifts = [], [], [], []
    with MoorDynDock(model, q0, v0, chain, dt) as dock:
        for k in range(1, int(round(duration / dt_out)) + 1):
            t = k * dt_out
            q, v = motion(t)
            dock.step(t, q, v)
            tension, uplift = dock.lines()
            times.append(t)
            qs.append([float(x) for x in q])
            tensions.append(tension)
            uplifts.append(uplift)
    motion_rows = np.array(qs)
    offset = motion_rows[:, :3]
    return DockRecord(
        np.array(times),
        offset,
        motion_rows[:, 3],
        np.array(tensions),
        np.array(uplifts),
        _spans(model, offset),
    )


def _spans(model: Any, offset: np.ndarray) -> np.ndarray:
    """Each hook's horizontal distance to its anchor [m] at the offsets (n, 3)."""
    c, s = np.cos(offset[:, 2:3]), np.sin(offset[:, 2:3])
    px, py = model.hook[:, 0], model.hook[:, 1]
    hx = offset[:, 0:1] + c * px - s * py
    hy = offset[:, 1:2] + s * px + c * py
    return np.hypot(model.anchor[:, 0] - hx, model.anchor[:, 1] - hy)


def _smooth(t: float, span: float) -> tuple[float, float]:
    """A smooth step from 0 (t <= 0) to 1 (t >= span) and its rate [1/s]."""
    u = min(max(t / span, 0.0), 1.0)
    return u * u * (3.0 - 2.0 * u), (6.0 * u * (1.0 - u) / span if 0.0 < u < 1.0 else 0.0)


def storm_motion(
    depth: float,
    rise: float,
    drift: tuple[float, float],
    drift_time: float,
    amplitude: float,
    period: float,
    waves_from: float = 10.0,
    heading: float = 90.0,
) -> Motion:
    """A storm at a dock: the tide rising ``rise`` [m/s] from ``depth`` [m]; the dock drifting
    to ``drift`` (X, Y) [m] over ``drift_time`` s (a smooth step, from rest); wave-frequency
    motion of ``amplitude`` [m] at ``period`` [s] along ``heading`` (deg clockwise from the
    bow: 90 a beam sea, sway), building over one ``waves_from`` s from ``waves_from`` s on."""
    w = 2.0 * math.pi / period
    ux, uy = math.cos(math.radians(heading)), -math.sin(math.radians(heading))

    def motion(t: float) -> tuple[Sequence[float], Sequence[float]]:
        s, ds = _smooth(t, drift_time)
        b, db = _smooth(t - waves_from, waves_from)
        a = amplitude * b * math.sin(w * t)
        da = amplitude * (db * math.sin(w * t) + b * w * math.cos(w * t))
        q = (drift[0] * s + ux * a, drift[1] * s + uy * a, 0.0, depth + rise * t)
        v = (drift[0] * ds + ux * da, drift[1] * ds + uy * da, 0.0, rise)
        return q, v

    return motion

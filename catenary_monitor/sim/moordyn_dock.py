"""The dock's chains in MoorDyn (NREL's lumped-mass mooring model), stepped as time goes: the
demo simulator's dynamic source (``catenary-monitor demo --moordyn``) and the study's reference
(:mod:`catenary_monitor_study.moordyn_scene`). Optional: the ``dynamics`` extra (PyPI
``moordyn``).

The dock is a MoorDyn body whose motion is prescribed (a coupled body: surge, sway, yaw, and
heave for the tide), each hook a point on it, each anchor a fixed point on a flat seabed
``SEABED`` below the model's water line; each line a chain of its own length and weight in
``Chain.segments`` segments. Per line it gives the hook tension (what a load pin reads) and the
anchor's vertical reaction (the uplift: the first segment's vertical tension at the anchor, less
the half segment's weight the anchor node carries, plus the seabed's contact force on it).

MoorDyn prints a line per step on file descriptor 1: it is redirected to /dev/null while it
runs. Units SI; the chain's mass per metre is its submerged weight over g plus the displaced
water of its volume-equivalent diameter (1.8 x the nominal one, studless chain practice).
"""

from __future__ import annotations

import math
import os
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Optional, Sequence, Union

import numpy as np

#: A motion vector ``(X, Y, yaw, depth)`` or its rates: a sequence or a numpy array.
Vector = Union[Sequence[float], np.ndarray]

__all__ = [
    'G',
    'RHO',
    'SEABED',
    'Chain',
    'PAPER_CHAIN',
    'MoorDynDock',
    'available',
    'line_type',
    'line_types_header',
    'options',
    'quiet',
]

G = 9.81  # m/s^2
RHO = 1025.0  # kg/m^3, sea water
SEABED = 40.0  # m below the water line of the model (the hook stays submerged)


def available() -> bool:
    """Whether the ``moordyn`` package is installed (the ``dynamics`` and ``test`` extras)."""
    try:
        import moordyn  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass(frozen=True)
class Chain:
    """A studlink chain: submerged ``weight`` [N/m], unstretched ``length`` [m], axial stiffness
    ``ea`` [N], nominal diameter [m], MoorDyn segments and the drag and added-mass coefficients
    (normal and axial, on the volume-equivalent diameter)."""

    weight: float = 1300.0
    length: float = 123.6847
    ea: float = 6.63e8
    diameter: float = 0.081
    segments: int = 40
    cd: float = 1.333
    ca: float = 1.0
    cd_axial: float = 0.64
    ca_axial: float = 0.5

    @property
    def volume_diameter(self) -> float:
        """Volume-equivalent diameter [m] (1.8 x nominal)."""
        return 1.8 * self.diameter

    @property
    def mass(self) -> float:
        """Mass per metre [kg/m]: the submerged weight over g plus the displaced water."""
        return self.weight / G + RHO * math.pi * self.volume_diameter**2 / 4.0


#: The seed paper's line 11 (81 mm U3 chain, 1.3 kN/m, 123.68 m; docs/dock_body.md).
PAPER_CHAIN = Chain()


def line_types_header() -> str:
    """The line types section's head (its rows: :func:`line_type`)."""
    return (
        '----------------------- LINE TYPES ------------------------------------------\n'
        'TypeName   Diam    Mass/m     EA     BA/-zeta    EI   Cd     Ca     CdAx    CaAx\n'
        '(name)     (m)     (kg/m)     (N)    (N-s/-)     (-)  (-)    (-)    (-)     (-)\n'
    )


def line_type(chain: Chain, name: str = 'chain') -> str:
    """One row of the line types: the chain's, named ``name``."""
    return (
        f'{name} {chain.volume_diameter:.6f} {chain.mass:.6f} {chain.ea:.6e} -0.8 0 '
        f'{chain.cd} {chain.ca} {chain.cd_axial} {chain.ca_axial}\n'
    )


def options(dt: float) -> str:
    """The options section and the file's last line: time step ``dt`` [s], seabed contact,
    depth, the static initial condition's settings."""
    return f"""---------------------- OPTIONS -----------------------------------------
{dt}   dtM
3.0e6    kbot
3.0e5    cbot
{SEABED}    WtrDpth
{G}  g
{RHO}  rho
1.0  dtIC
120.0 TmaxIC
0.001 threshIC
------------------------- need this line -------------------------------------
"""


@contextmanager
def quiet() -> Iterator[None]:
    """File descriptor 1 to /dev/null (MoorDyn prints a line per step there)."""
    saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    try:
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


def _dock_file(model: Any, chains: list[Chain], depth: float, dt: float) -> str:
    """The input file of a dock whose body starts ``depth`` [m] above the seabed."""
    types = ''.join(line_type(c, f'chain{i}') for i, c in enumerate(chains))
    points, lines = [], []
    for i in range(len(chains)):
        (ax, ay), (hx, hy) = model.anchor[i], model.hook[i]
        hz = float(model.hook_height[i])
        points.append(f'{2 * i + 1} Fixed {ax:.6f} {ay:.6f} {-SEABED} 0 0 0 0')
        points.append(f'{2 * i + 2} Body1 {hx:.6f} {hy:.6f} {hz:.6f} 0 0 0 0')
        lines.append(
            f'{i + 1} chain{i} {2 * i + 1} {2 * i + 2} {chains[i].length:.6f} '
            f'{chains[i].segments} -'
        )
    return (
        '--------------------- MoorDyn Input File ------------------------------------\n'
        'catenary_monitor: a dock as one body, its motion prescribed\n'
        + line_types_header()
        + types
        + '---------------------- BODIES ----------------------------------------------\n'
        'ID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG* I* Volume CdA* Ca*\n'
        '(#) (-) (m) (m) (m) (deg) (deg) (deg) (kg) (m) (kg-m^2) (m^3) (m^2) (-)\n'
        f'1 Coupled 0 0 {-SEABED + depth:.6f} 0 0 0 0 0 0 0 0 0\n'
        '---------------------------- POINTS -----------------------------------------------\n'
        'ID Attachment X Y Z Mass Volume CdA Ca\n'
        '(#) (-) (m) (m) (m) (kg) (m^3) (m^2) (-)\n'
        + '\n'.join(points) + '\n'
        '---------------------- LINES ----------------------------------------\n'
        'ID LineType AttachA AttachB UnstrLen NumSegs LineOutputs\n'
        '(#) (name) (#) (#) (m) (-) (-)\n'
        + '\n'.join(lines) + '\n'
        + options(dt)
    )


def _body(q: Vector, rate: bool = False) -> list[float]:
    """MoorDyn's coupled body DOFs (x, y, z, roll, pitch, yaw) of ``(X, Y, yaw, depth)``."""
    z = float(q[3]) if rate else float(q[3]) - SEABED
    return [float(q[0]), float(q[1]), z, 0.0, 0.0, float(q[2])]


def _line_state(line: Any, chain: Chain) -> tuple[float, float, float]:
    """Hook tension, the anchor's vertical reaction and its horizontal pull [N] of a line."""
    import moordyn

    n = moordyn.GetLineN(line)
    top = moordyn.GetLineNodeTen(line, n)
    anchor = moordyn.GetLineNodeTen(line, 0)
    bed = moordyn.GetLineNodeSeabedForce(line, 0)
    lift = anchor[2] - chain.weight * chain.length / chain.segments / 2.0 + bed[2]
    return math.sqrt(sum(c * c for c in top)), lift, math.hypot(anchor[0], anchor[1])


class MoorDynDock:
    """A dock in MoorDyn, stepped as time goes (a context manager: :meth:`close` at the end).

    ``model`` is a :class:`~catenary_monitor.core.body.dock_model.DockModel` (hooks, anchors,
    chain lengths, weights, hook heights); each line a ``chain`` of its own length and weight
    (``chain``'s stiffness, diameter, drag and segments). The motion is ``q = (X, Y, yaw,
    depth)`` [m, m, rad, m] (REP 103: yaw counter-clockwise seen from above; the depth the
    hooks' reference above the seabed) with its rates ``v``; MoorDyn starts from its static
    state at ``q0``, at rest (``v0`` is not used there: drag in its initial relaxation would
    leave the chains loaded), so a motion should start slowly.
    """

    def __init__(
        self,
        model: Any,
        q0: Vector,
        v0: Vector,
        chain: Optional[Chain] = None,
        dt: float = 1e-3,
    ) -> None:
        import moordyn

        base = PAPER_CHAIN if chain is None else chain
        self.chains = [
            Chain(
                weight=float(model.weight[i]),
                length=float(model.chain_length[i]),
                ea=base.ea,
                diameter=base.diameter,
                segments=base.segments,
                cd=base.cd,
                ca=base.ca,
                cd_axial=base.cd_axial,
                ca_axial=base.ca_axial,
            )
            for i in range(len(model.names))
        ]
        self.t = 0.0
        with tempfile.TemporaryDirectory() as tmp, quiet():
            path = Path(tmp) / 'dock.txt'
            path.write_text(_dock_file(model, self.chains, float(q0[3]), dt))
            self._system = moordyn.Create(str(path))
            # the static state at q0, at rest: a velocity here would load the initial
            # condition's relaxation with drag
            moordyn.Init(self._system, _body(q0), [0.0] * 6)
        self._lines = [moordyn.GetLine(self._system, i + 1) for i in range(len(self.chains))]

    def step(self, t: float, q: Vector, v: Vector) -> None:
        """Advance to time ``t`` [s] (after the last), the body at ``q`` moving at ``v``."""
        import moordyn

        if t <= self.t:
            return
        with quiet():
            moordyn.Step(self._system, _body(q), _body(v, rate=True), self.t, t - self.t)
        self.t = t

    def lines(self) -> tuple[np.ndarray, np.ndarray]:
        """Each line's hook tension and its anchor's vertical force (>= 0) now [N]."""
        rows = np.array([_line_state(h, c)[:2] for h, c in zip(self._lines, self.chains)])
        return rows[:, 0], np.maximum(rows[:, 1], 0.0)

    def close(self) -> None:
        """Free MoorDyn's system (once)."""
        import moordyn

        if self._system is not None:
            with quiet():
                moordyn.Close(self._system)
            self._system = None

    def __enter__(self) -> 'MoorDynDock':
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

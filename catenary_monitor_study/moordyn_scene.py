"""One chain in MoorDyn (NREL's lumped-mass mooring model), driven at its hook: the dynamic
reference the monitor's quasi-static solve, bounds and alarms are checked against.

The chain hangs from an anchor fixed on a flat seabed to a hook point that MoorDyn is told to
follow (a coupled point): the tide moves the hook up, the dock's slow drift and its
wave-frequency surge move it along the line. Recorded at every output step: the hook tension
(what a load pin reads), the hook's depth above the seabed (what the tide gauge gives, the
hook height taken as 0) and the anchor's vertical reaction (the uplift: the first segment's
vertical tension at the anchor, less the half segment's weight the anchor node carries, plus
the seabed's contact force on it).

MoorDyn prints a line per step on file descriptor 1: it is redirected to /dev/null while it
runs. Units SI; the chain's mass per metre is its submerged weight over g plus the displaced
water of its volume-equivalent diameter (1.8 x the nominal one, studless chain practice).
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NamedTuple

import numpy as np

__all__ = ['Chain', 'Record', 'run_line', 'available', 'PAPER_CHAIN']

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


class Record(NamedTuple):
    """MoorDyn's output at each step: time [s], hook span [m] and depth above the seabed [m],
    hook tension [N], the anchor's vertical reaction (uplift, >= 0) and horizontal pull [N]."""

    t: np.ndarray
    span: np.ndarray
    depth: np.ndarray
    tension: np.ndarray
    uplift: np.ndarray
    anchor_horizontal: np.ndarray


def _input_file(chain: Chain, span: float, depth: float, dt: float) -> str:
    return f"""--------------------- MoorDyn Input File ------------------------------------
catenary_monitor: one chain, hook driven
----------------------- LINE TYPES ------------------------------------------
TypeName   Diam    Mass/m     EA     BA/-zeta    EI   Cd     Ca     CdAx    CaAx
(name)     (m)     (kg/m)     (N)    (N-s/-)     (-)  (-)    (-)    (-)     (-)
chain {chain.volume_diameter:.6f} {chain.mass:.6f} {chain.ea:.6e} -0.8 0 {chain.cd} {chain.ca} \
{chain.cd_axial} {chain.ca_axial}
---------------------------- POINTS -----------------------------------------------
ID   Attachment  X       Y     Z      Mass  Volume  CdA    Ca
(#)   (-)        (m)     (m)   (m)    (kg)  (m^3)  (m^2)  (-)
1     Fixed      0       0     {-SEABED}  0     0       0      0
2     Coupled    {span:.6f}     0     {-SEABED + depth:.6f}       0     0       0      0
---------------------- LINES ----------------------------------------
ID    LineType   AttachA  AttachB  UnstrLen  NumSegs  LineOutputs
(#)   (name)     (#)      (#)      (m)       (-)      (-)
1     chain      1        2        {chain.length:.6f}  {chain.segments}       -
---------------------- OPTIONS -----------------------------------------
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
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / 'line.txt'
        path.write_text(_input_file(chain, x0, z0, dt))
        saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        try:
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
        finally:
            os.dup2(saved, 1)
            os.close(saved)
            os.close(null)
    a = np.array(rows)
    return Record(a[:, 0], a[:, 1], a[:, 2], a[:, 3], np.maximum(a[:, 4], 0.0), a[:, 5])

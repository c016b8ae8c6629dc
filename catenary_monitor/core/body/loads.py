"""Environmental loads on the dock by the seed paper's formulas (Hu & Tang 2004, example 1).

The paper gives, for a hull head-on (its units: t, kgf s^2/m^4, with 1 kgf taken as 10 N, the
g = 10 it uses throughout; SI here)::

    wind     R1 = 0.006 rho V^2 (F' + 0.31 F)          rho = 0.124 kgf s^2/m^4 (air)
    current  R2 = 0.01 f Omega v^1.83                  f = 0.18
    waves    R3 = 3/4 k rho g B (H_1/3 / 4)^2 cos(a)    k = 0.7, rho = 104.61 kgf s^2/m^4, g = 9.8

in kN, so in N: ``R1 = c_w V^2 (F' + k_h F)`` with ``c_w = 0.744 N s^2/m^4``, ``R2 = c_c Omega
v^n`` with ``c_c = 1.8``, ``n = 1.83``, ``R3 = c_d B (Hs/4)^2 cos(a)`` with
``c_d = 5382.1845 N/m^3`` (:class:`~catenary_monitor.core.config.parameters.DockConfig`, parameters
``dock_*``). F' is the superstructure's and F the hull freeboard's area projected on the
midship section, Omega the wetted area, B the beam, V, v the wind and current speeds [m/s],
Hs the significant wave height [m].

Directions (our extension; the paper treats the head-on case only): a wind, current or sea
coming *from* ``phi`` (deg, clockwise from the bow, as ``heading``) pushes along ``n = (-cos
phi, sin phi)`` in the dock frame. Each formula is applied per axis to that axis' component:
wind with the areas projected across that axis (``dock_wind_area_x``/``dock_hull_area_x`` on the
midship section, ``..._y`` on the centreline plane) and ``(V n_i)|V n_i|``; current with the
wetted area and ``sign(n_i) |v n_i|^n`` (the paper's formula is a friction law: across the hull
it underestimates form drag, see docs/dock_body.md); waves with the width facing them (B along x,
the length along y) and ``n_i``, the paper's ``cos(a)``. Waves come from the wind's direction.
The loads act at the reference point (no yaw moment: a symmetric dock); give a moment with
``--load``. They are fixed in the reference frame (the dock's yaw of a few tenths of a degree
changes the projections by less than 1e-4).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Optional

import numpy as np

from catenary_monitor.core.config.parameters import DockConfig

__all__ = ['Loads', 'environmental_load', 'push_direction', 'wind_load_per_speed2']


class Loads(NamedTuple):
    """Environmental loads (Fx, Fy, Mz) [N, N, N m] in the reference frame, by source."""

    wind: np.ndarray
    current: np.ndarray
    waves: np.ndarray

    @property
    def total(self) -> np.ndarray:
        """Their sum."""
        return self.wind + self.current + self.waves


def push_direction(from_deg: float) -> np.ndarray:
    """Unit vector (dock frame) along which something coming from ``from_deg`` pushes."""
    b = math.radians(from_deg)
    return np.array([-math.cos(b), math.sin(b)])


def _need(dock: DockConfig, *names: str) -> list[float]:
    values = []
    for name in names:
        value = getattr(dock, name)
        if value is None:
            raise ValueError(f'dock_{name} is not set: the {_USE[name]} needs it')
        values.append(float(value))
    return values


_USE = {
    'wind_area_x': 'wind load',
    'hull_area_x': 'wind load',
    'wind_area_y': 'wind load',
    'hull_area_y': 'wind load',
    'wetted_area': 'current load',
    'beam': 'wave drift load',
    'length': 'wave drift load',
}


def wind_load_per_speed2(dock: DockConfig, wind_from: float) -> np.ndarray:
    """Wind load (Fx, Fy, 0) [N] per (m/s)^2 of wind speed from ``wind_from`` (deg)."""
    ax, hx, ay, hy = _need(dock, 'wind_area_x', 'hull_area_x', 'wind_area_y', 'hull_area_y')
    n = push_direction(wind_from)
    k = dock.hull_wind_factor
    c = dock.wind_coefficient
    return np.array(
        [c * n[0] * abs(n[0]) * (ax + k * hx), c * n[1] * abs(n[1]) * (ay + k * hy), 0.0]
    )


def environmental_load(
    dock: DockConfig,
    wind: float = 0.0,
    wind_from: float = 0.0,
    current: float = 0.0,
    current_from: Optional[float] = None,
    hs: float = 0.0,
) -> Loads:
    """Wind V [m/s] from ``wind_from``, current v [m/s] from ``current_from`` (default: the
    wind's) and waves of significant height ``hs`` [m] from the wind's direction.

    ValueError (one line) for a negative or non-finite speed or height, or when a formula needs
    a dock area that is not set.
    """
    for name, value in (('wind', wind), ('current', current), ('hs', hs)):
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f'{name} must be a finite number >= 0, got {value!r}')
    for name, angle in (('wind_from', wind_from), ('current_from', current_from)):
        if angle is not None and not math.isfinite(angle):
            raise ValueError(f'{name} must be finite, got {angle!r}')
    zero = np.zeros(3)
    f_wind = wind_load_per_speed2(dock, wind_from) * wind * wind if wind > 0 else zero
    f_current = zero
    if current > 0:
        (omega,) = _need(dock, 'wetted_area')
        n = push_direction(wind_from if current_from is None else current_from)
        e = dock.current_exponent
        c = dock.current_coefficient * omega
        f_current = np.array(
            [
                c * math.copysign(abs(current * n[0]) ** e, n[0]),
                c * math.copysign(abs(current * n[1]) ** e, n[1]),
                0.0,
            ]
        )
    f_waves = zero
    if hs > 0:
        beam, length = _need(dock, 'beam', 'length')
        n = push_direction(wind_from)
        c = dock.wave_drift_coefficient * (hs / 4.0) ** 2
        f_waves = np.array([c * beam * n[0], c * length * n[1], 0.0])
    return Loads(f_wind, f_current, f_waves)

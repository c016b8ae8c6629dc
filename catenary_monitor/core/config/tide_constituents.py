"""The ``tide_table`` parameter: harmonic constituents ``NAME AMPLITUDE PHASE SPEED`` (m, deg,
deg/h) separated by ``;``, e.g. ``"M2 1.0 112.3 28.9841042; S2 0.33 141.0 30.0"``. The forecast
on them is :mod:`catenary_monitor.core.monitor.tide_table`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

__all__ = ['Constituent', 'parse_table']


class Constituent(NamedTuple):
    """One harmonic constituent: amplitude [m], phase [deg], speed [deg/h]."""

    name: str
    amplitude: float
    phase: float
    speed: float


def parse_table(text: str) -> tuple[Constituent, ...]:
    """The constituents of a ``tide_table`` string (empty: no table); ValueError says why not."""
    out = []
    for k, part in enumerate(p for p in text.split(';') if p.strip()):
        words = part.split()
        if len(words) != 4:
            raise ValueError(
                f'constituent {k + 1} {part.strip()!r}: expected NAME AMPLITUDE PHASE SPEED '
                '(m, deg, deg/h)'
            )
        try:
            amplitude, phase, speed = (float(w) for w in words[1:])
        except ValueError:
            raise ValueError(f'constituent {k + 1} {part.strip()!r}: not numbers') from None
        if not all(math.isfinite(v) for v in (amplitude, phase, speed)):
            raise ValueError(f'constituent {k + 1} {part.strip()!r}: must be finite')
        if not 0.0 <= amplitude <= 100.0 or not 0.0 < speed <= 1000.0:
            raise ValueError(
                f'constituent {k + 1} {part.strip()!r}: amplitude 0-100 m, speed 0-1000 deg/h'
            )
        out.append(Constituent(words[0], amplitude, phase, speed))
    return tuple(out)

"""The ``tide_table`` parameter: harmonic constituents ``NAME AMPLITUDE PHASE SPEED`` (m, deg,
deg/h) separated by ``;``, e.g. ``"M2 1.0 112.3 28.9841042; S2 0.33 141.0 30.0"``. The forecast
on them is :mod:`catenary_monitor.core.rules.tide_table`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

__all__ = ['Constituent', 'MAX_CONSTITUENTS', 'MAX_TABLE_CHARS', 'parse_table']

#: Most constituents a table may hold: a full harmonic analysis has about 150 (T_TIDE's and
#: UTide's lists: 146; NOAA's published sets: 37). Each costs about a microsecond of forecast
#: per tension sample (docs/node.md), so 200 keep a 12-line dock at 100 Hz within a quarter of
#: a core, where 100 000 kept the node from ever catching up (or hearing Ctrl-C).
MAX_CONSTITUENTS = 200
#: Longest ``tide_table`` string read (characters): 200 constituents take about 8 000.
MAX_TABLE_CHARS = 65536


class Constituent(NamedTuple):
    """One harmonic constituent: amplitude [m], phase [deg], speed [deg/h]."""

    name: str
    amplitude: float
    phase: float
    speed: float


def parse_table(text: str) -> tuple[Constituent, ...]:
    """The constituents of a ``tide_table`` string (empty: no table); ValueError says why not
    (also, before anything is parsed, for a table longer than :data:`MAX_TABLE_CHARS` or with
    more than :data:`MAX_CONSTITUENTS` constituents)."""
    if len(text) > MAX_TABLE_CHARS:
        raise ValueError(
            f'{len(text)} characters, more than the {MAX_TABLE_CHARS} a table may hold '
            f'(at most {MAX_CONSTITUENTS} constituents)'
        )
    if text.count(';') >= MAX_CONSTITUENTS:
        parts = [p for p in text.split(';') if p.strip()]
        if len(parts) > MAX_CONSTITUENTS:
            raise ValueError(
                f'{len(parts)} constituents, more than the {MAX_CONSTITUENTS} a table may hold'
            )
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

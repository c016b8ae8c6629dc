"""The twin's schedule over a window: the merged steps of a line (:func:`merge`,
:func:`line_steps`) and the newest sample at each step (:func:`newest`, :func:`pick`).

Three of them have a C loop (``_twin_loops.c`` beside this file: ``merge3``, ``newest``,
``pick``; optional: else the numpy passes, which give the same arrays,
test/test_batch_steps.py)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catenary_monitor.core.monitor.state import LineState
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.twin.window import KIND_DEPTH, KIND_TENSION, KIND_TICK, Window

try:  # three of the loops below in C (_twin_loops.c; optional: else the numpy passes)
    from catenary_monitor.core.twin import _twin_loops as _loops  # type: ignore[attr-defined]
except ImportError:  # not built
    _loops = None

__all__ = [
    'merge',
    'newest',
    'LineSteps',
    'line_steps',
    'pick',
    'level_changes',
]


def merge(dd: np.ndarray, tt: np.ndarray, kk: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge sorted depth, tension and tick times (ties: depth, tension, tick): (times, kinds)."""
    n = len(dd) + len(tt) + len(kk)
    if _loops is not None and dd.dtype == tt.dtype == kk.dtype == np.int64:
        times = np.empty(n, np.int64)
        kinds = np.empty(n, np.int8)
        sources = [np.ascontiguousarray(c) for c in (dd, tt, kk)]
        if _loops.merge3(*sources, times, kinds, KIND_DEPTH, KIND_TENSION, KIND_TICK):
            return times, kinds
    before = np.searchsorted
    pos_d = np.arange(len(dd)) + before(tt, dd, 'left') + before(kk, dd, 'left')
    pos_t = np.arange(len(tt)) + before(dd, tt, 'right') + before(kk, tt, 'left')
    pos_k = np.arange(len(kk)) + before(dd, kk, 'right') + before(tt, kk, 'right')
    times = np.empty(n, np.int64)
    kinds = np.empty(n, np.int8)
    for pos, src, kind in (
        (pos_d, dd, KIND_DEPTH),
        (pos_t, tt, KIND_TENSION),
        (pos_k, kk, KIND_TICK),
    ):
        times[pos] = src
        kinds[pos] = kind
    return times, kinds


def newest(mask: np.ndarray) -> np.ndarray:
    """Per step: index (within the window) of the newest step where ``mask`` holds (-1: none)."""
    return np.cumsum(mask) - 1


@dataclass
class LineSteps:
    """One line's steps in a window and what each step sees."""

    times: np.ndarray  # ns
    kinds: np.ndarray  # int8
    t_idx: np.ndarray  # newest tension sample in the window (-1: the core's)
    d_idx: np.ndarray  # newest depth sample in the window (-1: the core's)
    dk_idx: np.ndarray  # newest tide decision in the window (-1: the core's)
    solved: np.ndarray  # bool: the line is solved at this step
    s_idx: np.ndarray  # newest solve in the window (-1: the core's)
    k_idx: np.ndarray  # newest tick in the window (-1: the core's)


def line_steps(line: LineState, tt: np.ndarray, window: Window) -> LineSteps:
    times, kinds = merge(window.depth[0], tt, window.ticks)
    if _loops is not None:  # one loop instead of five cumulative sums
        n = len(kinds)
        t_idx, d_idx, dk_idx, k_idx, s_idx = np.empty((5, n), np.int64)
        solved = np.empty(n, bool)
        had = line.tension_s == line.tension_s  # a tension before the window
        kind_codes = (KIND_DEPTH, KIND_TENSION, KIND_TICK)
        _loops.newest(kinds, *kind_codes, had, t_idx, d_idx, dk_idx, k_idx, solved, s_idx)
        return LineSteps(times, kinds, t_idx, d_idx, dk_idx, solved, s_idx, k_idx)
    t_idx = newest(kinds == KIND_TENSION)
    known = (t_idx >= 0) | (line.tension_s == line.tension_s)
    solved = (kinds == KIND_TENSION) | ((kinds == KIND_DEPTH) & known)
    return LineSteps(
        times,
        kinds,
        t_idx,
        newest(kinds == KIND_DEPTH),
        newest(kinds != KIND_TENSION),
        solved,
        newest(solved),
        newest(kinds == KIND_TICK),
    )


def pick(idx: np.ndarray, column: np.ndarray, before: float) -> np.ndarray:
    """``column[idx]`` where ``idx >= 0``, else ``before`` (the core's value before the window;
    an empty column gives a read-only view of ``before``)."""
    if len(column) > 1 and not column.strides[0] and isinstance(before, (float, int)):
        same = column[0] == before or (column[0] != column[0] and before != before)
        if same or not (idx < 0).any():  # a constant column (a read-only view) stays one
            return np.broadcast_to(column[:1].astype(np.result_type(column, before)), (len(idx),))
    if (
        _loops is not None
        and len(column)
        and column.dtype == np.float64
        and isinstance(before, (float, int))
        and idx.dtype == np.int64
    ):
        out = np.empty(len(idx))
        _loops.pick(np.ascontiguousarray(idx), np.ascontiguousarray(column), before, out)
        return out
    if not len(column):  # the value before throughout: read-only, no memory per step
        return np.broadcast_to(np.asarray(before), (len(idx),))
    # ``before`` appended last: index -1 (``_newest``'s "none yet") picks it, one gather; the
    # dtype as ``np.where`` would give it (a Python scalar does not widen the column)
    picked = np.append(column, before)[idx]
    return picked.astype(np.result_type(column, before), copy=False)


def level_changes(levels: np.ndarray, before: Level) -> np.ndarray:
    """Indexes where the level differs from the one before (the first against ``before``)."""
    return np.flatnonzero(np.diff(levels, prepend=np.int8(before)))

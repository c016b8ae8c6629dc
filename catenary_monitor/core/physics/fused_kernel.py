"""The fused C kernel for problems 3 and 4 (hook tension given) with their margins, if built.

``_fused_kernel.c`` computes, in one pass over blocks of 256 elements, what
:func:`catenary_monitor.core.physics.inextensible.solve_inextensible` computes for a measured
tension: validation and status, the grounded chain, the uplift solve, the uplift state and the
three margins, with the formulas of :mod:`catenary_monitor.core.physics.catenary` (same start,
residual, stopping test and load-margin table).  Vectorized with glibc's vector math library on
x86-64; the instruction set is picked at import (``isa()``).  It is optional: where it was not
built (no C compiler at install time), ``AVAILABLE`` is False and ``solve()`` runs the numpy
implementation, which gives the same numbers to rounding (test/test_kernels.py).

Why it exists (docs/benchmarks.md, "Where the time goes"): numpy evaluates one operation over the
whole array at a time, about 1 ns per element each, and problem 4 with its margins needs about
130 of them; a plain-float Python solve costs ~10 us in interpreter overhead.  The fused kernel
keeps every intermediate in registers or L1 cache.

Array calls of at least two shares (``MIN_SHARE`` elements each, 2048) are cut into shares of
whole blocks solved on up to ``threads()`` threads, the GIL released; every element takes the
same code whatever its share, so the results do not depend on the thread count.  The default is
the CPUs this process may run on, or ``CATENARY_MONITOR_THREADS``; ``set_threads(1)`` keeps a
call on the calling thread.
"""

from __future__ import annotations

import math
import os
import warnings
from contextlib import contextmanager
from typing import Any, Iterator, Optional

import numpy as np

from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics.result import ALL_KEYS

try:  # the compiled module, next to this file
    from catenary_monitor.core.physics import _fused_kernel as _k  # type: ignore[attr-defined]
except ImportError:  # not built: solve() uses the numpy implementation
    _k = None

#: True where the compiled kernel is importable.
AVAILABLE = _k is not None
#: Number of result rows the kernel writes (``result.ALL_KEYS`` order).
NOUT = 12

#: The kernel's load-margin table: ``log D`` against ``log(h/x)`` from h/x = 1e-6 to 7e9 in
#: steps of 1/1024, solved at import by :func:`catenary._critical_table` (~3 ms).  Its cubic
#: Hermite interpolation agrees with the Newton-converged value to 1e-14 (test/test_kernels.py),
#: so inside it the kernel needs no residual; outside, the scalar Newton of catenary.py.
TABLE_Y0, TABLE_DY = math.log(1e-6), 1.0 / 1024.0
TABLE_N = int((math.log(7e9) - TABLE_Y0) / TABLE_DY)

if _k is not None:
    _eta, _slope = cat._critical_table(TABLE_N, TABLE_Y0, TABLE_DY)
    _k.set_table(
        TABLE_Y0,
        TABLE_DY,
        np.asarray(_eta, dtype=float).tobytes(),
        np.asarray(_slope, dtype=float).tobytes(),
    )
    del _eta, _slope


#: Elements per share of a threaded array call: a call uses a second thread from twice this.
MIN_SHARE = int(_k.MIN_SHARE) if _k is not None else 2048
#: Environment variable giving the most threads an array call uses (default: the usable CPUs).
THREADS_ENV = 'CATENARY_MONITOR_THREADS'


def default_threads() -> int:
    """The threads an array call uses unless told otherwise: ``CATENARY_MONITOR_THREADS``
    (1 to ``MAX_THREADS``), else the CPUs this process may run on (at most ``MAX_THREADS``)."""
    most = _k.MAX_THREADS if _k is not None else 1
    text = os.environ.get(THREADS_ENV, '').strip()
    if text:
        try:
            value = int(text)
        except ValueError:
            value = 0
        if 1 <= value <= most:
            return value
        warnings.warn(
            f'{THREADS_ENV}={text!r} is not a thread count from 1 to {most}; '
            'using the CPUs this process may run on',
            stacklevel=2,
        )
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    return max(1, min(cpus, most))


def threads() -> int:
    """The most threads one array call of the kernel uses (1 without the kernel)."""
    return int(_k.threads()) if _k is not None else 1


def set_threads(n: int) -> None:
    """Let array calls use at most ``n`` threads (1 to ``MAX_THREADS``; 1: the calling
    thread only).  Calls shorter than two shares of ``MIN_SHARE`` elements stay on one."""
    if _k is None:
        raise RuntimeError('the C kernel is not built')
    _k.set_threads(int(n))


@contextmanager
def cores_left_to(others: int) -> Iterator[int]:
    """Within the block, array calls use ``others`` fewer threads (at least one): for callers
    whose own threads or worker processes (replay's read-ahead decode) keep that many cores
    busy meanwhile.  Yields the thread count in force; the previous one comes back after."""
    before = threads()
    now = max(1, before - max(0, int(others)))
    if _k is not None:
        _k.set_threads(now)
    try:
        yield now
    finally:
        if _k is not None:
            _k.set_threads(before)


if _k is not None:
    _k.set_threads(default_threads())


def isa() -> str:
    """Instruction set the kernel runs ('x86-64-v4', 'x86-64-v3', 'baseline'), or 'none'."""
    return _k.isa() if _k is not None else 'none'


def supported() -> list[str]:
    """Instruction sets of the kernel this CPU runs (best first)."""
    return list(_k.supported()) if _k is not None else []


def set_isa(name: str) -> None:
    """Use another supported instruction set (tests compare them)."""
    if _k is None:
        raise RuntimeError('the C kernel is not built')
    _k.set_isa(name)


def set_result(cls: type, tails: tuple) -> None:
    """Make :func:`solve_one` return ``cls(12 values, status, *tails[2 has_x + has_mbl])``.

    ``cls`` must be a tuple subclass without instance fields (``SolveResult``); ``solve.py``
    registers it at import, so that the live node's call builds its result in C.
    """
    _k.set_result(cls, tails, cat.STEP_TOL)


def solve_one(w: Any, h: Any, t: Any, x: Any = None, mbl: Any = None) -> Any:
    """One element of problem 3 or 4 in plain numbers: the registered result (see
    :func:`set_result`), else the tuple ``(12 values in ALL_KEYS order, status)``; None when the
    inputs are not plain floats or ints.

    Values are NaN where they do not apply (no x: the margins; no mbl: the safety factor) and
    everywhere when ``status != 0``.
    """
    return _k.solve_one(w, h, t, None, x, None, mbl, None, cat.MAXITER)


def solve_arrays(
    w: Any,
    h: Any,
    t: Any,
    x: Any,
    mbl: Any,
    n: int,
    iters: Optional[np.ndarray] = None,
    rows: Optional[tuple[str, ...]] = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Arrays (float64, C-contiguous, length n) or floats: ``(rows (12, n), status (n,))``.

    ``x`` and ``mbl`` may be None.  ``iters``, if given (int64, n), receives the uplift
    residuals evaluated per element (0 where the anchor is not lifted).  ``rows``, if given
    (keys of ``result.ALL_KEYS``, in that order), asks for those rows only: the result is then
    ``(len(rows), n)`` and no memory is written for the others.
    """
    status = np.empty(n, dtype=np.int64)
    if rows is None:
        out = np.empty((NOUT, n))
        solve_into([w, h, t, x, mbl], out, status, ALL_ROWS, iters)
        return out, status
    out = np.empty((len(rows), n))
    solve_into([w, h, t, x, mbl], out, status, row_mask(rows), iters)
    return out, status


def row_mask(rows: tuple[str, ...]) -> int:
    """The kernel's row mask of ``rows`` (keys of ``result.ALL_KEYS``): bit r for row r."""
    return sum(1 << _ROW[k] for k in rows)


def solve_into(
    args: list[Any],
    out: np.ndarray,
    status: np.ndarray,
    mask: int,
    iters: Optional[np.ndarray] = None,
) -> None:
    """Solve ``args`` (``[w, h, t, x, mbl]``: float64 arrays of one length n or floats; x, mbl
    may be None) into ``out`` (C-contiguous float64, the rows of ``mask`` (:func:`row_mask`,
    ``ALL_ROWS``) in ``ALL_KEYS`` order, n each) and ``status`` (int64, n)."""
    w, h, t, x, mbl = args
    _k.solve_tension(w, h, t, x, mbl, out, status, iters, cat.MAXITER, cat.STEP_TOL, mask)


_ROW = {k: r for r, k in enumerate(ALL_KEYS)}
#: The kernel's row mask of every result row.
ALL_ROWS = (1 << NOUT) - 1

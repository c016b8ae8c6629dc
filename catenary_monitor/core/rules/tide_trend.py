"""The tide's trend (rate of rise, m/s) from recent depth samples, and each line's time to uplift.

Method (one decision, scalar :func:`step` and its vectorized twin :func:`series`):

* depth samples are averaged in :data:`BINS` time bins per ``tide_trend_window`` (W, s; 60 s
  bins at the default 1200 s), the bins aligned on the clock's epoch (``stamp_ns //
  bin_ns``), so live and replay bin alike whenever the monitor started;
* the rate at a depth sample is the Theil-Sen slope of the *complete* bins of the window before
  the sample's bin: the median of the slopes between every pair of bin means (mean time, mean
  depth), times measured from the sample's bin start (small numbers: exact with epoch-ns stamps);
* the tide's level at the sample is the Theil-Sen line there (intercept: the median of
  ``mean depth - rate * mean time`` of the bins); the sample's *excess* over it is the wave and
  the gauge noise of that sample;
* the rate is known once at least half of those bins hold samples (a minimum span of W / 2);
  before that, and after a gap that long, it is unknown (NaN).

Why this estimator: a bin mean averages waves (periods of seconds, far shorter than a bin) and
gauge noise (about 60 samples per bin at 1 Hz); the median of pairwise slopes ignores a bin
spoiled by a spike and a gap costs only its bins (a least-squares line would follow one bad
bin). Only complete bins enter, so the rate moves once per bin, and the per-bin sums are added
in sample order in both paths (``numpy.bincount`` adds sequentially), so the core and its twin
give the same bits: no running sums over the whole log, whose rounding grows with its length.
Non-finite depth samples do not enter the bins (they still decide the tide's level).

Each line's time to uplift (:func:`time_to_uplift`) is then ``(margin + excess) / rate``: the
margin counted from the tide's level, not from this sample's wave crest or trough. The margin is
the nearer of two views (:func:`nearer_margin`): the horizontal tension of the newest solve held
(``tide_margin``) and, with ``chain_length``, the chain's length and span held
(``tide_margin_at_length``: a fixed depth minus the depth, so the gauge's noise cancels with the
excess). Unknown (no trend yet, or after a gap) is NaN, distinct from inf (the tide is not
rising: not coming).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = [
    'BINS',
    'TrendState',
    'bin_ns',
    'step',
    'series',
    'nearer_margin',
    'time_to_uplift',
    'uplift_times',
]

#: Bins per trend window; the rate is known once BINS // 2 of them hold samples.
BINS = 20
_PAIRS = np.triu_indices(BINS, 1)


class TrendState(NamedTuple):
    """What the trend remembers: the open bin's index and sums (count, sum of offsets from its
    start [s], sum of depths [m]), the closed bins of the last window (index, mean offset [s],
    mean depth [m]; oldest first), the rate [m/s] and the tide's level at the open bin's start
    [m] (NaN: unknown) and the newest sample's excess over the level [m]."""

    bin: int = -(2**62)
    open: tuple[float, float, float] = (0.0, 0.0, 0.0)
    closed: tuple[tuple[int, float, float], ...] = ()
    rate: float = math.nan
    level: float = math.nan
    excess: float = math.nan


def bin_ns(window: float) -> int:
    """Bin width [ns] for a trend window of ``window`` s."""
    return max(int(round(window * 1e9 / BINS)), 1)


def _median(rows: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Median of the first ``m`` finite values of each row (the rest NaN), elementwise."""
    s = np.sort(rows, axis=1)  # NaN last
    k = np.arange(len(rows))
    a = s[k, np.maximum((m - 1) // 2, 0)]
    b = s[k, np.maximum(m // 2, 0)]
    return 0.5 * (a + b)


def _fit(
    q: np.ndarray, idx: np.ndarray, mu: np.ndarray, my: np.ndarray, width: int
) -> tuple[np.ndarray, np.ndarray]:
    """Theil-Sen rate [m/s] and level [m] at the start of each query bin ``q`` from the
    closed bins (``idx`` sorted, mean offsets ``mu`` [s], mean depths ``my`` [m]) in
    ``[q - BINS, q)``; NaN if fewer than ``BINS // 2``."""
    out = np.full(len(q), math.nan)
    if not len(idx) or not len(q):
        return out, out.copy()
    lo = np.searchsorted(idx, q - BINS, 'left')
    hi = np.searchsorted(idx, q, 'left')
    cols = lo[:, None] + np.arange(BINS)
    ok = cols < hi[:, None]
    c = np.minimum(cols, len(idx) - 1)
    tau = np.where(ok, (idx[c] - q[:, None]) * (width * 1e-9) + mu[c], math.nan)
    y = np.where(ok, my[c], math.nan)
    i, j = _PAIRS
    m = ok.sum(axis=1)
    with np.errstate(invalid='ignore'):
        rate = _median((y[:, j] - y[:, i]) / (tau[:, j] - tau[:, i]), m * (m - 1) // 2)
        level = _median(y - rate[:, None] * tau, m)
    known = m >= BINS // 2
    return np.where(known, rate, out), np.where(known, level, out)


def _rate(b: int, closed: tuple[tuple[int, float, float], ...], width: int) -> tuple[float, float]:
    """The scalar path's rate and level at bin ``b`` (the same arithmetic as :func:`_fit`)."""
    if not closed:
        return math.nan, math.nan
    idx, mu, my = (np.array(col) for col in zip(*closed))
    rate, level = _fit(np.array([b], np.int64), idx.astype(np.int64), mu, my, width)
    return float(rate[0]), float(level[0])


def step(state: TrendState, stamp_ns: int, depth: float, window: float) -> TrendState:
    """The trend after one depth sample [m] at ``stamp_ns`` (samples in time order; an older
    bin than the open one is ignored) over a window of ``window`` s."""
    width = bin_ns(window)
    b = int(stamp_ns) // width
    if b < state.bin:
        return state
    if b > state.bin:
        n, su, sy = state.open
        closed = state.closed + (((state.bin, su / n, sy / n),) if n > 0 else ())
        closed = tuple(c for c in closed if c[0] >= b - BINS)
        state = TrendState(b, (0.0, 0.0, 0.0), closed, *_rate(b, closed, width))
    u = (int(stamp_ns) - b * width) * 1e-9
    state = state._replace(excess=depth - (state.level + state.rate * u))
    if math.isfinite(depth):
        n, su, sy = state.open
        state = state._replace(open=(n + 1.0, su + u, sy + depth))
    return state


def series(
    state: TrendState, t_ns: np.ndarray, depth: np.ndarray, window: float
) -> tuple[np.ndarray, np.ndarray, TrendState]:
    """:func:`step` over sorted depth samples in vectorized code: the rate [m/s] and the
    excess [m] after each sample, and the state after the last."""
    if not len(t_ns):
        return np.zeros(0), np.zeros(0), state
    width = bin_ns(window)
    t_ns = np.asarray(t_ns, np.int64)
    b = t_ns // width
    keep = np.isfinite(depth) & (b >= state.bin)
    carry = state.open[0] > 0
    head = np.array([state.bin] if carry else [], np.int64)
    sb = np.concatenate([head, b[keep]])
    sn = np.concatenate([[state.open[0]] if carry else [], np.ones(int(keep.sum()))])
    u = (t_ns - b * width) * 1e-9
    su = np.concatenate([[state.open[1]] if carry else [], u[keep]])
    sy = np.concatenate([[state.open[2]] if carry else [], depth[keep]])
    ub, inv = np.unique(sb, return_inverse=True)
    n, su_, sy_ = (np.bincount(inv, w, len(ub)) for w in (sn, su, sy))
    old = np.array([c[0] for c in state.closed], np.int64)
    idx = np.concatenate([old, ub])
    mu = np.concatenate([[c[1] for c in state.closed], su_ / n])
    my = np.concatenate([[c[2] for c in state.closed], sy_ / n])
    qb, qinv = np.unique(b, return_inverse=True)
    fit_rate, fit_level = _fit(qb, idx, mu, my, width)
    same = b == state.bin
    rates = np.where(same, state.rate, fit_rate[qinv])
    levels = np.where(same, state.level, fit_level[qinv])
    excess = depth - (levels + rates * u)
    last = int(b[-1])
    is_open = ub == last
    opened = (float(n[is_open][0]), float(su_[is_open][0]), float(sy_[is_open][0]))
    window_bins = (idx >= last - BINS) & (idx < last)
    closed = tuple(
        (int(k), float(a), float(c))
        for k, a, c in zip(idx[window_bins], mu[window_bins], my[window_bins])
    )
    final = TrendState(
        last,
        opened if is_open.any() else (0.0, 0.0, 0.0),
        state.closed if last == state.bin else closed,
        float(rates[-1]),
        float(levels[-1]),
        float(excess[-1]),
    )
    return rates, excess, final


def nearer_margin(tide_margin: np.ndarray, at_length: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tide margin [m] the forecast counts down: the nearer of the R-held one
    (``tide_margin``) and the chain length's (``tide_margin_at_length``, NaN without
    ``chain_length``); and which view answered (1.0 the chain length's, 0.0 the R-held one,
    NaN where the line has no margin)."""
    with np.errstate(invalid='ignore'):
        length = at_length < tide_margin
    margin = np.where(length, at_length, tide_margin)
    view = np.where(length, 1.0, np.where(np.isnan(tide_margin), math.nan, 0.0))
    return margin, view


def time_to_uplift(tide_margin: float, uplift_force: float, rate: float, excess: float) -> float:
    """Time [s] until the anchor lifts if the tide keeps rising ``rate`` [m/s]: the margin
    (:func:`nearer_margin`) from the tide's level (``tide_margin + excess``, m: the wave and
    gauge noise of the depth sample taken out) over the rate; 0 while lifted (margin <= 0 or
    uplift > 0 N) or once the tide's level is past uplift, inf when the tide is not rising
    (not coming), NaN when the trend is unknown or the line is unsolved (unknown is not
    "never")."""
    if tide_margin != tide_margin:
        return math.nan
    if tide_margin <= 0.0 or uplift_force > 0.0:
        return 0.0
    if rate != rate:
        return math.nan
    if not rate > 0.0:
        return math.inf
    return max(tide_margin + excess, 0.0) / rate


def uplift_times(
    tide_margin: np.ndarray, uplift_force: np.ndarray, rate: np.ndarray, excess: np.ndarray
) -> np.ndarray:
    """:func:`time_to_uplift` on arrays [s] (its one column form, numpy and no C: on the
    million-message replay these passes take 9 ms of 1.3 s, a C loop took 3 ms)."""
    with np.errstate(divide='ignore', invalid='ignore'):
        up = rate > 0.0
        ahead = np.maximum(tide_margin + excess, 0.0)
        rising = np.where(up, ahead / np.where(up, rate, 1.0), math.inf)
        rising = np.where(np.isnan(rate), math.nan, rising)
        out = np.where((tide_margin <= 0.0) | (uplift_force > 0.0), 0.0, rising)
    return np.where(np.isnan(tide_margin), math.nan, out)

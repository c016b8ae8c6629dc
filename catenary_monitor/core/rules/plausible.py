"""Readings no mooring can produce: the plausibility bounds of a tension and a depth sample.

Pure: no rclpy, no clock. A finite reading beyond these bounds is an impossible input (a
sensor, scaling or wiring fault), reported with its own status code and sentence, not handed
to the solver (which would answer "did not converge" for a tension of 1e300 N). NaN and
infinite readings stay :attr:`Status.NON_FINITE`. The scalar core (``MonitorCore``) and its
batch twin both call :func:`reading_status`, so live and replay decide alike.

Bounds
------
* **Tension** above ``MAX_TENSION_PER_MBL`` x the line's MBL (10 x): a chain parts at its MBL,
  so a reading ten times above it is a measurement fault, whatever the safety margin of the
  MBL given; the safety-factor alarm covers every real overload below that.
* **Tension off by orders of magnitude below** (:attr:`Status.WRONG_UNITS`): 100 times or more
  below the hanging chain's own weight ``w * h`` (``UNITS_FACTOR``), or at or below ``w * h``
  where 1000 times the reading (a load cell in kN read as N) would lie between ``w * h`` and
  the MBL. A chain cannot hang with less than its own weight at the hook, so such a reading is
  a scale (or a parted chain); the message names the line's ``tension_scale``. A negative
  reading stays the solver's ``T <= w*h``.
* **Depth** (with the hook height) above ``MAX_DEPTH`` = 12 000 m: deeper than any sea
  (Challenger Deep, about 10 935 m).

Both tension sentences end with "wrong units?" and the parameter to check
(:func:`status_messages`: the status table of one line).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.config.parameters import LineConfig, MonitorConfig
from catenary_monitor.core.physics.result import STATUS_MESSAGES, Status

__all__ = [
    'MAX_DEPTH',
    'MAX_TENSION_PER_MBL',
    'UNITS_FACTOR',
    'KN',
    'reading_status',
    'reading_status_array',
    'status_messages',
    'units_hint',
    'UNIT_FACTORS',
    'UnitsRule',
    'UnitsMemory',
    'units_factor',
    'units_factors',
    'UNSURE_LOW',
    'UNSURE_HIGH',
    'units_claims',
    'rest_table',
    'units_ratios',
    'units_latch',
    'units_text',
    'units_decide',
    'dock_units',
    'others_calm',
    'most_flagged',
]

MAX_DEPTH = 12_000.0  # m
MAX_TENSION_PER_MBL = 10.0  # -, tension bound as a multiple of the MBL
UNITS_FACTOR = 100.0  # -, a tension this many times below w * h is off by orders of magnitude
KN = 1000.0  # N per kN: the scale a load cell in kN needs


def reading_status(
    tension: float,
    depth: float,
    mbl: float,
    weight: float = math.nan,
    low: float = -math.inf,
    high: float = MAX_DEPTH,
) -> int:
    """0, or the Status of an implausible finite reading.

    Parameters: hook tension [N], depth at the hook [m], minimum breaking load [N], the
    chain's submerged weight [N/m] (NaN: no check below), the chart range at the hook [m]
    (``depth_min``, ``depth_max`` + the hook height: outside it the depth is impossible). An
    implausible depth wins over an implausible tension; non-finite readings give 0 (the solver
    reports them).
    """
    if not (math.isfinite(tension) and math.isfinite(depth)):
        return 0
    if depth > MAX_DEPTH or depth > high or depth < low:
        return int(Status.IMPLAUSIBLE_DEPTH)
    if tension > MAX_TENSION_PER_MBL * mbl:
        return int(Status.IMPLAUSIBLE_TENSION)
    hanging = weight * depth
    if (
        depth > 0.0
        and tension >= 0.0
        and (tension * UNITS_FACTOR <= hanging or (tension <= hanging < KN * tension <= mbl))
    ):
        return int(Status.WRONG_UNITS)
    return 0


def reading_status_array(
    tension: Any,
    depth: Any,
    mbl: Any,
    weight: Any = math.nan,
    low: Any = -math.inf,
    high: Any = MAX_DEPTH,
) -> np.ndarray:
    """:func:`reading_status` element by element (int64 array of the broadcast shape)."""
    t, h = np.asarray(tension, dtype=float), np.asarray(depth, dtype=float)
    w = np.asarray(weight, dtype=float)
    with np.errstate(invalid='ignore'):
        finite = np.isfinite(t) & np.isfinite(h)
        deep = finite & ((h > MAX_DEPTH) | (h > high) | (h < low))
        strong = finite & ~deep & (t > MAX_TENSION_PER_MBL * np.asarray(mbl, dtype=float))
        hanging = w * h
        weak = (
            finite
            & ~deep
            & ~strong
            & (h > 0.0)
            & (t >= 0.0)
            & (
                (t * UNITS_FACTOR <= hanging)
                | ((t <= hanging) & (hanging < KN * t) & (KN * t <= np.asarray(mbl, float)))
            )
        )
    out = np.zeros(np.broadcast(t, h, w, deep).shape, dtype=np.int64)
    out[deep] = Status.IMPLAUSIBLE_DEPTH
    out[strong] = Status.IMPLAUSIBLE_TENSION
    out[weak] = Status.WRONG_UNITS
    return out


def units_hint(line: LineConfig, low: bool) -> str:
    """ "wrong units?" and the parameter to check, for a reading too low (``low``) or too high."""
    name, scale = f'{line.name}.tension_scale', line.tension_scale
    if low:
        return (
            f'wrong units? a load cell in kN needs {name}: {KN:g} (it is {scale:g}; the '
            'tension is the reading x the scale, in N)'
        )
    return (
        f'wrong units? check {name} (it is {scale:g}; the tension is the reading x the scale, '
        'in N)'
    )


def status_messages(line: LineConfig) -> dict[int, str]:
    """The status sentences of ``line``: :data:`STATUS_MESSAGES` with the implausible tension's
    and the wrong units' naming the line's scale parameter."""
    out = dict(STATUS_MESSAGES)
    out[Status.IMPLAUSIBLE_TENSION] = (
        f'{STATUS_MESSAGES[Status.IMPLAUSIBLE_TENSION]}: {units_hint(line, False)}'
    )
    out[Status.IMPLAUSIBLE_DEPTH] = (
        'depth outside the chart (depth_min, depth_max) or deeper than any sea (above '
        f'{MAX_DEPTH:g} m): the tide gauge\'s datum, scale or the sensor; not solved (the tide '
        'status names it)'
    )
    out[Status.WRONG_UNITS] = (
        'hook tension 100 times or more below the hanging chain\'s own weight w*h, or below it '
        f'where 1000 times the reading would fit the chain (or a parted chain): '
        f'{units_hint(line, True)}'
    )
    return out


# --- units that announce themselves: a tension off by a unit factor against the statics ---

#: Factors a tension reading can be off by (the true tension / the reading as configured),
#: each with the mistake it names; their order is the ``wrong_units`` sensor states' (codes
#: :data:`~catenary_monitor.core.rules.sensor_state.UNITS_BASE` + index).
UNIT_FACTORS = (
    (10.0, 'daN'),
    (9.80665, 'kgf on N, or tonnes-force on kN'),
    (100.0, 'hN, or a gain'),
    (1000.0, 'kN on N'),
    (4.4482216, 'lbf on N'),
    (4448.2216, 'kip on N'),
    (0.1, 'N on daN'),
    (0.101972, 'N on kgf, or kN on tonnes-force'),
    (0.001, 'N on kN'),
    (0.224809, 'N on lbf'),
    (2.24809e-4, 'N on kip'),
)
_LOG_FACTORS = np.log([f for f, _ in UNIT_FACTORS])
#: Claims whose factor the witness leaves unsure (indices after :data:`UNIT_FACTORS`'): the
#: reading far below the chain's statics (the truth a factor above 1 times it), far above.
UNSURE_LOW = len(UNIT_FACTORS)
UNSURE_HIGH = UNSURE_LOW + 1
#: Factors this close (log) are one candidate: 10 and 9.81 (the text names both).
_SAME = math.log(1.05)
#: Points of the at-rest table over the chart range (linear between them).
REST_POINTS = 400


class UnitsRule(NamedTuple):
    """The units check's thresholds. Two witnesses of a line's expected tension:

    * its statics at rest x the dock's common loading, judged only while the dock is calm
      (the 75th percentile of the lines' deviation from the common loading within ``calm``):
      a ratio (expected / reading) at least ``far`` off 1 and within ``tolerance``
      (relative) of a unit factor is a claim;
    * where the dock model exists, the dock estimate's expected tension from the lines that
      agree with each other (:mod:`~catenary_monitor.core.rules.dock_watch`), in any weather:
      a line the estimate flags as disagreeing, whose ratio is within ``dock_tolerance`` of a
      unit factor (and at least ``far`` off 1), while at most a third of the lines are flagged
      (the others agree: the estimate stands), is a claim.

    The statics' witness is as sure as the lines agree: its ratio's log may be off by
    ``spread`` x the calm measure besides ``tolerance``. Where another unit factor lies
    within that, the claim names no factor (:func:`units_claims`): a line near its anchor's
    lift point in a storm carries 1.5-2 x the common loading, and a daN cell there reads
    6 x below it, between lbf (x4.45) and daN (x10).

    A ratio within ``fit`` of 1 (the statics' at rest, or the dock estimate's while the line
    agrees with it) for ``window`` s clears it."""

    far: float = 3.0
    tolerance: float = 0.4
    fit: float = 1.25
    calm: float = 1.5
    window: float = 600.0
    dock_tolerance: float = 0.25
    spread: float = 2.0


class UnitsMemory(NamedTuple):
    """A line's units latch: the newest claim [s] and its factor's index, the newest tick whose
    ratio was not within ``fit`` of 1 [s], and the newest clearing [s] (-inf: never)."""

    claimed: float = -math.inf
    factor: int = -1
    far: float = -math.inf
    cleared: float = -math.inf


def units_factor(ratio: float, tolerance: float = 0.4, far: float = 3.0) -> int:
    """The index in :data:`UNIT_FACTORS` of the factor a tension is off by, from ``ratio`` =
    expected / reading: -1 while the ratio is within ``far`` of 1 (a dock's lines differ, a
    storm loads some: no claim) or near no factor (within ``tolerance``, relative, of the
    nearest; 10 and 9.81 are 2 % apart: the nearer is named, the text names both)."""
    return int(units_factors(np.array([ratio]), tolerance, far)[0])


def units_factors(ratio: np.ndarray, tolerance: float = 0.4, far: float = 3.0) -> np.ndarray:
    """:func:`units_factor` element by element (int64 of ``ratio``'s shape)."""
    with np.errstate(invalid='ignore', divide='ignore'):
        lr = np.log(np.asarray(ratio, np.float64))
        off = np.abs(lr[..., None] - _LOG_FACTORS)
        best = np.argmin(np.where(np.isnan(off), np.inf, off), axis=-1)
        near = np.take_along_axis(off, best[..., None], axis=-1)[..., 0] <= math.log1p(tolerance)
        claim = np.isfinite(lr) & (np.abs(lr) >= math.log(far)) & near
    return np.where(claim, best, -1)


def units_claims(
    ratio: np.ndarray, calm: np.ndarray, rule: UnitsRule
) -> np.ndarray:
    """The statics' witness per element of ``ratio`` (expected / reading; ``calm`` the calm
    measure, broadcast against it): the index in :data:`UNIT_FACTORS` of the factor named,
    :data:`UNSURE_LOW` / :data:`UNSURE_HIGH` where the reading is off by a unit factor but
    the factor is unsure, -1 for no claim. A factor is a candidate within ``rule.tolerance``
    (relative) plus ``rule.spread`` x ``calm`` (log) of the ratio; it is named when it is the
    nearest, within ``rule.tolerance`` alone, and no other candidate is left (10 and 9.81 are
    one); any candidate and the ratio at least ``rule.far`` off 1 is a claim."""
    with np.errstate(invalid='ignore', divide='ignore'):
        lr = np.log(np.asarray(ratio, np.float64))
        off = np.abs(lr[..., None] - _LOG_FACTORS)
        off = np.where(np.isnan(off), np.inf, off)
        best = np.argmin(off, axis=-1)
        nearest = np.take_along_axis(off, best[..., None], axis=-1)[..., 0]
        tight = math.log1p(rule.tolerance)
        band = tight + rule.spread * np.asarray(calm, np.float64)
        candidate = off <= np.broadcast_to(band, lr.shape)[..., None]
        other = candidate & (np.abs(_LOG_FACTORS - _LOG_FACTORS[best][..., None]) > _SAME)
        far = np.isfinite(lr) & (np.abs(lr) >= math.log(rule.far))
        named = far & (nearest <= tight) & ~np.any(other, axis=-1)
        unsure = far & np.any(candidate, axis=-1) & ~named
    side = np.where(lr > 0.0, UNSURE_LOW, UNSURE_HIGH)
    return np.where(named, best, np.where(unsure, side, -1)).astype(np.int64)


def rest_table(
    config: MonitorConfig, chart: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """Each line's hook tension [N] with the dock at rest over the ``chart`` range [m] of
    depths: ``(depths (k,), tensions (k, lines))``, its fixed-length chain at the installed
    span (NaN for a line without ``chain_length``, or beyond its reach); empty without chain
    lengths."""
    lines = config.lines
    if sum(line.chain_length is not None for line in lines) < 3 or not chart[1] > chart[0]:
        return np.zeros(0), np.zeros((0, len(lines)))
    from catenary_monitor.core.physics.fixed_length import statics_at_span

    depths = np.linspace(max(chart[0], 0.1), chart[1], REST_POINTS)
    w = np.array([line.weight for line in lines])
    length = np.array([math.nan if line.chain_length is None else line.chain_length
                       for line in lines])  # fmt: skip
    span = np.array([line.anchor_distance for line in lines])
    ea = np.array([math.inf if not line.ea else line.ea for line in lines])
    h = depths[:, None] + np.array([line.hook_height for line in lines])[None, :]
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        t = statics_at_span(w[None, :], h, length[None, :], span[None, :], ea[None, :])
    return depths, np.asarray(t.top_tension, np.float64)


def units_ratios(
    table: tuple[np.ndarray, np.ndarray], depth: np.ndarray, tension: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per (tick, line): the ratio of the expected tension to the reading (its at-rest
    statics at the tick's ``depth`` [m] x the dock's common loading, the median over the lines
    of reading / statics), and per tick the calm measure (the 75th percentile over the lines of
    the absolute log deviation from that loading; NaN where fewer than 3 lines are judged)."""
    n, m = tension.shape
    if not len(table[0]):
        return np.full((n, m), math.nan), np.full(n, math.nan)
    rel = _relative(table, depth, tension)
    with np.errstate(invalid='ignore', divide='ignore'):
        judged = np.sum(np.isfinite(rel), axis=1)
        load = _nanmedian_rows(rel)
        dev = np.abs(np.log(rel / load[:, None]))
        calm = _nanpercentile_rows(dev, 75.0)
        ratio = load[:, None] / rel
    calm = np.where(judged >= 3, calm, math.nan)
    return ratio, calm


def _relative(
    table: tuple[np.ndarray, np.ndarray], depth: np.ndarray, tension: np.ndarray
) -> np.ndarray:
    """Per (tick, line): the reading over its at-rest statics at the tick's depth (NaN where
    either is unknown or not positive)."""
    depths, rest_rows = table
    n, m = tension.shape
    rest = np.empty((n, m))
    for k in range(m):
        rest[:, k] = np.interp(depth, depths, rest_rows[:, k], left=math.nan, right=math.nan)
    with np.errstate(invalid='ignore', divide='ignore'):
        rel = tension / rest
    return np.where((rel > 0) & np.isfinite(rel), rel, math.nan)


def others_calm(
    table: tuple[np.ndarray, np.ndarray], depth: np.ndarray, tension: np.ndarray
) -> np.ndarray:
    """Per (tick, line): the calm measure of the other lines (as :func:`units_ratios`', the
    line left out; NaN where fewer than 2 others are judged). Whether the dock is calm for a
    line's claim: on a dock of four lines one reading off by x10 is a quarter of the lines,
    and its own deviation kept the dock from ever being calm (the 75th percentile of four
    takes a quarter of the largest), so it was never claimed. The claim's band keeps the
    measure of all the lines (:func:`units_claims`): at a lift point the line judged carries
    2-3 x the others' loading, and the band then holds more than one factor (none named)."""
    n, m = tension.shape
    if not len(table[0]) or m < 3:
        return np.full((n, m), math.nan)
    rel = _relative(table, depth, tension)
    others = np.array([[j for j in range(m) if j != k] for k in range(m)], np.int64)
    rows = rel[:, others].reshape(n * m, m - 1)  # row (tick, line): the other lines
    with np.errstate(invalid='ignore', divide='ignore'):
        load = _nanmedian_rows(rows)
        calm = _nanpercentile_rows(np.abs(np.log(rows / load[:, None])), 75.0)
    judged = np.sum(np.isfinite(rows), axis=1)
    return np.where(judged >= 2, calm, math.nan).reshape(n, m)


def _nanmedian_rows(x: np.ndarray) -> np.ndarray:
    """The median of each row's finite values (NaN for none), quietly."""
    return _nanpercentile_rows(x, 50.0)


def _nanpercentile_rows(x: np.ndarray, q: float) -> np.ndarray:
    """The ``q`` percentile of each row's non-NaN values (linear between the order statistics,
    as numpy's default; NaN for none): a sort, not ``np.nanpercentile`` (20 times the cost on a
    tick's row)."""
    n = len(x)
    if not n or not x.shape[1]:
        return np.full(n, math.nan)
    ranked = np.sort(x, axis=1)  # NaN last
    count = np.sum(~np.isnan(x), axis=1)
    pos = q / 100.0 * np.maximum(count - 1, 0)
    lo = np.floor(pos).astype(np.int64)
    hi = np.minimum(lo + 1, np.maximum(count - 1, 0))
    rows = np.arange(n)
    a, b = ranked[rows, lo], ranked[rows, hi]
    return np.where(count > 0, a + (pos - lo) * (b - a), math.nan)


def units_latch(
    memory: list[UnitsMemory],
    now: np.ndarray,
    ratio: np.ndarray,
    calm: np.ndarray,
    judged: np.ndarray,
    rule: UnitsRule,
    dock: Optional[tuple[np.ndarray, np.ndarray]] = None,
    apart: Optional[np.ndarray] = None,
) -> tuple[np.ndarray, list[UnitsMemory]]:
    """Per (tick, line): the index of the unit factor a line is claimed off by (-1: none),
    and each line's latch after the last tick. A claim needs a calm dock (``calm`` within
    ``rule.calm``; ``apart`` given: the other lines' measure per (tick, line) within it,
    :func:`others_calm`) and the line's ``ratio`` off by a unit factor (:func:`units_claims`), or
    the dock estimate's claim ``dock`` = (factor index (-1: none), the line tested and
    agreeing) per (tick, line) (:func:`dock_units`); it holds until the ratio was within
    ``rule.fit`` of 1, or of the dock estimate's expectation while agreeing with it, for
    ``rule.window`` s (a tick
    not ``judged``, e.g. a stale reading or depth, is not within). Ticks ``now`` [s]."""
    n, m = ratio.shape
    with np.errstate(invalid='ignore', divide='ignore'):
        quiet = (calm[:, None] if apart is None else apart) <= math.log(rule.calm)
        idx = units_claims(ratio, calm[:, None], rule)
        claim = (idx >= 0) & quiet & judged
        near = judged & (np.abs(np.log(ratio)) < math.log(rule.fit))
    if dock is not None:
        idx = np.where(dock[0] >= 0, dock[0], idx)
        claim |= dock[0] >= 0
        near |= dock[1]
    if not n:
        return np.full((0, m), -1, np.int64), list(memory)
    before = np.array([[x.claimed for x in memory], [x.far for x in memory],
                       [x.cleared for x in memory]])  # fmt: skip
    claimed = _newest(np.where(claim, now[:, None], -math.inf), before[0])
    far = _newest(np.where(near, -math.inf, now[:, None]), before[1])
    cleared = _newest(np.where(now[:, None] - far >= rule.window, now[:, None], -math.inf),
                      before[2])  # fmt: skip
    last = _newest(np.where(claim, np.arange(n)[:, None], -1), np.full(m, -1.0))
    last = last.astype(np.int64)
    picked = np.take_along_axis(idx, np.maximum(last, 0), axis=0)
    factor = np.where(last >= 0, picked, np.array([x.factor for x in memory])[None, :])
    out = np.where(claimed > cleared, factor, -1).astype(np.int64)
    after = [
        UnitsMemory(float(claimed[-1, k]), int(factor[-1, k]), float(far[-1, k]),
                    float(cleared[-1, k]))  # fmt: skip
        for k in range(m)
    ]
    return out, after


def _newest(x: np.ndarray, before: np.ndarray) -> np.ndarray:
    """The running maximum down the rows of ``x`` (ticks, lines) after the row ``before``."""
    return np.maximum.accumulate(np.vstack([before[None, :], x]), axis=0)[1:]


def units_text(name: str, scale: float, index: int, tension: float) -> str:
    """The ``wrong units?`` sentence of line ``name`` (its ``tension_scale``) claimed off by
    :data:`UNIT_FACTORS` ``[index]``, reading ``tension`` [N]: the factor, the mistake it names
    and the scale that would fit; for :data:`UNSURE_LOW` / :data:`UNSURE_HIGH` the side and
    the scale to check, no factor."""
    if index in (UNSURE_LOW, UNSURE_HIGH):
        side = 'below' if index == UNSURE_LOW else 'above'
        return (
            f'wrong units? reading far {side} the chain\'s statics: check {name}.tension_scale '
            f'(the unit unsure; it is {scale:g}, the tension is the reading x the scale, in N; '
            f'reads {tension / 1e3:.1f} kN)'
        )
    factor, mistake = UNIT_FACTORS[index]
    also = ''
    if factor in (10.0, 9.80665):
        also = ' or kgf/tonnes-force, x9.81?' if factor == 10.0 else ' or daN, x10?'
    what = f'x{factor:.4g}' if factor >= 1.0 else f'/{1.0 / factor:.4g}'
    return (
        f'wrong units? reading {what} fits the chain\'s statics ({mistake}?{also}): '
        f'{name}.tension_scale {scale:g} -> {scale * factor:.6g} '
        f'(reads {tension / 1e3:.1f} kN)'
    )


def most_flagged(m: int) -> int:
    """How many of ``m`` lines the estimate may flag and still stand (a third, at least one;
    the units check's dock witness asks the same): beyond, the others do not agree with each
    other and the estimate cannot tell the bad lines from the good (one reading off by x10 of
    a four-line dock biased the fit so that the three good lines disagreed with it)."""
    return max(1, m // 3)


def dock_units(
    inputs: np.ndarray, tension: np.ndarray, fresh: np.ndarray, rule: UnitsRule
) -> tuple[np.ndarray, np.ndarray]:
    """The dock estimate's witness of the units, per (tick, line): the index of the unit
    factor a line's ``tension`` [N] is off by against the estimate's expected tension (-1:
    none), and whether the line was tested, agrees and reads within ``rule.fit`` of the
    expected tension (a witness that the reading fits). ``inputs`` (ticks, lines, 4) are the
    estimate's :data:`~catenary_monitor.core.rules.dock_watch.LINE_INPUTS` at the tick (flag
    1.0 disagreeing, 0.0 agreeing, NaN untested; the expected tension the others' fitted
    position gives the line); ``fresh`` the readings judged. A claim needs the line flagged
    and at most a third of the lines flagged (the rest agree with each other)."""
    flag, expected = inputs[..., 0], inputs[..., 2]
    m = tension.shape[1]
    with np.errstate(invalid='ignore', divide='ignore'):
        flagged = fresh & (flag == 1.0)
        few = np.sum(flag == 1.0, axis=1) <= most_flagged(m)
        ratio = expected / tension
        fits = fresh & (flag == 0.0) & (np.abs(np.log(ratio)) < math.log(rule.fit))
        ratio = np.where(flagged & few[:, None], ratio, math.nan)
    idx = units_factors(ratio, rule.dock_tolerance, rule.far)
    return idx, fits


def units_decide(
    table: tuple[np.ndarray, np.ndarray],
    rule: UnitsRule,
    memory: list[UnitsMemory],
    now: np.ndarray,
    tension: np.ndarray,
    tension_s: np.ndarray,
    depth: np.ndarray,
    depth_s: np.ndarray,
    timeouts: tuple[float, float],
    chart: tuple[float, float],
    dock: Optional[np.ndarray] = None,
) -> tuple[np.ndarray, list[UnitsMemory]]:
    """The units check at ticks ``now`` [s] (the core's one tick, the twin's window of them):
    per (tick, line) the index of the unit factor a line is claimed off by (-1: none), and the
    latches after (:func:`units_latch`). From each line's newest tension [N] and its stamp [s]
    and the newest depth [m] and its stamp [s] per tick, and the dock estimate's line inputs
    at the tick (``dock`` (ticks, lines, 4), :func:`dock_units`; None: no dock model); a
    reading older than its timeout (``tension_timeout``, ``depth_timeout`` [s]) or a depth
    outside the ``chart`` is not judged. ``rule.window`` 0: no check."""
    n, m = tension.shape
    if not rule.window > 0.0 or (not len(table[0]) and dock is None):
        return np.full((n, m), -1, np.int64), list(memory)
    with np.errstate(invalid='ignore'):
        depth_ok = (now - depth_s <= timeouts[1]) & (depth >= chart[0]) & (depth <= chart[1])
        fresh = (now[:, None] - tension_s <= timeouts[0]) & depth_ok[:, None]
    ratio, calm = units_ratios(table, np.where(depth_ok, depth, math.nan),
                               np.where(fresh, tension, math.nan))  # fmt: skip
    witness = None if dock is None else dock_units(dock, tension, fresh, rule)
    apart = others_calm(table, np.where(depth_ok, depth, math.nan),
                        np.where(fresh, tension, math.nan))  # fmt: skip
    return units_latch(memory, now, ratio, calm, fresh & np.isfinite(ratio), rule, witness,
                       apart)  # fmt: skip

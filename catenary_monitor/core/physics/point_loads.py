"""A chain with point loads: clump weights (sinkers) and buoys at known places along it.

Seed 002 (Guo & Li 2016, a highline with a hanging load) joins two catenaries at a point load:
the horizontal tension ``H`` is the same on both sides, the vertical tension jumps by the
load's weight. On a mooring chain the loads sit at arc lengths ``s_k`` from the anchor with
submerged weights ``W_k`` (N; positive a clump weight, negative a buoy). Between loads the chain
is a catenary with ``V(s)`` growing by ``w`` per metre, so every quantity is closed form per
segment (from the start of a segment at ``(x0, z0)`` with vertical tension ``V0``):

    x = x0 + H / w (asinh(V / H) - asinh(V0 / H)),    z = z0 + (hypot(H, V) - hypot(H, V0)) / w

The monitor's problems (inextensible chain, plain floats, one line at a time):

* :func:`solve_tension`: the hook tension ``T`` at depth ``h`` and anchor distance ``x``: the
  minimum anchor distance without uplift (the whole chain from the anchor suspended, tangent
  there), the critical tension at ``x`` (the load margin), and the state at ``x``: lifted (the
  anchor's vertical force ``V_A > 0``) or grounded (chain lying on the seabed from the anchor
  to a touchdown point; loads on that part lie on the seabed and act on nothing);
* :func:`solve_length`: the chain length ``L`` and span ``x`` (problem 5) give ``T``, ``H``,
  ``V_A``.

Each is a nest of bracketed one-dimensional roots (``scipy.optimize.brentq``, relative
tolerance :data:`RTOL`). A buoy strong enough to pull the chain below it off the seabed (a hump
the static model here does not follow) or a chain that would pass through the seabed gives
``status`` :data:`NOT_MODELLED` with NaN values (a hook tension the hanging chain and its loads
cannot reach: ``Status.TENSION``). ``test/test_point_loads.py`` checks them against MoorPy (a
free point between two lines) to 1e-6 and against seed 002's equation (6).
"""

from __future__ import annotations

import functools
import math
from typing import Any, Callable, NamedTuple, Optional, Sequence


from catenary_monitor.core.physics.result import ALL_KEYS, SolveResult, Status

__all__ = [
    'MODEL',
    'RTOL',
    'NOT_MODELLED',
    'PointLoads',
    'Profile',
    'walk',
    'solve_tension',
    'solve_length',
    'Answer',
    'solve_result',
    'min_anchor',
    'critical',
    'line_statics',
    'span_at_tension',
    'lift_depth',
]

#: ``model`` of an answer with point loads.
MODEL = 'inextensible catenary with point loads'
#: Relative tolerance of every root (on H, V_A, the grounded length).
RTOL = 1e-13
#: Status of a scene this static model does not follow (a buoy lifting a hump off the seabed,
#: a chain through the seabed): see the module docstring.
NOT_MODELLED = int(Status.NOT_MODELLED)
_BIG = 1e300


class PointLoads(NamedTuple):
    """Point loads along a chain: ``positions`` (m from the anchor, ascending) and submerged
    ``weights`` (N, + a clump weight, - a buoy)."""

    positions: tuple[float, ...]
    weights: tuple[float, ...]

    @classmethod
    def of(cls, positions: Sequence[float], weights: Sequence[float]) -> PointLoads:
        """Sorted by position (the pairs kept together)."""
        pairs = sorted(zip((float(p) for p in positions), (float(w) for w in weights)))
        return cls(tuple(p for p, _ in pairs), tuple(w for _, w in pairs))


class Profile(NamedTuple):
    """Where a walk up the chain stopped: span ``x``, height ``z`` (m above the anchor or
    touchdown), arc length ``s`` from it, vertical tension ``v`` (N) there, the lowest height
    on the way ``z_min`` and the loads passed ``((x, z), ...)``."""

    x: float
    z: float
    s: float
    v: float
    z_min: float
    passed: tuple[tuple[float, float], ...]


def _rise(w: float, h_: float, v0: float, v1: float) -> float:
    return (math.hypot(h_, v1) - math.hypot(h_, v0)) / w


def _run(w: float, h_: float, v0: float, v1: float) -> float:
    return h_ / w * (math.asinh(v1 / h_) - math.asinh(v0 / h_))


def walk(
    w: float,
    horizontal: float,
    v_anchor: float,
    loads: PointLoads,
    *,
    depth: Optional[float] = None,
    span: Optional[float] = None,
    length: Optional[float] = None,
    shift: float = 0.0,
) -> Optional[Profile]:
    """Walk up the chain from the anchor (or the touchdown, ``shift`` m of chain before it lying
    on the seabed: loads at ``s_k - shift <= 0`` lie there) with horizontal tension
    ``horizontal`` and vertical tension ``v_anchor`` at its start, until it reaches ``depth``
    (first time), ``span`` or arc ``length`` (give one). None when it never does."""
    h_ = horizontal
    x = z = s = 0.0
    v = v_anchor
    z_min = 0.0
    passed: list[tuple[float, float]] = []
    ends = [(p - shift, wk) for p, wk in zip(loads.positions, loads.weights) if p - shift > 0.0]
    for end, wk in [*ends, (math.inf, 0.0)]:
        v_end = v + w * (end - s) if end != math.inf else math.inf
        stop = _stop_in(w, h_, x, z, s, v, v_end, depth, span, length)
        if v < 0.0:  # the chain falls here before it rises: its lowest point
            z_low = z + _rise(w, h_, v, 0.0) if v_end > 0.0 else z + _rise(w, h_, v, v_end)
            z_min = min(z_min, z_low)
        if stop is not None:
            vs = stop
            return Profile(
                x + _run(w, h_, v, vs),
                z + _rise(w, h_, v, vs),
                s + (vs - v) / w,
                vs,
                z_min,
                tuple(passed),
            )
        x, z = x + _run(w, h_, v, v_end), z + _rise(w, h_, v, v_end)
        s, v = end, v_end + wk
        passed.append((x, z))
    return None


def _stop_in(
    w: float,
    h_: float,
    x: float,
    z: float,
    s: float,
    v0: float,
    v1: float,
    depth: Optional[float],
    span: Optional[float],
    length: Optional[float],
) -> Optional[float]:
    """The vertical tension where the walk stops within the segment ``[v0, v1]``, or None."""
    if length is not None:
        vs = v0 + w * (length - s)
        return vs if vs <= v1 else None
    if span is not None:
        arg = w * (span - x) / h_ + math.asinh(v0 / h_)
        if arg > 700.0:
            return None if v1 < _BIG else _BIG
        vs = h_ * math.sinh(arg)
        return vs if vs <= v1 else None
    assert depth is not None
    c = w * (depth - z) + math.hypot(h_, v0)
    if c <= h_:
        return None  # (a falling stretch below the target: never here)
    vs = math.sqrt((c - h_) * (c + h_))
    return vs if vs <= v1 and vs >= v0 else None


class Answer(NamedTuple):
    """One solved line: status (0 ok), ``H``, ``V_A`` (anchor uplift), top tension ``T``,
    minimum anchor distance, critical tension at the span, suspended length, the top's
    vertical tension and the load points ``((x, z), ...)`` (NaN where they do not apply)."""

    status: int
    horizontal: float
    uplift: float
    tension: float
    min_anchor_distance: float
    critical_tension: float
    suspended_length: float
    top_vertical: float
    points: tuple[tuple[float, float], ...] = ()


_NAN_ANSWER = Answer(NOT_MODELLED, *((math.nan,) * 7))


@functools.lru_cache(maxsize=None)
def _brentq() -> Any:
    """``scipy.optimize.brentq``, imported on a chain's first point-load solve (scipy.optimize
    takes about 0.3 s to import: every command paid it at start, for lines most docks lack)."""
    from scipy.optimize import brentq

    return brentq


def _root(f: object, lo: float, hi: float) -> float:
    return float(_brentq()(f, lo, hi, xtol=1e-300, rtol=RTOL, maxiter=400))


def _top(w: float, h_: float, va: float, loads: PointLoads, depth: float, shift: float) -> Profile:
    p = walk(w, h_, va, loads, depth=depth, shift=shift)
    if p is None:
        raise ValueError('the chain never reaches the depth')
    return p


def min_anchor(w: float, depth: float, tension: float, loads: PointLoads) -> tuple[float, float]:
    """(minimum anchor distance, its H): the whole chain from the anchor suspended and tangent
    there (``V_A = 0``), reaching ``depth`` with hook tension ``tension``; (0, NaN) where that
    tension cannot lift the clump weights near the anchor (the anchor never lifts)."""

    def excess(h_: float) -> float:
        p = _top(w, h_, 0.0, loads, depth, 0.0)
        return math.hypot(h_, p.v) - tension

    if tension <= w * depth:
        raise _TooLow
    if excess(tension * 1e-12) >= 0.0:  # the chain cannot lift its clumps: never the anchor
        return 0.0, math.nan
    h_ = _root(excess, tension * 1e-12, tension)
    return _top(w, h_, 0.0, loads, depth, 0.0).x, h_


class _TooLow(Exception):
    """The hook tension does not exceed the hanging chain's weight with its loads."""


def critical(w: float, depth: float, span: float, loads: PointLoads) -> tuple[float, Profile]:
    """(H, profile) of the chain tangent at the anchor spanning ``span`` to ``depth``: its hook
    tension is the tension at which the anchor starts to lift."""

    def height(h_: float) -> float:
        p = walk(w, h_, 0.0, loads, span=span)
        return (_BIG if p is None else p.z) - depth

    hi = w * span
    while height(hi) > 0.0:
        hi *= 4.0
    lo = hi / 4.0
    while height(lo) < 0.0:
        lo /= 4.0
    h_ = _root(height, lo, hi)
    p = walk(w, h_, 0.0, loads, span=span)
    assert p is not None
    return h_, p


def _lifted_va(w: float, h_: float, span: float, depth: float, loads: PointLoads) -> float:
    """The anchor's vertical tension that brings the chain (H given) to ``depth`` at ``span``."""

    def height(va: float) -> float:
        p = walk(w, h_, va, loads, span=span)
        return (_BIG if p is None else p.z) - depth

    if height(0.0) >= 0.0:
        return 0.0
    hi = max(h_, w * depth)
    while height(hi) < 0.0:
        hi *= 4.0
    return _root(height, 0.0, hi)


def solve_tension(
    w: float, depth: float, tension: float, span: float, loads: PointLoads
) -> Answer:
    """Problems 3 and 4 with point loads: hook tension, depth and anchor distance."""
    try:
        x_min, _ = min_anchor(w, depth, tension, loads)
        h_c, crit = critical(w, depth, span, loads)
        t_crit = math.hypot(h_c, crit.v)
        if tension > t_crit:  # the anchor lifts

            def excess(h_: float) -> float:
                va = _lifted_va(w, h_, span, depth, loads)
                p = walk(w, h_, va, loads, span=span)
                assert p is not None
                return math.hypot(h_, p.v) - tension

            h_ = _root(excess, h_c, tension)
            va = _lifted_va(w, h_, span, depth, loads)
            p = walk(w, h_, va, loads, span=span)
            assert p is not None
            return _answer(h_, va, p, x_min, t_crit, 0.0)
        shift, _, h_, p = _grounded(w, depth, tension, span, loads, x_min)
        if _buoy_grounded(loads, shift):
            return _NAN_ANSWER
        return _answer(h_, 0.0, p, x_min, t_crit, shift)
    except _TooLow:
        return _NAN_ANSWER._replace(status=int(Status.TENSION))
    except (ValueError, OverflowError, ZeroDivisionError, AssertionError):
        return _NAN_ANSWER


def _touchdown_path(
    f: Callable[[float, float], float], loads: PointLoads, g_max: float
) -> tuple[float, float]:
    """The grounded state ``(g, v0)`` where ``f(g, v0) = 0``: ``g`` m of chain lying on the
    seabed from the anchor, ``v0`` the vertical tension just above the touchdown. The path runs
    from ``g = 0`` (tangent at the anchor) to ``g_max``; where the touchdown reaches a clump
    weight it stays there while the clump settles (``v0`` from its weight to 0, the seabed
    taking the rest), then moves on past it. ``f`` is negative at the start and positive at
    the end (ValueError otherwise)."""
    pieces: list[tuple[str, float, float]] = []
    prev = 0.0
    for p, wk in zip(loads.positions, loads.weights):
        if wk > 0.0 and 0.0 < p < g_max:
            pieces += [('g', prev, p), ('v', p, wk)]
            prev = p
    pieces.append(('g', prev, g_max))

    def at(piece: tuple[str, float, float], t: float) -> float:
        kind, lo, hi = piece
        if kind == 'v':
            return f(lo, hi * (1.0 - t))  # t = 0: the clump just lifted; 1: resting
        g = lo + t * (hi - lo)
        nxt = [q for q in pieces if q[0] == 'v' and q[1] == hi]
        return f(hi, nxt[0][2]) if t >= 1.0 and nxt else f(g, 0.0)

    for piece in pieces:
        start, end = at(piece, 0.0), at(piece, 1.0)
        if start <= 0.0 <= end:
            if start == 0.0:
                t = 0.0
            elif end == 0.0:
                t = 1.0
            else:
                t = _root(lambda t: at(piece, t), 0.0, 1.0)
            kind, lo, hi = piece
            return (lo, hi * (1.0 - t)) if kind == 'v' else (lo + t * (hi - lo), 0.0)
    raise ValueError('no grounded state')


def _buoy_grounded(loads: PointLoads, g: float) -> bool:
    """A buoy on the grounded part (it would lift a hump there: not modelled)."""
    return any(wk < 0.0 and p <= g for p, wk in zip(loads.positions, loads.weights))


def _grounded(
    w: float, depth: float, tension: float, span: float, loads: PointLoads, x_min: float
) -> tuple[float, float, float, Profile]:
    """The grounded state at ``span``: the length lying on the seabed, the vertical tension
    above the touchdown, H and the profile from the touchdown."""

    def state(g: float, v0: float) -> tuple[float, Profile]:
        def excess(h_: float) -> float:
            return math.hypot(h_, _top(w, h_, v0, loads, depth, g).v) - tension

        h_ = _root(excess, tension * 1e-12, tension)
        return h_, _top(w, h_, v0, loads, depth, g)

    # all loads on the seabed: the plain chain (H = T - w h) where its grounded length allows
    h_plain = tension - w * depth
    if h_plain > 0.0:
        plain = walk(w, h_plain, 0.0, PointLoads((), ()), depth=depth)
        if plain is not None and span - plain.x > max(loads.positions, default=0.0):
            g = span - plain.x
            p = walk(w, h_plain, 0.0, loads, depth=depth, shift=g)
            assert p is not None
            return g, 0.0, h_plain, p
    g, v0 = _touchdown_path(lambda g, v0: g + state(g, v0)[1].x - span, loads, span)
    h_, p = state(g, v0)
    return g, v0, h_, p


def _answer(h_: float, va: float, p: Profile, x_min: float, t_crit: float, shift: float) -> Answer:
    if p.z_min < -1e-9 * max(abs(p.z), 1.0):
        return _NAN_ANSWER  # the chain would pass through the seabed (a buoy's hump)
    points = tuple((x + shift, z) for x, z in p.passed)
    return Answer(0, h_, va, math.hypot(h_, p.v), x_min, t_crit, p.s, p.v, points)


def solve_length(w: float, depth: float, length: float, span: float, loads: PointLoads) -> Answer:
    """Problem 5 with point loads: chain length, depth and anchor distance give the tension."""
    try:

        def grounded(g: float, v0: float = 0.0) -> tuple[float, Profile]:
            def reach(h_: float) -> float:
                return _top(w, h_, v0, loads, depth, g).s - (length - g)

            hi = w * length
            while reach(hi) < 0.0:
                hi *= 4.0
            h_ = _root(reach, hi * 1e-15, hi)
            return h_, _top(w, h_, v0, loads, depth, g)

        h0, p0 = grounded(0.0)
        if span <= p0.x:  # chain lying on the seabed
            g_hi = (length - depth) * (1.0 - 1e-9)
            if span <= g_hi:  # more chain than a straight drop and the span: slack
                return _NAN_ANSWER._replace(status=int(Status.CHAIN_SLACK))
            g, v0 = _touchdown_path(lambda g, v0: -(g + grounded(g, v0)[1].x - span), loads, g_hi)
            if _buoy_grounded(loads, g):
                return _NAN_ANSWER
            h_, p = grounded(g, v0)
            return _answer(h_, 0.0, p, math.nan, math.nan, g)

        def short(h_: float) -> float:
            def height(va: float) -> float:
                q = walk(w, h_, va, loads, length=length)
                assert q is not None
                return q.z - depth

            hi = w * length + abs(sum(loads.weights))
            while height(hi) < 0.0:
                hi *= 4.0
            va = 0.0 if height(0.0) >= 0.0 else _root(height, 0.0, hi)
            q = walk(w, h_, va, loads, length=length)
            assert q is not None
            return q.x - span

        hi = h0 * 2.0
        while short(hi) < 0.0:
            hi *= 2.0
            if hi > 1e15 * max(h0, 1.0):
                return _NAN_ANSWER._replace(status=int(Status.CHAIN_TOO_SHORT))
        h_ = _root(short, h0, hi)

        def height(va: float) -> float:
            q = walk(w, h_, va, loads, length=length)
            assert q is not None
            return q.z - depth

        top = w * length + abs(sum(loads.weights)) + h_
        while height(top) < 0.0:
            top *= 4.0
        va = _root(height, 0.0, top)
        end = walk(w, h_, va, loads, length=length)
        assert end is not None
        return _answer(h_, va, end, math.nan, math.nan, 0.0)
    except (ValueError, OverflowError, ZeroDivisionError, AssertionError):
        return _NAN_ANSWER


def solve_result(
    weight: float,
    depth: float,
    tension: Optional[float],
    anchor_distance: float,
    chain_length: Optional[float],
    mbl: Optional[float],
    loads: PointLoads,
) -> SolveResult:
    """One element of :func:`catenary_monitor.solve` with point loads, as a SolveResult: the
    hook ``tension`` (problems 3, 4) or the ``chain_length`` (problem 5) at
    ``anchor_distance``."""
    from catenary_monitor.core.physics.inextensible import result_keys  # the plain chain's keys

    w, h, x = float(weight), float(depth), float(anchor_distance)
    problem = 'tension' if tension is not None else 'chain_length'
    keys = result_keys(problem, True, mbl is not None)
    nan: Any = dict.fromkeys(ALL_KEYS, math.nan)
    if not all(math.isfinite(v) for v in (w, h, x, tension if tension is not None else 1.0)):
        return SolveResult(**nan, status=int(Status.NON_FINITE), problem=problem, keys=keys)
    for value, code in ((w, Status.WEIGHT), (h, Status.DEPTH), (x, Status.DISTANCE)):
        if not value > 0.0:
            return SolveResult(**nan, status=int(code), problem=problem, keys=keys)
    grounded = math.nan
    if tension is None:
        assert chain_length is not None
        fixed = solve_length(w, h, float(chain_length), x, loads)
        if fixed.status:
            return SolveResult(**nan, status=fixed.status, problem=problem, keys=keys, model=MODEL)
        tension = fixed.tension
        grounded = float(chain_length) - fixed.suspended_length
    ans = solve_tension(w, h, float(tension), x, loads)
    if ans.status:
        return SolveResult(**nan, status=ans.status, problem=problem, keys=keys, model=MODEL)
    tide = walk(w, ans.horizontal, 0.0, loads, span=x)
    found = {
        'horizontal_tension': ans.horizontal,
        'top_tension': ans.tension,
        'min_anchor_distance': ans.min_anchor_distance,
        'suspended_length': ans.suspended_length,
        'top_angle_deg': math.degrees(math.atan2(ans.top_vertical, ans.horizontal)),
        'anchor_angle_deg': math.degrees(math.atan2(ans.uplift, ans.horizontal)),
        'uplift_force': ans.uplift,
        'anchor_margin': x - ans.min_anchor_distance,
        'tide_margin': (math.inf if tide is None else tide.z) - h,
        'load_margin': ans.critical_tension - ans.tension,
        'grounded_length': grounded,
        'safety_factor': math.nan if mbl is None else float(mbl) / ans.tension,
    }
    values: Any = {k: (v if k in keys else math.nan) for k, v in found.items()}
    return SolveResult(
        **values,
        status=0,
        problem=problem,
        keys=keys,
        model=MODEL,
        method='two-segment catenaries at the point loads (seed 002), nested brentq',
    )


#: Span step of :func:`line_statics`' difference quotients, relative to the span (the roots'
#: RTOL of 1e-13 leaves ~1e-8 relative error in dR/ds, the truncation ~1e-10).
SPAN_STEP = 1e-5


def line_statics(
    w: float, depth: float, length: float, span: float, loads: PointLoads
) -> tuple[float, ...]:
    """A fixed-length chain with point loads at ``span`` (the dock model's line):
    ``(R, T, V, V_A, grounded length, suspended length, dR/ds, dT/ds, regime)`` in the order
    and units of :class:`~catenary_monitor.core.physics.fixed_length.LineStatics` (regime a
    ``LineRegime``). The state is :func:`solve_length`'s; the stiffnesses are central
    differences of it over :data:`SPAN_STEP` of the span (one-sided next to the slack and taut
    ends). SLACK: the chain hangs straight down from the hook (R = 0; T the weight of the
    hanging chain and the loads on it); TAUT: the chain cannot reach (R = inf); a scene the
    static model does not follow (:data:`NOT_MODELLED`): INVALID with NaN."""
    from catenary_monitor.core.physics.fixed_length import LineRegime

    nan = math.nan
    state = _state_at(w, depth, length, span, loads)
    if state is None:
        return (nan,) * 8 + (float(LineRegime.INVALID),)
    if state == 'slack':
        hang = w * depth + sum(v for p, v in zip(*loads) if p > length - depth)
        if not hang > 0.0:
            return (nan,) * 8 + (float(LineRegime.INVALID),)
        return (0.0, hang, hang, 0.0, length - depth, depth, 0.0, 0.0, float(LineRegime.SLACK))
    if state == 'taut':
        return (math.inf,) + (nan,) * 7 + (float(LineRegime.TAUT),)
    assert isinstance(state, Answer)
    ds = SPAN_STEP * max(span, 1.0)
    hi, lo = _state_at(w, depth, length, span + ds, loads), _state_at(
        w, depth, length, span - ds, loads
    )
    if isinstance(hi, Answer) and isinstance(lo, Answer):
        a1, x1, a0, x0 = hi, span + ds, lo, span - ds
    elif isinstance(hi, Answer):  # next to the slack end
        a1, x1, a0, x0 = hi, span + ds, state, span
    elif isinstance(lo, Answer):  # next to the taut end
        a1, x1, a0, x0 = state, span, lo, span - ds
    else:
        a1, x1, a0, x0 = state, span, state, span
    run = x1 - x0
    dr = (a1.horizontal - a0.horizontal) / run if run else nan
    dt = (a1.tension - a0.tension) / run if run else nan
    ans = state
    grounded = length - ans.suspended_length
    regime = LineRegime.LIFTED if ans.uplift > 0.0 else LineRegime.GROUNDED
    return (
        ans.horizontal,
        ans.tension,
        ans.top_vertical,
        ans.uplift,
        grounded,
        ans.suspended_length,
        dr,
        dt,
        float(regime),
    )


def _state_at(
    w: float, depth: float, length: float, span: float, loads: PointLoads
) -> Optional[Any]:
    """:func:`solve_length` at ``span``: its Answer, ``'slack'``, ``'taut'`` or None."""
    if not (w > 0.0 and depth > 0.0 and length > depth and span >= 0.0):
        return None
    if span >= math.sqrt((length - depth) * (length + depth)):
        return 'taut'  # beyond the straight chain's reach, whatever it carries
    ans = solve_length(w, depth, length, span, loads)
    if ans.status == int(Status.CHAIN_SLACK):
        return 'slack'
    if ans.status == int(Status.CHAIN_TOO_SHORT):
        return 'taut'
    return ans if ans.status == 0 else None


def span_at_tension(
    w: float, depth: float, length: float, tension: float, loads: PointLoads, start: float
) -> float:
    """The span [m] at which a chain of ``length`` with its point loads, at ``depth``, has hook
    ``tension`` (the inverse of :func:`solve_length`: the holding's implied anchor distance).
    Brent's method from a bracket grown around ``start`` (the installed span) within the
    slack and taut spans; NaN where the tension does not fix the span (at most the slack
    chain's) or a span on the way is not modelled."""
    lo, hi = length - depth, math.sqrt((length - depth) * (length + depth))
    if not (w > 0.0 and depth > 0.0 and lo > 0.0 and math.isfinite(tension)):
        return math.nan

    def excess(x: float) -> float:
        a = solve_length(w, depth, length, x, loads)
        if a.status == int(Status.CHAIN_TOO_SHORT):
            return math.inf
        if a.status:
            raise ValueError('not modelled')
        return a.tension - tension

    try:
        a, b = _bracket(excess, min(max(start, lo), hi), lo, hi)
        if a != a:
            return math.nan
        return float(_brentq()(excess, a, b, xtol=1e-12, rtol=1e-13, maxiter=200))
    except (ValueError, OverflowError, ZeroDivisionError):
        return math.nan


def _bracket(
    f: Callable[[float], float], x: float, lo: float, hi: float
) -> tuple[float, float]:
    """``(a, b)`` within ``(lo, hi)`` around ``x`` where ``f`` changes sign (NaN, NaN: none):
    steps from 0.25 m doubling toward the sign change."""
    eps = 1e-9 * hi
    lo, hi = lo + eps, hi - eps
    x = min(max(x, lo), hi)
    fx = f(x)
    step = 0.25 if fx < 0.0 else -0.25
    while True:
        y = min(max(x + step, lo), hi)
        fy = f(y)
        if (fx < 0.0) != (fy < 0.0):
            return (x, y) if x < y else (y, x)
        if y in (lo, hi):
            return math.nan, math.nan
        x, fx, step = y, fy, step * 2.0


def lift_depth(w: float, length: float, span: float, loads: PointLoads) -> float:
    """The depth [m] at which a chain of ``length`` with its point loads, its hook ``span`` m
    from the anchor, lifts the anchor: the whole chain hangs, horizontal at the anchor (the
    holding's ``tide_margin_at_length``). NaN where there is none (``span >= length``) or the
    chain would pass through the seabed on the way (a buoy's hump)."""
    if not (w > 0.0 and 0.0 < span < length):
        return math.nan

    def reach(h_: float) -> float:
        p = walk(w, h_, 0.0, loads, length=length)
        return (-math.inf if p is None else p.x) - span

    try:
        hi = w * length
        while reach(hi) < 0.0:
            hi *= 4.0
        lo = hi / 4.0
        while reach(lo) > 0.0:
            lo /= 4.0
        p = walk(w, _root(reach, lo, hi), 0.0, loads, length=length)
    except (ValueError, OverflowError, ZeroDivisionError):
        return math.nan
    if p is None or p.z_min < -1e-9 * max(abs(p.z), 1.0) or not p.z > 0.0:
        return math.nan
    return p.z

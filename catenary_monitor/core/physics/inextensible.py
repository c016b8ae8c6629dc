"""The inextensible chain: :func:`solve_inextensible` with validation and a status per element.

Two tiers of errors (scipy / sgp4 style):

* a mistake in the call itself (no load given, two loads given, chain length without anchor
  distance) raises ``ValueError`` naming the rule;
* a physically impossible element (NaN, non-positive weight, ``T <= w h``, a chain too short, ...)
  never raises: it gets a non-zero ``status`` and NaN outputs, and the other elements are solved
  as if it were not there.  ``STATUS_MESSAGES`` maps each code to one sentence.
"""

from __future__ import annotations

import functools
import math
from typing import Any, Optional, TypeGuard, Union

import numpy as np

from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics import fused_kernel
from catenary_monitor.core.physics.result import ALL_KEYS, INF_MARGINS, SolveResult, Status

ArrayLike = Union[float, int, np.ndarray, list]


def _check_call(tension: Any, horizontal: Any, chain_length: Any, anchor_distance: Any) -> str:
    given = [
        name
        for name, v in (
            ('tension', tension),
            ('horizontal', horizontal),
            ('chain_length', chain_length),
        )
        if v is not None
    ]
    if len(given) != 1:
        raise ValueError(
            'give exactly one of tension, horizontal, chain_length '
            f'(got {", ".join(given) if given else "none"})'
        )
    if given[0] == 'chain_length' and anchor_distance is None:
        raise ValueError(
            'chain_length needs anchor_distance (the chain lies on the seabed '
            'between hook and anchor)'
        )
    return given[0]


def solve_inextensible(
    weight: ArrayLike,
    depth: ArrayLike,
    tension: Optional[ArrayLike] = None,
    horizontal: Optional[ArrayLike] = None,
    anchor_distance: Optional[ArrayLike] = None,
    chain_length: Optional[ArrayLike] = None,
    mbl: Optional[ArrayLike] = None,
) -> SolveResult:
    """Solve the anchor-chain catenary for the minimum anchor distance, uplift and margins.

    Parameters
    ----------
    weight : submerged chain weight per metre w [N/m].
    depth : vertical distance anchor -> hook point h [m].
    tension : measured hook tension T [N] (problems 3, 4), or
    horizontal : horizontal tension R [N] (problems 1, 2), or
    chain_length : paid-out chain length Lm [m] (problem 5; needs ``anchor_distance``).
    anchor_distance : horizontal distance hook -> anchor x [m]; adds the uplift state and margins.
    mbl : minimum breaking load [N]; adds ``safety_factor = mbl / top_tension``.

    Returns
    -------
    SolveResult, whose attributes are the JSON keys; ``status`` flags impossible elements.

    Notes
    -----
    Every input may be an array; arrays broadcast and are solved in vectorized code.  The
    relative error against a 50-digit reference is below 1e-12 wherever the problem is
    well-conditioned (docs/solver.md, "Accuracy").  With all-scalar ``tension`` or ``horizontal``
    inputs a plain-float path gives the same numbers to rounding, an order of magnitude faster.
    """
    if _ONE is not None:  # one element of problem 3 or 4 in plain numbers: the C kernel
        try:
            one = _ONE(
                weight,
                depth,
                tension,
                horizontal,
                anchor_distance,
                chain_length,
                mbl,
                None,
                cat.MAXITER,
            )
        except OverflowError:  # an int beyond float range: the general path says so
            one = None
        if one is not None:
            return one
    if (
        horizontal is None
        and chain_length is None
        and tension is not None
        and _plain(weight)
        and _plain(depth)
        and _plain(tension)
        and (anchor_distance is None or _plain(anchor_distance))
        and (mbl is None or _plain(mbl))
    ):  # the node's case: skip the generic dispatch
        try:
            return _solve_scalar(
                'tension',
                float(weight),
                float(depth),
                float(tension),
                None if anchor_distance is None else float(anchor_distance),
                None if mbl is None else float(mbl),
            )
        except (OverflowError, ZeroDivisionError, ValueError):
            pass  # beyond float range in plain math (e.g. sinh overflow): numpy gives inf instead
    problem = _check_call(tension, horizontal, chain_length, anchor_distance)
    if problem == 'tension' and fused_kernel.AVAILABLE and tension is not None:
        return _solve_tension_kernel(weight, depth, tension, anchor_distance, mbl)
    inputs: dict[str, Any] = {  # user values, checked below (np.ndim, float(), asarray)
        'weight': weight,
        'depth': depth,
        'tension': tension,
        'horizontal': horizontal,
        'anchor_distance': anchor_distance,
        'chain_length': chain_length,
        'mbl': mbl,
    }
    given = {k: v for k, v in inputs.items() if v is not None}
    scalar = all(np.ndim(v) == 0 for v in given.values())
    if scalar and problem != 'chain_length':
        try:
            floats = {k: float(v) for k, v in given.items()}
        except (TypeError, ValueError) as exc:
            raise ValueError(f'inputs must be numbers: {exc}') from None
        try:
            return _solve_scalar(
                problem,
                floats['weight'],
                floats['depth'],
                floats[problem],
                floats.get('anchor_distance'),
                floats.get('mbl'),
            )
        except (OverflowError, ZeroDivisionError, ValueError):
            pass  # beyond float range in plain math (e.g. sinh overflow): numpy gives inf instead
    try:
        arrays = dict(
            zip(given, np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in given.values())))
        )
    except ValueError as exc:
        raise ValueError(f'inputs do not broadcast together: {exc}') from None
    return _solve_arrays(problem, arrays, scalar)


def _solve_tension_kernel(
    weight: ArrayLike,
    depth: ArrayLike,
    tension: ArrayLike,
    anchor_distance: Optional[ArrayLike],
    mbl: Optional[ArrayLike],
) -> SolveResult:
    """Problems 3 and 4 through the C kernel (:mod:`catenary_monitor.core.physics.fused_kernel`).

    0-d inputs are passed as floats (no broadcast copy); arrays as flat float64 of the broadcast
    shape.  The kernel writes the result rows that apply in place and the status per element.
    """
    flat = _flat_inputs(weight, depth, tension, anchor_distance, mbl)
    if flat is not None:  # the common call: 1-D float64 arrays of one length, floats
        return _kernel_result(flat[0], (flat[1],), anchor_distance, mbl)
    given = [v for v in (weight, depth, tension, anchor_distance, mbl)]
    try:
        arrays = [None if v is None else np.asarray(v, dtype=float) for v in given]
        shape = np.broadcast_shapes(*(a.shape for a in arrays if a is not None))
    except ValueError as exc:
        raise ValueError(f'inputs do not broadcast together: {exc}') from None
    n = math.prod(shape)
    args: list[Any] = []
    for a in arrays:
        if a is None or a.ndim == 0:
            args.append(None if a is None else float(a))
        elif a.shape == shape:
            args.append(np.ascontiguousarray(a).reshape(n))
        else:
            args.append(np.ascontiguousarray(np.broadcast_to(a, shape)).reshape(n))
    if not shape:  # every input 0-d (but not all plain floats: e.g. float32 or 0-d arrays)
        keys = result_keys('tension', anchor_distance is not None, mbl is not None)
        rows, status = fused_kernel.solve_arrays(args[0], args[1], args[2], args[3], args[4], n)
        values: dict[str, Any] = dict(zip(ALL_KEYS, (float(v) for v in rows[:, 0])))
        return SolveResult(**values, status=int(status[0]), problem='tension', keys=keys)
    return _kernel_result(args, shape, anchor_distance, mbl)


_F64 = np.dtype(np.float64)
_NAN_BYTES = np.float64(np.nan).tobytes()  # read-only: arrays on it are read-only


def _flat_inputs(*given: Any) -> Optional[tuple[list[Any], int]]:
    """``(kernel arguments, n)`` when every input is None, a float, an int or a 1-D
    C-contiguous float64 array, the arrays of one length n (at least one array); else None.

    The library user's array call, taken without the generic broadcast (~15 us less a call:
    at 1e3 elements as much as the floor itself)."""
    n = -1
    args: list[Any] = []
    for v in given:
        kind = type(v)
        if kind is np.ndarray:
            if v.dtype != _F64 or v.ndim != 1 or not v.flags.c_contiguous:
                return None
            if n < 0:
                n = v.shape[0]
            elif v.shape[0] != n:
                return None
        elif kind is int:
            try:
                v = float(v)
            except OverflowError:  # the general path says so
                return None
        elif v is not None and kind is not float:
            return None
        args.append(v)
    return (args, n) if n > 0 else None


@functools.lru_cache(maxsize=None)
def _row_plan(has_x: bool, has_mbl: bool) -> tuple[tuple[str, ...], int, tuple[int, ...]]:
    """The keys that apply, the kernel's row mask for them, and per key of ``ALL_KEYS`` its
    row in the kernel's output (-1: NaN, not computed)."""
    keys = result_keys('tension', has_x, has_mbl)
    where = tuple(keys.index(k) if k in keys else -1 for k in ALL_KEYS)
    return keys, fused_kernel.row_mask(keys), where


def _kernel_result(
    args: list[Any], shape: tuple[int, ...], anchor_distance: Any, mbl: Any
) -> SolveResult:
    """Solve flat kernel arguments of ``math.prod(shape)`` elements into a result of ``shape``.

    Only the rows that apply are computed into memory of their own; the others are NaN
    everywhere, one read-only NaN broadcast to the shape (no memory written for them)."""
    keys, mask, where = _row_plan(anchor_distance is not None, mbl is not None)
    out = np.empty((len(keys),) + shape)
    status = np.empty(shape, dtype=np.int64)
    fused_kernel.solve_into(args, out, status, mask)
    nan = np.ndarray(shape, _F64, _NAN_BYTES, 0, (0,) * len(shape))
    rows = tuple(out)
    columns = [nan if j < 0 else rows[j] for j in where]
    return _new_tuple(SolveResult, (*columns, status, 'tension', keys, *_TAIL))


@functools.lru_cache(maxsize=None)
def result_keys(problem: str, has_x: bool, has_mbl: bool) -> tuple[str, ...]:
    """The :class:`SolveResult` fields a ``problem`` fills (given an anchor distance, an MBL)."""
    skip = set()
    if not has_x:
        skip |= {'anchor_margin', 'tide_margin', 'load_margin'}
    if problem != 'chain_length':
        skip.add('grounded_length')
    if not has_mbl:
        skip.add('safety_factor')
    return tuple(k for k in ALL_KEYS if k not in skip)


def _validate(problem: str, a: dict[str, np.ndarray]) -> np.ndarray:
    """Status per element, first violated rule wins (order of the Status enum)."""
    shape = a['weight'].shape
    status = np.zeros(shape, dtype=np.int64)

    def flag(cond: np.ndarray, code: Status) -> None:
        status[(status == 0) & cond] = code

    finite = np.ones(shape, dtype=bool)
    for v in a.values():
        finite &= np.isfinite(v)
    flag(~finite, Status.NON_FINITE)
    w, h = a['weight'], a['depth']
    flag(~(w > 0), Status.WEIGHT)
    flag(~(h > 0), Status.DEPTH)
    if problem == 'tension':
        flag(~(a['tension'] > w * h), Status.TENSION)
    if problem == 'horizontal':
        flag(~(a['horizontal'] > 0), Status.HORIZONTAL)
    if 'anchor_distance' in a:
        flag(~(a['anchor_distance'] > 0), Status.DISTANCE)
    if problem == 'chain_length':
        x, lm = a['anchor_distance'], a['chain_length']
        flag(~(lm > np.hypot(x, h)), Status.CHAIN_TOO_SHORT)
        flag(~(lm < x + h), Status.CHAIN_SLACK)
    if 'mbl' in a:
        flag(~(a['mbl'] > 0), Status.MBL)
    return status


def _solve_arrays(problem: str, full: dict[str, np.ndarray], scalar: bool) -> SolveResult:
    with np.errstate(over='ignore', invalid='ignore', divide='ignore'):
        return _solve_valid(problem, full, scalar)


def _solve_valid(problem: str, full: dict[str, np.ndarray], scalar: bool) -> SolveResult:
    status = _validate(problem, full)
    shape = status.shape
    ok = status == 0
    a = {k: v[ok] for k, v in full.items()}  # 1-D views of the valid elements
    n = int(ok.sum())
    out = {k: np.full(n, np.nan) for k in ALL_KEYS}
    conv = np.ones(n, dtype=bool)
    w, h = a['weight'], a['depth']
    x = a.get('anchor_distance')
    if problem == 'tension':
        b = cat.two_prod_diff(a['tension'], w, h) / w  # anchor-end tension / w
        _fill_grounded(out, w, b, h)
        out['top_tension'] = a['tension'].copy()
        if x is not None:
            lift = x < out['min_anchor_distance']
            if lift.any():
                state, _, c = cat.lifted_from_tension(w[lift], b[lift], h[lift], x[lift])
                _fill_lifted(out, lift, state)
                out['top_tension'][lift] = a['tension'][lift]  # measured, not recomputed
                conv[lift] = c
    elif problem == 'horizontal':
        r = a['horizontal']
        _fill_grounded(out, w, r / w, h)
        if x is not None:
            lift = x < out['min_anchor_distance']
            if lift.any():
                _fill_lifted(
                    out,
                    lift,
                    cat.lifted_from_horizontal(w[lift], h[lift], r[lift] / w[lift], x[lift]),
                )
    else:
        x = a['anchor_distance']  # chain_length needs anchor_distance (_check_call)
        lm = a['chain_length']
        am, c = cat.grounded_parameter_from_length(h, lm - x)
        conv &= c
        _fill_grounded(out, w, am, h)
        out['grounded_length'] = lm - out['suspended_length']
        taut = out['grounded_length'] < 0  # the chain cannot lie on the seabed: anchor lifted
        if taut.any():
            at, c = cat.taut_parameter_from_length(h[taut], x[taut], lm[taut])
            conv[taut] &= c
            g = cat.grounded(at, h[taut])
            out['min_anchor_distance'][taut] = g.min_anchor_distance
            state = cat.lifted_from_horizontal(w[taut], h[taut], at, x[taut])
            _fill_lifted(out, taut, state)
            out['grounded_length'][taut] = 0.0
    if x is not None:
        conv &= _fill_margins(out, w, h, x)
    if 'mbl' in a:
        out['safety_factor'] = a['mbl'] / out['top_tension']
    keys = result_keys(problem, x is not None, 'mbl' in a)
    # never status 0 with inf or NaN: a solved element whose results under- or overflowed
    # (a margin of +inf excepted, INF_MARGINS: result.in_range)
    beyond = np.zeros(n, dtype=bool)
    for k in keys:
        beyond |= ~(np.isfinite(out[k]) | ((out[k] == np.inf) & (k in INF_MARGINS)))
    bad = ~conv | beyond
    if bad.any():
        for v in out.values():
            v[bad] = np.nan
        sub = status[ok]
        sub[beyond] = Status.OUT_OF_RANGE
        sub[~conv] = Status.NO_CONVERGENCE
        status[ok] = sub
    result: dict[str, Any] = {}
    for k in ALL_KEYS:
        full_v = np.full(shape, np.nan)
        if k in keys:
            full_v[ok] = out[k]
        result[k] = float(full_v) if scalar else full_v
    return SolveResult(
        **result, status=int(status) if scalar else status, problem=problem, keys=keys
    )


def _fill_grounded(
    out: dict[str, np.ndarray], w: np.ndarray, a: np.ndarray, h: np.ndarray
) -> None:
    g = cat.grounded(a, h)
    out['horizontal_tension'] = w * a
    out['top_tension'] = w * (a + h)
    out['min_anchor_distance'] = g.min_anchor_distance
    out['suspended_length'] = g.suspended_length
    out['top_angle_deg'] = np.degrees(g.top_angle)
    out['anchor_angle_deg'] = np.zeros_like(a)
    out['uplift_force'] = np.zeros_like(a)


def _fill_lifted(out: dict[str, np.ndarray], where: np.ndarray, s: cat.Lifted) -> None:
    out['horizontal_tension'][where] = s.horizontal_tension
    out['top_tension'][where] = s.top_tension
    out['suspended_length'][where] = s.suspended_length
    out['top_angle_deg'][where] = np.degrees(s.top_angle)
    out['anchor_angle_deg'][where] = np.degrees(s.anchor_angle)
    out['uplift_force'][where] = s.uplift_force


def _fill_margins(
    out: dict[str, np.ndarray], w: np.ndarray, h: np.ndarray, x: np.ndarray
) -> np.ndarray:
    """Anchor, tide and load margins; returns the load-margin solve's converged flags."""
    out['anchor_margin'] = x - out['min_anchor_distance']
    a_now = out['horizontal_tension'] / w
    out['tide_margin'] = cat.depth_reached(a_now, x) - h
    a_crit, conv = cat.critical_parameter(h, x)
    out['load_margin'] = w * (a_crit + h) - out['top_tension']
    return conv


# --------------------------------------------------------------------------------------------
# Plain-float path for one measured tension (the live node's case): same formulas, no arrays.
# --------------------------------------------------------------------------------------------
_NAN = math.nan
#: Input types that take the plain-float path straight away (``float()`` is exact for them).
_PLAIN = (float, int, np.float64)


def _plain(v: object) -> TypeGuard[float]:
    """True for the exact types of :data:`_PLAIN` (subclasses take the generic path)."""
    return type(v) in _PLAIN


_new_tuple = tuple.__new__  # builds a SolveResult without its keyword-handling constructor
_MODEL, _METHOD = SolveResult._field_defaults['model'], SolveResult._field_defaults['method']
_TAIL = (_MODEL, _METHOD)
_NAN12 = (_NAN,) * 12


def _solve_scalar(
    problem: str,
    w: float,
    h: float,
    load: float,
    x: Optional[float] = None,
    mbl: Optional[float] = None,
) -> SolveResult:
    """Problems 1-4 for one element in plain floats (same checks and formulas as arrays).

    ``load`` is the hook tension T (``problem='tension'``) or the horizontal tension R
    (``'horizontal'``).  ``cat.grounded`` and ``cat.depth_reached`` are written out inline, in
    their operation order.
    """
    isfinite = math.isfinite
    by_tension = problem == 'tension'
    if not (
        isfinite(w)
        and isfinite(h)
        and isfinite(load)
        and (x is None or isfinite(x))
        and (mbl is None or isfinite(mbl))
    ):
        status = Status.NON_FINITE
    elif not w > 0:
        status = Status.WEIGHT
    elif not h > 0:
        status = Status.DEPTH
    elif by_tension and not load > w * h:
        status = Status.TENSION
    elif not by_tension and not load > 0:
        status = Status.HORIZONTAL
    elif x is not None and not x > 0:
        status = Status.DISTANCE
    elif mbl is not None and not mbl > 0:
        status = Status.MBL
    else:
        status = Status.OK
    keys = result_keys(problem, x is not None, mbl is not None)
    if status:
        return _new_tuple(SolveResult, _NAN12 + (int(status), problem, keys) + _TAIL)
    if by_tension:
        b = cat.two_prod_diff(load, w, h) / w  # anchor-end tension / w
        t = load
    else:
        b = load / w
        t = w * (b + h)
    z = h / b
    x_min = b * math.log1p(z + math.sqrt(z * (2.0 + z)))
    length = math.sqrt(h) * math.sqrt(h + 2.0 * b)  # cat.grounded's form: no underflow
    beta = math.atan2(length, b)
    r, alpha, uplift = w * b, 0.0, 0.0
    anchor_margin = tide_margin = load_margin = safety = _NAN
    if x is not None:
        if x < x_min:
            if by_tension:
                s, _, converged = cat.lifted_from_tension_scalar(w, b, h, x)
                if not converged:
                    return _new_tuple(
                        SolveResult, _NAN12 + (int(Status.NO_CONVERGENCE), problem, keys) + _TAIL
                    )
                r, uplift, alpha, _, beta, length = s  # top_tension: the measured one
            else:
                r, uplift, alpha, t, beta, length = cat.lifted_from_horizontal(
                    w, h, b, x, cat._MATH
                )
        anchor_margin = x - x_min
        a_now = r / w
        try:
            half = math.sinh(0.5 * x / a_now)
        except OverflowError:  # x/a > ~1421: the depth is beyond float64, as numpy's inf
            half = math.inf
        tide_margin = 2.0 * a_now * half * half - h
        load_margin = w * (cat.critical_parameter_scalar(h, x) + h) - t
        if load_margin != load_margin:  # NaN: the load-margin solve did not converge
            return _new_tuple(
                SolveResult, _NAN12 + (int(Status.NO_CONVERGENCE), problem, keys) + _TAIL
            )
    if mbl is not None:
        safety = mbl / t
    values = (
        r,
        t,
        x_min,
        length,
        math.degrees(beta),
        math.degrees(alpha),
        uplift,
        anchor_margin,
        tide_margin,
        load_margin,
        _NAN,
        safety,
    )
    if not all(
        isfinite(v) or (v == math.inf and k in INF_MARGINS)
        for v, k in zip(values, ALL_KEYS)
        if k in keys
    ):
        # never status 0 with inf or NaN: a result under- or overflowed
        return _new_tuple(SolveResult, _NAN12 + (int(Status.OUT_OF_RANGE), problem, keys) + _TAIL)
    return _new_tuple(SolveResult, values + (0, problem, keys, _MODEL, _METHOD))


_ONE = fused_kernel._k.solve_one if fused_kernel.AVAILABLE else None
if fused_kernel.AVAILABLE:  # the kernel builds the SolveResult of a one-element call itself
    fused_kernel.set_result(
        SolveResult,
        tuple(
            (
                'tension',
                result_keys('tension', has_x, has_mbl),
                SolveResult._field_defaults['model'],
                SolveResult._field_defaults['method'],
            )
            for has_x in (False, True)
            for has_mbl in (False, True)
        ),
    )

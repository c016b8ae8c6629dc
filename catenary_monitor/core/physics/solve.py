"""``solve()``: the one public entry to every chain model, with a status code per element.

``solve(weight, depth, tension=T | horizontal=R | chain_length=Lm, anchor_distance=x, mbl=M,
ea=EA)`` returns a :class:`~catenary_monitor.core.physics.result.SolveResult` whatever the model:

* without ``ea`` (or ``ea=None``): the inextensible catenary of the seed paper
  (:mod:`catenary_monitor.core.physics.inextensible`);
* with ``ea`` [N], the axial stiffness: the elastic catenary where it changes the answer by more
  than ``elastic.ELASTIC_TOL`` (1e-6), else the inextensible one
  (:mod:`catenary_monitor.core.physics.elastic`); ``result.model`` names the model that answered,
  per element for arrays. The elastic chain is solved for a measured hook tension (problems 3 and
  4) or a chain length (problem 5, :mod:`catenary_monitor.core.physics.fixed_length`).

Two tiers of errors: a mistake in the call itself raises ``ValueError`` naming the rule; a
physically impossible element gets a non-zero ``status`` and NaN outputs
(:data:`~catenary_monitor.core.physics.result.STATUS_MESSAGES`).
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any, Optional

import numpy as np

from catenary_monitor.core.physics import elastic, fixed_length, fused_kernel
from catenary_monitor.core.physics import point_loads as point_loads_mod
from catenary_monitor.core.physics.inextensible import ArrayLike, solve_inextensible
from catenary_monitor.core.physics.result import (
    ALL_KEYS,
    STATUS_MESSAGES,
    SolveResult,
    Status,
    in_range,
)

__all__ = ['solve', 'SolveResult', 'Status', 'STATUS_MESSAGES', 'ALL_KEYS']


def solve(
    weight: ArrayLike,
    depth: ArrayLike,
    tension: Optional[ArrayLike] = None,
    horizontal: Optional[ArrayLike] = None,
    anchor_distance: Optional[ArrayLike] = None,
    chain_length: Optional[ArrayLike] = None,
    mbl: Optional[ArrayLike] = None,
    ea: Optional[Any] = None,
    point_loads: Any = None,
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
    ea : axial stiffness EA [N] (> 0; ``inf`` is the inextensible chain); with ``tension`` or
        ``chain_length``.
    point_loads : ``(positions, weights)``: clump weights (weight > 0 N, submerged) and buoys
        (< 0) at those arc lengths from the anchor [m]; with ``tension`` or ``chain_length``
        and ``anchor_distance``, inextensible (:mod:`catenary_monitor.core.physics.point_loads`;
        arrays are solved element by element).

    Returns
    -------
    SolveResult, whose attributes are the JSON keys; ``status`` flags impossible elements and
    ``model`` names the model that answered.

    Notes
    -----
    Every input may be an array; arrays broadcast and are solved in vectorized code.  The
    relative error against a 50-digit reference is below 1e-12 wherever the problem is
    well-conditioned (docs/solver.md).  With all-scalar inputs a plain-float path gives the same
    numbers to rounding, an order of magnitude faster.
    """
    if point_loads is not None and len(point_loads[0]):
        return _with_loads(
            weight, depth, tension, horizontal, anchor_distance, chain_length, mbl, ea, point_loads
        )
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
                ea,
                _CAT.MAXITER,
            )
        except OverflowError:  # an int beyond float range: the general path says so
            one = None
        if one is not None:
            return one
    if ea is None:
        return solve_inextensible(
            weight, depth, tension, horizontal, anchor_distance, chain_length, mbl
        )
    if chain_length is not None and tension is None and horizontal is None:
        if anchor_distance is None:
            raise ValueError(
                'chain_length needs anchor_distance (the chain lies on the seabed '
                'between hook and anchor)'
            )
        return in_range(
            fixed_length.solve_chain_length(weight, depth, chain_length, anchor_distance, ea, mbl)
        )
    if tension is None or horizontal is not None or chain_length is not None:
        raise ValueError(
            'ea (an elastic chain) is solved for a measured hook tension (problems 3 and 4) '
            'or a chain length (problem 5): give tension or chain_length, not horizontal'
        )
    return in_range(
        elastic.solve_with_correction(weight, depth, tension, anchor_distance, ea=ea, mbl=mbl)[0]
    )


def _with_loads(
    weight: Any,
    depth: Any,
    tension: Any,
    horizontal: Any,
    anchor_distance: Any,
    chain_length: Any,
    mbl: Any,
    ea: Any,
    point_loads: tuple[Any, Any],
) -> SolveResult:
    """solve() with point loads: element by element (point_loads.solve_result)."""
    positions, weights = (np.atleast_1d(np.asarray(v, float)) for v in point_loads)
    if positions.shape != weights.shape or positions.ndim != 1:
        raise ValueError(
            'point_loads: positions and weights must be two 1-D sequences of one length'
        )
    if (
        horizontal is not None
        or anchor_distance is None
        or (tension is None) == (chain_length is None)
    ):
        raise ValueError(
            'point_loads are solved for a hook tension or a chain length at an anchor distance'
        )
    if ea is not None and np.any(np.isfinite(np.asarray(ea, float))):
        raise ValueError('point_loads are solved with the inextensible chain (no ea)')
    loads = point_loads_mod.PointLoads.of(positions.tolist(), weights.tolist())
    given = [weight, depth, tension if tension is not None else chain_length, anchor_distance]
    given.append(np.nan if mbl is None else mbl)
    arrays = np.broadcast_arrays(*(np.asarray(v, float) for v in given))
    shape = arrays[0].shape
    results = [
        point_loads_mod.solve_result(
            w, h, t if tension is not None else None, x, t if tension is None else None,
            None if mbl is None else m, loads,
        )
        for w, h, t, x, m in zip(*(a.ravel().tolist() for a in arrays))
    ]  # fmt: skip
    if not shape:
        return results[0]
    first = results[0]
    columns: Any = {
        k: np.array([getattr(r, k) for r in results]).reshape(shape) for k in ALL_KEYS
    }
    status = np.array([r.status for r in results]).reshape(shape)
    return first._replace(**columns, status=status)


_ONE = fused_kernel._k.solve_one if fused_kernel.AVAILABLE else None
_CAT = fused_kernel.cat  # MAXITER is read per call (tests lower it)

if not TYPE_CHECKING and fused_kernel.AVAILABLE:
    # The same function with its one-element path in C (the node's call costs ~0.3 us less):
    # one element of problem 3 or 4 in plain numbers is solved there, every other call comes
    # here unchanged (catenary_monitor.core.physics._fused_kernel.Entry).
    solve = functools.update_wrapper(fused_kernel._k.Entry(solve, fused_kernel.cat), solve)

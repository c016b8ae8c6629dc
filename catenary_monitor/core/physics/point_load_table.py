"""A surrogate of the chain-length problem with point loads: one table per line, built once.

The live dock estimate asks two things of each line at every tick, at the tide depth ``h``:
the span a measured hook tension implies (with ``dT/ds``), and the hook and horizontal
tension at the span the fitted offset gives. With clump weights or buoys each is a nest of
roots (:mod:`.point_loads`, milliseconds); a table answers both in microseconds, vectorized.

The table holds the exact state (:func:`.point_loads.state_at_horizontal`) on a grid of hook
depths (``DEPTH_STEP`` apart over the range given, one node of margin each side) and of
``u = ln H`` (``U_NODES`` nodes from ``H_MIN_FACTOR w L`` to ``H_MAX_FACTOR`` times the
line's MBL): span ``s``, hook tension ``T`` and ``H`` itself. In ``u`` the span rises from the
slack chain's to the taut one's with no steep end, smoothly but for the kinks where the anchor
lifts and the touchdown reaches a clump. A query interpolates the nodes to the depth (cubic
Lagrange over four depth nodes), then finds ``u`` where ``T`` (or ``s``) has the value asked
(the cubic through the four nodes around it, Newton from the chord, a fixed count of steps)
and reads the other columns there; ``dT/ds`` is the ratio of the two cubics' slopes. Only
``+ - * /`` on each element: the same bits one at a time (the live core) and over a log (its
twin).

Its error is measured when it is built: the exact state at every cell's centre (between two
depth nodes and two ``u`` nodes, where interpolation errs most) against the table's answer, the
largest span error in metres (:attr:`PointLoadTable.span_error`) and relative tension error
(:attr:`PointLoadTable.tension_error`). On the paper's chain with a clump they are near 1e-4 m
and 1e-4 (``test/test_point_load_table.py`` checks random states against these bounds).
Outside the table (a depth outside the range, a tension below the slackest node or above the
top) the answer is NaN: the estimate then does not use the line (a slacker span gives ``H`` 0).
"""

from __future__ import annotations

import bisect
import dataclasses
import functools
import math
from typing import Optional

import numpy as np

from catenary_monitor.core.physics.point_loads import PointLoads, state_at_horizontal

__all__ = [
    'PointLoadTable',
    'build_table',
    'TableError',
    'DEPTH_STEP',
    'U_NODES',
    'H_MIN_FACTOR',
    'H_MAX_FACTOR',
]

#: Depth nodes' spacing [m].
DEPTH_STEP = 0.5
#: Nodes in ``u = ln H``.
U_NODES = 256
#: Lowest node: H = this times the chain's weight ``w L`` (below it the chain is as good as slack).
H_MIN_FACTOR = 1e-4
#: Highest node: H = this times the MBL (a reading above the MBL is implausible anyway).
H_MAX_FACTOR = 1.05
#: Newton steps on a cell's cubic (from the chord; the cubic is nearly straight in a cell).
NEWTON_STEPS = 6
#: Queries of at most this many elements run in plain floats (:class:`_Scalar`), larger ones
#: in numpy: the same operations in the same order, so the same bits.
SCALAR_MAX = 8


class TableError(ValueError):
    """The chain's states cannot be tabulated over the range (one line why)."""


@dataclasses.dataclass(frozen=True, eq=False)
class PointLoadTable:
    """One line's table (see the module docstring): depth nodes ``depth0 + k depth_step``,
    and per node (rows) the span, hook tension and H at the ``u`` nodes (columns)."""

    depth0: float
    depth_step: float
    depth_lo: float  # m, the range asked for (hook depths)
    depth_hi: float
    span: np.ndarray  # (nh, nu) m
    tension: np.ndarray  # (nh, nu) N
    horizontal: np.ndarray  # (nh, nu) N
    span_error: float  # m, the largest measured at the cells' centres
    tension_error: float  # relative, the largest measured at the cells' centres
    slack_horizontal: float = 0.0  # N, H at a span below the first node (NaN: not modelled)

    def _at_depth(self, h: np.ndarray) -> tuple[np.ndarray, ...]:
        """The three columns at depths ``h`` (n,): (n, nu) each, NaN rows outside the range."""
        nh = self.span.shape[0]
        x = (h - self.depth0) / self.depth_step
        inside = (h >= self.depth_lo) & (h <= self.depth_hi)
        j = np.clip(np.floor(np.where(inside, x, 1.0)), 1, nh - 3).astype(np.intp)
        c = _weights(np.where(inside, x, 1.0) - j)
        out = []
        for grid in (self.span, self.tension, self.horizontal):
            v = (
                c[0][:, None] * grid[j - 1]
                + c[1][:, None] * grid[j]
                + c[2][:, None] * grid[j + 1]
                + c[3][:, None] * grid[j + 2]
            )
            out.append(np.where(inside[:, None], v, math.nan))
        return tuple(out)

    def span_at_tension(self, h: np.ndarray, tension: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(span [m], dT/ds [N/m]) of hook tensions ``tension`` at hook depths ``h`` (n,)."""
        h, tension = np.asarray(h, float), np.asarray(tension, float)
        if h.size <= SCALAR_MAX:  # the live core's few: plain floats, the same bits
            one = _scalar(self).span_at_tension
            return _columns([one(a, b) for a, b in zip(h.tolist(), tension.tolist())])
        return self._span_at_tension(h, tension)

    def state_at_span(self, h: np.ndarray, span: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(hook tension [N], H [N]) at spans ``span`` and hook depths ``h`` (n,): NaN outside
        the table but H 0 for a span slacker than its lowest node (NaN where the slackest
        states are not modelled: a buoy)."""
        h, span = np.asarray(h, float), np.asarray(span, float)
        if h.size <= SCALAR_MAX:
            one = _scalar(self).state_at_span
            return _columns([one(a, b) for a, b in zip(h.tolist(), span.tolist())])
        return self._state_at_span(h, span)

    def span_at_tension_one(self, h: float, tension: float) -> tuple[float, float]:
        """:meth:`span_at_tension` of one query in plain floats (the same bits)."""
        return _scalar(self).span_at_tension(h, tension)

    def state_at_span_one(self, h: float, span: float) -> tuple[float, float]:
        """:meth:`state_at_span` of one query in plain floats (the same bits)."""
        return _scalar(self).state_at_span(h, span)

    def _span_at_tension(
        self, h: np.ndarray, tension: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        s, t, _ = self._at_depth(np.asarray(h, float))
        k, tt = _locate(t, np.asarray(tension, float))
        value, ds = _cubic(s, k, tt)
        _, dt = _cubic(t, k, tt)
        with np.errstate(invalid='ignore', divide='ignore'):
            return value, np.where(ds != 0.0, dt / ds, math.nan)

    def _state_at_span(self, h: np.ndarray, span: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s, t, hor = self._at_depth(np.asarray(h, float))
        span = np.asarray(span, float)
        k, tt = _locate(s, span)
        tension, _ = _cubic(t, k, tt)
        horizontal, _ = _cubic(hor, k, tt)
        with np.errstate(invalid='ignore'):
            slack = span < s[:, 0]
        return tension, np.where(slack, self.slack_horizontal, horizontal)


def _columns(pairs: list[tuple[float, float]]) -> tuple[np.ndarray, np.ndarray]:
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])


def _weights(t: np.ndarray) -> tuple[np.ndarray, ...]:
    """Cubic Lagrange weights of nodes -1, 0, 1, 2 at ``t`` (0 at node 0, 1 at node 1)."""
    return (
        -t * (t - 1.0) * (t - 2.0) / 6.0,
        (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0,
        -(t + 1.0) * t * (t - 2.0) / 2.0,
        (t + 1.0) * t * (t - 1.0) / 6.0,
    )


def _slopes(t: np.ndarray) -> tuple[np.ndarray, ...]:
    """d/dt of :func:`_weights`."""
    return (
        -(3.0 * t * t - 6.0 * t + 2.0) / 6.0,
        (3.0 * t * t - 4.0 * t - 1.0) / 2.0,
        -(3.0 * t * t - 2.0 * t - 2.0) / 2.0,
        (3.0 * t * t - 1.0) / 6.0,
    )


def _stencil(grid: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, ...]:
    """The four nodes around cell ``k`` of each row (the stencil kept inside the row: at the
    ends it is shifted, ``t`` measured from its second node)."""
    nu = grid.shape[1]
    j = np.clip(k, 1, nu - 3)
    rows = np.arange(grid.shape[0])
    return tuple(grid[rows, j + d] for d in (-1, 0, 1, 2))


def _cubic(grid: np.ndarray, k: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Value and d/du (per node spacing) of each row's cubic at cell ``k``, ``t`` in it."""
    nu = grid.shape[1]
    shift = k - np.clip(k, 1, nu - 3)
    x = t + shift
    nodes = _stencil(grid, k)
    c, d = _weights(x), _slopes(x)
    value = c[0] * nodes[0] + c[1] * nodes[1] + c[2] * nodes[2] + c[3] * nodes[3]
    slope = d[0] * nodes[0] + d[1] * nodes[1] + d[2] * nodes[2] + d[3] * nodes[3]
    return value, slope


def _locate(grid: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cell ``k`` and place ``t`` in it where each row's cubic takes ``y`` (rising rows);
    ``t`` NaN where ``y`` is outside the row's nodes."""
    nu = grid.shape[1]
    with np.errstate(invalid='ignore'):
        below = np.sum(grid <= y[:, None], axis=1)
        inside = (below >= 1) & (below <= nu - 1) & np.isfinite(y)
        inside &= np.isfinite(grid[:, 0])
    k = np.clip(below - 1, 0, nu - 2)
    rows = np.arange(grid.shape[0])
    a, b = grid[rows, k], grid[rows, k + 1]
    with np.errstate(invalid='ignore', divide='ignore'):
        t = np.where(inside, (y - a) / (b - a), math.nan)
        for _ in range(NEWTON_STEPS):
            value, slope = _cubic(grid, k, t)
            step = np.where(slope != 0.0, (value - y) / slope, 0.0)
            t = np.clip(t - step, 0.0, 1.0)
    return k, np.where(inside, t, math.nan)


@functools.lru_cache(maxsize=64)
def build_table(
    w: float, length: float, loads: PointLoads, mbl: float, depth_lo: float, depth_hi: float
) -> PointLoadTable:
    """The table of a chain (``w`` N/m, ``length`` m, its loads, its MBL N) over hook depths
    ``[depth_lo, depth_hi]`` m, its error measured (:class:`TableError` where the chain's
    states are not all modelled or not rising in ``H``). Cached: lines alike share one."""
    if not (0.0 < depth_lo <= depth_hi < length):
        raise TableError(f'hook depths {depth_lo:g}-{depth_hi:g} m: needs 0 < low <= high < L')
    cells = max(int(math.ceil((depth_hi - depth_lo) / DEPTH_STEP - 1e-9)), 1)
    step = (depth_hi - depth_lo) / cells if depth_hi > depth_lo else DEPTH_STEP
    depths = depth_lo + step * np.arange(-1, cells + 2)
    if depths[0] <= 0.0:
        raise TableError(f'hook depths from {depth_lo:g} m: the table needs {step:g} m below')
    u = np.linspace(math.log(H_MIN_FACTOR * w * length), math.log(H_MAX_FACTOR * mbl), U_NODES)
    span, tension, horizontal = _grid(w, length, loads, depths, np.exp(u), trim=True)
    slack = 0.0 if horizontal.shape[1] == u.size else math.nan
    u = u[u.size - horizontal.shape[1] :]
    table = PointLoadTable(
        float(depths[0]), step, depth_lo, depth_hi, span, tension, horizontal, 0.0, 0.0, slack
    )
    span_error, tension_error = _measured_error(table, w, length, loads, u)
    return dataclasses.replace(table, span_error=span_error, tension_error=tension_error)


def _grid(
    w: float,
    length: float,
    loads: PointLoads,
    depths: np.ndarray,
    horizontal: np.ndarray,
    trim: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The exact states on the grid (rows depths, columns H); ``trim``: the slackest columns
    not modelled at some depth left out (a buoy that would lie on the seabed)."""
    shape = (depths.size, horizontal.size)
    span, tension = np.empty(shape), np.empty(shape)
    for j, h in enumerate(depths.tolist()):
        for i, hor in enumerate(horizontal.tolist()):
            s, ans = state_at_horizontal(w, h, length, hor, loads)
            span[j, i], tension[j, i] = s, ans.tension
    good = np.all(np.isfinite(span) & np.isfinite(tension), axis=0)
    first = int(np.argmax(good)) if good.any() else horizontal.size
    if trim and first < horizontal.size - 8:  # a buoy on the seabed at the slackest: from here
        span, tension, horizontal = span[:, first:], tension[:, first:], horizontal[first:]
        shape, good = span.shape, good[first:]
    if not good.all():
        raise TableError('a state the static model does not follow (a buoy on the seabed)')
    if not (np.all(np.diff(span, axis=1) > 0.0) and np.all(np.diff(tension, axis=1) > 0.0)):
        raise TableError('span or tension not rising with the horizontal tension')
    return span, tension, np.broadcast_to(horizontal, shape).copy()


def _measured_error(
    table: PointLoadTable, w: float, length: float, loads: PointLoads, u: np.ndarray
) -> tuple[float, float]:
    """The largest span error [m] and relative tension error of the table at the centres of
    its cells within the range, against the exact state."""
    depths = table.depth0 + table.depth_step * np.arange(table.span.shape[0])
    mid_h = (depths[1:-2] + depths[2:-1]) / 2.0
    mid_h = mid_h[(mid_h >= table.depth_lo) & (mid_h <= table.depth_hi)]
    if mid_h.size == 0:
        mid_h = np.array([table.depth_lo])
    hor = np.exp((u[1:] + u[:-1]) / 2.0)
    span, tension, _ = _grid(w, length, loads, mid_h, hor)
    h = np.repeat(mid_h, hor.size)
    s_tab, _ = table.span_at_tension(h, tension.ravel())
    t_tab, _ = table.state_at_span(h, span.ravel())
    ds = np.abs(s_tab - span.ravel())
    dt = np.abs(t_tab / tension.ravel() - 1.0)
    return _largest(ds), _largest(dt)


def _largest(err: np.ndarray) -> float:
    return float(np.max(np.where(np.isfinite(err), err, math.inf)))


def table_for(
    w: float,
    length: float,
    loads: Optional[PointLoads],
    mbl: float,
    depth_range: Optional[tuple[float, float]],
) -> Optional[PointLoadTable]:
    """:func:`build_table` for a line with point loads and a depth range, else None."""
    if loads is None or depth_range is None:
        return None
    return build_table(float(w), float(length), loads, float(mbl), *map(float, depth_range))


class _Scalar:
    """A table's queries in plain floats for one element at a time (the live core: numpy on
    one-element arrays costs ~1 ms a query). Every operation is the numpy path's, in its order:
    the depth's weights, the cell where the nodes interpolated to the depth pass the value (the
    numpy path counts them; the same cell where they rise), the chord and Newton steps (their
    fixed count: a zero step leaves the rest as they are)."""

    __slots__ = ('table', 'span', 'tension', 'horizontal', 'nh', 'nu')

    def __init__(self, table: PointLoadTable) -> None:
        self.table = table
        self.span = table.span.tolist()
        self.tension = table.tension.tolist()
        self.horizontal = table.horizontal.tolist()
        self.nh, self.nu = table.span.shape

    def _depth(self, h: float) -> Optional[tuple[int, tuple[float, ...]]]:
        tab = self.table
        if not (tab.depth_lo <= h <= tab.depth_hi):
            return None
        x = (h - tab.depth0) / tab.depth_step
        j = int(min(max(math.floor(x), 1), self.nh - 3))
        return j, _weights_f(x - j)

    @staticmethod
    def _node(grid: list[list[float]], at: tuple[int, tuple[float, ...]], i: int) -> float:
        j, c = at
        return c[0] * grid[j - 1][i] + c[1] * grid[j][i] + c[2] * grid[j + 1][i] + c[3] * grid[
            j + 2
        ][i]

    def _locate(
        self, grid: list[list[float]], at: tuple[int, tuple[float, ...]], y: float
    ) -> Optional[tuple[int, float, tuple[float, ...]]]:
        """(cell k, t in it, the cubic's four nodes) where the cubic takes ``y``, or None."""
        if y != y:
            return None
        node = self._node
        # The count of nodes <= y: from the depth node's own row (rising), moved to the
        # interpolated row's (a cell or two at most), as a bisection over it finds.
        lo = bisect.bisect_right(grid[at[0]], y)
        while lo > 0 and node(grid, at, lo - 1) > y:
            lo -= 1
        while lo < self.nu and node(grid, at, lo) <= y:
            lo += 1
        if not (1 <= lo <= self.nu - 1):
            return None
        k = lo - 1
        nodes = self._stencil(grid, at, k)
        a, b = node(grid, at, k), node(grid, at, k + 1)
        t = (y - a) / (b - a)
        shift = k - min(max(k, 1), self.nu - 3)
        for _ in range(NEWTON_STEPS):
            value, slope = _cubic_f(nodes, t + shift)
            step = (value - y) / slope if slope != 0.0 else 0.0
            new = min(max(t - step, 0.0), 1.0)
            if new == t:  # so at every step left: the same bits
                break
            t = new
        return k, t, nodes

    def _stencil(
        self, grid: list[list[float]], at: tuple[int, tuple[float, ...]], k: int
    ) -> tuple[float, ...]:
        j = min(max(k, 1), self.nu - 3)
        return tuple(self._node(grid, at, j + d) for d in (-1, 0, 1, 2))

    def span_at_tension(self, h: float, tension: float) -> tuple[float, float]:
        at = self._depth(h)
        found = None if at is None else self._locate(self.tension, at, tension)
        if at is None or found is None:
            return math.nan, math.nan
        k, t, t_nodes = found
        x = t + (k - min(max(k, 1), self.nu - 3))
        value, ds = _cubic_f(self._stencil(self.span, at, k), x)
        _, dt = _cubic_f(t_nodes, x)
        return value, (dt / ds if ds != 0.0 else math.nan)

    def state_at_span(self, h: float, span: float) -> tuple[float, float]:
        at = self._depth(h)
        found = None if at is None else self._locate(self.span, at, span)
        if at is None or found is None:
            slack = at is not None and span < self._node(self.span, at, 0)
            return math.nan, (self.table.slack_horizontal if slack else math.nan)
        k, t, _ = found
        x = t + (k - min(max(k, 1), self.nu - 3))
        tension, _ = _cubic_f(self._stencil(self.tension, at, k), x)
        horizontal, _ = _cubic_f(self._stencil(self.horizontal, at, k), x)
        return tension, horizontal


@functools.lru_cache(maxsize=64)
def _scalar(table: PointLoadTable) -> _Scalar:
    return _Scalar(table)


def _weights_f(t: float) -> tuple[float, ...]:
    """:func:`_weights` in plain floats (the same operations)."""
    return (
        -t * (t - 1.0) * (t - 2.0) / 6.0,
        (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0,
        -(t + 1.0) * t * (t - 2.0) / 2.0,
        (t + 1.0) * t * (t - 1.0) / 6.0,
    )


def _cubic_f(nodes: tuple[float, ...], x: float) -> tuple[float, float]:
    """:func:`_cubic` in plain floats: value and slope at ``x`` of the four nodes' cubic."""
    c = _weights_f(x)
    d = (
        -(3.0 * x * x - 6.0 * x + 2.0) / 6.0,
        (3.0 * x * x - 4.0 * x - 1.0) / 2.0,
        -(3.0 * x * x - 2.0 * x - 2.0) / 2.0,
        (3.0 * x * x - 1.0) / 6.0,
    )
    value = c[0] * nodes[0] + c[1] * nodes[1] + c[2] * nodes[2] + c[3] * nodes[3]
    slope = d[0] * nodes[0] + d[1] * nodes[1] + d[2] * nodes[2] + d[3] * nodes[3]
    return value, slope

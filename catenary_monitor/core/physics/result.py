"""The result of every catenary solve: :class:`SolveResult`, status codes and their messages."""

from __future__ import annotations

from enum import IntEnum
from typing import Any, NamedTuple

import numpy as np

__all__ = ['Status', 'STATUS_MESSAGES', 'ALL_KEYS', 'INF_MARGINS', 'SolveResult', 'in_range']


class Status(IntEnum):
    """Per-element outcome of :func:`solve` (0 = solved)."""

    OK = 0
    NON_FINITE = 1
    WEIGHT = 2
    DEPTH = 3
    TENSION = 4
    HORIZONTAL = 5
    DISTANCE = 6
    CHAIN_TOO_SHORT = 7
    CHAIN_SLACK = 8
    MBL = 9
    NO_CONVERGENCE = 10
    IMPLAUSIBLE_TENSION = 11  # a reading, see core/rules/plausible.py
    IMPLAUSIBLE_DEPTH = 12
    OUT_OF_RANGE = 13  # a result float64 cannot hold (never status 0 with inf or NaN)
    WRONG_UNITS = 14  # a reading off by orders of magnitude, see core/rules/plausible.py
    NOT_MODELLED = 15  # point loads: a scene the static model does not follow (point_loads.py)


STATUS_MESSAGES: dict[int, str] = {
    Status.OK: 'solved',
    Status.NON_FINITE: 'an input is NaN or infinite',
    Status.WEIGHT: 'weight must be > 0 N/m',
    Status.DEPTH: 'depth must be > 0 m',
    Status.TENSION: (
        'hook tension must exceed weight x depth (T > w*h): the chain cannot reach the seabed'
    ),
    Status.HORIZONTAL: 'horizontal tension must be > 0 N',
    Status.DISTANCE: 'anchor distance must be > 0 m',
    Status.CHAIN_TOO_SHORT: (
        'chain length must exceed the straight distance hook-anchor '
        'sqrt(x^2 + h^2): the chain cannot reach the anchor'
    ),
    Status.CHAIN_SLACK: (
        'chain length must be below anchor distance + depth (x + h): '
        'a longer chain is slack, with no horizontal tension'
    ),
    Status.MBL: 'minimum breaking load must be > 0 N',
    Status.NO_CONVERGENCE: 'solver did not converge (please report these inputs)',
    Status.IMPLAUSIBLE_TENSION: (
        'hook tension above 10 x MBL: no chain carries that, a sensor or scaling fault'
    ),
    Status.IMPLAUSIBLE_DEPTH: (
        'depth above 12000 m, deeper than any sea: a sensor or scaling fault'
    ),
    Status.OUT_OF_RANGE: (
        'a result is beyond float64 range (inf or NaN): the inputs are too extreme to solve'
    ),
    Status.WRONG_UNITS: (
        'hook tension 100 times or more below the hanging chain\'s own weight w*h, or below it '
        'where 1000 times the reading would fit the chain: wrong units? check the tension scale'
    ),
    Status.NOT_MODELLED: (
        'point loads: a buoy would lift a hump of chain off the seabed or the chain would pass '
        'through it (not modelled by the static chain with point loads)'
    ),
}

#: Every result key, in display order (the JSON keys of ``catenary-monitor solve --json``).
ALL_KEYS = (
    'horizontal_tension',
    'top_tension',
    'min_anchor_distance',
    'suspended_length',
    'top_angle_deg',
    'anchor_angle_deg',
    'uplift_force',
    'anchor_margin',
    'tide_margin',
    'load_margin',
    'grounded_length',
    'safety_factor',
)

#: The keys a solved element may report as +inf: margins beyond float64 on the safe side (a
#: grounded chain's ``a (cosh(x/a) - 1)`` or critical hook tension ``~ w x^2 / 2h`` overflows),
#: real margins no tide or load reaches.  Every other value of status 0 is finite.
INF_MARGINS = ('tide_margin', 'load_margin')


class SolveResult(NamedTuple):
    """Solution of one catenary problem, element by element (SI units, angles in degrees).

    An immutable named tuple (cheap to build: the live node makes one per update).
    Attributes carry the JSON key names. Arrays have the broadcast shape of the inputs; when every
    input was a scalar they are Python floats (``status`` an int).  Values are NaN where
    ``status != 0`` and for keys that do not apply to the problem (see ``keys``).
    """

    horizontal_tension: Any  # N
    top_tension: Any  # N, hook tension
    min_anchor_distance: Any  # m, shortest anchor distance with no uplift, for this load
    suspended_length: Any  # m
    top_angle_deg: Any  # deg from the horizontal, at the hook
    anchor_angle_deg: Any  # deg, chain angle at the anchor (0: not lifted)
    uplift_force: Any  # N, vertical pull on the anchor (0: not lifted)
    anchor_margin: Any  # m, anchor distance minus minimum anchor distance
    tide_margin: Any  # m, depth rise (R held) before the anchor lifts
    load_margin: Any  # N, hook tension increase (depth held) before the anchor lifts
    grounded_length: Any  # m, chain lying on the seabed (chain-length problem)
    safety_factor: Any  # MBL / hook tension
    status: Any  # int codes, see Status
    problem: str  # 'tension', 'horizontal' or 'chain_length'
    keys: tuple[str, ...] = ()
    model: Any = 'inextensible catenary'  # str; per element (object array) for arrays
    method: str = 'closed form + safeguarded Newton (catenary_monitor.core.physics.catenary)'

    @property
    def ok(self) -> Any:
        """True where the element was solved."""
        return np.asarray(self.status) == 0 if np.ndim(self.status) else self.status == 0

    @property
    def message(self) -> Any:
        """One sentence per element describing its status."""
        if np.ndim(self.status) == 0:
            return STATUS_MESSAGES[int(self.status)]
        return np.vectorize(lambda s: STATUS_MESSAGES[int(s)], otypes=[object])(self.status)

    def to_dict(self) -> dict[str, Any]:
        """The keys that apply, as floats (scalar result) or lists (array result)."""
        out: dict[str, Any] = {}
        for key in self.keys:
            value = getattr(self, key)
            out[key] = float(value) if np.ndim(value) == 0 else np.asarray(value).tolist()
        return out


def in_range(result: SolveResult) -> SolveResult:
    """``result`` with every solved element whose results (the keys that apply) are not all
    finite turned into :attr:`Status.OUT_OF_RANGE` with NaN values: never status 0 with inf or
    NaN.  Returns ``result`` itself when there is none.

    The exceptions are the margins of :data:`INF_MARGINS` at +inf: real margins beyond float64
    (a grounded chain whose ``a (cosh(x/a) - 1)`` or critical tension overflows).
    """
    status = np.asarray(result.status)
    beyond = np.zeros(status.shape, dtype=bool)
    for key in result.keys:
        value = np.asarray(getattr(result, key), dtype=float)
        beyond |= ~(np.isfinite(value) | ((value == np.inf) & (key in INF_MARGINS)))
    beyond &= status == 0
    if not beyond.any():
        return result
    if status.ndim == 0:
        nan: dict[str, Any] = dict.fromkeys(ALL_KEYS, float('nan'))
        return result._replace(**nan, status=int(Status.OUT_OF_RANGE))
    changed: dict[str, Any] = {}
    for key in ALL_KEYS:
        value = np.array(getattr(result, key), dtype=float)
        value[beyond] = np.nan
        changed[key] = value
    new_status = status.copy()
    new_status[beyond] = Status.OUT_OF_RANGE
    return result._replace(**changed, status=new_status)

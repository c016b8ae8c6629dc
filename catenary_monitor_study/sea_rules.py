"""Prototypes of sensor rules that know the sea still to come in the core (a design study;
not wired into the core).

The rules the core now takes are there, not here: the stuck depth gauge against the tide's
known motion, spikes beyond the stamps' bunching and the gauge's own noise, steps counted by
rounding (``catenary_monitor.core.rules.sensor_state``: ``sample_depth``, ``tide_motion``,
``decide_depth``) and the intake's warning by share and count
(``catenary_monitor.core.rules.health.intake_status``); ``test/test_sea_rules.py`` runs them
on generated normal days and faults. Pure functions on plain arrays (SI: m, N, s), each the
judgement one of the core's rules would make instead of today's (DESIGN_ALARMS.md says where
each goes and with which parameters):

* (moved into the core: inputs that fell silent together are
  ``catenary_monitor.core.rules.health.common_cause``, a flood's first out among the alarms
  still active ``catenary_monitor.core.alarms.flood.first_out``.)
* :func:`units_factor`, :func:`units_check`: a tension off by a unit factor (10, 9.80665, 100,
  1000, lbf...) against the line's own statics, scaled by the dock's common loading; now the
  core's (``core/rules/plausible.py``), called from here.
* :func:`chart_range`: default ``depth_min``/``depth_max`` from the lines; now the core's
  (``MonitorConfig.chart``).
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.config.parameters import chart_range as chart_from_lines
from catenary_monitor.core.rules import plausible

__all__ = [
    'UNIT_FACTORS',
    'units_factor',
    'units_check',
    'chart_range',
]


#: Factors a tension reading can be off by (the true tension / the reading as configured),
#: each with the mistake it names: the core's (:data:`catenary_monitor.core.rules.plausible.
#: UNIT_FACTORS`).
UNIT_FACTORS = dict(plausible.UNIT_FACTORS)


def units_factor(ratio: float, tolerance: float = 0.4, far: float = 3.0) -> Optional[float]:
    """The unit factor a tension is off by, from ``ratio`` = expected / reading (None: no
    claim): the core's :func:`catenary_monitor.core.rules.plausible.units_factor`."""
    k = plausible.units_factor(ratio, tolerance, far)
    return plausible.UNIT_FACTORS[k][0] if k >= 0 else None


def units_check(
    config: MonitorConfig, tensions: np.ndarray, depth: float
) -> list[Optional[float]]:
    """Per line, the unit factor its tension [N, as configured] is off by (None: fits), from
    one window's median readings, as the core judges a tick
    (:func:`catenary_monitor.core.rules.plausible.units_ratios`: each line against its own
    at-rest statics scaled by the dock's common loading; the calm gate left out)."""
    table = plausible.rest_table(config, config.chart)
    ratio, _ = plausible.units_ratios(
        table, np.array([depth]), np.asarray(tensions, np.float64)[None, :]
    )
    return [units_factor(float(r)) for r in ratio[0]]


def chart_range(config: MonitorConfig) -> tuple[float, float]:
    """Default ``(depth_min, depth_max)`` [m] from the lines: the core's
    :func:`catenary_monitor.core.config.parameters.chart_range`."""
    return chart_from_lines(config.lines)

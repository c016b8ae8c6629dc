"""The monitor's decisions, in one event schedule.

:mod:`.monitor_core` ``MonitorCore.step(event) -> Step``: the one decision path the node,
replay and the what-if all run. Around it: :mod:`.alarms` (per-condition latches, levels,
messages), :mod:`.acknowledge` (alarm states and acknowledgement), :mod:`.health` (tide, logger,
clock, intake statuses), :mod:`.plausible` and :mod:`.sensor_state` (impossible readings and
sensor faults), :mod:`.tide_trend` and :mod:`.tide_table` (the tide's trend and forecast, the time
to uplift), :mod:`.uncertainty` (bounds within the sensors' accuracy), :mod:`.holding` (holding
capacity, drag margin), :mod:`.dock_watch` (the live dock estimate and lines that disagree),
:mod:`.whatif_scene` (the core on one scene). :mod:`.twin` is the core's vectorized twin over
log columns (tested equal to it), with its optional C loops in ``_twin_loops.c``.

May import :mod:`catenary_monitor.core.physics`, :mod:`~catenary_monitor.core.config` and
:mod:`~catenary_monitor.core.body`: the top room of the core.
"""

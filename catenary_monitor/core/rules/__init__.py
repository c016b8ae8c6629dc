"""The per-line rules: each decision of one line (or sensor) in a scalar step, the reference the
live core runs, and in one column loop over a log for the twin (C only where measured faster).

:mod:`.readings` (a line's inputs from the configuration), :mod:`.plausible` and
:mod:`.sensor_state` (impossible readings and sensor faults), :mod:`.channels` (a line of
several load-cell channels), :mod:`.tide_trend` and :mod:`.tide_table` (the tide's trend and
forecast, the time to uplift), :mod:`.uncertainty` (bounds within the sensors' accuracy),
:mod:`.holding` (holding capacity, drag margin), :mod:`.fatigue` (rainflow and Miner's damage,
its C loop in ``_fatigue_loop.c``), :mod:`.wave_window` (wave-frequency tension, its C loop in
``_wave_loop.c``), :mod:`.dock_watch` (the live dock estimate and lines that disagree),
:mod:`.health` (the tide, logger, clock, intake and sensors statuses) and :mod:`.level` (the
levels and their order).

May import :mod:`catenary_monitor.core.physics`, :mod:`~catenary_monitor.core.config` and
:mod:`~catenary_monitor.core.body`.
"""

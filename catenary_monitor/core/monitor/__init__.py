"""The monitor's decisions, in one event schedule.

:mod:`.monitor_core` ``MonitorCore.step(event) -> Step``: the one decision path the node,
replay and the what-if all run. Around it: :mod:`.events` (the events and their records),
:mod:`.state` (what the core remembers, a line's values, the typed parts the twin writes
through), :mod:`.derived` (what a solve gets added), :mod:`.status` (the /diagnostics
statuses) and :mod:`.whatif_scene` (the core on one scene).

May import :mod:`catenary_monitor.core.alarms`, :mod:`~catenary_monitor.core.rules`,
:mod:`~catenary_monitor.core.body`, :mod:`~catenary_monitor.core.config` and
:mod:`~catenary_monitor.core.physics`.
"""

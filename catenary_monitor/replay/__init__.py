"""Replay of recorded logs, without ROS: :mod:`.driver` (the one driver: a log read once, the
node's schedule rebuilt, the core advanced window by window), :mod:`.line_split` (a window's
lines in two processes) and :mod:`.outputs` (CSV rows, the results MCAP, PNG charts and the
summary); the fleet replay of many docks on Dask
(:mod:`.fleet_tasks`, :mod:`.fleet_dataset`, :mod:`.fleet_cluster`; the ``fleet`` extra).

May import :mod:`catenary_monitor.core` and :mod:`catenary_monitor.io`; the command line and
the console call it.
"""

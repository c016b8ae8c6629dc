"""The core's vectorized twin: the monitor core's decisions over log columns, for replay.

:mod:`.engine` (``advance``, ``run_log``, ``recompute``: the core stepped through a window of
events at once, leaving it as stepping event by event would), :mod:`.window` (the columns of
events and the results), :mod:`.schedule` (the steps of a line, with optional C loops in
``_twin_loops.c``), :mod:`.decisions` (the window-wide decisions), :mod:`.solve_columns` (the
solves on arrays), :mod:`.snapshots` (the diagnostic snapshots). Tested equal to the core
(test/test_batch.py); it writes the core's state only through its typed door.

May import every other room of the core: :mod:`catenary_monitor.core.monitor`,
:mod:`~catenary_monitor.core.alarms`, :mod:`~catenary_monitor.core.rules`,
:mod:`~catenary_monitor.core.body`, :mod:`~catenary_monitor.core.config`,
:mod:`~catenary_monitor.core.physics`: the top room of the core.
"""

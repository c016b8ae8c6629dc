"""The monitor's pure core: plain Python and numpy, no rclpy, no clock, no files (but the params
file :func:`~catenary_monitor.core.config.parameters.load_params_file` is handed).

Seven rooms, each importing only those before it (test/test_architecture.py):

* :mod:`.physics` the chain models and ``solve()``: catenary closed forms and roots, the
  inextensible, elastic and fixed-length chains, the fused C kernel;
* :mod:`.config` the parameter table, the monitor's configuration and the params-file loader;
* :mod:`.body` the dock as one body: geometry, loads, equilibrium, envelope, estimate;
* :mod:`.rules` the per-line rules: readings, sensor and tide checks, forecasts, bounds,
  holding, fatigue, waves, the dock watch, the components' statuses;
* :mod:`.alarms` alarm management: the latches, acknowledgement, shelving, floods, journal;
* :mod:`.monitor` the event schedule (``MonitorCore.step``): events, state, derived values,
  statuses;
* :mod:`.twin` the core's vectorized twin over log columns, for replay.

The node, replay, the console and the command line are thin shells around it.
"""

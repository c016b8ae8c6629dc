"""The dock as one body: its chains in equilibrium, the uplift envelope, and the live estimate
of the dock's offset and load from the measured tensions (pure numpy and plain floats, no
rclpy, no clock).

* :mod:`.dock_model` geometry, line states, restoring force and stiffness at an offset;
* :mod:`.loads` wind, current and wave drift by the seed paper's formulas;
* :mod:`.equilibrium` the safeguarded Newton for the offset under a load;
* :mod:`.envelope` the smallest load (and wind) from each direction that lifts an anchor;
* :mod:`.estimate` offset and load from measured tensions, residuals, inconsistent lines;
* :mod:`.estimate_tick` one tick's estimate in plain floats (the live core's and its twin's).

The monitor's live use of the estimate is :mod:`catenary_monitor.core.rules.dock_watch`.
May import :mod:`catenary_monitor.core.physics` and :mod:`~catenary_monitor.core.config`.
See docs/dock_body.md.
"""

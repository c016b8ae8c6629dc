"""The methods study and the benchmarks: outside the monitor's runtime import graph.

Every known way to solve the live problems (``methods``) and the benchmark commands (``bench``,
``bench-methods``, ``bench-replay``, ``bench-latency``, registered through the
``catenary_monitor.commands`` entry point). This package imports ``catenary_monitor``; the monitor
never imports it.
"""

"""The monitor's configuration: :mod:`.parameters` the one parameter table (``PARAMETERS``: name,
unit, range, default, description), ``MonitorConfig`` and its validation and hash;
:mod:`.params_file` the params-file loader (rcl's YAML rules); :mod:`.tide_constituents` the
``tide_table`` parameter's constituents.

May import :mod:`catenary_monitor.core.physics`, nothing else of the project.
"""

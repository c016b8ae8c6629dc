"""catenary_monitor: live anchor-uplift monitoring for moored floating docks (ROS 2 Jazzy).

The numerical core (this package's top level, ``catenary``, ``solve``) imports no rclpy.
"""

from catenary_monitor.core.monitor.whatif_scene import whatif
from catenary_monitor.core.physics.solve import (
    ALL_KEYS,
    STATUS_MESSAGES,
    SolveResult,
    Status,
    solve,
)

__version__ = '0.2.0'
__all__ = [
    'solve',
    'whatif',
    'SolveResult',
    'Status',
    'STATUS_MESSAGES',
    'ALL_KEYS',
    '__version__',
]

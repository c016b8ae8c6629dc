"""Monitor configuration: one parameter table, frozen dataclasses, ROS params YAML loading.

No rclpy here. The node declares its parameters from :data:`PARAMETERS` (description, unit,
range) and builds a :class:`MonitorConfig` with :func:`config_from_params`; replay builds the same
dataclass from the same YAML with :func:`load_params_file`, which reads it by rcl's rules
(:mod:`catenary_monitor.core.config.params_file`). Both share one validation, and every failure is
a
:class:`ConfigError` whose message is one line naming the parameter and the rule.

Units are SI: N, N/m, m, s, Hz.
"""

from __future__ import annotations

import dataclasses
import difflib
import hashlib
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Iterator, Mapping, NamedTuple, Optional

from catenary_monitor.core.config.responses import DEFAULT_RESPONSES, RESPONSE_PREFIX
from catenary_monitor.core.config.tide_constituents import (
    MAX_CONSTITUENTS,
    MAX_TABLE_CHARS,
    Constituent,
    parse_table,
)

__all__ = [
    'REQUIRED',
    'ALARM_CONDITIONS',
    'SENSORS_ALARM',
    'COMPONENTS',
    'RESERVED_NAMES',
    'FLOAT64',
    'TENSION_TYPES',
    'DEPTH_TYPES',
    'AXES',
    'DEFAULT_TENSION_ACCURACY',
    'ParamSpec',
    'PARAMETERS',
    'ROS_BUILTIN_PARAMETERS',
    'ConfigError',
    'LineConfig',
    'AlarmConfig',
    'MonitorConfig',
    'DockConfig',
    'GEOMETRY',
    'all_parameters',
    'params_file_text',
    'expand_parameters',
    'load_params_file',
    'config_from_params',
    'config_to_params',
    'config_hash',
    'NON_DECIDING',
    'runtime_change_refusal',
    'runtime_change_messages',
    'change_message',
    'parameters_markdown',
    'resolve_topic',
]


#: A line's tension accuracy where ``NAME.tension_accuracy`` is not set, as a share of its MBL:
#: a load pin is rated near the line's working load (about half the MBL: the MEG4 working load
#: limit) and calibrated to about +-1 % of its rating (docs/node.md, "Sensor accuracies").
DEFAULT_TENSION_ACCURACY = 0.005


class _Required:
    """Sentinel for a parameter that has no default."""

    def __repr__(self) -> str:
        return 'REQUIRED'


REQUIRED: Any = _Required()


class ParamSpec(NamedTuple):
    """One row of the parameter table.

    ``name`` is the full name for ``scope == 'global'`` and the suffix after ``NAME.`` for
    ``scope == 'line'``. ``type`` is one of ``double``, ``bool``, ``string``, ``string_array``;
    ``default`` is a value or :data:`REQUIRED`; a string default may contain ``{line}``.
    ``min`` / ``max`` are inclusive (ROS ``FloatingPointRange`` semantics) or ``None``.
    ``optional`` doubles default to NaN, which means "not given" (the dataclasses hold None);
    a given value is range-checked.
    """

    name: str
    type: str
    default: Any
    description: str
    unit: str
    min: float | None
    max: float | None
    scope: str = 'global'
    read_only: bool = False
    optional: bool = False
    group: str = ''  # '' the monitor's table (docs/node.md); 'dock' docs/dock_body.md's; 'holding'
    # docs/holding.md's

    def full_name(self, line: str | None = None) -> str:
        """Parameter name as declared on the node (``NAME.weight`` for per-line rows)."""
        return f'{line}.{self.name}' if self.scope == 'line' else self.name

    def default_for(self, line: str | None = None) -> Any:
        """Default value with ``{line}`` substituted, or :data:`REQUIRED`."""
        if isinstance(self.default, str) and line is not None:
            return self.default.format(line=line)
        return self.default


_L = 'line'
#: The default message type of the inputs.
FLOAT64 = 'std_msgs/msg/Float64'
#: The message types each input accepts.
TENSION_TYPES = (FLOAT64, 'geometry_msgs/msg/WrenchStamped')
DEPTH_TYPES = (FLOAT64, 'sensor_msgs/msg/FluidPressure', 'sensor_msgs/msg/Range')
AXES = ('x', 'y', 'z', 'norm')
_NOT_GIVEN = math.nan
#: The one source of truth for every parameter: the node declares these, the docs render them.
PARAMETERS: tuple[ParamSpec, ...] = (
    ParamSpec(
        'lines',
        'string_array',
        REQUIRED,
        (
            'Names of the monitored chains (a letter, then letters, digits, _; not tide, sensors,'
            ' alarms, logger, dock, parameters, clock, intake, fatigue, all); each NAME gets the '
            'NAME.* '
            'parameters below'
        ),
        '',
        None,
        None,
        read_only=True,
    ),
    ParamSpec(
        'depth_topic',
        'string',
        '/tide/depth',
        'Topic of the depth sensor (its message type: depth_type); the depth at the hooks (m)',
        '',
        None,
        None,
        read_only=True,
    ),
    ParamSpec(
        'log_dir',
        'string',
        '~/.ros/catenary_monitor',
        'Directory for the MCAP logs (~ is expanded by the logger)',
        '',
        None,
        None,
        read_only=True,
    ),
    ParamSpec(
        'log_rotate_size',
        'double',
        256.0,
        'An MCAP log file is closed and a new one started at this size',
        'MiB',
        0.1,
        1048576.0,
        read_only=True,
    ),
    ParamSpec(
        'log_rotate_duration',
        'double',
        3600.0,
        'An MCAP log file is closed and a new one started after this long',
        's',
        1.0,
        604800.0,
        read_only=True,
    ),
    ParamSpec(
        'log_max_total_size',
        'double',
        0.0,
        'Retention: the log folder\'s MCAP files are kept under this size, the oldest finished '
        'files deleted first, never the open one (0: keep all; at least 2 x log_rotate_size)',
        'B',
        0.0,
        1.0e15,
        read_only=True,
    ),
    ParamSpec(
        'log_max_age',
        'double',
        0.0,
        'Retention: a finished MCAP log file is deleted this long after it ended (0: keep all)',
        's',
        0.0,
        3.2e9,
        read_only=True,
    ),
    ParamSpec(
        'log_min_free_space',
        'double',
        1073741824.0,
        'The logger status is WARN while the log\'s file system has less free space than this '
        '(before a full disk stops the logging; 0: not checked)',
        'B',
        0.0,
        1.0e15,
        read_only=True,
    ),
    ParamSpec(
        'log_create_dir',
        'bool',
        True,
        'Create log_dir when it is missing (at start, or after it vanished); false: wait for '
        'it to reappear (e.g. a mount point), the logger status ERROR meanwhile',
        '',
        None,
        None,
        read_only=True,
    ),
    ParamSpec(
        'allow_runtime_changes',
        'bool',
        False,
        'Accept runtime set_parameters changes (each one logged); false: all are refused '
        '(use_sim_time is refused at runtime either way)',
        '',
        None,
        None,
        read_only=True,
    ),
    ParamSpec(
        'acknowledge_from_ros',
        'bool',
        True,
        'Accept alarm acknowledgements (/catenary_monitor/acknowledge) and shelving requests '
        '(/catenary_monitor/shelve) from any publisher; false: only from a console (a node '
        'catenary_console_*, the message\'s publisher): where operators act through the '
        'authenticated console (docs/node.md, Security)',
        '',
        None,
        None,
        read_only=True,
    ),
    ParamSpec(
        'runtime_change_warn_time',
        'double',
        3600.0,
        'An accepted runtime change is shown as a WARN (status "parameters" on /diagnostics) '
        'for this long',
        's',
        0.0,
        31536000.0,
        read_only=True,
    ),
    ParamSpec(
        'depth_type',
        'string',
        FLOAT64,
        'Message type of depth_topic: std_msgs/msg/Float64 (the depth, stamped at arrival), '
        'sensor_msgs/msg/FluidPressure (a pressure gauge) or sensor_msgs/msg/Range (a radar '
        'or sonar gauge looking down), the latter two at their header stamps',
        '',
        None,
        None,
        read_only=True,
        group='inputs',
    ),
    ParamSpec(
        'water_density',
        'double',
        1025.0,
        'FluidPressure: density of the water above the gauge (1025 sea water, 1000 fresh)',
        'kg/m^3',
        900.0,
        1300.0,
        read_only=True,
        group='inputs',
    ),
    ParamSpec(
        'atmospheric_pressure',
        'double',
        101325.0,
        'FluidPressure: the air pressure the gauge reads at the surface (0 for a gauge that '
        'reports pressure relative to the air)',
        'Pa',
        0.0,
        200000.0,
        read_only=True,
        group='inputs',
    ),
    ParamSpec(
        'gauge_height',
        'double',
        0.0,
        'FluidPressure and Range: the gauge\'s height above the seabed (depth = gauge_height + '
        '(pressure - atmospheric_pressure) / (water_density g); depth = gauge_height - range)',
        'm',
        -100.0,
        12000.0,
        read_only=True,
        group='inputs',
    ),
    ParamSpec(
        'depth_offset',
        'double',
        0.0,
        'Added to every depth reading (the datum: from the gauge\'s zero to the depth at the '
        'hooks)',
        'm',
        -1000.0,
        1000.0,
        read_only=True,
        group='inputs',
    ),
    ParamSpec(
        'stamp_ahead_max',
        'double',
        1.0,
        'A stamped sample whose header stamp is this far ahead of the monitor\'s clock at its '
        'arrival is refused (sensor state bad_stamp), as is one stamped more than a year '
        'behind it or before the one before',
        's',
        0.0,
        3600.0,
        group='inputs',
    ),
    # Per line.
    ParamSpec(
        'weight',
        'double',
        REQUIRED,
        'Submerged weight of the chain per metre',
        'N/m',
        1.0,
        1.0e5,
        _L,
    ),
    ParamSpec(
        'anchor_distance',
        'double',
        REQUIRED,
        'Installed horizontal distance anchor to hook point',
        'm',
        0.1,
        1.0e4,
        _L,
    ),
    ParamSpec(
        'mbl', 'double', REQUIRED, 'Minimum breaking load of the chain', 'N', 1.0, 1.0e9, _L
    ),
    ParamSpec(
        'allowed_uplift',
        'double',
        0.0,
        'Vertical force on the anchor tolerated before the uplift alarm',
        'N',
        0.0,
        1.0e9,
        _L,
    ),
    ParamSpec(
        'hook_height',
        'double',
        0.0,
        'Height of the hook point above the water surface, added to the depth',
        'm',
        -100.0,
        100.0,
        _L,
    ),
    ParamSpec(
        'tension_topic',
        'string',
        '/mooring/{line}/tension',
        'Topic of the line\'s load cell (its message type: NAME.tension_type)',
        '',
        None,
        None,
        _L,
        read_only=True,
    ),
    ParamSpec(
        'ea',
        'double',
        0.0,
        'Axial stiffness EA of the chain; 0 means inextensible',
        'N',
        0.0,
        1.0e12,
        _L,
    ),
    # Inputs as the sensors' drivers publish them (core/rules/readings.py; docs/node.md).
    ParamSpec(
        'tension_type',
        'string',
        FLOAT64,
        'Message type of NAME.tension_topic: std_msgs/msg/Float64 (the reading, stamped at '
        'arrival) or geometry_msgs/msg/WrenchStamped (one force axis, at its header stamp)',
        '',
        None,
        None,
        _L,
        read_only=True,
        group='inputs',
    ),
    ParamSpec(
        'tension_axis',
        'string',
        'norm',
        'With a WrenchStamped: the tension is its force x, y, z or norm (the vector\'s length)',
        '',
        None,
        None,
        _L,
        read_only=True,
        group='inputs',
    ),
    ParamSpec(
        'tension_scale',
        'double',
        1.0,
        'The tension is the reading x this (1000 for a load cell in kN; negative for an axis '
        'that reads tension below zero; not 0)',
        'N/unit',
        -1.0e9,
        1.0e9,
        _L,
        read_only=True,
        group='inputs',
    ),
    # Dock geometry (the dock model, core/body): optional; NaN means not given.
    ParamSpec(
        'hook_x',
        'double',
        _NOT_GIVEN,
        'Hook position on the dock: x toward the bow from the dock reference point (REP 103)',
        'm',
        -1.0e4,
        1.0e4,
        _L,
        optional=True,
        group='dock',
    ),
    ParamSpec(
        'hook_y',
        'double',
        _NOT_GIVEN,
        'Hook position on the dock: y to port from the dock reference point (REP 103)',
        'm',
        -1.0e4,
        1.0e4,
        _L,
        optional=True,
        group='dock',
    ),
    ParamSpec(
        'heading',
        'double',
        math.nan,
        'Direction hook to anchor, clockwise from the dock\'s bow; not set (nan): evenly spread',
        'deg',
        -360.0,
        360.0,
        _L,
        optional=True,
    ),
    ParamSpec(
        'chain_length',
        'double',
        _NOT_GIVEN,
        'Unstretched chain length hook -> anchor',
        'm',
        0.1,
        1.0e4,
        _L,
        optional=True,
    ),
    ParamSpec(
        'tension_accuracy',
        'double',
        _NOT_GIVEN,
        'Stated accuracy of the tension sensor, a bound: a reading is within +- this of the true '
        'tension (the margin bounds take the worst case within it; the dock estimate takes it '
        'as a reading\'s standard deviation); not set: 0.5 % of NAME.mbl (a load pin rated near '
        'half the MBL, +-1 % of its rating)',
        'N',
        1.0,
        1.0e9,
        _L,
        optional=True,
    ),
    # A line measured by several channels (core/rules/channels.py, docs/channels.md).
    ParamSpec(
        'tension_topics',
        'string_array',
        (),
        'The topics of a load cell\'s channels (std_msgs/Float64, N each), instead of '
        'tension_topic: the tension from the healthy channels (empty: tension_topic)',
        '',
        None,
        None,
        _L,
        read_only=True,
        group='channels',
    ),
    ParamSpec(
        'min_channels',
        'double',
        1.0,
        'Fewer healthy channels than this and the line is blind (STALE); a whole number',
        '',
        1.0,
        16.0,
        _L,
        group='channels',
    ),
    # Point loads on the chain (core/physics/point_loads.py, docs/point_loads.md).
    ParamSpec(
        'point_load_positions',
        'double_array',
        (),
        'Clump weights and buoys on the chain: their places, m along the chain from the anchor '
        '(one per entry of point_load_weights; empty: none)',
        'm',
        0.0,
        1.0e4,
        _L,
        group='point_loads',
    ),
    ParamSpec(
        'point_load_weights',
        'double_array',
        (),
        'Submerged weight of each point load: > 0 a clump weight (sinker), < 0 a buoy',
        'N',
        -1.0e8,
        1.0e8,
        _L,
        group='point_loads',
    ),
    # Chain fatigue (core/rules/fatigue.py, docs/fatigue.md): seed 001's S-N curve.
    ParamSpec(
        'fatigue_m',
        'double',
        3.36,
        'S-N curve N (delta_sigma / 1 MPa)^m = 10^log_a: m (seed 001, anchor chain)',
        '',
        1.0,
        20.0,
        _L,
        group='fatigue',
    ),
    ParamSpec(
        'fatigue_log_a',
        'double',
        13.6451,
        'S-N curve N (delta_sigma / 1 MPa)^m = 10^log_a: log10 a (seed 001, anchor chain)',
        '',
        1.0,
        40.0,
        _L,
        group='fatigue',
    ),
    ParamSpec(
        'fatigue_stress_per_tension',
        'double',
        _NOT_GIVEN,
        'Stress range per tension range of a link; not set: seed 001\'s 80.5 Pa/N for its '
        '12 421 kN chain scaled to this MBL (80.5 x 12421e3 / mbl: the same stress at the '
        'same fraction of MBL)',
        'Pa/N',
        1.0e-6,
        1.0e9,
        _L,
        optional=True,
        group='fatigue',
    ),
    ParamSpec(
        'fatigue_damage_initial',
        'double',
        0.0,
        'Miner damage the chain had when monitoring began (used only where the fatigue store '
        'holds none for the line)',
        '',
        0.0,
        10.0,
        _L,
        group='fatigue',
    ),
    # Holding (docs/holding.md): optional; NaN means not given (no holding values).
    ParamSpec(
        'anchor_holding',
        'double',
        _NOT_GIVEN,
        "Holding force of the anchor or sinker itself (weight in water x holding coefficient)",
        'N',
        0.0,
        1.0e9,
        _L,
        optional=True,
        group='holding',
    ),
    ParamSpec(
        'anchor_weight',
        'double',
        _NOT_GIVEN,
        'Weight in water of a sinker: its holding falls as anchor_holding (1 - uplift / this); '
        'not set: any uplift leaves the anchor no holding',
        'N',
        1.0,
        1.0e9,
        _L,
        optional=True,
        group='holding',
    ),
    ParamSpec(
        'chain_friction',
        'double',
        _NOT_GIVEN,
        'Friction coefficient of the chain lying on the seabed (holding: weight x this x '
        'grounded length; needs chain_length)',
        '',
        0.0,
        10.0,
        _L,
        optional=True,
        group='holding',
    ),
    # Alarm thresholds (WARN).
    ParamSpec(
        'anchor_margin_warn',
        'double',
        5.0,
        'WARN when installed minus minimum anchor distance falls below this',
        'm',
        0.0,
        1000.0,
    ),
    ParamSpec(
        'anchor_margin_deadband',
        'double',
        1.0,
        'Anchor-margin warning clears only at warn + deadband or more',
        'm',
        0.0,
        100.0,
    ),
    ParamSpec(
        'tide_margin_warn',
        'double',
        1.0,
        'WARN when the depth rise the chain can take without uplift falls below this',
        'm',
        0.0,
        100.0,
    ),
    ParamSpec(
        'tide_margin_deadband',
        'double',
        0.2,
        'Tide-margin warning clears only at warn + deadband or more',
        'm',
        0.0,
        10.0,
    ),
    ParamSpec(
        'tide_trend_window',
        'double',
        1200.0,
        'Tide trend: Theil-Sen rate of 20 bin means over this window (known after half of it)',
        's',
        5.0,
        86400.0,
    ),
    ParamSpec(
        'uplift_time_warn',
        'double',
        1800.0,
        'WARN when the time to uplift at the tide\'s trend falls below this',
        's',
        0.0,
        86400.0,
    ),
    ParamSpec(
        'uplift_time_deadband',
        'double',
        300.0,
        'Time-to-uplift warning clears only at warn + deadband or more',
        's',
        0.0,
        86400.0,
    ),
    # The tide table (core/rules/tide_table.py; table in docs/node.md).
    ParamSpec(
        'tide_table',
        'string',
        '',
        'Tide table: constituents "NAME AMPLITUDE PHASE SPEED; ..." (m, deg, deg/h), at most '
        f'{MAX_CONSTITUENTS} ({MAX_TABLE_CHARS} characters); empty: none (the trend)',
        '',
        None,
        None,
        group='tide',
    ),
    ParamSpec(
        'tide_table_epoch',
        'double',
        0.0,
        'The time the table\'s phases refer to (Unix time on the monitor\'s clock)',
        's',
        -1.0e10,
        1.0e10,
        group='tide',
    ),
    ParamSpec(
        'tide_forecast_horizon',
        'double',
        43200.0,
        'With a table, time_to_uplift follows its forecast this far ahead (inf beyond)',
        's',
        600.0,
        604800.0,
        group='tide',
    ),
    # Sensor sanity (core/rules/sensor_state.py; table in docs/node.md).
    *(
        ParamSpec(
            name, 'double', default, text, unit, lo, hi, group='sensor',
            optional=name in ('depth_min', 'depth_max'),  # NaN: the chart from the lines
        )  # fmt: skip
        for name, default, text, unit, lo, hi in (
            (
                'tension_resolution',
                100.0,
                'stuck: the tension sensor\'s step; readings within one step are no change',
                'N',
                0.0,
                1.0e7,
            ),
            (
                'depth_resolution',
                0.001,
                'stuck: the depth sensor\'s step; readings within one step are no change',
                'm',
                0.0,
                10.0,
            ),
            (
                'stuck_time',
                60.0,
                'stuck: no change beyond the resolution this long while the dock moves (a line); '
                'the depth gauge at least this long still (and see depth_stuck_steps)',
                's',
                1.0,
                86400.0,
            ),
            (
                'tension_rate_max',
                0.5,
                'spike: a tension step above this x MBL per second (+ the resolution)',
                'MBL/s',
                0.001,
                1000.0,
            ),
            (
                'depth_rate_max',
                1.0,
                'spike: a depth step above this rate (+ the resolution)',
                'm/s',
                0.001,
                1000.0,
            ),
            (
                'stamp_jitter',
                0.25,
                'spike: a reading\'s stamp may be off by this much, for every input type '
                '(delivery bunches a Float64\'s arrival stamps, a driver\'s double read its '
                'header stamps); a step is compared with the rate x (dt + this)',
                's',
                0.0,
                10.0,
            ),
            (
                'spike_noise_k',
                5.0,
                'spike: a depth step must also exceed this x sqrt(2) x the gauge\'s own noise '
                '(1 sigma, estimated online from its successive differences)',
                '',
                0.0,
                100.0,
            ),
            (
                'spike_noise_time',
                600.0,
                'spike: time constant of the depth gauge\'s online noise estimate',
                's',
                1.0,
                86400.0,
            ),
            (
                'depth_stuck_steps',
                3.0,
                'stuck: the depth gauge is stuck when the tide is known to have moved more '
                'than this many resolution steps (depth_resolution or the gauge\'s own '
                'step, the larger) since its last step: the tide_table\'s forecast, else the '
                'trend\'s rate at that step less the most the tide bends',
                '',
                1.0,
                1000.0,
            ),
            (
                'depth_residual_rate',
                2.0e-5,
                'stuck: with a tide_table, the sea may differ from its forecast by this rate '
                '(a surge the table does not hold); taken off the forecast\'s motion',
                'm/s',
                0.0,
                1.0,
            ),
            (
                'depth_still_max',
                10800.0,
                'stuck: no depth step this long is stuck on a gauge that saw 10 steps of tide '
                'over the last day, whatever the tide\'s motion (no tide rests this long)',
                's',
                60.0,
                1.0e7,
            ),
            (
                'sensor_hold',
                30.0,
                'spike and suspected_parted stay this long after their pattern was last seen',
                's',
                0.0,
                3600.0,
            ),
            (
                'parted_drop',
                0.75,
                'suspected_parted: the tension fell by this fraction in parted_window, to at or '
                'below the hanging chain\'s own weight w*h',
                '',
                0.05,
                1.0,
            ),
            (
                'parted_window',
                5.0,
                'suspected_parted: the tension is compared with its value this long ago',
                's',
                1.0,
                3600.0,
            ),
            (
                'depth_min',
                math.nan,
                'Chart range of the depth sensor: a depth below this is impossible (out_of_range: '
                'the tide ERROR, no line solves on it); NaN: from the lines, 0.05 x the '
                'shallowest depth at which a chain lifts its anchor at its installed span (0 '
                'without chain lengths): a gauge\'s datum or scale fault, never a low water; '
                'give the lowest water less a margin to catch a smaller datum error',
                'm',
                0.0,
                12000.0,
            ),
            (
                'depth_max',
                math.nan,
                'Chart range of the depth sensor: a depth above this is impossible (out_of_range: '
                'the tide ERROR, no line solves on it); NaN: from the lines, 1.25 x the deepest '
                'depth at which a chain lifts its anchor at its installed span (12000 without '
                'chain_length)',
                'm',
                0.0,
                12000.0,
            ),
            (
                'units_window',
                600.0,
                'wrong units: a line whose reading is off by a unit factor (10, 9.81, 100, 1000, '
                '4.45, 4448 or their inverses) against its fixed-length statics at rest x the '
                'dock\'s common loading, judged while the dock is calm, or against the dock '
                'estimate\'s expected tension from the lines that agree, in any weather, is an '
                'input ERROR naming its tension_scale; held until its reading fits for this long '
                '(0: no check; needs chain_length on 3 lines or more)',
                's',
                0.0,
                86400.0,
            ),
            (
                'tension_sample_rate',
                0.0,
                'Intake: each load cell publishes at this rate; fewer samples are counted '
                'missing (0: not checked)',
                'Hz',
                0.0,
                100000.0,
            ),
            (
                'depth_sample_rate',
                0.0,
                'Intake: the depth gauge publishes at this rate (0: not checked)',
                'Hz',
                0.0,
                100000.0,
            ),
            (
                'intake_step_budget',
                0.05,
                'Intake: of the samples waiting on an input, the node steps the newest that '
                'this much time of steps takes (at the recent cost of one) and coalesces the '
                'older ones: logged and counted, not stepped (0: only the newest)',
                's',
                0.0,
                1.0,
            ),
            (
                'intake_warn_count',
                10.0,
                'Intake: a WARN needs at least this many samples dropped (lost, missing or '
                'coalesced) in the last 60 s, and intake_warn_share of them; fewer are counted '
                'in the values, the status OK (ERROR from 5 % as ever)',
                '',
                0.0,
                1.0e9,
            ),
            (
                'intake_warn_share',
                0.01,
                'Intake: a WARN needs at least this share of the last 60 s\'s samples dropped, '
                'and intake_warn_count of them',
                '',
                0.0,
                0.05,
            ),
        )
    ),
    ParamSpec(
        'depth_accuracy',
        'double',
        0.02,
        'Stated accuracy of the depth sensor, a bound: a reading is within +- this of the true '
        'depth (the margin bounds take the worst case within it; 0: exact; 0.02: a radar or '
        'pressure tide gauge, about 1 cm, and the hooks\' survey)',
        'm',
        0.0,
        100.0,
    ),
    ParamSpec(
        'wave_window',
        'double',
        30.0,
        'Wave-frequency tension: each line\'s peak and half-range (wave_tension) over this '
        'window of its newest readings',
        's',
        1.0,
        3600.0,
    ),
    ParamSpec(
        'wave_allowance',
        'double',
        0.3,
        'The dynamic uplift (and the bounds) take the window\'s peak tension plus this x '
        'wave_tension: the anchor\'s dynamic force beyond the quasi-static (MoorDyn study)',
        '',
        0.0,
        10.0,
    ),
    ParamSpec(
        'drag_margin_warn',
        'double',
        0.0,
        'WARN when holding capacity minus horizontal load falls below this (0: only when the '
        'load exceeds the holding)',
        'N',
        0.0,
        1.0e9,
        group='holding',
    ),
    ParamSpec(
        'drag_margin_deadband',
        'double',
        1.0e4,
        'Drag-margin warning clears only at warn + deadband or more',
        'N',
        0.0,
        1.0e8,
        group='holding',
    ),
    ParamSpec(
        'drag_tolerance',
        'double',
        1.0,
        'ERROR (anchor dragging) when the load exceeds the holding and the implied anchor '
        'distance is beyond the installed one by more than this',
        'm',
        0.0,
        1000.0,
        group='holding',
    ),
    ParamSpec(
        'channel_tolerance',
        'double',
        0.05,
        'A load-cell channel is out of line when its estimate differs from the median of the '
        'channels\' by more than this fraction of it (+ tension_resolution)',
        '',
        0.001,
        1.0,
        group='channels',
    ),
    ParamSpec(
        'fatigue_damage_warn',
        'double',
        0.5,
        'WARN when a line\'s cumulative Miner damage reaches this (1: the S-N curve\'s failure)',
        '',
        0.0,
        10.0,
        group='fatigue',
    ),
    ParamSpec(
        'load_margin_warn',
        'double',
        0.0,
        'WARN when the load margin falls below this (0: only a negative margin warns)',
        'N',
        0.0,
        1.0e9,
    ),
    ParamSpec(
        'load_margin_deadband',
        'double',
        1.0e4,
        'Load-margin warning clears only at warn + deadband or more',
        'N',
        0.0,
        1.0e8,
    ),
    ParamSpec(
        'safety_factor_warn',
        'double',
        2.0,
        'WARN when MBL / top tension falls below this (2.0: tension above 50 % MBL)',
        '',
        1.0,
        100.0,
    ),
    ParamSpec(
        'safety_factor_deadband',
        'double',
        0.1,
        'Safety-factor warning clears only at warn + deadband or more',
        '',
        0.0,
        10.0,
    ),
    ParamSpec(
        'warn_clear_hold',
        'double',
        30.0,
        'A warning clears only after its clear condition has held this long',
        's',
        0.0,
        3600.0,
    ),
    ParamSpec(
        'margin_clear_hold',
        'double',
        600.0,
        'A margin warning (anchor, tide, load and drag margins, safety factor, time to '
        'uplift) clears only after its value has held at or above warn + deadband this long: '
        'longer than the lulls between the wave groups and gusts that reach a threshold\'s '
        'edge in a storm (raising is not delayed)',
        's',
        0.0,
        3600.0,
    ),
    # Uplift alarm (ERROR).
    ParamSpec(
        'on_delay',
        'double',
        0.0,
        'Uplift and warnings are raised only after persisting this long (0: at once)',
        's',
        0.0,
        3600.0,
    ),
    ParamSpec(
        'uplift_clear_hysteresis',
        'double',
        1.0e4,
        'Uplift alarm clears at uplift <= allowed_uplift - this (not below 0 N)',
        'N',
        0.0,
        1.0e8,
    ),
    ParamSpec(
        'uplift_clear_margin',
        'double',
        1.0,
        'When the clear level is 0 N, the anchor margin must also reach this, and at least '
        'the anchor-margin warning\'s clear level (anchor_margin_warn + '
        'anchor_margin_deadband): the ERROR never steps down into that warning',
        'm',
        0.0,
        100.0,
    ),
    ParamSpec(
        'clear_hold',
        'double',
        30.0,
        'An ERROR (uplift or impossible input) clears only after clear input held this long',
        's',
        0.0,
        3600.0,
    ),
    # Staleness and rates.
    ParamSpec(
        'tension_timeout',
        'double',
        5.0,
        'STALE when the newest tension sample is older than this',
        's',
        0.01,
        3600.0,
    ),
    ParamSpec(
        'depth_timeout',
        'double',
        60.0,
        'STALE when the newest depth sample is older than this',
        's',
        0.01,
        86400.0,
    ),
    ParamSpec(
        'common_cause_window',
        'double',
        1.0,
        'Inputs whose last samples lie within this of each other fell silent together: two or '
        'more raise the one sensors alarm, a lone silent line its own STALE this much later',
        's',
        0.0,
        60.0,
    ),
    ParamSpec(
        'parted_consequence_window',
        'double',
        300.0,
        'A margin warning (anchor, tide, load, safety factor, time to uplift, uplift possible, '
        'drag margin) of another line raised within this after a line\'s chain is suspected '
        'parted is that part\'s consequence (the load shifted onto the lines left): shown, '
        'suppressed by design while the part stands, not annunciated; ERRORs (uplift, over '
        'MBL) always annunciate (0: none)',
        's',
        0.0,
        86400.0,
    ),
    ParamSpec(
        'diagnostic_rate',
        'double',
        1.0,
        'Rate of the periodic /diagnostics publication',
        'Hz',
        0.01,
        100.0,
    ),
    # Alarm management (ISA-18.2 / IEC 62682, EEMUA 191): shelving, chattering, floods.
    ParamSpec(
        'shelve_max',
        'double',
        28800.0,
        'Longest an operator may shelve an alarm (one shift; 0: shelving disabled)',
        's',
        0.0,
        604800.0,
    ),
    ParamSpec(
        'unshelvable_conditions',
        'string_array',
        ('uplift', 'input', 'sensor_error', 'stale', 'dragging', 'sensors'),
        'Alarm conditions no operator may shelve: by default what blinds or endangers the dock '
        '(a lifted anchor, an impossible input, wrong units or depth, a parted or slack chain or '
        'over MBL, a stale line, a dragging anchor, and the sensors common-cause alarm); a '
        'shelved alarm still annunciates them',
        '',
        None,
        None,
    ),
    ParamSpec(
        'chatter_count',
        'double',
        3.0,
        'An alarm with this many level changes or more within chatter_window is chattering '
        '(a whole number)',
        '',
        2.0,
        1000.0,
    ),
    ParamSpec(
        'chatter_window',
        'double',
        60.0,
        'The window of the chattering count',
        's',
        1.0,
        86400.0,
    ),
    ParamSpec(
        'flood_count',
        'double',
        10.0,
        'More than this many alarms raised within flood_window is an alarm flood (a whole '
        'number)',
        '',
        1.0,
        10000.0,
    ),
    ParamSpec(
        'flood_window',
        'double',
        600.0,
        'The window of the flood count',
        's',
        1.0,
        86400.0,
    ),
    # The dock as one body (core/body): loads by the seed paper's formulas (docs/dock_body.md).
    *(
        ParamSpec(
            name,
            'double',
            _NOT_GIVEN,
            text,
            'm' if 'area' not in name else 'm^2',
            0.0,
            1.0e6,
            optional=True,
            group='dock',
        )
        for name, text in (
            ('dock_length', 'Dock length along x (wave drift of beam seas; paper: 246.4 m)'),
            ('dock_beam', 'Dock beam along y (wave drift of head seas; paper: 51 m)'),
            ('dock_wind_area_x', "Superstructure area F' projected on the midship section"),
            ('dock_hull_area_x', 'Hull freeboard area F projected on the midship section'),
            ('dock_wind_area_y', "Superstructure area F' projected on the centreline plane"),
            ('dock_hull_area_y', 'Hull freeboard area F projected on the centreline plane'),
            ('dock_wetted_area', 'Wetted hull area Omega (current drag)'),
        )
    ),
    ParamSpec(
        'dock_wind_coefficient',
        'double',
        0.744,
        "Wind load R1 = c V^2 (F' + k F): c (paper: 0.006 x rho 0.124 kgf s^2/m^4, in N)",
        'N s^2/m^4',
        0.0,
        100.0,
        group='dock',
    ),
    ParamSpec(
        'dock_hull_wind_factor',
        'double',
        0.31,
        "Wind load R1 = c V^2 (F' + k F): k, the hull freeboard's share (paper: 0.31)",
        '',
        0.0,
        10.0,
        group='dock',
    ),
    ParamSpec(
        'dock_current_coefficient',
        'double',
        1.8,
        'Current load R2 = c Omega v^n: c (paper: 0.01 x f, f = 0.18, in N)',
        'N s^n/m^(n+2)',
        0.0,
        1.0e4,
        group='dock',
    ),
    ParamSpec(
        'dock_current_exponent',
        'double',
        1.83,
        'Current load R2 = c Omega v^n: n (paper: 1.83)',
        '',
        1.0,
        3.0,
        group='dock',
    ),
    ParamSpec(
        'dock_wave_drift_coefficient',
        'double',
        5382.1845,
        'Wave drift R3 = c B (Hs/4)^2: c (paper: 3/4 k rho g, k = 0.7, 104.61 x 9.8, in N)',
        'N/m^3',
        0.0,
        1.0e6,
        group='dock',
    ),
    ParamSpec(
        'dock_residual_time',
        'double',
        10.0,
        "Time constant of the smoothing of each line's normalized residual over the ticks",
        's',
        0.1,
        3600.0,
        group='dock',
    ),
    *(
        ParamSpec(
            name,
            'double',
            _NOT_GIVEN,
            text,
            'm',
            0.0,
            1.0e4,
            optional=True,
            group='point_loads',
        )
        for name, text in (
            (
                'dock_table_depth_min',
                'Lowest tide depth the live dock estimate tabulates its lines with point loads '
                'at (needed with hook_x, hook_y and point loads; the line adds its hook_height)',
            ),
            (
                'dock_table_depth_max',
                'Highest tide depth the live dock estimate tabulates its lines with point loads '
                'at (needed with hook_x, hook_y and point loads)',
            ),
        )
    ),
    ParamSpec(
        'dock_residual_limit',
        'double',
        5.0,
        'A line is inconsistent when its smoothed normalized residual exceeds this',
        'sigma',
        1.0,
        100.0,
        group='dock',
    ),
    # The response text of each alarm condition (core/config/responses.py; docs/alarm_texts.md).
    *(
        ParamSpec(
            f'{RESPONSE_PREFIX}{cond}',
            'string',
            text,
            f'What the operator reads for {cond!r} beside its headline: cause, consequence, '
            'action',
            '',
            None,
            None,
            group='responses',
        )
        for cond, text in DEFAULT_RESPONSES.items()
    ),
)

_GLOBAL = {p.name: p for p in PARAMETERS if p.scope == 'global'}
_PER_LINE = {p.name: p for p in PARAMETERS if p.scope == 'line'}

#: Parameters rclpy itself may find in a params file; accepted and ignored here.
ROS_BUILTIN_PARAMETERS = frozenset({'use_sim_time', 'start_type_description_service'})
_ROS_BUILTIN_PREFIXES = ('qos_overrides.',)

#: The sensors' common-cause alarm: a name of ``unshelvable_conditions`` besides the conditions.
SENSORS_ALARM = 'sensors'

#: Every condition of a line's alarm, the one list of their names: the latched ones in message
#: order, ERRORs then WARNs (:data:`catenary_monitor.core.alarms.latches.CONDITIONS`), then
#: ``stale`` (no latch); the names of ``unshelvable_conditions`` and of a shelved condition.
ALARM_CONDITIONS = (
    'uplift',
    'input',
    'anchor_margin',
    'tide_margin',
    'load_margin',
    'safety_factor',
    'time_to_uplift',
    'inconsistent',
    # Margins within the sensors' accuracy, and holding.
    'uplift_possible',
    'drag_margin',
    # Sensor sanity: core/rules/sensor_state.py.
    'sensor_error',
    'sensor_warn',
    # Hou et al.'s third regime, the anchor dragging: core/rules/holding.py.
    'dragging',
    # Chain fatigue (Miner's damage): core/rules/fatigue.py.
    'fatigue',
    # A load cell's channel failed (the tension from the others): core/rules/channels.py.
    'channel',
    'stale',
)

_LINE_NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*\Z')
#: The monitor's own statuses on /diagnostics (``catenary_monitor: tide``, ...), not lines.
COMPONENTS = (
    'tide',
    'sensors',
    'alarms',
    'logger',
    'dock',
    'parameters',
    'clock',
    'intake',
    'fatigue',
)
#: The names no line may take: the components', and ``all`` (the acknowledgement of every
#: alarm, :data:`catenary_monitor.core.alarms.acknowledge.ALL_LINES`).
RESERVED_NAMES = (*COMPONENTS, 'all')


def _check_line_name(name: object) -> None:
    """Raise ConfigError unless ``name`` is a usable line name."""
    if not isinstance(name, str) or not _LINE_NAME.match(name):
        raise ConfigError(
            'lines',
            f'line name {name!r} must start with a letter and hold only letters, digits and _',
        )
    if name in RESERVED_NAMES:
        raise ConfigError(
            'lines',
            f'line name {name!r} is the name of one of the monitor\'s own statuses '
            f'({", ".join(RESERVED_NAMES)}): choose another',
        )


_TOPIC = re.compile(r'/?[A-Za-z_~{][A-Za-z0-9_{}]*(/[A-Za-z_{][A-Za-z0-9_{}]*)*\Z')


class ConfigError(ValueError):
    """Invalid configuration: ``str(err)`` is one line naming the parameter and the rule."""

    def __init__(self, parameter: str, rule: str) -> None:
        self.parameter = parameter
        self.rule = ' '.join(str(rule).split())
        super().__init__(f"parameter '{parameter}': {self.rule}")


def _check(full_name: str, spec: ParamSpec, value: Any) -> Any:
    """Return ``value`` converted to the spec's type, or raise ConfigError."""
    if value is REQUIRED:
        raise ConfigError(full_name, 'missing required parameter')
    if spec.type == 'double':
        # ROS YAML gives 1300 as an integer for a double parameter: accept it; reject bool.
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(
                full_name,
                f'expected a number ({spec.unit or "-"}), '
                f'got {type(value).__name__} {value!r}',
            )
        value = float(value)
        if value != value and (spec.optional or spec.default != spec.default):
            return value  # an optional parameter (default NaN) left unset
        if not math.isfinite(value):
            raise ConfigError(full_name, f'must be finite, got {value!r}')
        if spec.min is not None and value < spec.min or spec.max is not None and value > spec.max:
            raise ConfigError(
                full_name,
                f'{value!r} out of range [{spec.min!r}, {spec.max!r}]' f' {spec.unit}'.rstrip(),
            )
        return value
    if spec.type == 'bool':
        if not isinstance(value, bool):
            raise ConfigError(
                full_name, f'expected true or false, got {type(value).__name__} {value!r}'
            )
        return value
    if spec.type == 'string':
        if not isinstance(value, str):
            raise ConfigError(
                full_name, f'expected a string, got {type(value).__name__} ' f'{value!r}'
            )
        return value
    if spec.type == 'string_array':
        if value is None and spec.default == ():  # rcl reads an empty YAML list [] as "not set"
            return ()
        if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
            raise ConfigError(full_name, f'expected a list of strings, got {value!r}')
        return tuple(value)
    if spec.type == 'double_array':
        if value is None:  # rcl reads an empty YAML list [] as "not set"
            return ()
        if not isinstance(value, (list, tuple)) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value
        ):
            raise ConfigError(
                full_name, f'expected a list of numbers ({spec.unit}), got {value!r}'
            )
        out = tuple(float(v) for v in value)
        for v in out:
            if not math.isfinite(v) or not spec.min <= v <= spec.max:  # type: ignore[operator]
                raise ConfigError(
                    full_name, f'{v!r} out of range [{spec.min!r}, {spec.max!r}] {spec.unit}'
                )
        return out
    raise AssertionError(f'unknown parameter type {spec.type!r}')  # table bug, not user error


def _check_topic(full_name: str, topic: str) -> None:
    if not _TOPIC.match(topic) or '//' in topic:
        raise ConfigError(full_name, f'{topic!r} is not a valid ROS topic name')


def _PER_LINE_DEFAULT(name: str) -> Any:  # noqa: N802 - read as a constant
    return _PER_LINE[name].default


@dataclass(frozen=True)
class LineConfig:
    """One anchor chain. SI units: weight N/m (submerged), distances m, forces N.

    ``tension_topic`` ``''`` means ``/mooring/NAME/tension``; ``ea`` ``None`` (or 0) means an
    inextensible chain. The dock geometry (``hook_x``, ``hook_y`` m, ``heading`` deg,
    ``chain_length`` m), ``tension_accuracy`` (N) and the holding data (``anchor_holding``,
    ``anchor_weight`` N, ``chain_friction``) are None when not given. Values are
    validated against :data:`PARAMETERS` on construction.
    """

    name: str
    weight: float
    anchor_distance: float
    mbl: float
    allowed_uplift: float = 0.0
    hook_height: float = 0.0
    tension_topic: str = ''
    ea: float | None = None
    heading: float = math.nan  # deg, clockwise from the bow toward the anchor; NaN: not set
    hook_x: float | None = None
    hook_y: float | None = None
    chain_length: float | None = None
    tension_accuracy: float | None = None
    anchor_holding: float | None = None
    anchor_weight: float | None = None
    chain_friction: float | None = None
    tension_topics: tuple[str, ...] = ()
    min_channels: float = 1.0
    point_load_positions: tuple[float, ...] = ()
    point_load_weights: tuple[float, ...] = ()
    fatigue_m: float = _PER_LINE_DEFAULT('fatigue_m')
    fatigue_log_a: float = _PER_LINE_DEFAULT('fatigue_log_a')
    fatigue_stress_per_tension: float | None = None
    fatigue_damage_initial: float = 0.0
    tension_type: str = FLOAT64
    tension_axis: str = 'norm'
    tension_scale: float = 1.0

    def __post_init__(self) -> None:
        _check_line_name(self.name)
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        if values['tension_topic'] == '':
            values['tension_topic'] = _PER_LINE['tension_topic'].default_for(self.name)
        if values['ea'] is None:
            values['ea'] = 0.0
        none_default = {f.name for f in dataclasses.fields(self) if f.default is None}
        for key, spec in _PER_LINE.items():
            value = values[key]
            if spec.optional:
                value = _NOT_GIVEN if value is None else value
            value = _check(spec.full_name(self.name), spec, value)
            if spec.optional and math.isnan(value) and key in none_default:
                value = None  # (heading keeps NaN for "not set", as the console reads it)
            object.__setattr__(self, key, value)
        _check_topic(f'{self.name}.tension_topic', self.tension_topic)
        _check_choice(f'{self.name}.tension_type', self.tension_type, TENSION_TYPES)
        _check_choice(f'{self.name}.tension_axis', self.tension_axis, AXES)
        if self.tension_scale == 0.0:
            raise ConfigError(
                f'{self.name}.tension_scale', 'must not be 0 (1 for a load cell in N)'
            )
        if self.ea == 0.0:
            object.__setattr__(self, 'ea', None)
        _check_point_loads(self)
        _check_channels(self)

    @property
    def channel_topics(self) -> tuple[str, ...]:
        """The channels' topics when the line has several (else ``()``: ``tension_topic``)."""
        return self.tension_topics if len(self.tension_topics) > 1 else ()

    @property
    def topics(self) -> tuple[str, ...]:
        """Every tension topic of the line (its channels', or ``tension_topic``)."""
        return self.tension_topics or (self.tension_topic,)

    @property
    def point_loads(self) -> Optional[tuple[tuple[float, ...], tuple[float, ...]]]:
        """``(positions, weights)`` of the chain's point loads, or None."""
        if not self.point_load_positions:
            return None
        return self.point_load_positions, self.point_load_weights

    @property
    def stress_per_tension(self) -> float:
        """Pa of stress range per N of tension range: ``fatigue_stress_per_tension``, or seed
        001's 80.5 Pa/N for its 12 421 kN chain scaled to this line's MBL."""
        if self.fatigue_stress_per_tension is not None:
            return self.fatigue_stress_per_tension
        return 80.5 * 12421.0e3 / self.mbl

    @property
    def tension_accuracy_or_default(self) -> float:
        """The tension sensor's accuracy [N]: ``tension_accuracy``, or where it is not set
        :data:`DEFAULT_TENSION_ACCURACY` of the MBL."""
        if self.tension_accuracy is not None:
            return self.tension_accuracy
        return DEFAULT_TENSION_ACCURACY * self.mbl


def _check_channels(line: LineConfig) -> None:
    """Channels: valid, distinct topics; a whole min_channels no more than the channels."""
    key = f'{line.name}.tension_topics'
    object.__setattr__(line, 'tension_topics', tuple(line.tension_topics))
    for topic in line.tension_topics:
        _check_topic(key, topic)
    if len(set(line.tension_topics)) != len(line.tension_topics):
        raise ConfigError(key, 'a topic is given twice')
    if len(line.tension_topics) > 16:
        raise ConfigError(key, f'{len(line.tension_topics)} channels: at most 16')
    if len(line.tension_topics) > 1 and line.tension_type != FLOAT64:
        raise ConfigError(key, f'the channels of a load cell are {FLOAT64} topics')
    n = max(len(line.tension_topics), 1)
    if line.min_channels != int(line.min_channels):
        raise ConfigError(f'{line.name}.min_channels', 'must be a whole number of channels')
    if line.min_channels > n:
        raise ConfigError(
            f'{line.name}.min_channels',
            f'{int(line.min_channels)} but the line has {n} channel(s) (tension_topics)',
        )


def _check_point_loads(line: LineConfig) -> None:
    """Point loads: one weight per position, inside the chain, no axial stiffness, and no
    buoy lifting more than the chain and clumps below it weigh (it would lift the anchor by
    itself)."""
    name, pos, wts = line.name, line.point_load_positions, line.point_load_weights
    if len(pos) != len(wts):
        raise ConfigError(
            f'{name}.point_load_weights',
            f'{len(wts)} weights for {len(pos)} positions (point_load_positions): one each',
        )
    if not pos:
        return
    if line.ea is not None:
        raise ConfigError(
            f'{name}.ea',
            'point loads are solved with the inextensible chain: set ea to 0 or remove them',
        )
    for p, w in zip(pos, wts):
        if w == 0.0:
            raise ConfigError(f'{name}.point_load_weights', 'a point load of 0 N: remove it')
        if line.chain_length is not None and p >= line.chain_length:
            raise ConfigError(
                f'{name}.point_load_positions',
                f'{p!r} m is beyond the chain (chain_length {line.chain_length!r} m)',
            )
        below = line.weight * p + sum(v for q, v in zip(pos, wts) if q < p and v > 0.0)
        if w < 0.0 and -w >= below:
            raise ConfigError(
                f'{name}.point_load_weights',
                f'a buoy of {-w:g} N at {p:g} m lifts more than the chain below it weighs '
                f'({below:g} N): it would lift the anchor by itself',
            )


def _default(name: str) -> Any:
    return _GLOBAL[name].default


def _check_choice(full_name: str, value: str, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ConfigError(full_name, f'{value!r} is not one of {", ".join(choices)}')


@dataclass(frozen=True)
class AlarmConfig:
    """Alarm thresholds, deadbands, hold times, timeouts and rates.

    Field names are the global parameter names; units, defaults and ranges are in
    :data:`PARAMETERS` (m for margins, N for forces, s for times, Hz for rates).
    """

    anchor_margin_warn: float = _default('anchor_margin_warn')
    anchor_margin_deadband: float = _default('anchor_margin_deadband')
    tide_margin_warn: float = _default('tide_margin_warn')
    tide_margin_deadband: float = _default('tide_margin_deadband')
    tide_trend_window: float = _default('tide_trend_window')
    uplift_time_warn: float = _default('uplift_time_warn')
    uplift_time_deadband: float = _default('uplift_time_deadband')
    depth_accuracy: float = _default('depth_accuracy')
    wave_window: float = _default('wave_window')
    wave_allowance: float = _default('wave_allowance')
    drag_margin_warn: float = _default('drag_margin_warn')
    drag_margin_deadband: float = _default('drag_margin_deadband')
    drag_tolerance: float = _default('drag_tolerance')
    fatigue_damage_warn: float = _default('fatigue_damage_warn')
    channel_tolerance: float = _default('channel_tolerance')
    tension_resolution: float = _default('tension_resolution')
    depth_resolution: float = _default('depth_resolution')
    stuck_time: float = _default('stuck_time')
    tension_rate_max: float = _default('tension_rate_max')
    depth_rate_max: float = _default('depth_rate_max')
    stamp_jitter: float = _default('stamp_jitter')
    spike_noise_k: float = _default('spike_noise_k')
    spike_noise_time: float = _default('spike_noise_time')
    depth_stuck_steps: float = _default('depth_stuck_steps')
    depth_residual_rate: float = _default('depth_residual_rate')
    depth_still_max: float = _default('depth_still_max')
    sensor_hold: float = _default('sensor_hold')
    parted_drop: float = _default('parted_drop')
    parted_window: float = _default('parted_window')
    depth_min: float = _default('depth_min')
    depth_max: float = _default('depth_max')
    units_window: float = _default('units_window')
    stamp_ahead_max: float = _default('stamp_ahead_max')
    tension_sample_rate: float = _default('tension_sample_rate')
    depth_sample_rate: float = _default('depth_sample_rate')
    intake_step_budget: float = _default('intake_step_budget')
    intake_warn_count: float = _default('intake_warn_count')
    intake_warn_share: float = _default('intake_warn_share')
    tide_table: str = _default('tide_table')
    tide_table_epoch: float = _default('tide_table_epoch')
    tide_forecast_horizon: float = _default('tide_forecast_horizon')
    load_margin_warn: float = _default('load_margin_warn')
    load_margin_deadband: float = _default('load_margin_deadband')
    safety_factor_warn: float = _default('safety_factor_warn')
    safety_factor_deadband: float = _default('safety_factor_deadband')
    warn_clear_hold: float = _default('warn_clear_hold')
    margin_clear_hold: float = _default('margin_clear_hold')
    on_delay: float = _default('on_delay')
    uplift_clear_hysteresis: float = _default('uplift_clear_hysteresis')
    uplift_clear_margin: float = _default('uplift_clear_margin')
    clear_hold: float = _default('clear_hold')
    tension_timeout: float = _default('tension_timeout')
    depth_timeout: float = _default('depth_timeout')
    common_cause_window: float = _default('common_cause_window')
    parted_consequence_window: float = _default('parted_consequence_window')
    diagnostic_rate: float = _default('diagnostic_rate')
    shelve_max: float = _default('shelve_max')
    unshelvable_conditions: tuple[str, ...] = _default('unshelvable_conditions')
    chatter_count: float = _default('chatter_count')
    chatter_window: float = _default('chatter_window')
    flood_count: float = _default('flood_count')
    flood_window: float = _default('flood_window')

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = _check(f.name, _GLOBAL[f.name], getattr(self, f.name))
            object.__setattr__(self, f.name, value)
        for name in ('chatter_count', 'flood_count'):
            if getattr(self, name) != int(getattr(self, name)):
                raise ConfigError(name, f'must be a whole number, got {getattr(self, name)!r}')
        for cond in self.unshelvable_conditions:
            if cond not in ALARM_CONDITIONS and cond != SENSORS_ALARM:
                raise ConfigError(
                    'unshelvable_conditions',
                    f'unknown alarm condition {cond!r} '
                    f'(conditions: {", ".join(ALARM_CONDITIONS)}, {SENSORS_ALARM})',
                )
        try:
            table = parse_table(self.tide_table)
        except ValueError as err:
            raise ConfigError('tide_table', str(err)) from None
        object.__setattr__(self, '_constituents', table)

    @property
    def constituents(self) -> tuple[Constituent, ...]:
        """The tide table's constituents (empty: no table)."""
        return getattr(self, '_constituents')


@dataclass(frozen=True)
class DockConfig:
    """The dock as one body: its size, projected areas (None: not given) and the load-formula
    coefficients of the seed paper (field names are the ``dock_*`` parameters without the
    prefix; units and sources in :data:`PARAMETERS` and docs/dock_body.md)."""

    length: float | None = None
    beam: float | None = None
    wind_area_x: float | None = None
    hull_area_x: float | None = None
    wind_area_y: float | None = None
    hull_area_y: float | None = None
    wetted_area: float | None = None
    wind_coefficient: float = _default('dock_wind_coefficient')
    hull_wind_factor: float = _default('dock_hull_wind_factor')
    current_coefficient: float = _default('dock_current_coefficient')
    current_exponent: float = _default('dock_current_exponent')
    wave_drift_coefficient: float = _default('dock_wave_drift_coefficient')
    residual_limit: float = _default('dock_residual_limit')
    residual_time: float = _default('dock_residual_time')
    table_depth_min: float | None = None
    table_depth_max: float | None = None

    @property
    def table_depths(self) -> Optional[tuple[float, float]]:
        """The tide depths ``(low, high)`` [m] of the point-load lines' tables, or None."""
        if self.table_depth_min is None or self.table_depth_max is None:
            return None
        return self.table_depth_min, self.table_depth_max

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            spec = _GLOBAL[f'dock_{f.name}']
            value = getattr(self, f.name)
            if spec.optional and value is None:
                continue
            value = _check(spec.name, spec, value)
            object.__setattr__(self, f.name, None if math.isnan(value) else value)


#: Global parameters held by MonitorConfig itself (not by its alarm or dock parts).
_TOP_LEVEL = (
    'depth_topic',
    'log_dir',
    'log_rotate_size',
    'log_rotate_duration',
    'log_max_total_size',
    'log_max_age',
    'log_min_free_space',
    'log_create_dir',
    'allow_runtime_changes',
    'acknowledge_from_ros',
    'runtime_change_warn_time',
    'depth_type',
    'water_density',
    'atmospheric_pressure',
    'gauge_height',
    'depth_offset',
)

#: Per-line parameters that place a line on the dock (all given on every line, or none).
GEOMETRY = ('hook_x', 'hook_y', 'heading', 'chain_length')

#: The default chart range as multiples of the shallowest (``depth_min``) and the deepest
#: (``depth_max``) depth [m] at which a line's fixed-length chain lifts its anchor at its
#: installed span. The depths the dock was laid for lie below the lift depths, and far above a
#: twentieth of them: a chain laid with much grounded length lifts deeper than the dock floats
#: (130 m of chain at a 100 m span lifts at about 60 m; a dock moored so lies at 15-20 m, a
#: quarter of it), none at twenty times its depth. A gauge reading below a twentieth of the
#: shallowest lift depth (a pressure gauge stepping to 0.3 m; paper dock: below 1.1 m) or a
#: quarter above the deepest is a datum, scale or sensor fault.
CHART_LOW = 0.05
CHART_HIGH = 1.25


def chart_range(lines: Iterable[LineConfig]) -> tuple[float, float]:
    """The default ``(depth_min, depth_max)`` [m] from the lines: :data:`CHART_LOW` x the
    shallowest and :data:`CHART_HIGH` x the deepest depth at which a fixed-length chain lifts
    its anchor at its installed span (the hook height taken off; 0 and 12000 without chain
    lengths). The low bound is loose on purpose: a shallower sea only lays more chain on the
    seabed (a long chain on a short span lifts its anchor far deeper than the dock lies), so it
    catches a gauge's datum or scale fault (a pressure gauge stepping to 0.3 m), never a low
    water; an installer who knows the lowest water gives ``depth_min`` closer."""
    from catenary_monitor.core.physics.fixed_length import lift_depth_scalar

    lifts = []
    for line in lines:
        if line.chain_length is None or not line.chain_length == line.chain_length:
            continue
        ea = math.inf if not line.ea else line.ea
        try:
            lift = lift_depth_scalar(line.weight, line.chain_length, line.anchor_distance, ea)
        except (ValueError, OverflowError, ZeroDivisionError):
            continue
        if lift == lift and lift - line.hook_height > 0.0:
            lifts.append(lift - line.hook_height)
    if not lifts:
        return 0.0, 12000.0
    return CHART_LOW * min(lifts), min(CHART_HIGH * max(lifts), 12000.0)


@dataclass(frozen=True)
class MonitorConfig:
    """The whole monitor: its lines (at least one, unique names and topics), alarm settings
    and the dock's data."""

    lines: tuple[LineConfig, ...]
    depth_topic: str = _default('depth_topic')
    log_dir: str = _default('log_dir')
    allow_runtime_changes: bool = _default('allow_runtime_changes')
    acknowledge_from_ros: bool = _default('acknowledge_from_ros')
    runtime_change_warn_time: float = _default('runtime_change_warn_time')  # s
    log_rotate_size: float = _default('log_rotate_size')  # MiB
    log_rotate_duration: float = _default('log_rotate_duration')  # s
    log_create_dir: bool = _default('log_create_dir')
    log_max_total_size: float = _default('log_max_total_size')  # B
    log_max_age: float = _default('log_max_age')  # s
    log_min_free_space: float = _default('log_min_free_space')  # B
    depth_type: str = _default('depth_type')
    water_density: float = _default('water_density')  # kg/m^3
    atmospheric_pressure: float = _default('atmospheric_pressure')  # Pa
    gauge_height: float = _default('gauge_height')  # m
    depth_offset: float = _default('depth_offset')  # m
    alarm: AlarmConfig = field(default_factory=AlarmConfig)
    dock: DockConfig = field(default_factory=DockConfig)
    #: The ``response_texts.<condition>`` parameters that differ from the shipped texts
    #: (:data:`~catenary_monitor.core.config.responses.DEFAULT_RESPONSES`), as (condition, text).
    response_texts: tuple[tuple[str, str], ...] = ()
    #: Built for the dock as one body only (``equilibrium``, ``envelope``), not for the monitor:
    #: lines with point loads may then be placed on the dock. Not a parameter.
    body_only: bool = field(default=False, compare=False, repr=False)

    @property
    def has_dock_model(self) -> bool:
        """True when every line is placed on the dock (hook, heading, chain length)."""
        return all(_set(getattr(line, key)) for line in self.lines for key in GEOMETRY)

    def __post_init__(self) -> None:
        object.__setattr__(self, 'lines', tuple(self.lines))
        if not self.lines:
            raise ConfigError('lines', 'must name at least one line')
        names = [line.name for line in self.lines]
        for name in names:
            if names.count(name) > 1:
                raise ConfigError('lines', f'duplicate line name {name!r}')
        for key in _TOP_LEVEL:
            object.__setattr__(self, key, _check(key, _GLOBAL[key], getattr(self, key)))
        _check_topic('depth_topic', self.depth_topic)
        _check_choice('depth_type', self.depth_type, DEPTH_TYPES)
        rotate = self.log_rotate_size * 2**20
        if 0.0 < self.log_max_total_size < 2.0 * rotate:
            raise ConfigError(
                'log_max_total_size',
                f'{self.log_max_total_size:g} B is below 2 x log_rotate_size ({2 * rotate:g} B): '
                'the open file and a finished one must fit',
            )
        if not self.log_dir:
            raise ConfigError('log_dir', 'must not be empty')
        _check_geometry(self.lines, self.body_only)
        if self.has_dock_model and not self.body_only:
            _check_tables(self.lines, self.dock)
        seen = {self.depth_topic: 'depth_topic'}
        for line in self.lines:
            many = bool(line.tension_topics)
            name = f'{line.name}.tension_topics' if many else f'{line.name}.tension_topic'
            for topic in line.topics:
                other = seen.setdefault(topic, name)
                if other != name:
                    raise ConfigError(name, f'topic {topic!r} is already used by {other}')

    @property
    def chart(self) -> tuple[float, float]:
        """The depth sensor's chart range ``(depth_min, depth_max)`` [m]: as set, else from the
        lines (:func:`chart_range`)."""
        got = getattr(self, '_chart', None)
        if got is None:
            lo, hi = self.alarm.depth_min, self.alarm.depth_max
            if lo != lo or hi != hi:
                low, high = chart_range(self.lines)
                lo, hi = (low if lo != lo else lo), (high if hi != hi else hi)
            got = (lo, hi)
            object.__setattr__(self, '_chart', got)
        return got

    def headings(self) -> list[float]:
        """Each line's heading (deg, clockwise from the bow, in [0, 360)): ``NAME.heading``
        where set, else evenly spread, line k of n at ``(k + 0.5) * 360 / n``."""
        n = len(self.lines)
        return [
            (((k + 0.5) * 360.0 / n) if line.heading != line.heading else line.heading) % 360.0
            for k, line in enumerate(self.lines)
        ]

    def line(self, name: str) -> LineConfig:
        """The line called ``name`` (KeyError if there is none)."""
        for line in self.lines:
            if line.name == name:
                return line
        raise KeyError(name)


def _set(value: Any) -> bool:
    """A parameter value that is given (neither None nor NaN)."""
    return value is not None and value == value


def _check_geometry(lines: tuple[LineConfig, ...], body_only: bool = False) -> None:
    """A line with a hook position asks for the dock model: every line then needs all of
    :data:`GEOMETRY` (``heading`` or ``chain_length`` alone are other features' business).
    Lines with point loads are checked by :func:`_check_tables` (``body_only``: not)."""
    if not any(line.hook_x is not None or line.hook_y is not None for line in lines):
        return
    for line in lines:
        for key in GEOMETRY:
            if not _set(getattr(line, key)):
                raise ConfigError(
                    f'{line.name}.{key}',
                    'missing: the dock model (hook_x, hook_y given) needs hook_x, hook_y, '
                    'heading and chain_length on every line',
                )


def _check_tables(lines: tuple[LineConfig, ...], dock: DockConfig) -> None:
    """The live dock estimate takes a line with point loads through its table over
    ``dock_table_depth_min`` - ``dock_table_depth_max`` (built here, once per distinct chain:
    :mod:`catenary_monitor.core.physics.point_load_table`); one line if it cannot."""
    from catenary_monitor.core.physics.point_load_table import TableError, table_for
    from catenary_monitor.core.physics.point_loads import PointLoads

    loaded = [line for line in lines if line.point_loads is not None]
    if not loaded:
        return
    depths = dock.table_depths
    if depths is None:
        raise ConfigError(
            'dock_table_depth_min',
            f'{loaded[0].name} has point loads: the live dock estimate (hook_x, hook_y given) '
            'tabulates such lines over the tide depths dock_table_depth_min - '
            'dock_table_depth_max (m): give both',
        )
    if not depths[0] <= depths[1]:
        raise ConfigError('dock_table_depth_max', f'{depths[1]:g} m is below the minimum')
    for line in loaded:
        assert line.point_loads is not None and line.chain_length is not None
        hooks = (depths[0] + line.hook_height, depths[1] + line.hook_height)
        try:
            table_for(
                line.weight, line.chain_length, PointLoads.of(*line.point_loads), line.mbl, hooks
            )
        except TableError as err:
            raise ConfigError(
                f'{line.name}.point_load_positions', f'no table for the dock estimate: {err}'
            ) from err


def expand_parameters(lines: tuple[str, ...] | list[str]) -> Iterator[tuple[str, ParamSpec]]:
    """Yield ``(full_name, spec)`` for every parameter of a node monitoring ``lines``."""
    for spec in PARAMETERS:
        if spec.scope == 'global':
            yield spec.name, spec
    for line in lines:
        for spec in _PER_LINE.values():
            yield spec.full_name(line), spec


def load_params_file(
    path: str | Path, node_name: str = 'catenary_monitor', node_namespace: str = '/'
) -> dict[str, Any]:
    """Parameters of node ``node_namespace/node_name`` in a ROS 2 params YAML, flattened.

    Read as the live node reads ``--params-file`` (:mod:`catenary_monitor.core.config.params_file`:
    rcl's YAML rules, rclpy's section matching): the same files are refused, and the dotted names,
    types and values are those of ``node._parameter_overrides`` (``1300`` an int, ``1e6`` a
    float, ``[]`` None). A file with no section for the node gives ``{}``. Every failure is one
    :class:`ConfigError` line for ``--params-file``.
    """
    from catenary_monitor.core.config.params_file import ParamsFileError, read_params_file

    try:
        return read_params_file(path, node_name, node_namespace)
    except ParamsFileError as err:
        raise ConfigError('--params-file', str(err)) from err


def params_file_text(flat: Mapping[str, Any], node_name: str = 'catenary_monitor') -> str:
    """A ROS 2 params file (``node_name: ros__parameters:``, dotted names) holding ``flat``
    (bools, ints, floats, strings and lists of them), which :func:`load_params_file` and rcl
    read back to the same values: floats by ``repr`` with a ``.`` always (rcl reads ``1e-300``
    as a string, ``1.0e-300`` as a double), strings quoted."""

    def scalar(v: Any) -> str:
        if isinstance(v, bool):
            return 'true' if v else 'false'
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, float):
            if not math.isfinite(v):
                return '.nan' if v != v else ('.inf' if v > 0 else '-.inf')
            text = repr(v)
            return text if '.' in text else text.replace('e', '.0e')
        return repr(v)

    out = [f'{node_name}:', '  ros__parameters:']
    for key, value in flat.items():
        if isinstance(value, (list, tuple)):
            out.append(f'    {key}: [{", ".join(scalar(v) for v in value)}]')
        else:
            out.append(f'    {key}: {scalar(value)}')
    return '\n'.join(out) + '\n'


def config_from_params(flat: Mapping[str, Any], *, body_only: bool = False) -> MonitorConfig:
    """Validate flat (dotted) parameters and build the :class:`MonitorConfig` (``body_only``:
    for the dock as one body, not the monitor; see :class:`MonitorConfig`).

    Raises :class:`ConfigError` for the first problem found: ``lines`` missing, empty, of the
    wrong type or with a bad or duplicate name; an unknown parameter; a missing required
    parameter; a wrong type; a value out of range; a topic used twice.
    """
    lines_spec = _GLOBAL['lines']
    lines = _check('lines', lines_spec, flat.get('lines', REQUIRED))
    if not lines:
        raise ConfigError('lines', 'must name at least one line')
    for name in lines:
        _check_line_name(name)
        if lines.count(name) > 1:
            raise ConfigError('lines', f'duplicate line name {name!r}')
    known = dict(expand_parameters(lines))
    for name in flat:
        if (
            name in known
            or name in ROS_BUILTIN_PARAMETERS
            or name.startswith(_ROS_BUILTIN_PREFIXES)
        ):
            continue
        close = difflib.get_close_matches(name, list(known), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ''
        raise ConfigError(name, f'unknown parameter{hint}')
    values = {
        name: _check(
            name,
            spec,
            flat.get(name, spec.default_for(name.split('.')[0] if spec.scope == 'line' else None)),
        )
        for name, spec in known.items()
    }
    line_configs = tuple(
        LineConfig(name=line, **{key: values[f'{line}.{key}'] for key in _PER_LINE})
        for line in lines
    )
    alarm = AlarmConfig(**{f.name: values[f.name] for f in dataclasses.fields(AlarmConfig)})
    dock = DockConfig(
        **{f.name: _given(values[f'dock_{f.name}']) for f in dataclasses.fields(DockConfig)}
    )
    return MonitorConfig(
        lines=line_configs,
        **{key: values[key] for key in _TOP_LEVEL},
        alarm=alarm,
        dock=dock,
        response_texts=tuple(
            (cond, values[RESPONSE_PREFIX + cond])
            for cond, text in DEFAULT_RESPONSES.items()
            if values[RESPONSE_PREFIX + cond] != text
        ),
        body_only=body_only,
    )


def _given(value: Any) -> Any:
    """None for a NaN (an optional parameter not given), else the value."""
    return None if isinstance(value, float) and math.isnan(value) else value


def config_to_params(config: MonitorConfig) -> dict[str, Any]:
    """Flat parameters that :func:`config_from_params` turns back into ``config``.

    Optional parameters that are not given are left out (so configurations that do not use
    them keep their hash, and the JSON of logs stays free of NaN); see :func:`all_parameters`.
    """
    flat: dict[str, Any] = {
        'lines': [line.name for line in config.lines],
        **{key: getattr(config, key) for key in _TOP_LEVEL},
    }
    flat.update(dataclasses.asdict(config.alarm))
    for key, value in dataclasses.asdict(config.dock).items():
        if value is not None:
            flat[f'dock_{key}'] = value
    for line in config.lines:
        for key in _PER_LINE:
            value = getattr(line, key)
            if _PER_LINE[key].optional and (value is None or value != value):
                continue  # not given
            flat[f'{line.name}.{key}'] = 0.0 if key == 'ea' and value is None else value
    for cond, text in config.response_texts:  # the shipped ones are left out (the defaults)
        flat[RESPONSE_PREFIX + cond] = text
    return flat


def all_parameters(config: MonitorConfig) -> dict[str, Any]:
    """Every parameter's value (what the node declares): :func:`config_to_params` with the
    optional parameters not given as NaN."""
    flat = config_to_params(config)
    names = [line.name for line in config.lines]
    return {
        name: flat.get(name, spec.default if spec.group == 'responses' else math.nan)
        for name, spec in expand_parameters(names)
    }


def resolve_topic(topic: str, node_name: str = 'catenary_monitor') -> str:
    """A topic name as a node ``node_name`` in the root namespace resolves it."""
    if topic.startswith('~'):
        return f'/{node_name}' + ('/' + topic[1:].lstrip('/') if len(topic) > 1 else '')
    return topic if topic.startswith('/') else '/' + topic


#: Parameters that decide no result (where logs go and how they rotate, whether changes are
#: accepted): left out of :func:`config_hash`, so ``--log-dir`` or a runtime-change policy
#: does not make replay think a log was recorded with other parameters.
NON_DECIDING = frozenset(
    {
        'log_dir',
        'log_rotate_size',
        'log_rotate_duration',
        'log_max_total_size',
        'log_max_age',
        'log_min_free_space',
        'log_create_dir',
        'allow_runtime_changes',
        'acknowledge_from_ros',
        *(RESPONSE_PREFIX + cond for cond in DEFAULT_RESPONSES),
    }
)


def config_hash(config: MonitorConfig) -> str:
    """SHA-256 hex digest of the parameters that decide results (all but
    :data:`NON_DECIDING`), for logs and MCAP metadata."""
    flat = {k: v for k, v in config_to_params(config).items() if k not in NON_DECIDING}
    text = json.dumps(flat, sort_keys=True, separators=(',', ':'))
    return hashlib.sha256(text.encode('utf-8')).hexdigest()


def parameters_markdown(group: str = '') -> str:
    """The parameter table as Markdown: name, default (doubles unless noted), unit, range,
    description; ``group`` ``''`` the monitor's (docs/node.md), ``'dock'`` the dock model's,
    ``'holding'`` the holding's (docs/holding.md)."""
    rows = ['| parameter | default | unit | range | description |', '|---|---|---|---|---|']
    for spec in PARAMETERS:
        if spec.group != group:
            continue
        name = spec.full_name('NAME')
        if spec.default is REQUIRED:
            default = 'required'
        elif spec.optional:
            default = 'not set (NaN)'
        elif isinstance(spec.default, tuple):
            default = f'`[{", ".join(spec.default)}]`'
        else:
            default = f'`{spec.default_for("NAME")!r}`'
        if spec.type != 'double':
            default += f' ({spec.type.replace("_", " ")})'
        span = '' if spec.min is None else f'{spec.min:g} – {spec.max:g}'
        ro = ' (read-only)' if spec.read_only else ''
        if spec.type == 'double_array':
            default = '`[]` (double array)'
        rows.append(f'| `{name}` | {default} | {spec.unit} | {span} | {spec.description}{ro} |')
    return '\n'.join(rows) + '\n'


def runtime_change_refusal(config: MonitorConfig, names: Iterable[str]) -> Optional[str]:
    """Why a runtime change of ``names`` is refused (one line), or None when it may go ahead.

    Every declared monitor parameter decides alarms or their schedule (line constants, MBL,
    allowed uplift, thresholds, holds, timeouts, rates) and ``use_sim_time`` can stop the
    clock: unless the params file sets ``allow_runtime_changes: true``, changing any of them
    at runtime is refused. ``use_sim_time`` is refused even then (switching clocks mid-run
    would jump every stamp; a stopped ``/clock`` set at start is reported by the node's
    wall-clock watchdog).
    """
    names = list(names)
    if 'use_sim_time' in names:
        return 'use_sim_time cannot change at runtime (a stopped /clock would silence the monitor)'
    if config.allow_runtime_changes or not names:
        return None
    return (
        f"{', '.join(names)}: runtime changes are refused (they decide alarms); set "
        'allow_runtime_changes: true in the params file to allow them'
    )


def _shown(value: Any, unit: str) -> str:
    """A parameter value for a log line: numbers as ``%g`` with their unit."""
    if isinstance(value, float) and not isinstance(value, bool):
        return f'{value:g} {unit}'.rstrip()
    return repr(value)


def change_message(name: str, old: Any, new: Any) -> str:
    """One log line for an accepted runtime change, e.g. ``allowed_uplift of line_11 changed
    0 N -> 1e+09 N at runtime`` (units from :data:`PARAMETERS`)."""
    line, _, key = name.rpartition('.')
    if line and key in _PER_LINE:
        what, unit = f'{key} of {line}', _PER_LINE[key].unit
    else:
        what, unit = name, _GLOBAL[name].unit if name in _GLOBAL else ''
    return f'{what} changed {_shown(old, unit)} -> {_shown(new, unit)} at runtime'


def runtime_change_messages(old: MonitorConfig, new: MonitorConfig) -> list[str]:
    """One :func:`change_message` per parameter that differs between ``old`` and ``new``
    (sorted by name; NaN for an optional parameter not given)."""
    before, after = all_parameters(old), all_parameters(new)
    out = []
    for name in sorted(set(before) | set(after)):
        a, b = before.get(name, math.nan), after.get(name, math.nan)
        if isinstance(a, tuple) or isinstance(b, tuple):
            a, b = list(a), list(b)
        if a != b and not (_is_nan(a) and _is_nan(b)):
            out.append(change_message(name, a, b))
    return out


def _is_nan(value: Any) -> bool:
    return isinstance(value, float) and value != value

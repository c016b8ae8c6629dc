"""Monitor configuration: one parameter table, frozen dataclasses, ROS params YAML loading.

No rclpy here. The node declares its parameters from :data:`PARAMETERS` (description, unit,
range) and builds a :class:`MonitorConfig` with :func:`config_from_params`; replay builds the same
dataclass from the same YAML with :func:`load_params_file`, which reads it by rcl's rules
(:mod:`catenary_monitor.core.params_file`). Both share one validation, and every failure is a
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
from typing import Any, Iterator, Mapping, NamedTuple

__all__ = [
    'REQUIRED',
    'ParamSpec',
    'PARAMETERS',
    'ROS_BUILTIN_PARAMETERS',
    'ConfigError',
    'LineConfig',
    'AlarmConfig',
    'MonitorConfig',
    'expand_parameters',
    'load_params_file',
    'config_from_params',
    'config_to_params',
    'config_hash',
    'parameters_markdown',
    'resolve_topic',
]


class _Required:
    """Sentinel for a parameter that has no default."""

    def __repr__(self) -> str:
        return 'REQUIRED'


REQUIRED: Any = _Required()


class ParamSpec(NamedTuple):
    """One row of the parameter table.

    ``name`` is the full name for ``scope == 'global'`` and the suffix after ``NAME.`` for
    ``scope == 'line'``. ``type`` is one of ``double``, ``string``, ``string_array``. ``default``
    is a value or :data:`REQUIRED`; a string default may contain ``{line}``. ``min`` / ``max`` are
    inclusive (ROS ``FloatingPointRange`` semantics) or ``None``.
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

    def full_name(self, line: str | None = None) -> str:
        """Parameter name as declared on the node (``NAME.weight`` for per-line rows)."""
        return f'{line}.{self.name}' if self.scope == 'line' else self.name

    def default_for(self, line: str | None = None) -> Any:
        """Default value with ``{line}`` substituted, or :data:`REQUIRED`."""
        if isinstance(self.default, str) and line is not None:
            return self.default.format(line=line)
        return self.default


_L = 'line'
#: The one source of truth for every parameter: the node declares these, the README renders them.
PARAMETERS: tuple[ParamSpec, ...] = (
    ParamSpec(
        'lines',
        'string_array',
        REQUIRED,
        'Names of the monitored chains; each NAME gets the NAME.* parameters below',
        '',
        None,
        None,
        read_only=True,
    ),
    ParamSpec(
        'depth_topic',
        'string',
        '/tide/depth',
        'std_msgs/Float64 topic with the water depth at the hooks (m)',
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
        'std_msgs/Float64 topic with the measured hook tension (N)',
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
    ParamSpec(
        'heading',
        'double',
        math.nan,
        'Direction hook to anchor, clockwise from the dock\'s bow; not set (nan): evenly spread',
        'deg',
        -360.0,
        360.0,
        _L,
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
        'When the clear level is 0 N, the anchor margin must also reach this',
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
        'diagnostic_rate',
        'double',
        1.0,
        'Rate of the periodic /diagnostics publication',
        'Hz',
        0.01,
        100.0,
    ),
)

_GLOBAL = {p.name: p for p in PARAMETERS if p.scope == 'global'}
_PER_LINE = {p.name: p for p in PARAMETERS if p.scope == 'line'}

#: Parameters rclpy itself may find in a params file; accepted and ignored here.
ROS_BUILTIN_PARAMETERS = frozenset({'use_sim_time', 'start_type_description_service'})
_ROS_BUILTIN_PREFIXES = ('qos_overrides.',)

_LINE_NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*\Z')
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
        if value != value and spec.default != spec.default:
            return value  # an optional parameter (default NaN) left unset
        if not math.isfinite(value):
            raise ConfigError(full_name, f'must be finite, got {value!r}')
        if spec.min is not None and value < spec.min or spec.max is not None and value > spec.max:
            raise ConfigError(
                full_name,
                f'{value!r} out of range [{spec.min!r}, {spec.max!r}]' f' {spec.unit}'.rstrip(),
            )
        return value
    if spec.type == 'string':
        if not isinstance(value, str):
            raise ConfigError(
                full_name, f'expected a string, got {type(value).__name__} ' f'{value!r}'
            )
        return value
    if spec.type == 'string_array':
        if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
            raise ConfigError(full_name, f'expected a list of strings, got {value!r}')
        return tuple(value)
    raise AssertionError(f'unknown parameter type {spec.type!r}')  # table bug, not user error


def _check_topic(full_name: str, topic: str) -> None:
    if not _TOPIC.match(topic) or '//' in topic:
        raise ConfigError(full_name, f'{topic!r} is not a valid ROS topic name')


@dataclass(frozen=True)
class LineConfig:
    """One anchor chain. SI units: weight N/m (submerged), distances m, forces N.

    ``tension_topic`` ``''`` means ``/mooring/NAME/tension``; ``ea`` ``None`` (or 0) means an
    inextensible chain. Values are validated against :data:`PARAMETERS` on construction.
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

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _LINE_NAME.match(self.name):
            raise ConfigError(
                'lines',
                f'line name {self.name!r} must start with a letter and '
                'hold only letters, digits and _',
            )
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        if values['tension_topic'] == '':
            values['tension_topic'] = _PER_LINE['tension_topic'].default_for(self.name)
        if values['ea'] is None:
            values['ea'] = 0.0
        for key, spec in _PER_LINE.items():
            object.__setattr__(self, key, _check(spec.full_name(self.name), spec, values[key]))
        _check_topic(f'{self.name}.tension_topic', self.tension_topic)
        if self.ea == 0.0:
            object.__setattr__(self, 'ea', None)


def _default(name: str) -> Any:
    return _GLOBAL[name].default


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
    load_margin_warn: float = _default('load_margin_warn')
    load_margin_deadband: float = _default('load_margin_deadband')
    safety_factor_warn: float = _default('safety_factor_warn')
    safety_factor_deadband: float = _default('safety_factor_deadband')
    warn_clear_hold: float = _default('warn_clear_hold')
    on_delay: float = _default('on_delay')
    uplift_clear_hysteresis: float = _default('uplift_clear_hysteresis')
    uplift_clear_margin: float = _default('uplift_clear_margin')
    clear_hold: float = _default('clear_hold')
    tension_timeout: float = _default('tension_timeout')
    depth_timeout: float = _default('depth_timeout')
    diagnostic_rate: float = _default('diagnostic_rate')

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = _check(f.name, _GLOBAL[f.name], getattr(self, f.name))
            object.__setattr__(self, f.name, value)


@dataclass(frozen=True)
class MonitorConfig:
    """The whole monitor: its lines (at least one, unique names and topics) and alarm settings."""

    lines: tuple[LineConfig, ...]
    depth_topic: str = _default('depth_topic')
    log_dir: str = _default('log_dir')
    alarm: AlarmConfig = field(default_factory=AlarmConfig)

    def __post_init__(self) -> None:
        object.__setattr__(self, 'lines', tuple(self.lines))
        if not self.lines:
            raise ConfigError('lines', 'must name at least one line')
        names = [line.name for line in self.lines]
        for name in names:
            if names.count(name) > 1:
                raise ConfigError('lines', f'duplicate line name {name!r}')
        for key in ('depth_topic', 'log_dir'):
            object.__setattr__(self, key, _check(key, _GLOBAL[key], getattr(self, key)))
        _check_topic('depth_topic', self.depth_topic)
        if not self.log_dir:
            raise ConfigError('log_dir', 'must not be empty')
        seen = {self.depth_topic: 'depth_topic'}
        for line in self.lines:
            other = seen.setdefault(line.tension_topic, f'{line.name}.tension_topic')
            if other != f'{line.name}.tension_topic':
                raise ConfigError(
                    f'{line.name}.tension_topic',
                    f'topic {line.tension_topic!r} is already used by {other}',
                )

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

    Read as the live node reads ``--params-file`` (:mod:`catenary_monitor.core.params_file`:
    rcl's YAML rules, rclpy's section matching): the same files are refused, and the dotted names,
    types and values are those of ``node._parameter_overrides`` (``1300`` an int, ``1e6`` a
    float, ``[]`` None). A file with no section for the node gives ``{}``. Every failure is one
    :class:`ConfigError` line for ``--params-file``.
    """
    from catenary_monitor.core.params_file import ParamsFileError, read_params_file

    try:
        return read_params_file(path, node_name, node_namespace)
    except ParamsFileError as err:
        raise ConfigError('--params-file', str(err)) from err


def config_from_params(flat: Mapping[str, Any]) -> MonitorConfig:
    """Validate flat (dotted) parameters and build the :class:`MonitorConfig`.

    Raises :class:`ConfigError` for the first problem found: ``lines`` missing, empty, of the
    wrong type or with a bad or duplicate name; an unknown parameter; a missing required
    parameter; a wrong type; a value out of range; a topic used twice.
    """
    lines_spec = _GLOBAL['lines']
    lines = _check('lines', lines_spec, flat.get('lines', REQUIRED))
    if not lines:
        raise ConfigError('lines', 'must name at least one line')
    for name in lines:
        if not _LINE_NAME.match(name):
            raise ConfigError(
                'lines',
                f'line name {name!r} must start with a letter and '
                'hold only letters, digits and _',
            )
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
    return MonitorConfig(
        lines=line_configs,
        depth_topic=values['depth_topic'],
        log_dir=values['log_dir'],
        alarm=alarm,
    )


def config_to_params(config: MonitorConfig) -> dict[str, Any]:
    """Flat parameters that :func:`config_from_params` turns back into ``config``."""
    flat: dict[str, Any] = {
        'lines': [line.name for line in config.lines],
        'depth_topic': config.depth_topic,
        'log_dir': config.log_dir,
    }
    flat.update(dataclasses.asdict(config.alarm))
    for line in config.lines:
        for key in _PER_LINE:
            value = getattr(line, key)
            flat[f'{line.name}.{key}'] = 0.0 if key == 'ea' and value is None else value
    return flat


def resolve_topic(topic: str, node_name: str = 'catenary_monitor') -> str:
    """A topic name as a node ``node_name`` in the root namespace resolves it."""
    if topic.startswith('~'):
        return f'/{node_name}' + ('/' + topic[1:].lstrip('/') if len(topic) > 1 else '')
    return topic if topic.startswith('/') else '/' + topic


def config_hash(config: MonitorConfig) -> str:
    """SHA-256 hex digest of the canonical parameters, for logs and MCAP metadata."""
    text = json.dumps(config_to_params(config), sort_keys=True, separators=(',', ':'))
    return hashlib.sha256(text.encode('utf-8')).hexdigest()


def parameters_markdown() -> str:
    """The parameter table as Markdown: name, default (doubles unless noted), unit, range,
    description."""
    rows = ['| parameter | default | unit | range | description |', '|---|---|---|---|---|']
    for spec in PARAMETERS:
        name = spec.full_name('NAME')
        default = 'required' if spec.default is REQUIRED else f'`{spec.default_for("NAME")!r}`'
        if spec.type != 'double':
            default += f' ({spec.type.replace("_", " ")})'
        span = '' if spec.min is None else f'{spec.min:g} – {spec.max:g}'
        ro = ' (read-only)' if spec.read_only else ''
        rows.append(f'| `{name}` | {default} | {spec.unit} | {span} | {spec.description}{ro} |')
    return '\n'.join(rows) + '\n'

"""Configuration: the parameter table, YAML loading, validation messages, round trips."""

import dataclasses
import math
from pathlib import Path

import pytest

from catenary_monitor.core.config.parameters import (
    PARAMETERS,
    REQUIRED,
    AlarmConfig,
    ConfigError,
    LineConfig,
    MonitorConfig,
    config_from_params,
    config_hash,
    config_to_params,
    expand_parameters,
    load_params_file,
    parameters_markdown,
)

DOCK_YAML = Path(__file__).resolve().parents[1] / 'config' / 'floating_dock.yaml'


def _minimal(**extra):
    flat = {'lines': ['a'], 'a.weight': 1300, 'a.anchor_distance': 120.0, 'a.mbl': 4.8e6}
    flat.update(extra)
    return flat


def _error(flat) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        config_from_params(flat)
    message = str(info.value)
    assert '\n' not in message
    return info.value


# --- floating_dock.yaml -----------------------------------------------------------------------


def test_floating_dock_matches_the_paper():
    config = config_from_params(load_params_file(DOCK_YAML))
    assert [line.name for line in config.lines] == [f'line_{i:02d}' for i in range(1, 13)]
    for line in config.lines:
        assert line.weight == 0.13 * 1000 * 10  # 0.13 t/m with g = 10, as in the paper
        assert line.anchor_distance == (121.06 if line.name == 'line_11' else 120.0)
        assert line.tension_topic == f'/mooring/{line.name}/tension'
        assert line.allowed_uplift == 0.0
        assert line.ea is None
        # U3 (grade 3) stud link, IACS W18 / ISO 1704: 0.01961 d^2 (44 - 0.08 d) kN, d = 81 mm.
        assert line.mbl == pytest.approx(0.01961 * 81**2 * (44 - 0.08 * 81) * 1e3, rel=1e-3)
    assert config.depth_topic == '/tide/depth'


def test_grade_formula_reproduces_the_papers_grade2_chain():
    # The same formula family (grade 2 coefficient) gives the paper's AM2 48 mm breaking force.
    assert 0.01373 * 48**2 * (44 - 0.08 * 48) == pytest.approx(1270.0, abs=0.5)


def test_round_trip_through_flat_parameters():
    config = config_from_params(load_params_file(DOCK_YAML))
    again = config_from_params(config_to_params(config))
    assert again == config
    assert config_hash(again) == config_hash(config)


def test_hash_changes_with_any_value():
    config = config_from_params(load_params_file(DOCK_YAML))
    changed = config_to_params(config)
    changed['line_07.anchor_distance'] = 120.5
    assert config_hash(config_from_params(changed)) != config_hash(config)
    assert len(config_hash(config)) == 64


# --- loading YAML -----------------------------------------------------------------------------


def test_nested_line_dicts_flatten_and_integers_become_floats(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text(
        '/**:\n  ros__parameters:\n    lines: [a]\n'
        '    a: {weight: 1300, anchor_distance: 120, mbl: 4800000}\n'
        '    clear_hold: 5\n'
    )
    flat = load_params_file(path)
    assert flat['a.weight'] == 1300
    config = config_from_params(flat)
    assert isinstance(config.line('a').weight, float) and config.line('a').weight == 1300.0
    assert isinstance(config.alarm.clear_hold, float)


def test_node_section_overrides_wildcard(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text(
        '/**:\n  ros__parameters:\n    clear_hold: 5.0\n    depth_topic: /x\n'
        'catenary_monitor:\n  ros__parameters:\n    clear_hold: 7.0\n'
    )
    assert load_params_file(path) == {'clear_hold': 7.0, 'depth_topic': '/x'}


def test_other_node_name(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text('mon2:\n  ros__parameters:\n    clear_hold: 5.0\n')
    assert load_params_file(path, node_name='mon2') == {'clear_hold': 5.0}
    # rcl gives a node without a section no parameters (no error): validation then names 'lines'
    assert load_params_file(path) == {}
    with pytest.raises(ConfigError, match="'lines': missing required"):
        config_from_params(load_params_file(path))


@pytest.mark.parametrize(
    'text, rule',
    [
        ('catenary_monitor:\n  lines: [a]\n', 'Sequences can only be values'),
        ('catenary_monitor:\n  lines: a\n', 'Cannot have a value before ros__parameters'),
        ('- a\n- b\n', 'Sequences cannot be key'),
        ('catenary_monitor: {ros__parameters: [\n', 'cannot read'),
    ],
)
def test_bad_files_give_one_line(tmp_path, text, rule):
    path = tmp_path / 'p.yaml'
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_params_file(path)
    assert rule in str(info.value) and '\n' not in str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(ConfigError, match='cannot read'):
        load_params_file(tmp_path / 'nope.yaml')


# --- validation messages ----------------------------------------------------------------------


@pytest.mark.parametrize(
    'flat, parameter, rule',
    [
        ({}, 'lines', 'missing required'),
        ({'lines': []}, 'lines', 'at least one line'),
        ({'lines': 'a'}, 'lines', 'list of strings'),
        ({'lines': ['a', 'a']}, 'lines', "duplicate line name 'a'"),
        ({'lines': ['1a']}, 'lines', 'start with a letter'),
        ({'lines': ['a.b']}, 'lines', 'start with a letter'),
        ({'lines': ['a', 'tide']}, 'lines', "line name 'tide' is the name of one of the"),
        ({'lines': ['sensors']}, 'lines', "'sensors' is the name of one of the monitor's own"),
        ({'lines': ['all']}, 'lines', 'choose another'),
        (
            _minimal(**{'a.wieght': 3.0}),
            'a.wieght',
            "unknown parameter (did you mean 'a.weight'?)",
        ),
        (_minimal(**{'b.weight': 3.0}), 'b.weight', 'unknown parameter'),
        (_minimal(bogus=1), 'bogus', 'unknown parameter'),
        (
            {'lines': ['a'], 'a.weight': 1300.0, 'a.mbl': 1e6},
            'a.anchor_distance',
            'missing required',
        ),
        (_minimal(**{'a.weight': '1300'}), 'a.weight', "expected a number (N/m), got str '1300'"),
        (_minimal(**{'a.weight': True}), 'a.weight', 'got bool'),
        (_minimal(**{'a.weight': -1.0}), 'a.weight', '-1.0 out of range [1.0, 100000.0] N/m'),
        (_minimal(**{'a.mbl': math.nan}), 'a.mbl', 'must be finite'),
        (_minimal(**{'a.allowed_uplift': -5}), 'a.allowed_uplift', 'out of range'),
        (_minimal(**{'a.tension_topic': 5}), 'a.tension_topic', 'expected a string'),
        (_minimal(**{'a.tension_topic': 'bad topic'}), 'a.tension_topic', 'not a valid ROS topic'),
        (
            _minimal(depth_topic='/mooring/a/tension'),
            'a.tension_topic',
            'already used by depth_topic',
        ),
        (_minimal(clear_hold=-1.0), 'clear_hold', 'out of range [0.0, 3600.0] s'),
        (_minimal(tension_timeout=0), 'tension_timeout', 'out of range'),
        (_minimal(diagnostic_rate='fast'), 'diagnostic_rate', 'expected a number (Hz)'),
        (_minimal(log_dir=''), 'log_dir', 'must not be empty'),
    ],
)
def test_every_error_is_one_line_naming_the_parameter(flat, parameter, rule):
    err = _error(flat)
    assert err.parameter == parameter
    assert str(err).startswith(f"parameter '{parameter}': ")
    assert rule in str(err)


def test_two_lines_on_one_topic():
    flat = _minimal(
        **{
            'lines': ['a', 'b'],
            'b.weight': 1.0,
            'b.anchor_distance': 1.0,
            'b.mbl': 1.0,
            'b.tension_topic': '/mooring/a/tension',
        }
    )
    assert _error(flat).parameter == 'b.tension_topic'


def test_ros_builtin_parameters_are_accepted():
    config = config_from_params(
        _minimal(use_sim_time=True, **{'qos_overrides./parameter_events.publisher.depth': 1000})
    )
    assert config.line('a').tension_topic == '/mooring/a/tension'


def test_defaults_come_from_the_table():
    config = config_from_params(_minimal())
    table = {spec.name: spec for spec in PARAMETERS}
    for f in dataclasses.fields(AlarmConfig):
        got, default = getattr(config.alarm, f.name), table[f.name].default
        assert got == default or (got != got and default != default), f.name  # NaN: not set
    assert config.depth_topic == table['depth_topic'].default == '/tide/depth'
    assert config.line('a').allowed_uplift == table['allowed_uplift'].default == 0.0
    assert config.line('a').hook_height == 0.0


def test_ea_zero_means_rigid_and_positive_is_kept():
    assert config_from_params(_minimal(**{'a.ea': 0})).line('a').ea is None
    assert config_from_params(_minimal(**{'a.ea': 5e8})).line('a').ea == 5e8


# --- the table itself -------------------------------------------------------------------------


def test_table_covers_every_config_field_and_contract_names():
    global_names = {s.name for s in PARAMETERS if s.scope == 'global'}
    line_names = {s.name for s in PARAMETERS if s.scope == 'line'}
    assert {f.name for f in dataclasses.fields(AlarmConfig)} <= global_names
    assert {'lines', 'depth_topic', 'log_dir'} <= global_names
    assert {
        'weight',
        'anchor_distance',
        'mbl',
        'allowed_uplift',
        'hook_height',
        'tension_topic',
    } <= line_names
    assert line_names == {f.name for f in dataclasses.fields(LineConfig)} - {'name'}


def test_every_parameter_is_described_with_a_valid_range():
    for spec in PARAMETERS:
        types = {'double', 'bool', 'string', 'string_array', 'double_array'}
        assert spec.description and spec.type in types
        if spec.type in ('double', 'double_array'):
            assert spec.min is not None and spec.max is not None and spec.min < spec.max
            if spec.optional:  # NaN: not given
                assert spec.default != spec.default
            elif spec.type == 'double_array':
                assert all(spec.min <= v <= spec.max for v in spec.default)
            elif spec.default is not REQUIRED:
                assert spec.min <= spec.default <= spec.max


def test_expand_parameters_and_markdown():
    names = [name for name, _ in expand_parameters(['x', 'y'])]
    assert 'x.weight' in names and 'y.tension_topic' in names and 'clear_hold' in names
    assert len(names) == len(set(names))
    text = parameters_markdown()
    assert '| `NAME.weight` | required | N/m | 1 – 100000 |' in text
    assert "`'/mooring/NAME/tension'`" in text


def test_dataclasses_validate_when_built_directly():
    with pytest.raises(ConfigError, match="'a.mbl'"):
        LineConfig('a', 1300.0, 120.0, -1.0)
    with pytest.raises(ConfigError, match="'clear_hold'"):
        AlarmConfig(clear_hold=-3.0)
    with pytest.raises(ConfigError, match='duplicate'):
        MonitorConfig(lines=(LineConfig('a', 1.0, 1.0, 1.0), LineConfig('a', 1.0, 1.0, 1.0)))


def test_heading_is_optional_and_checked():
    """NAME.heading (deg, clockwise from the bow): not set -> evenly spread; out of range
    refused in one line; the same value through config_to_params."""
    import math

    from catenary_monitor.core.config.parameters import (
        ConfigError,
        config_from_params,
        config_to_params,
    )

    flat = {
        'lines': ['a', 'b', 'c', 'd'],
        **{
            f'{n}.{k}': v
            for n in 'abcd'
            for k, v in (('weight', 1300.0), ('anchor_distance', 120.0), ('mbl', 4.8e6))
        },
    }
    config = config_from_params(flat)
    assert math.isnan(config.line('a').heading)
    assert config.headings() == [45.0, 135.0, 225.0, 315.0]
    config = config_from_params({**flat, 'b.heading': -90, 'c.heading': 360.0})
    assert config.headings() == [45.0, 270.0, 0.0, 315.0]
    assert config_from_params(config_to_params(config)) == config
    try:
        config_from_params({**flat, 'a.heading': 400.0})
    except ConfigError as err:
        assert str(err).startswith("parameter 'a.heading': 400.0 out of range")
    else:
        raise AssertionError('heading 400 must be refused')
    try:
        config_from_params({**flat, 'a.heading': float('inf')})
    except ConfigError as err:
        assert 'finite' in str(err)
    else:
        raise AssertionError('an infinite heading must be refused')


def test_a_line_named_like_a_monitor_status_is_refused_when_built_directly():
    """LineConfig checks the name as the params-file reader does: a line called ``tide``
    would share its /diagnostics name with the tide's status."""
    from catenary_monitor.core.config.parameters import RESERVED_NAMES, LineConfig

    for name in RESERVED_NAMES:
        with pytest.raises(ConfigError, match='own statuses'):
            LineConfig(name=name, weight=1300.0, anchor_distance=120.0, mbl=4.8e6)

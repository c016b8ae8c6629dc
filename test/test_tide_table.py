"""The tide table (core.rules.tide_table): time_to_uplift on the table's own forecast.

A tide that follows its table exactly, the horizontal tension held: at every depth sample the
published ``time_to_uplift`` is the first crossing of the critical depth (the catenary closed
form, mpmath) on the harmonic curve, found independently here by scipy's brentq in a fine scan;
``inf`` where the curve does not reach it within the horizon; the tide says it used the table,
the WARN message too, and the core and its batch twin agree event by event.
"""

import math

import numpy as np
import pytest
from replay_data import T0_NS
from scipy.optimize import brentq
from test_batch import compare
from test_tide_trend import H, W, X, exact_crossing_depth

from catenary_monitor.core.config.parameters import (
    AlarmConfig,
    ConfigError,
    LineConfig,
    MonitorConfig,
)
from catenary_monitor.core.config.tide_constituents import parse_table
from catenary_monitor.core.rules import tide_table
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS

TABLE = 'M2 0.9 40.0 28.9841042; S2 0.3 100.0 30.0; K1 0.25 10.0 15.0410686'
EPOCH = T0_NS * 1e-9 - 29400.0  # the record starts near low water
HORIZON = 3 * 3600.0


def curve(t):
    """The table's tide about its mean [m] at ``t`` [s] (written out, not the module's)."""
    hours = (t - EPOCH) / 3600.0
    return sum(
        a * math.cos(math.radians(s * hours - p))
        for a, p, s in ((0.9, 40.0, 28.9841042), (0.3, 100.0, 30.0), (0.25, 10.0, 15.0410686))
    )


def first_crossing(now, level):
    """The first t in (now, now + HORIZON] with curve(t) = level (brentq in a 60 s scan)."""
    grid = now + np.arange(0.0, HORIZON + 60.0, 60.0)
    values = np.array([curve(t) for t in grid]) - level
    if values[0] >= 0:
        return 0.0
    above = np.flatnonzero(values >= 0)
    if not len(above) or grid[above[0]] > now + HORIZON:
        return math.inf
    j = above[0]
    return brentq(lambda t: curve(t) - level, grid[j - 1], grid[j], xtol=1e-9) - now


def scene(seconds=6 * 3600.0, step=60.0):
    """Depth at ``step`` s following the table about a mean 0.6 m below the critical depth;
    the tension of the held horizontal load 0.3 s later."""
    crit = exact_crossing_depth()
    mean = crit - 0.6
    t = np.arange(0.0, seconds, step)
    stamps = T0_NS * 1e-9 + t
    h = mean + np.array([curve(s) for s in stamps])
    tension = H + W * h  # touchdown catenary: T = H + w h (the depth changes slowly)
    t_ns = T0_NS + np.rint(t * 1e9).astype(np.int64)
    return crit, mean, stamps, (t_ns, h), (t_ns + 300_000_000, tension)


def config(**alarm):
    # exact sensors: the forecast's warning is the first (no bound within accuracy before it)
    line = LineConfig(name='line_11', weight=W, anchor_distance=X, mbl=4.8e6, tension_accuracy=1.0)
    alarm = {
        'tide_table': TABLE,
        'tide_table_epoch': EPOCH,
        'tide_forecast_horizon': HORIZON,
        'tension_resolution': 0.0,
        'depth_resolution': 0.0,  # a noise-free gauge at one sample a minute
        'depth_timeout': 120.0,
        'tension_timeout': 120.0,
        'anchor_margin_warn': 0.0,
        'tide_margin_warn': 0.0,
        'depth_accuracy': 0.0,
        **alarm,
    }
    return MonitorConfig(lines=(line,), alarm=AlarmConfig(**alarm))


def test_the_forecast_is_the_first_crossing_on_the_tables_own_curve():
    crit, mean, stamps, depth, tension = scene()
    ticks = depth[0][::3] + 600_000_000
    steps = compare(config(), {'line_11': tension}, depth, ticks, [T0_NS + int(7e12)])
    at, m_at = OUTPUT_FIELDS.index('time_to_uplift'), OUTPUT_FIELDS.index('tide_margin')
    rows = [
        ((s.stamp_ns - 300_000_000) * 1e-9, o.values[at], o.values[m_at])
        for s in steps
        if s.kind == 'tension'
        for o in s.outputs
    ]
    checked = {'finite': 0, 'inf': 0}
    for now, got, margin in rows:
        if not margin > 0:
            assert got == 0.0
            continue
        want = first_crossing(now, crit - mean)
        if math.isinf(want):
            assert math.isinf(got), now
            checked['inf'] += 1
        else:
            assert got == pytest.approx(want, abs=0.5), now  # the solver's margin: ~1e-4 m
            checked['finite'] += 1
    assert checked['finite'] > 30 and checked['inf'] > 5, checked
    words = [
        dict(st.values)['tide_forecast']
        for s in steps
        if s.snapshot is not None
        for st in s.snapshot.statuses
        if st.name.endswith(': tide')
    ]
    assert set(words) == {'table'}
    warn = [
        c.transition
        for s in steps
        for c in s.transitions
        if c.component == 'line_11' and c.transition.new.name == 'WARN'
    ]
    assert warn and "on the tide table's forecast" in warn[0].message


def test_the_module_against_the_curve_at_a_few_points():
    table = parse_table(TABLE)
    now = np.array([EPOCH + 1234.0, EPOCH + 20000.0, EPOCH + 40000.0])
    p0 = np.array([curve(t) for t in now])
    margin = np.array([0.5, 0.2, 5.0])
    got = tide_table.uplift_times(table, EPOCH, HORIZON, now, margin, np.zeros(3))
    for k in range(3):
        want = first_crossing(now[k], p0[k] + margin[k])
        assert (math.isinf(want) and math.isinf(got[k])) or got[k] == pytest.approx(want, abs=1e-4)
    assert math.isinf(got[2])  # a 5 m rise: never
    np.testing.assert_array_equal(
        tide_table.uplift_times(table, EPOCH, HORIZON, now[:1], [-1.0], [0.0]), [0.0]
    )
    assert math.isnan(tide_table.uplift_times(table, EPOCH, HORIZON, now[:1], [math.nan], [0])[0])


def test_without_a_table_the_trend_is_used_and_said():
    crit, mean, stamps, depth, tension = scene(seconds=3600.0)
    steps = compare(config(tide_table=''), {'line_11': tension}, depth, depth[0] + 600_000_000)
    words = {
        dict(st.values)['tide_forecast']
        for s in steps
        if s.snapshot is not None
        for st in s.snapshot.statuses
        if st.name.endswith(': tide')
    }
    assert words == {'unknown', 'trend'}


@pytest.mark.parametrize(
    'text', ['M2 1.0 40', 'M2 one 40 28.98', 'M2 1.0 40 -3', 'M2 1.0 nan 28.98']
)
def test_a_bad_table_is_one_config_error(text):
    with pytest.raises(ConfigError, match='tide_table'):
        config(tide_table=text)


def test_node_md_tide_parameter_table_is_generated():
    from pathlib import Path

    from catenary_monitor.core.config.parameters import parameters_markdown

    page = (Path(__file__).resolve().parents[1] / 'docs' / 'node.md').read_text()
    begin, end = '<!-- tide-parameters:begin -->\n', '<!-- tide-parameters:end -->'
    assert page.split(begin, 1)[1].split(end, 1)[0] == parameters_markdown('tide')


def test_a_table_past_its_bounds_is_refused_before_it_is_parsed():
    """200 constituents (a full harmonic analysis has about 150) and 65 536 characters: a
    100 000-constituent or 10 MB table is one ConfigError in microseconds, not minutes."""
    import time

    from catenary_monitor.core.config.tide_constituents import MAX_CONSTITUENTS, parse_table

    one = 'M2 0.01 10.0 28.98; '
    assert len(parse_table(one * MAX_CONSTITUENTS)) == MAX_CONSTITUENTS
    for text, needle in [
        (one * (MAX_CONSTITUENTS + 1), '201 constituents, more than the 200'),
        (one * 100_000, 'characters, more than the 65536'),
        ('M2 0.01 10.0 28.98' + ' ' * 10_000_000, 'characters, more than the 65536'),
    ]:
        start = time.process_time()
        with pytest.raises(ConfigError, match='tide_table') as info:
            config(tide_table=text)
        assert needle in str(info.value)
        assert time.process_time() - start < 0.5

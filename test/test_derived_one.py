"""A tension event's derived values in plain floats (core/monitor/derived.py: derived_one)
against the array path the core takes for several lines at once and the twin for columns: the
same event sequences stepped through two cores, one forced onto the arrays, every output equal
to rounding (1e-12 relative, 1e-9 absolute), every transition the same."""

import dataclasses

import numpy as np
import pytest
from replay_data import T0_NS, dock_config, events_of, generate

from catenary_monitor.core.config.parameters import LineConfig, MonitorConfig
from catenary_monitor.core.monitor import derived
from catenary_monitor.core.monitor.monitor_core import MonitorCore


def _config(table: bool) -> MonitorConfig:
    """Four lines: an elastic one with a chain length (the sampled box), a sinker with its
    holding data, a drag anchor, a line with a clump and a buoy; the tide table or the trend."""
    base = dock_config(3, depth_accuracy=0.3, drag_margin_warn=150e3)
    extra = [
        dict(tension_accuracy=40e3, ea=6.0e8, chain_length=300.0),
        dict(
            tension_accuracy=20e3,
            chain_length=250.0,
            anchor_holding=500e3,
            anchor_weight=400e3,
            chain_friction=0.7,
        ),
        dict(chain_length=140.0, anchor_holding=300e3),
    ]
    lines = [dataclasses.replace(lc, **e) for lc, e in zip(base.lines, extra)]
    lines.append(
        LineConfig(
            name='line_04',
            weight=1300.0,
            anchor_distance=121.06,
            mbl=4.827e6,
            point_load_positions=(40.0, 90.0),
            point_load_weights=(60e3, -25e3),
        )
    )
    alarm = base.alarm
    if table:
        alarm = dataclasses.replace(
            alarm,
            tide_table='M2 0.9 40.0 28.9841042; S2 0.3 100.0 30.0',
            tide_table_epoch=T0_NS * 1e-9 - 29400.0,
            tide_forecast_horizon=3 * 3600.0,
        )
    return dataclasses.replace(base, lines=tuple(lines), alarm=alarm)


def _arrays(line, alarm, depth_s, trend):
    """derived_one's values by the array path (add_derived of the line and a copy of it)."""
    twin = dataclasses.replace(line)
    derived.add_derived([line, twin], alarm, depth_s, trend)
    return line.values


@pytest.mark.parametrize('table', [False, True])
def test_a_tension_events_plain_floats_give_the_array_paths_numbers(table, monkeypatch):
    config = _config(table)
    tensions, depth = generate(config, seconds=20.0, seed=5, storm_line=1)
    stamps, values = generate(config, seconds=20.0, seed=6, storm_line=2)[0]['line_01']
    tensions['line_04'] = stamps[::10], values[::10]  # (a point-load solve takes milliseconds)
    events = events_of(config, tensions, depth, np.zeros(0, np.int64))
    plain = MonitorCore(config, 0)
    want = [plain.step(ev) for ev in events]
    monkeypatch.setattr(derived, 'derived_one', _arrays)
    arrays = MonitorCore(config, 0)
    got = [arrays.step(ev) for ev in events]
    lifted = 0
    for g, w in zip(got, want):
        assert [c.transition for c in g.transitions] == [c.transition for c in w.transitions]
        for go, wo in zip(g.outputs, w.outputs):
            np.testing.assert_allclose(go.values, wo.values, rtol=1e-12, atol=1e-9)
            lifted += wo.values[5] > 0
    assert lifted > 20  # the storms lift anchors: the lifted bounds are in the comparison

"""A line measured by several channels (core/rules/channels.py): a three-channel load cell whose
channels fail one at a time, through the monitor core and its replay twin."""

import math

import numpy as np
import pytest

from catenary_monitor.core.config.parameters import (
    AlarmConfig,
    ConfigError,
    LineConfig,
    MonitorConfig,
)
from catenary_monitor.core.rules import channels
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.monitor.events import Depth, Tension, Tick
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.twin.window import Window
from catenary_monitor.core.twin.engine import run_log

TOPICS = ('/cell/a', '/cell/b', '/cell/c')
GAIN = (1.04, 0.97, 0.99)  # an eccentric link: each gauge carries its own share
NOISE = 400.0  # N, each channel's noise (1 sigma)


def _config(min_channels=1):
    line = LineConfig(
        name='cell',
        weight=1300.0,
        anchor_distance=130.0,
        mbl=4.827e6,
        tension_topics=TOPICS,
        min_channels=float(min_channels),
    )
    alarm = AlarmConfig(
        stuck_time=10.0, tension_timeout=5.0, warn_clear_hold=0.0, margin_clear_hold=0.0,
        depth_timeout=86400.0,
    )
    return MonitorConfig(lines=(line,), alarm=alarm)


def truth(t):
    return 4.0e5 + 5.0e4 * np.sin(0.01 * t)


def _samples(seconds, fail):
    """Each channel at 2 Hz (staggered); ``fail``: channel -> (time, how): silent, stuck,
    drift (out of line). Returns (time s, channel, value) in time order."""
    rng = np.random.default_rng(4)
    rows = []
    for j in range(3):
        t = np.arange(0.0, seconds, 0.5) + 0.1 * j
        v = GAIN[j] * truth(t) + rng.normal(0.0, NOISE, t.size)
        when, how = fail.get(j, (math.inf, ''))
        after = t >= when
        if how == 'stuck':
            v[after] = v[np.argmax(after) - 1]
        elif how == 'drift':
            v[after] *= 1.2
        keep = ~after if how == 'silent' else np.ones(t.size, bool)
        rows += [(float(a), j, float(b)) for a, b in zip(t[keep], v[keep])]
    return sorted(rows)


def _run(config, rows, end):
    """The core, event by event (a tick a second), and the twin over the same log."""
    core = MonitorCore(config, 0)
    core.step(Depth(1, 20.85))
    outs, changes = [], []
    ticks = iter(np.arange(1.0, end, 1.0) * 1e9 + 3)
    tick = next(ticks)
    for t, j, v in rows:
        stamp = int(t * 1e9) + 10
        while tick < stamp:
            changes += core.step(Tick(int(tick))).transitions
            tick = next(ticks, math.inf)
        step = core.step(Tension(stamp, 0, v, None, j))
        outs.append((t, dict(zip(OUTPUT_FIELDS, step.outputs[0].values))))
        changes += step.transitions
    times = np.array([int(t * 1e9) + 10 for t, _, _ in rows], np.int64)
    window = Window(
        [(times, np.array([v for _, _, v in rows]))],
        (np.array([1], np.int64), np.array([20.85])),
        (np.arange(1.0, end, 1.0) * 1e9 + 3).astype(np.int64),
        channels=[np.array([j for _, j, _ in rows], np.int64)],
    )
    result, twin_core = run_log(MonitorCore(config, 0), window)
    return core, outs, [c.transition for c in changes if c.component == 'cell'], result, twin_core


def test_channels_failing_one_at_a_time_keep_the_tension_until_min_channels():
    """b silent at 300 s, c stuck at 500 s: the tension from the rest stays within the last
    channel's accuracy (its learned share: not its 4 % bias), each failure named (WARN), the
    line blind (STALE) once a too goes silent at 700 s; replay decides alike."""
    rows = _samples(800.0, {1: (300.0, 'silent'), 2: (500.0, 'stuck'), 0: (700.0, 'silent')})
    core, outs, changes, result, twin_core = _run(_config(), rows, 800.0)
    settle = {300.0: 5.5, 500.0: 10.5, 700.0: 5.5}  # timeout, stuck_time (the rules' delays)
    for t, o in outs:
        if t < 30.0 or any(w <= t < w + d for w, d in settle.items()) or t >= 700.0:
            continue
        assert abs(o['top_tension'] - truth(t)) < 5 * NOISE, t  # a channel's accuracy (5 sigma)
    last = [o for t, o in outs if 600 < t < 700]
    assert {o['channels_healthy'] for o in last} == {1.0}
    assert channels.decode(last[-1]['channel_states'], 3) == [0, 1, 2]  # ok, silent, stuck
    # a's own reading is 4 % high: without its learned share the tension would be 16 kN off
    assert abs(1.04 * truth(650.0) - truth(650.0)) > 10 * NOISE
    warns = [c for c in changes if c.new == Level.WARN]
    assert [c.time for c in warns] == [pytest.approx(305.0, abs=0.5)]  # b: silent for 5 s
    assert 'load-cell channel /cell/b silent: tension from the other 2' in warns[0].message
    stale = [c for c in changes if c.new == Level.STALE]
    assert stale and stale[-1].time > 700.0
    assert '0 of 3 load-cell channels healthy (min_channels 1)' in stale[-1].message
    assert '/cell/a silent' in stale[-1].message and 'impossible' not in stale[-1].message
    # replay: the same values, levels and state
    r = result.lines[0]
    got = r.values['top_tension'][r.tension_rows]
    assert np.array_equal(got, [o['top_tension'] for _, o in outs], equal_nan=True)
    states = [o['channel_states'] for _, o in outs]
    assert np.array_equal(r.values['channel_states'][r.tension_rows], states)
    assert [(c.time, c.new, c.message) for c in r.transitions] == [
        (c.time, c.new, c.message) for c in changes
    ]
    assert twin_core.state.lines[0].channels == core.state.lines[0].channels


def test_a_channel_out_of_line_is_named_and_min_channels_blinds_the_line():
    """c reads 20 % high from 300 s: out of line against the median of three, the tension from
    a and b; b silent at 500 s with min_channels 2: blind (STALE), the message says why (two
    channels that disagree: which one is wrong cannot be told, both are out of line)."""
    rows = _samples(700.0, {2: (300.0, 'drift'), 1: (500.0, 'silent')})
    core, outs, changes, result, _ = _run(_config(min_channels=2), rows, 700.0)
    mid = [o for t, o in outs if 320 < t < 500]
    assert all(channels.decode(o['channel_states'], 3) == [0, 0, 3] for o in mid)
    assert all(abs(o['top_tension'] - truth(t)) < 5 * NOISE for t, o in outs if 320 < t < 500)
    assert any('/cell/c out_of_line' in c.message for c in changes if c.new == Level.WARN)
    blind = [c for c in changes if c.new == Level.STALE][-1]
    assert '0 of 3 load-cell channels healthy (min_channels 2)' in blind.message
    assert '/cell/b silent' in blind.message and '/cell/c out_of_line' in blind.message
    assert all(math.isnan(o['top_tension']) for t, o in outs if t > 506)
    r = result.lines[0]
    assert [(c.time, c.new) for c in r.transitions] == [(c.time, c.new) for c in changes]


@pytest.mark.parametrize(
    'extra,message',
    [
        (dict(tension_topics=('/a', '/b'), min_channels=3.0), '3 but the line has 2'),
        (dict(tension_topics=('/a', '/a')), 'given twice'),
        (dict(tension_topics=('/a', '/b'), min_channels=1.5), 'whole number'),
        (dict(tension_topics=('/a', 'not a topic')), 'not a valid ROS topic'),
    ],
)
def test_bad_channel_parameters_are_one_line_errors(extra, message):
    with pytest.raises(ConfigError, match=message):
        LineConfig(name='x', weight=1300.0, anchor_distance=120.0, mbl=4.8e6, **extra)


def test_replaying_a_log_of_the_channels_gives_the_core_steps(tmp_path):
    """The channels' topics in an MCAP log, replayed by the driver (their samples merged in
    time order, the channels fused as the core fuses them): the core's tensions and levels."""
    from replay_data import write_log

    from catenary_monitor.replay.driver import expand, replay_log

    rows = _samples(400.0, {1: (200.0, 'silent')})
    config = _config()
    core, outs, changes, _, _ = _run(config, rows, 400.0)
    per_topic = MonitorConfig(
        lines=tuple(
            LineConfig(
                name=f'ch{j}', weight=1300.0, anchor_distance=130.0, mbl=4.827e6,
                tension_topic=topic,
            )
            for j, topic in enumerate(TOPICS)
        )
    )  # fmt: skip
    columns = {
        f'ch{j}': (
            np.array([int(t * 1e9) + 10 for t, c, _ in rows if c == j], np.int64),
            np.array([v for _, c, v in rows if c == j]),
        )
        for j in range(3)
    }
    depth = (np.array([1], np.int64), np.array([20.85]))
    log = write_log(tmp_path / 'cell.mcap', per_topic, columns, depth)
    got = replay_log(expand([str(log)]), config, ticks='grid', window_messages=700).result
    r = got.lines[0]
    want = [o['top_tension'] for _, o in outs]
    assert np.array_equal(r.values['top_tension'][r.tension_rows], want, equal_nan=True)
    assert [c.new for c in r.transitions][-1] == Level.WARN  # b silent: named, from the rest


def test_channels_doc_parameter_table_is_generated():
    from pathlib import Path

    from catenary_monitor.core.config.parameters import parameters_markdown

    page = (Path(__file__).resolve().parent.parent / 'docs' / 'channels.md').read_text()
    begin, end = '<!-- channels-parameters:begin -->\n', '<!-- channels-parameters:end -->'
    assert page.split(begin, 1)[1].split(end, 1)[0] == parameters_markdown('channels')


def _channel_log(tmp_path, rows):
    """An MCAP log of the three channels' topics (Float64) and a depth: (path, columns)."""
    from replay_data import write_log

    per_topic = MonitorConfig(
        lines=tuple(
            LineConfig(
                name=f'ch{j}', weight=1300.0, anchor_distance=130.0, mbl=4.827e6,
                tension_topic=topic,
            )
            for j, topic in enumerate(TOPICS)
        )
    )  # fmt: skip
    columns = {
        f'ch{j}': (
            np.array([int(t * 1e9) + 10 for t, c, _ in rows if c == j], np.int64),
            np.array([v for _, c, v in rows if c == j]),
        )
        for j in range(3)
    }
    depth = (np.array([1]), np.array([20.85]))
    return write_log(tmp_path / 'cell.mcap', per_topic, columns, depth), columns


def test_whatif_log_takes_a_load_cells_tension_from_every_channel(tmp_path):
    """whatif --log: a three-channel line's newest tension is the monitor's, fused from every
    channel (b silent: a's and c's readings with their learned shares), not channel a's raw
    reading; below min_channels it is unknown and whatif says so in one line."""
    import argparse

    from replay_data import params_yaml

    from catenary_monitor.cli.whatif import WhatIfError, _from_log, cmd_whatif

    rows = _samples(400.0, {1: (200.0, 'silent')})
    log, columns = _channel_log(tmp_path, rows)
    core, outs, _, _, _ = _run(_config(), rows, 400.0)
    last, _ = _from_log([str(log)], _config())
    assert last['cell'] == outs[-1][1]['top_tension']
    assert abs(last['cell'] - truth(rows[-1][0])) < 5 * NOISE
    assert abs(columns['ch0'][1][-1] - truth(rows[-1][0])) > 10 * NOISE  # a's raw reading
    blind, _ = _from_log([str(log)], _config(min_channels=3))
    assert math.isnan(blind['cell'])
    params = params_yaml(_config(min_channels=3), tmp_path / 'p.yaml')
    args = argparse.Namespace(
        params_file=str(params), depth='20.85', tension=[], anchor_distance=[],
        tide_rate=None, log=[str(log)], json=False,
    )  # fmt: skip
    with pytest.raises(WhatIfError, match='line cell: its newest tension in --log is unknown'):
        cmd_whatif(args)


def test_replay_publish_plays_every_channel_of_a_load_cell(tmp_path):
    """replay --publish with the params file: each channel's topic with all its samples (the
    monitor listening to the playback then fuses them as live)."""
    from catenary_monitor.cli.replay import _publish_messages

    rows = _samples(60.0, {1: (30.0, 'silent')})
    log, columns = _channel_log(tmp_path, rows)
    messages, _ = _publish_messages([log], _config())
    for j, topic in enumerate(TOPICS):
        assert np.array_equal(messages[topic][0], columns[f'ch{j}'][0]), topic

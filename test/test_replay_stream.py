"""Replay streams: the command's results window by window equal those of the whole log at once.

The reference is the whole log as one window (:func:`catenary_monitor.replay.driver.replay_log`,
then
``write_csv`` / ``write_mcap`` / ``summary_dict`` on the one result). The streamed replay runs
with tiny reader batches and windows (a few dozen messages), so window edges fall between
ticks and the inputs at the same stamp, between a recorded event and the inputs around it,
inside alarm episodes and across the files of a rotated set.
"""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from replay_data import dock_config, generate, params_yaml

from catenary_monitor.cli.main import main
from catenary_monitor.core.monitor.events import (
    EVENTS_TOPIC,
    Acknowledge,
    LoggerHealth,
    Start,
    Tick,
    event_record,
)
from catenary_monitor.io import mcap_read, mcap_scan
from catenary_monitor.io.cdr import string_message
from catenary_monitor.io.mcap_read import iter_messages
from catenary_monitor.io.mcap_scan import ReadReport
from catenary_monitor.replay import outputs as out
from catenary_monitor.replay.driver import input_topics, replay_log

T0 = 1_763_900_000_000_000_000


def _events(tensions, depth):
    """A node's events channel: a start, ticks at 1 Hz (some at an input's very stamp), a
    logger failure and its end, an acknowledgement, a restart of the monitor."""
    first = min(int(t[0]) for t, _ in tensions.values())
    last = max(int(t[-1]) for t, _ in tensions.values())
    ticks = np.arange(first + 100_001, last, 1_000_000_000, dtype=np.int64)
    line0 = next(iter(tensions.values()))[0]
    ticks[5::7] = line0[np.searchsorted(line0, ticks[5::7])]  # a tick at a tension's stamp
    ticks[3::11] = depth[0][np.searchsorted(depth[0], ticks[3::11]).clip(0, len(depth[0]) - 1)]
    out_ = [Start(first - 500_000_000)] + [Tick(int(t)) for t in np.unique(ticks)]
    mid = (first + last) // 2
    out_ += [
        LoggerHealth(first + 20_000_000_123, 'disk full', '/tmp/x.mcap'),
        LoggerHealth(first + 27_000_000_123, None, '/tmp/y.mcap'),
        Acknowledge(mid + 3_000_000_017, None, 'console'),
        Start(mid + 20_000_000_011),
    ]
    return sorted(out_, key=lambda e: e.stamp_ns)


def _write(path, config, tensions, depth, events, cut=None):
    """The inputs and events in time order through the node's logger (small chunks); ``cut``
    keeps only the stamps in [cut[0], cut[1])."""
    import struct

    from catenary_monitor.io.mcap_log import McapLogger

    rows = [(int(t), 0, config.depth_topic, v) for t, v in zip(*depth)]
    for line in config.lines:
        rows += [(int(t), 1, line.tension_topic, v) for t, v in zip(*tensions[line.name])]
    rows += [(e.stamp_ns, 2, EVENTS_TOPIC, e) for e in events]
    rows.sort(key=lambda r: (r[0], r[1]))
    log = McapLogger(path.parent, prefix=path.stem, chunk_size=2048, fsync=False)
    for line in config.lines:
        log.register(line.tension_topic, 'std_msgs/msg/Float64', 'sensor_data')
    log.register(config.depth_topic, 'std_msgs/msg/Float64', 'sensor_data')
    log.register(EVENTS_TOPIC, 'std_msgs/msg/String')
    for stamp, kind, topic, value in rows:
        if cut is not None and not cut[0] <= stamp < cut[1]:
            continue
        if kind == 2:
            data = string_message(json.dumps(event_record(value)))
        else:
            data = b'\x00\x01\x00\x00' + struct.pack('<d', value)
        log.write(topic, data, stamp)
    log.close()
    log.files[0].rename(path)
    return path


@pytest.fixture(scope='module')
def node_log(tmp_path_factory):
    tmp = tmp_path_factory.mktemp('stream')
    config = dock_config(3)
    tensions, depth = generate(config, seconds=80.0, seed=11)
    events = _events(tensions, depth)
    log = _write(tmp / 'node.mcap', config, tensions, depth, events)
    first = min(int(t[0]) for t, _ in tensions.values()) - 10**9
    last = max(int(t[-1]) for t, _ in tensions.values()) + 10**9
    cuts = [first, first + 31_000_000_000, first + 57_000_000_000, last]
    rotated = tmp / 'rotated'
    rotated.mkdir()
    for k in range(3):
        _write(rotated / f'part_{k}.mcap', config, tensions, depth, events, (cuts[k], cuts[k + 1]))
    params = params_yaml(config, tmp / 'params.yaml')
    return dict(tmp=tmp, config=config, log=log, rotated=rotated, params=params)


def _messages(path):
    """Every message of an MCAP file per topic: [(log time, bytes)] in file order."""
    by_topic = {}
    for m in iter_messages([path]):
        by_topic.setdefault(m.topic, []).append((m.log_time_ns, m.data))
    return by_topic


def _reference(paths, config, tmp, ticks='auto'):
    """The whole-log replay: CSV bytes, MCAP messages and the summary's lines."""
    result, tensions, depth, report = replay_log(
        paths, config, ticks=ticks, snapshots=True, window_messages=None
    )
    with open(tmp / 'ref.csv', 'wb') as f:
        out.write_csv(f, result, None, [n for n, _ in out.CSV_ALL])
    topics, depth_topic = input_topics(config)
    with open(tmp / 'ref.mcap', 'wb') as f:
        out.write_mcap(
            f, result, config, tensions, depth, topics, depth_topic, [str(p) for p in paths]
        )
    summary = out.summary_dict(result, report)
    return (tmp / 'ref.csv').read_bytes(), _messages(tmp / 'ref.mcap'), summary


def _streamed(paths, params, tmp, capsys, *extra):
    code = main(
        [
            'replay',
            *map(str, paths),
            '--params-file',
            str(params),
            '--csv',
            str(tmp / 's.csv'),
            '--csv-columns',
            'all',
            '--out',
            str(tmp / 's.mcap'),
            '--json',
            *extra,
        ]
    )
    captured = capsys.readouterr()
    assert code == 0, captured.err
    summary = json.loads(captured.out)
    return (tmp / 's.csv').read_bytes(), _messages(tmp / 's.mcap'), summary, captured.err


def _same(ref, got):
    csv_ref, mcap_ref, sum_ref = ref
    csv_got, mcap_got, sum_got, _ = got
    assert csv_got == csv_ref
    assert mcap_got.keys() == mcap_ref.keys()
    for topic in mcap_ref:
        assert mcap_got[topic] == mcap_ref[topic], topic
    ref_json = json.loads(json.dumps(sum_ref, default=float))
    for key in ('files', 'messages', 'skipped', 'ticks', 'start', 'end', 'lines', 'complete'):
        assert sum_got[key] == ref_json[key], key


@pytest.fixture
def tiny_batches(monkeypatch):
    """Reader batches of one small chunk: windows can end anywhere."""
    monkeypatch.setattr(mcap_scan, '_BATCH_BYTES', 1)


@pytest.mark.parametrize('window', ['1', '23', '400', '5000'])
def test_windows_give_the_whole_log_result(
    node_log, tmp_path, capsys, tiny_batches, window, monkeypatch
):
    if window == '5000':  # one window, recomputed in parts of 3 ticks (the snapshots' bound)
        from catenary_monitor.replay import driver

        monkeypatch.setattr(driver, 'TICKS_PER_PART', 3)
    ref = _reference([node_log['log']], node_log['config'], tmp_path)
    got = _streamed(
        [node_log['log']], node_log['params'], tmp_path, capsys, '--window-messages', window
    )
    assert got[2]['streaming']['windows'] > {'1': 10, '23': 10, '400': 2, '5000': 0}[window]
    assert got[2]['streaming']['streamed']
    # the log has what the windows must carry across: episodes, a restart, logger events
    assert any(ln['episodes'] for ln in ref[2]['lines'].values())
    assert ref[2]['ticks']['source'] == 'recorded by the node'
    _same(ref, got)


def test_grid_ticks_across_windows(node_log, tmp_path, capsys, tiny_batches):
    ref = _reference([node_log['log']], node_log['config'], tmp_path, ticks='grid')
    got = _streamed(
        [node_log['log']],
        node_log['params'],
        tmp_path,
        capsys,
        '--window-messages',
        '17',
        '--ticks',
        'grid',
    )
    assert got[2]['ticks']['source'] == 'synthetic grid' and got[2]['streaming']['windows'] > 10
    _same(ref, got)


@pytest.mark.parametrize('jobs', ['1', '2'])
def test_rotated_set_in_any_order_and_jobs(node_log, tmp_path, capsys, tiny_batches, jobs):
    files = sorted(node_log['rotated'].glob('*.mcap'))
    ref = _reference(files, node_log['config'], tmp_path)
    given = [files[2], files[0], files[1]]
    got = _streamed(
        given, node_log['params'], tmp_path, capsys, '--window-messages', '31', '--jobs', jobs
    )
    # (the worker processes read with the default batches: a window per file at least)
    assert got[2]['streaming']['windows'] >= 3 and got[2]['streaming']['jobs'] == int(jobs)
    assert got[2]['files'] == [str(p) for p in given]
    ref[2]['files'] = [str(p) for p in given]
    _same(ref, got)


def test_overlapping_files_fall_back_to_one_window(node_log, tmp_path, capsys, tiny_batches):
    """Two files that overlap in time cannot be cut into windows: the command says so on one
    line and replays the log as one window, with the same results."""
    config = node_log['config']
    tensions, depth = generate(config, seconds=40.0, seed=5)
    a = {k: (t[::2], v[::2]) for k, (t, v) in tensions.items()}
    b = {k: (t[1::2], v[1::2]) for k, (t, v) in tensions.items()}
    folder = tmp_path / 'overlap'
    folder.mkdir()
    _write(folder / 'a.mcap', config, a, depth, [])
    _write(folder / 'b.mcap', config, b, (depth[0][:0], depth[1][:0]), [])
    ref = _reference([folder], config, tmp_path)
    got = _streamed([folder], node_log['params'], tmp_path, capsys, '--window-messages', '5')
    assert 'cannot stream this log' in got[3] and not got[2]['streaming']['streamed']
    _same(ref, got)


def test_plot_envelopes_are_bounded_and_keep_peaks():
    env = out.Envelope(bins=100)
    rng = np.random.default_rng(3)
    t = np.sort(rng.integers(0, 10**13, 20_000)).astype(np.int64)
    v = rng.normal(size=len(t))
    v[7777] = 50.0
    for lo in range(0, len(t), 999):
        env.add(t[lo : lo + 999], v[lo : lo + 999])
    x, y = env.points()
    assert len(x) <= 200 and np.nanmax(y) == 50.0 and np.nanmin(y) == v.min()
    assert np.all(np.diff(x) >= 0)


def test_window_state_is_the_stepped_state(node_log):
    """The stream's read report equals the whole-log reader's (files, counts, no skips)."""
    report = ReadReport()
    topics, depth_topic = input_topics(node_log['config'])
    windows = list(
        mcap_read.iter_windows(
            [node_log['log']], [depth_topic, *topics.values()], [EVENTS_TOPIC], 50, report
        )
    )
    cols, ref = mcap_read.read_float64_topics([node_log['log']], [depth_topic, *topics.values()])
    for topic, (t, v) in cols.items():
        got_t = np.concatenate([w.columns[topic][0] for w in windows])
        got_v = np.concatenate([w.columns[topic][1] for w in windows])
        assert np.array_equal(got_t, t) and np.array_equal(got_v, v, equal_nan=True)
    assert [dataclasses.asdict(f) for f in report.files] == [
        dataclasses.asdict(f) for f in ref.files
    ]
    assert report.messages == ref.messages and report.skips == ref.skips
    assert Path(report.files[0].path) == node_log['log']

"""``catenary-monitor replay``: the command's contract, its outputs and damaged input.

Logs are generated here (seeded), never downloaded. The command runs in-process through
``catenary_monitor.cli.main.main`` except where its exit status or stderr must be seen from
outside.
"""

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from replay_data import core_steps, dock_config, generate, params_yaml, write_log

from catenary_monitor.cli.main import main
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.rules.holding import FIELDS as HOLDING
from catenary_monitor.core.rules.holding import LENGTH_FIELDS
from catenary_monitor.core.twin.window import LineResult
from catenary_monitor.core.twin.engine import recompute
from catenary_monitor.core.rules.uncertainty import FIELDS as BOUNDS

ROOT = Path(__file__).resolve().parents[1]
CONTRACT = [
    'time',
    'line',
    'top_tension',
    'depth',
    'min_anchor_distance',
    'anchor_margin',
    'uplift_force',
    'level',
]


@pytest.fixture(scope='module')
def scene(tmp_path_factory):
    """A 3-line, 90 s log with a storm, dropouts, NaN/negative samples; its params file."""
    tmp = tmp_path_factory.mktemp('replay')
    config = dock_config(3)
    tensions, depth = generate(config, seconds=90.0, seed=4)
    log = write_log(tmp / 'dock.mcap', config, tensions, depth)
    params = params_yaml(config, tmp / 'params.yaml')
    return dict(tmp=tmp, config=config, tensions=tensions, depth=depth, log=log, params=params)


def run_cli(*args, capsys=None):
    code = main(['replay', *map(str, args)])
    out = capsys.readouterr() if capsys is not None else None
    return code, out


def test_csv_json_mcap_png(scene, capsys):
    tmp = scene['tmp']
    code, out = run_cli(
        scene['log'],
        '--params-file',
        scene['params'],
        '--csv',
        tmp / 'out.csv',
        '--out',
        tmp / 'out.mcap',
        '--plot',
        tmp / 'chart.png',
        '--json',
        capsys=capsys,
    )
    assert code == 0, out.err
    summary = json.loads(out.out)
    ref = recompute(scene['config'], scene['tensions'], scene['depth'])
    # Summary: per line the worst margins and each alarm episode.
    assert set(summary['lines']) == {'line_01', 'line_02', 'line_03'}
    assert summary['complete'] and summary['ticks']['source'] == 'synthetic grid'
    for r in ref.lines:
        s = summary['lines'][r.name]
        assert s['transitions'] == len(r.transitions)
        assert s['worst']['anchor_margin']['value'] == pytest.approx(
            float(np.nanmin(r.values['anchor_margin']))
        )
        assert [e['start'] for e in s['episodes']] == [e['start'] for e in r.episodes(ref.end_ns)]
        # the level after the last step, OK included (Level.OK is 0: falsy)
        assert s['final_level'] == Level(int(r.step_level[-1])).name
    assert {s['final_level'] for s in summary['lines'].values()} & {'OK', 'WARN'}
    storm = summary['lines']['line_02']
    assert storm['worst']['uplift_force']['value'] > 50e3
    assert any(e['worst'] == 'ERROR' for e in storm['episodes'])
    # The other components as the lines: the tide (with its dropouts), the sensors alarm and
    # the alarm system's flood status.
    assert list(summary['components']) == ['tide', 'sensors', 'alarms']
    tide = summary['components']['tide']
    assert tide['transitions'] == len(ref.tide) and tide['final_level'] == ref.tide[-1].new.name
    episodes = LineResult('tide', *[np.zeros(0)] * 8, ref.tide).episodes(ref.end_ns)
    assert tide['episodes'] == episodes and episodes[0]['worst'] == 'STALE'  # a depth dropout
    for name in ('sensors', 'alarms'):
        changes = [c.transition for c in ref.others if c.component == name]
        assert summary['components'][name]['transitions'] == len(changes)
    # CSV: the contract columns, one row per tension message, in time order.
    with open(tmp / 'out.csv', newline='') as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == CONTRACT
    n_tension = sum(len(t) for t, _ in scene['tensions'].values())
    assert len(rows) == n_tension
    times = [float(r['time']) for r in rows]
    assert times == sorted(times)
    assert {r['level'] for r in rows} <= {'OK', 'WARN', 'ERROR', 'STALE'}
    # Values parse back: time exact to the ns, forces and lengths to 3 decimals.
    by_line = {r.name: r for r in ref.lines}
    seen = {name: 0 for name in by_line}
    for row in rows:
        r = by_line[row['line']]
        i = r.tension_rows[seen[row['line']]]
        seen[row['line']] += 1
        assert int(row['time'].replace('.', '')) == int(r.t_ns[i])
        assert row['level'] == Level(int(r.level[i])).name
        for key in CONTRACT[2:-1]:
            want, got = r.values[key][i], float(row[key])
            assert (math.isnan(want) and math.isnan(got)) or abs(got - want) <= 5.0001e-4, key
    # PNG: an overview and one chart per line.
    for name in ('chart.png', 'chart_line_01.png', 'chart_line_02.png', 'chart_line_03.png'):
        assert (tmp / name).read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


def test_results_mcap_is_a_node_shaped_log(scene, capsys):
    """The results log opens with the mcap reader (CRCs checked) and rclpy; replaying it uses
    its /diagnostics as ticks and gives the same alarm levels."""
    from diagnostic_msgs.msg import DiagnosticArray
    from mcap.reader import make_reader
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64MultiArray

    tmp = scene['tmp']
    out = tmp / 'results.mcap'
    code, _ = run_cli(
        scene['log'], '--params-file', scene['params'], '--out', out, '--quiet', capsys=capsys
    )
    assert code == 0
    ref = recompute(scene['config'], scene['tensions'], scene['depth'])
    with open(out, 'rb') as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        topics = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
        assert reader.get_header().profile == 'ros2'
        assert topics['/catenary_monitor/line_02/outputs'] == 'std_msgs/msg/Float64MultiArray'
        assert topics['/diagnostics'] == 'diagnostic_msgs/msg/DiagnosticArray'
        assert topics['/mooring/line_01/tension'] == 'std_msgs/msg/Float64'
        outputs, diags = [], []
        for _, channel, message in reader.iter_messages(log_time_order=True):
            if channel.topic == '/catenary_monitor/line_02/outputs':
                outputs.append(
                    (message.log_time, deserialize_message(message.data, Float64MultiArray))
                )
            elif channel.topic == '/diagnostics':
                diags.append(
                    (message.log_time, deserialize_message(message.data, DiagnosticArray))
                )
    r = ref.lines[1]
    assert [t for t, _ in outputs] == r.t_ns.tolist()
    fields = outputs[0][1].layout.dim[0].label.split(',')
    assert fields[11:14] == ['status', 'level', 'time_to_uplift']  # appended, then the bounds
    k = 14 + len(BOUNDS + HOLDING)
    assert fields[14:k] == list(BOUNDS + HOLDING)  # and the holding values
    assert fields[k : k + 3] == ['sensor_state', *LENGTH_FIELDS, 'drag_state']  # appended
    waves = ['wave_tension', 'peak_tension', 'dynamic_uplift', 'time_to_uplift_view']
    w = fields.index('wave_tension')
    assert fields[w : w + 4] == waves  # appended, then the channels', then the span's
    assert fields[-4:] == ['channels_healthy', 'channel_states', 'span', 'span_source']
    got = np.array([m.data for _, m in outputs])
    np.testing.assert_array_equal(
        got[:, fields.index('time_to_uplift')], r.values['time_to_uplift']
    )
    np.testing.assert_array_equal(got[:, fields.index('sensor_state')], r.values['sensor_state'])
    np.testing.assert_array_equal(got[:, fields.index('level')], r.level)
    np.testing.assert_array_equal(got[:, fields.index('uplift_force')], r.values['uplift_force'])
    assert len(diags) >= len(ref.tick_ns)
    names = [s.name for s in diags[-1][1].status]
    assert names == [
        'catenary_monitor: line_01',
        'catenary_monitor: line_02',
        'catenary_monitor: line_03',
        'catenary_monitor: tide',
        'catenary_monitor: sensors',
        'catenary_monitor: alarms',
        'catenary_monitor: logger',
    ]
    keys = {kv.key for kv in diags[-1][1].status[1].values}
    assert {'top_tension', 'uplift_force', 'anchor_margin', 'safety_factor'} <= keys
    # Replaying the results log: its recorded ticks are taken, levels are unchanged.
    code, res = run_cli(out, '--params-file', scene['params'], '--json', capsys=capsys)
    again = json.loads(res.out)
    assert again['ticks']['source'] == 'recorded by the node'
    for r in ref.lines:
        assert again['lines'][r.name]['transitions'] == len(r.transitions)
        assert [e['start'] for e in again['lines'][r.name]['episodes']] == [
            e['start'] for e in r.episodes()
        ]


def test_csv_all_columns_and_stdout_summary(scene, capsys):
    tmp = scene['tmp']
    code, out = run_cli(
        scene['log'],
        '--params-file',
        scene['params'],
        '--csv',
        tmp / 'all.csv',
        '--csv-columns',
        'all',
        capsys=capsys,
    )
    assert code == 0
    with open(tmp / 'all.csv', newline='') as f:
        header = next(csv.reader(f))
        models = {row[header.index('model')] for row in csv.reader(f)}
    assert header[:2] == ['time', 'line']
    k = header.index('status')
    assert header[k : k + 4] == ['status', 'level', 'model', 'drag_state']
    assert header[k + 4 : k + 7] == ['fatigue_damage', 'fatigue_damage_rate', 'fatigue_life_left']
    assert header[k + 7 : k + 9] == ['channels_healthy', 'channel_states']
    assert {'tide_margin', 'load_margin', 'safety_factor', 'horizontal_tension'} <= set(header)
    assert 'time_to_uplift' in header
    assert 'inextensible catenary' in models and models <= {'none', 'inextensible catenary'}
    text = out.out
    assert 'line_02:' in text and 'worst anchor margin' in text and 'ERROR from' in text
    code, out = run_cli(
        scene['log'],
        '--params-file',
        scene['params'],
        '--csv',
        tmp / 'x.csv',
        '--csv-columns',
        'time,bogus',
        capsys=capsys,
    )
    assert code == 2 and "unknown column 'bogus'" in out.err


def test_identity_through_the_command(scene, capsys, tmp_path):
    """Written by the node's own logger, replayed by the command: the CSV levels equal the
    levels the monitor core gives after each tension message, stepped one event at a time."""
    log = write_log(
        tmp_path / 'node_like.mcap',
        scene['config'],
        scene['tensions'],
        scene['depth'],
        writer='logger',
    )
    code, _ = run_cli(
        log,
        '--params-file',
        scene['params'],
        '--csv',
        tmp_path / 'o.csv',
        '--csv-columns',
        'time,line,status,level',
        capsys=capsys,
    )
    assert code == 0
    rep = recompute(scene['config'], scene['tensions'], scene['depth'])
    _, steps = core_steps(
        scene['config'], scene['tensions'], scene['depth'], rep.tick_ns, rep.start_ns
    )
    with open(tmp_path / 'o.csv', newline='') as f:
        rows = list(csv.DictReader(f))
    for k, line in enumerate(scene['config'].lines):
        want = [
            Level(int(o.values[12])).name
            for s in steps
            if s.kind == 'tension'
            for o in s.outputs
            if o.line == k
        ]
        assert [r['level'] for r in rows if r['line'] == line.name] == want


def test_rosbag2_style_and_rotated_set(scene, capsys, tmp_path):
    """An mcap_ros2-written log, and the same log split in two files, give the same result."""
    cfg = scene['config']
    ten, dep = scene['tensions'], scene['depth']
    one = write_log(tmp_path / 'ros2.mcap', cfg, ten, dep, writer='ros2')
    cut = int(np.median(dep[0]))
    first = {k: (t[t < cut], v[t < cut]) for k, (t, v) in ten.items()}
    second = {k: (t[t >= cut], v[t >= cut]) for k, (t, v) in ten.items()}
    d1 = (dep[0][dep[0] < cut], dep[1][dep[0] < cut])
    d2 = (dep[0][dep[0] >= cut], dep[1][dep[0] >= cut])
    rot = tmp_path / 'rotated'
    rot.mkdir()
    write_log(rot / 'b_0001.mcap', cfg, second, d2)
    write_log(rot / 'a_0000.mcap', cfg, first, d1)
    results = []
    for paths in ([one], [rot], [rot / 'b_0001.mcap', rot / 'a_0000.mcap']):
        code, out = run_cli(*paths, '--params-file', scene['params'], '--json', capsys=capsys)
        assert code == 0
        results.append(json.loads(out.out)['lines'])
    assert results[0] == results[1] == results[2]


def _cut_log(scene, tmp_path):
    log = write_log(
        tmp_path / 'killed.mcap',
        scene['config'],
        scene['tensions'],
        scene['depth'],
        writer='logger',
        chunk_size=8 * 1024,
    )
    return log.read_bytes()


@pytest.mark.parametrize('fraction', [0.35, 0.8])
def test_truncated_log_uses_what_is_readable(scene, capsys, tmp_path, fraction):
    data = _cut_log(scene, tmp_path)
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(data[: int(len(data) * fraction)])
    code, out = run_cli(
        cut,
        '--params-file',
        scene['params'],
        '--json',
        '--csv',
        tmp_path / 'cut.csv',
        capsys=capsys,
    )
    assert code == 0, out.err
    summary = json.loads(out.out)
    assert not summary['complete']
    assert summary['unfinished_files'] == [str(cut)]
    assert any(s['kind'] == 'truncated' for s in summary['skipped'])
    n = sum(summary['messages'].values())
    total = sum(len(t) for t, _ in scene['tensions'].values()) + len(scene['depth'][0])
    assert 0.2 * total < n < total
    # Everything before the cut is used: the rows are a prefix of the full replay's rows.
    with open(tmp_path / 'cut.csv', newline='') as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == sum(summary['lines'][k]['tension_messages'] for k in summary['lines'])
    code, text = run_cli(cut, '--params-file', scene['params'], capsys=capsys)
    assert 'DAMAGED INPUT' in text.out and 'not finished by its writer' in text.out


def test_corrupt_chunk_is_skipped_and_reported(scene, capsys, tmp_path):
    import io

    from mcap.reader import make_reader

    data = bytearray(_cut_log(scene, tmp_path))
    chunks = make_reader(io.BytesIO(bytes(data))).get_summary().chunk_indexes
    assert len(chunks) > 4
    # Damage the compressed body of a chunk in the middle of the file.
    mid = chunks[len(chunks) // 2]
    at = mid.chunk_start_offset + mid.chunk_length // 2
    for k in range(at, at + 40):
        data[k] ^= 0x5A
    bad = tmp_path / 'corrupt.mcap'
    bad.write_bytes(bytes(data))
    code, out = run_cli(bad, '--params-file', scene['params'], '--json', capsys=capsys)
    assert code == 0, out.err
    summary = json.loads(out.out)
    assert summary['skipped'], summary
    assert [s['kind'] for s in summary['skipped']] == ['corrupt_chunk']
    lost = summary['skipped'][0]['messages_lost']
    total = sum(len(t) for t, _ in scene['tensions'].values()) + len(scene['depth'][0])
    assert lost and sum(summary['messages'].values()) == total - lost


def _cli(*args):
    return subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli', 'replay', *map(str, args)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_unexpected_topic_type_is_a_clear_error(scene, tmp_path):
    from mcap_ros2.writer import Writer

    from catenary_monitor.io.ros_schemas import message_definition

    path = tmp_path / 'wrong.mcap'
    with open(path, 'wb') as f:
        w = Writer(f)
        schema = w.register_msgdef(
            'std_msgs/msg/String', message_definition('std_msgs/msg/String')
        )
        w.write_message(
            '/mooring/line_01/tension', schema, {'data': '372 kN'}, log_time=1, publish_time=1
        )
        w.finish()
    p = _cli(path, '--params-file', scene['params'])
    assert p.returncode == 2
    assert "'/mooring/line_01/tension'" in p.stderr and 'std_msgs/msg/String' in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1


def test_empty_log_and_bad_arguments(scene, tmp_path):
    empty = write_log(
        tmp_path / 'empty.mcap', dock_config(1), {}, (np.zeros(0, np.int64), np.zeros(0))
    )
    p = _cli(empty, '--params-file', scene['params'])
    assert p.returncode == 3 and 'empty log' in p.stderr and 'no messages' in p.stderr
    p = _cli(tmp_path / 'missing.mcap', '--params-file', scene['params'])
    assert p.returncode == 2 and 'no such MCAP file' in p.stderr
    p = _cli(scene['log'])
    assert p.returncode == 2 and '--params-file' in p.stderr
    bad = tmp_path / 'bad.yaml'
    bad.write_text('catenary_monitor:\n  ros__parameters:\n    lines: [a]\n    a.weight: -1.0\n')
    p = _cli(scene['log'], '--params-file', bad)
    assert p.returncode == 2 and "'a.weight'" in p.stderr
    text = tmp_path / 'notmcap.mcap'
    text.write_text('hello')
    p = _cli(text, '--params-file', scene['params'])
    assert p.returncode == 2 and 'not an MCAP file' in p.stderr
    # without --params-file the file's own fault comes first, not the missing parameters
    p = _cli(text)
    assert p.returncode == 2 and 'not an MCAP file' in p.stderr, p.stderr
    zero = tmp_path / 'zero.mcap'
    zero.write_bytes(b'')
    p = _cli(zero)
    assert p.returncode == 3 and 'empty log' in p.stderr, p.stderr


def test_progress_on_long_logs(scene, tmp_path):
    p = _cli(
        scene['log'], '--params-file', scene['params'], '--progress', '--csv', tmp_path / 'p.csv'
    )
    assert p.returncode == 0
    # a streamed replay: the share of the files' bytes walked, with an ETA, then done
    assert 'replay: 100% of' in p.stderr and 'ETA' in p.stderr
    assert 'replay: done' in p.stderr
    p = _cli(scene['log'], '--params-file', scene['params'], '--quiet')
    assert p.stderr == ''


def test_offline_replay_imports_without_rclpy():
    """Offline replay needs no ROS: its modules import with rclpy unavailable."""
    code = (
        'import sys; sys.modules["rclpy"] = None\n'
        'import catenary_monitor.core.twin.engine, catenary_monitor.cli.replay, '
        'catenary_monitor.replay.outputs, catenary_monitor.io.csv_columns, '
        'catenary_monitor.io.cdr, '
        'catenary_monitor.io.mcap_column_writer, catenary_monitor_study.bench_replay\n'
        'from catenary_monitor.cli.main import build_parser; build_parser()\n'
    )
    p = subprocess.run(
        [sys.executable, '-c', code], cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    assert p.returncode == 0, p.stderr


def test_topic_names_resolve_like_the_node(tmp_path):
    from catenary_monitor.core.config.parameters import resolve_topic
    from catenary_monitor.ros.playback import input_topics_of_log

    assert resolve_topic('/tide/depth') == '/tide/depth'
    assert resolve_topic('mooring/a/tension') == '/mooring/a/tension'
    assert resolve_topic('~/a/tension') == '/catenary_monitor/a/tension'
    # --publish without a params file plays every topic of an input type (summary, or a scan
    # when the file has none).
    config = dock_config(2)
    tensions, depth = generate(config, seconds=5.0, seed=2, dropouts=False)
    log = write_log(tmp_path / 'a.mcap', config, tensions, depth)
    want = ['/mooring/line_01/tension', '/mooring/line_02/tension', '/tide/depth']
    assert sorted(input_topics_of_log([log])) == want
    assert set(input_topics_of_log([log]).values()) == {'std_msgs/msg/Float64'}
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(log.read_bytes()[:-200])
    assert sorted(input_topics_of_log([cut])) == want


def test_bench_replay_command_runs():
    """Smoke test of the benchmark command (not a timing test: the figures are not checked)."""
    p = subprocess.run(
        [
            sys.executable,
            '-m',
            'catenary_monitor.cli',
            'bench-replay',
            '--messages',
            '20000',
            '--baseline-messages',
            '300',
            '--json',
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 0, p.stderr
    r = json.loads(p.stdout)
    assert r['messages'] == 20000 and r['csv_rows'] > 19000 and r['transitions'] > 0
    assert r['baseline_messages'] == 300 and r['mcap_out_messages'] > 40000


def test_ticks_option(scene, capsys):
    code, out = run_cli(
        scene['log'], '--params-file', scene['params'], '--ticks', 'log', capsys=capsys
    )
    assert code == 2 and 'no catenary_monitor events channel' in out.err
    code, out = run_cli(
        scene['log'], '--params-file', scene['params'], '--ticks', 'grid', '--json', capsys=capsys
    )
    assert code == 0 and json.loads(out.out)['ticks']['source'] == 'synthetic grid'


def test_parameters_recorded_in_the_log(scene, capsys, tmp_path):
    """Without --params-file, replay takes the parameters the log recorded (the node's
    metadata record); with one, the summary says whether they differ from the recorded."""
    results = tmp_path / 'results.mcap'
    assert (
        run_cli(scene['log'], '--params-file', scene['params'], '--out', results, capsys=capsys)[0]
        == 0
    )
    code, out = run_cli(results, '--json', capsys=capsys)
    assert code == 0, out.err
    par = json.loads(out.out)['parameters']
    assert par['source'] == 'recorded in the log' and par['same_as_recorded'] is True
    other = params_yaml(dock_config(3, clear_hold=9.0), tmp_path / 'other.yaml')
    code, out = run_cli(results, '--params-file', other, capsys=capsys)
    assert code == 0 and 'the log was recorded with other parameters' in out.out
    # An unfinished file written by the node's logger: the record is near its start.
    from catenary_monitor.core.config.parameters import config_hash, config_to_params
    from catenary_monitor.io.mcap_log import McapLogger
    from catenary_monitor.replay.driver import log_parameters

    log = McapLogger(tmp_path / 'node', fsync=False)
    log.add_metadata(
        'catenary_monitor',
        {
            'config_hash': config_hash(scene['config']),
            'parameters': json.dumps(config_to_params(scene['config'])),
        },
    )
    log.register('/tide/depth', 'std_msgs/msg/Float64')
    log.write('/tide/depth', b'\x00\x01\x00\x00' + bytes(8), 1)
    log.flush()
    got = log_parameters([log.current_path])
    assert got is not None and got[0] == config_hash(scene['config'])
    log.close()

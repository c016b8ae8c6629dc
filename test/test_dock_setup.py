"""A new dock's set-up commands: ``params-template`` (the shipped config/dock_template.yaml is
its ``--lines 4``) and ``disk-estimate``, checked against a real node's MCAP log: the node run
with the dock simulator publishing 12 lines at 10 Hz and the depth at 10 Hz, its logging rate
over the steady part of the run (every chunk and its message indexes) within 10 % of the
estimate."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader
from ros_harness import child_env

from catenary_monitor.cli.dock_setup import NODE_FLUSH_PERIOD, NODE_TICK, estimate
from catenary_monitor.cli.main import main
from catenary_monitor.core.config.parameters import config_from_params, load_params_file

ROOT = Path(__file__).resolve().parents[1]


def test_params_template_writes_every_line_and_is_the_shipped_template(tmp_path, capsys):
    assert main(['params-template', '--lines', '4']) == 0
    assert capsys.readouterr().out == (ROOT / 'config/dock_template.yaml').read_text()
    out = tmp_path / 'dock.yaml'
    assert main(['params-template', '--lines', '12', '--out', str(out)]) == 0
    text = out.read_text()
    config = config_from_params(load_params_file(out))
    assert [lc.name for lc in config.lines] == [f'line_{k:02d}' for k in range(1, 13)]
    for line in config.lines:  # every line in full, each value to measure marked
        block = text.split(f'    {line.name}:\n')[1].split('\n    line_')[0]
        for key in ('weight', 'anchor_distance', 'mbl', 'hook_height', 'tension_topic',
                    'tension_type', 'tension_scale'):  # fmt: skip
            assert re.search(rf'^      {key}: .*# CHECK', block, re.M), (line.name, key)
    assert 'std_msgs/msg/Float64' in text and 'geometry_msgs/msg/WrenchStamped' in text
    assert main(['params-template', '--names', 'bow,stern', '--out', str(out)]) == 0
    assert [lc.name for lc in config_from_params(load_params_file(out)).lines] == [
        'bow', 'stern']  # fmt: skip
    assert main(['params-template', '--lines', '3', '--names', 'bow,stern']) == 2


def test_disk_estimate_command(tmp_path, capsys):
    params = ROOT / 'config/floating_dock.yaml'
    assert main(['disk-estimate', '--params-file', str(params)]) == 2
    assert 'give --tension-rate' in capsys.readouterr().err
    template = ROOT / 'config/dock_template.yaml'
    assert main(['disk-estimate', '--params-file', str(template), '--json']) == 0
    answer = json.loads(capsys.readouterr().out)
    assert (answer['lines'], answer['tension_rate'], answer['depth_rate']) == (4, 10.0, 1.0)
    days = 50e9 / answer['bytes_per_day']
    assert answer['days_in_log_max_total_size'] == pytest.approx(days)
    per_day = answer['bytes_per_second'] * 86400 + answer['files_per_day'] * answer[
        'file_fixed_bytes']  # fmt: skip
    assert answer['bytes_per_day'] == pytest.approx(per_day)


def test_the_estimate_uses_the_nodes_logger_settings():
    source = (ROOT / 'catenary_monitor/ros/node.py').read_text()
    assert re.search(rf'flush_period={NODE_FLUSH_PERIOD},', source)
    assert f'checked every {NODE_TICK} s' in source


def _steady_rate(path: Path) -> tuple[float, float]:
    """(bytes per second, seconds) of the chunks (and their message indexes) written while
    every tension came in, the first 2 s of it left out."""
    with open(path, 'rb') as f:
        reader = make_reader(f)
        first, last = [], []
        summary = reader.get_summary()
        assert summary is not None
        tension = {c.id for c in summary.channels.values() if c.topic.endswith('/tension')}
        for _, channel, message in reader.iter_messages(log_time_order=True):
            if channel.id in tension:
                first.append(message.log_time) if not first else None
                last[:] = [message.log_time]
    start, end = first[0] + 2e9, last[0]
    chunks = [c for c in summary.chunk_indexes
              if c.message_start_time >= start and c.message_end_time <= end]  # fmt: skip
    span = (max(c.message_end_time for c in chunks) - min(c.message_start_time for c in chunks))
    total = sum(c.chunk_length + c.message_index_length for c in chunks)
    return total / (span / 1e9), span / 1e9


@pytest.mark.slow
@pytest.mark.ros
def test_the_estimate_is_within_10_percent_of_a_real_log(tmp_path):
    params = ROOT / 'config/floating_dock.yaml'
    env = child_env()
    node = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor', 'run', '--params-file', str(params),
         '--log-dir', str(tmp_path / 'log')],
        stdout=open(tmp_path / 'node.out', 'w'), stderr=subprocess.STDOUT, env=env,
    )  # fmt: skip
    simulator = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.ros.simulator', '--rate', '10',
         '--depth-rate', '10', '--duration', '600'],
        stdout=open(tmp_path / 'sim.out', 'w'), stderr=subprocess.STDOUT, env=env,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 60.0
        # the node logs level changes only: starting to every sensor reporting is OK to OK
        while not ('monitoring 12 lines' in (tmp_path / 'node.out').read_text()
                   and 'publishing' in (tmp_path / 'sim.out').read_text()):  # fmt: skip
            assert node.poll() is None and time.monotonic() < deadline, (
                tmp_path / 'node.out').read_text()  # fmt: skip
            time.sleep(0.5)
        time.sleep(25.0)
    finally:
        simulator.send_signal(signal.SIGTERM)
        simulator.wait(30)
        node.send_signal(signal.SIGTERM)
        assert node.wait(30) == 0, (tmp_path / 'node.out').read_text()
    real, seconds = _steady_rate(next((tmp_path / 'log').glob('*.mcap')))
    assert seconds > 15.0
    config = config_from_params(load_params_file(params))
    estimated = estimate(config, 10.0, 10.0, seconds=60.0)['bytes_per_second']
    print(f'real {real:.0f} B/s over {seconds:.0f} s, estimated {estimated:.0f} B/s')
    assert estimated == pytest.approx(real, rel=0.10)

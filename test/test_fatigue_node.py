"""Chain fatigue in the live node (real rclpy, the monitor as its own process): the count goes
on across a restart through the store beside the log, and replaying the log folder gives the
node's damage to the bit (docs/fatigue.md)."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest
import rainflow
from ros_harness import start_monitor, stop, write_params
from rclpy.serialization import deserialize_message
from std_msgs.msg import Float64, Float64MultiArray

from catenary_monitor.core.config.parameters import config_from_params, load_params_file
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.io.mcap_read import iter_messages
from catenary_monitor.replay.driver import expand, replay_log

pytestmark = [pytest.mark.ros, pytest.mark.usefixtures('no_callback_errors')]

TOPIC, OUT = '/mooring/ch/tension', '/catenary_monitor/ch/outputs'
FATIGUE = 'catenary_monitor: fatigue'


def _logged(log_dir: Path, topic: str) -> list:
    return list(iter_messages(sorted(log_dir.glob('*.mcap')), [topic]))


def _run(client, params, log_dir, values, store_state):
    """One life of the node: its store read (``store_state``), ``values`` published and logged,
    then SIGTERM (a clean stop writes the store)."""
    proc = start_monitor(params, log_dir)
    try:
        client.wait_matched([TOPIC], 30.0)
        status = client.wait_status(
            FATIGUE, 30.0, check=lambda s: s['values'].get('store_state') == store_state
        )
        assert status['level'] == (1 if store_state in ('missing', 'damaged') else 0)
        client.feed('/tide/depth', 20.85)
        before = len(_logged(log_dir, TOPIC))
        for v in values:
            client.publish(TOPIC, v)
            time.sleep(0.004)
        deadline = time.monotonic() + 30.0
        while len(_logged(log_dir, TOPIC)) < before + len(values):
            assert time.monotonic() < deadline, 'the monitor does not log every sample'
            time.sleep(0.2)
    finally:
        client.feed('/tide/depth', None)
        assert stop(proc) == 0
    return status


def test_damage_is_carried_across_a_restart_and_equal_in_replay(client, tmp_path):
    lines = {
        'ch': dict(
            weight=1300.0,
            anchor_distance=120.0,
            mbl=4.827e6,
            fatigue_stress_per_tension=2.0e3,  # a small link: damage in a short test
            fatigue_damage_initial=0.01,
        )
    }
    params = write_params(tmp_path / 'params.yaml', lines, tension_timeout=60.0)
    log_dir = tmp_path / 'log'
    rng = np.random.default_rng(3)
    x = 4.0e5 + 5e4 * np.sin(np.arange(240) * 0.9) + rng.normal(0.0, 5e3, 240)
    first = _run(client, params, log_dir, x[:120].tolist(), 'new')
    assert 'new fatigue store' in first['message']
    stored = json.loads((log_dir / 'chain_fatigue.json').read_text())
    assert stored['lines']['ch']['closed'] > 0.01
    _run(client, params, log_dir, x[120:].tolist(), 'loaded')

    # the node's own last output, and what replaying the folder gives
    outputs = _logged(log_dir, OUT)
    last = deserialize_message(outputs[-1].data, Float64MultiArray).data
    live = last[OUTPUT_FIELDS.index('fatigue_damage')]
    config = config_from_params(load_params_file(params))
    replayed = replay_log(expand([str(log_dir)]), config).result.lines[0]
    assert replayed.values['fatigue_damage'][replayed.tension_rows][-1] == live
    # ... and the count of every sample of both lives, as one history (the restart is seamless)
    sent = [deserialize_message(m.data, Float64).data for m in _logged(log_dir, TOPIC)]
    assert np.allclose(sent, x)
    curve = 2.0e3 * 1e-6
    whole = sum(
        n * (r * curve) ** 3.36 / 10**13.6451 for r, _, n, _, _ in rainflow.extract_cycles(sent)
    )
    assert live == pytest.approx(0.01 + whole, rel=1e-9)

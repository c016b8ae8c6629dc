"""A load cell of three channels in the live node (real rclpy, the monitor as its own process):
a channel that falls silent is named in /diagnostics and the tension comes from the others;
every channel's samples go through the node's intake (a burst on one coalesced as a single
topic's would be) and are counted for the line; replaying the node's log folder gives the
node's tensions (docs/channels.md)."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest
from ros_harness import start_monitor, stop, write_params
from rclpy.serialization import deserialize_message
from std_msgs.msg import Float64MultiArray

from catenary_monitor.core.config.parameters import config_from_params, load_params_file
from catenary_monitor.core.monitor.events import EVENTS_TOPIC
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.io.cdr import string_text
from catenary_monitor.io.mcap_read import iter_messages
from catenary_monitor.replay.driver import expand, replay_log

pytestmark = [pytest.mark.ros, pytest.mark.usefixtures('no_callback_errors')]

TOPICS = ['/cell/a', '/cell/b', '/cell/c']
LINE = 'catenary_monitor: cell'


def test_a_silent_channel_is_named_live_and_replay_agrees(client, tmp_path):
    lines = {
        'cell': dict(
            weight=1300.0,
            anchor_distance=130.0,
            mbl=4.827e6,
            tension_topics=TOPICS,
            min_channels=2.0,
        )
    }
    params = write_params(
        tmp_path / 'params.yaml', lines, tension_timeout=1.0, intake_step_budget=0.0
    )
    log_dir = tmp_path / 'log'
    proc = start_monitor(params, log_dir)
    try:
        client.wait_matched(TOPICS, 30.0)
        client.feed('/tide/depth', 20.85)
        for k in range(40):  # a burst on c: the node steps the newest of what waits
            client.publish(TOPICS[2], 4.08e5 + 50.0 * (k % 7))
        end = time.monotonic() + 3.0
        k = 0
        while time.monotonic() < end:  # all three, then b falls silent
            for j, topic in enumerate(TOPICS):
                if j != 1 or time.monotonic() < end - 1.5:
                    client.publish(topic, 4.0e5 * (1.0 + 0.02 * (j - 1)) + 50.0 * (k % 7))
            k += 1
            time.sleep(0.05)
        status = client.wait_status(
            LINE, 15.0, 1, check=lambda s: '/cell/b silent' in s['message']
        )
        assert 'tension from the other 2' in status['message']
        assert status['values']['channels_healthy'] == '2.0'
    finally:
        client.feed('/tide/depth', None)
        assert stop(proc) == 0
    files = sorted(log_dir.glob('*.mcap'))
    outputs = list(iter_messages(files, ['/catenary_monitor/cell/outputs']))
    live = [deserialize_message(m.data, Float64MultiArray).data for m in outputs]
    at = OUTPUT_FIELDS.index('top_tension')
    config = config_from_params(load_params_file(params))
    r = replay_log(expand([str(log_dir)]), config).result.lines[0]
    np.testing.assert_array_equal(r.values['top_tension'], [o[at] for o in live])
    # the intake counts every channel's samples for the line: stepped or coalesced, each one
    # the log holds (the counts of the node's Intake records, the last at its close)
    logged = sum(1 for _ in iter_messages(files, TOPICS))
    counted = [0, 0]
    for m in iter_messages(files, [EVENTS_TOPIC]):
        record = json.loads(string_text(m.data))
        if record.get('kind') == 'intake':
            counted[0] += record['received'][0]
            counted[1] += (record['coalesced'] or [0])[0]
    print('cell: stepped, coalesced, logged', counted, logged)
    assert sum(counted) == logged

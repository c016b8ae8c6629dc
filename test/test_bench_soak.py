"""``catenary-monitor bench-soak``, short: the node with rotation every few seconds loses
nothing, finishes every file (the ``mcap`` reader, CRCs validated) and exits 0. RSS is
reported, not judged here (a short run says little about growth; docs/benchmarks.md)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from ros_harness import child_env

pytestmark = pytest.mark.ros


def test_a_short_soak_loses_nothing_and_finishes_every_file():
    cmd = [
        sys.executable, '-m', 'catenary_monitor.cli.main', 'bench-soak', '--lines', '3',
        '--rate', '20', '--duration', '20', '--rotate-duration', '5', '--sample', '1', '--json',
    ]
    done = subprocess.run(cmd, capture_output=True, text=True, env=child_env(), timeout=240)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result['sent'] >= 3 * 20 * 15 and result['lost'] == 0, result
    assert result['logged'] == result['sent'], result
    assert result['files'] >= 3 and not result['unfinished'] and not result['reader_errors']
    assert result['exit_code'] == 0 and result['intake_messages_dropped'] == '0'
    assert result['rss_samples'] >= 10 and result['rss_max_mb'] > 0

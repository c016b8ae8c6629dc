"""A reader of /diagnostics joining a running monitor hears it at once, not one period later.

The monitor publishes a fresh array (a tick) when a new reader of ``/diagnostics`` matches
(the harbour starting, a console joining late); with a 10 s period a late reader has the
monitor's array within seconds, and the periodic rate goes on as before.
"""

from __future__ import annotations

import signal
import time

import pytest
from ros_harness import Client, start_monitor, stop, write_params

pytestmark = [pytest.mark.ros, pytest.mark.usefixtures('no_callback_errors')]

LINES = {'l1': dict(weight=1300.0, anchor_distance=121.06, mbl=4.827e6)}
PERIOD = 10.0  # s: the monitor's /diagnostics period


def test_a_late_reader_hears_the_monitor_at_once(tmp_path):
    params = write_params(
        tmp_path / 'p.yaml', LINES, diagnostic_rate=1.0 / PERIOD, depth_timeout=60.0
    )
    monitor = start_monitor(params, tmp_path / 'log')
    first = late = None
    try:
        first = Client('on_match_first')
        first.wait_matched(['/tide/depth', '/mooring/l1/tension'], 60.0)
        first.wait_status('catenary_monitor: l1', 60.0)
        # a second reader joins while the monitor runs: its first array well within a period
        t0 = time.monotonic()
        late = Client('on_match_late')
        late.wait_status('catenary_monitor: l1', 60.0)
        assert time.monotonic() - t0 < PERIOD / 2, time.monotonic() - t0
    finally:
        for client in (first, late):
            if client is not None:
                client.close()
        assert stop(monitor, signal.SIGTERM) == 0

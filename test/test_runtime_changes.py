"""Nobody silences the monitor at runtime: set_parameters against a monitor process.

A monitor started without ``allow_runtime_changes`` refuses (successful=False, a reason) a
line's ``allowed_uplift`` raised to 1e9 N and ``use_sim_time`` set to true; ``/diagnostics``
keeps coming and an active uplift stays ERROR. With ``allow_runtime_changes: true`` the same
change is accepted, logged as one line with old and new values and recorded on the events
channel of the MCAP log, and shown as a WARN on the ``parameters`` status (the uplift ERROR
held meanwhile). Every wait is bounded and waits for the event it needs.
"""

from __future__ import annotations

import json
import time

import pytest
from ros_harness import output_of, start_monitor, stop, write_params

from catenary_monitor.core.monitor.events import EVENTS_TOPIC
from catenary_monitor.io.mcap_read import iter_messages

pytestmark = pytest.mark.ros

W, DEPTH, MBL = 1300.0, 20.85, 4.827e6
LINES = {'up': dict(weight=W, anchor_distance=121.06, mbl=MBL)}
UP, TIDE = 'catenary_monitor: up', 'catenary_monitor: tide'
FLAG = 'catenary_monitor: parameters'
OK, WARN, ERROR = 0, 1, 2


def _start(client, tmp, **extra):
    """A monitor with ``up`` in uplift ERROR, and the monotonic time [s] it was started: the
    module's client also holds the statuses of the module's earlier monitors (same names)."""
    params = write_params(tmp / 'params.yaml', LINES, diagnostic_rate=4.0, **extra)
    t0 = time.monotonic()
    proc = start_monitor(params, tmp / 'log')
    client.wait_matched(['/tide/depth', '/mooring/up/tension'], 30.0)
    client.feed('/tide/depth', DEPTH)
    client.feed('/mooring/up/tension', 1623.5e3)  # the table-3 typhoon: the anchor lifts
    s = client.wait_status(UP, 15.0, ERROR, since=t0)
    assert 'uplift' in s['message'], s
    return proc, t0


def _set(client, name, value):
    """One SetParameters call on /catenary_monitor/set_parameters: its SetParametersResult."""
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    srv = client.node.create_client(SetParameters, '/catenary_monitor/set_parameters')
    try:
        assert srv.wait_for_service(timeout_sec=10.0)
        msg = Parameter(name, value=value).to_parameter_msg()
        request = SetParameters.Request(parameters=[msg])
        future = srv.call_async(request)
        client.wait_for(future.done, 10.0, f'set {name}')
        return future.result().results[0]
    finally:
        client.node.destroy_client(srv)


def test_alarm_parameters_and_use_sim_time_are_refused_by_default(client, tmp_path):
    proc, _ = _start(client, tmp_path)
    try:
        r = _set(client, 'up.allowed_uplift', 1e9)
        assert not r.successful and 'allow_runtime_changes' in r.reason, r.reason
        r = _set(client, 'use_sim_time', True)
        assert not r.successful and 'use_sim_time' in r.reason, r.reason
        r = _set(client, 'clear_hold', 1e6)
        assert not r.successful, r.reason
        t0 = time.monotonic()
        client.wait_for(
            lambda: len(client.levels(UP, t0)) >= 8, 10.0, '/diagnostics after the refusals'
        )
        assert set(client.levels(UP, t0)) == {ERROR}
        assert client.latest_status(TIDE)['level'] == OK
        assert proc.poll() is None
        assert 'changed' not in output_of(proc)
    finally:
        client.feed('/mooring/up/tension', None)
        stop(proc)


def test_allowed_changes_are_logged_and_recorded(client, tmp_path):
    proc, t0 = _start(client, tmp_path, allow_runtime_changes=True)
    try:
        before = client.wait_status(FLAG, 10.0, OK, since=t0)
        assert before['message'] == 'runtime changes allowed; none made', before
        r = _set(client, 'up.allowed_uplift', 1e9)
        assert r.successful, r.reason
        line = 'allowed_uplift of up changed 0 N -> 1e+09 N at runtime'
        client.wait_for(lambda: line in output_of(proc), 10.0, 'the change log line')
        # The flag: a WARN naming old and new values, in the very array that first shows it
        # the active uplift still ERROR (it clears only after clear_hold of clear input).
        flagged = client.wait_status(FLAG, 10.0, WARN, since=t0)
        assert flagged['values']['detail'] == line and flagged['values']['changes'] == '1', flagged
        with client.lock:
            first = next(
                e
                for t, e in client.diagnostics
                if t >= t0 and e.get(FLAG, {}).get('level') == WARN
            )
        assert first[UP]['level'] == ERROR, first[UP]
        assert f'ALARM parameters: OK -> WARN: {line}' in output_of(proc)
        r = _set(client, 'use_sim_time', True)  # never: a stopped /clock would silence it
        assert not r.successful and 'use_sim_time' in r.reason
        t1 = time.monotonic()
        client.wait_for(lambda: len(client.levels(UP, t1)) >= 4, 10.0, 'diagnostics after')
    finally:
        client.feed('/mooring/up/tension', None)
        assert stop(proc) == 0
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import String

    records = [
        json.loads(deserialize_message(m.data, String).data)
        for m in iter_messages(sorted((tmp_path / 'log').glob('*.mcap')), [EVENTS_TOPIC])
    ]
    configured = [r for r in records if r.get('kind') == 'configure']
    assert configured and configured[-1]['parameters']['up.allowed_uplift'] == 1e9, configured

"""Operators' requests from the ROS graph: rate-limited per publisher, every refusal recorded
and answered (core/alarms/requests.py, ros/request_reader.py, the Refusal event).

A node gone wrong sends 1,000 shelving requests a second for 10 s (a shelf toggled on and off
on a warning line); meanwhile a console acknowledges and shelves. The monitor must stay quiet
(it had published 562 /diagnostics arrays a second and logged 5,700 lines in 10 s; the
toggling raised the warning 34 times), take the console's requests (the console is one
publisher: never locked out; a request the flood pushed out of the monitor's queue is resent
with its id until answered, and applied once), and account for every request of the flood in
its records.
Requests refused before the alarm rules (a duration of nan, inf or -1, an unknown alarm or
line, an empty acknowledgement) each leave a record and an answer.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from ros_harness import Client, child_env, output_of, start_monitor, stop, write_params

from catenary_monitor.core.alarms.requests import BURST, REPORT_EVERY, RequestLimit

HERE = Path(__file__).resolve().parent
ACK = '/catenary_monitor/acknowledge'
SHELVE = '/catenary_monitor/shelve'
LINE = dict(weight=1300.0, anchor_distance=120.0, mbl=4.827e6)
OK_T, WARN_T = 372e3, 450e3  # line_01 at 450 kN: anchor margin 4.1 m, WARN
PROBES = 10  # requests sent once each mid-flood, none resent


def test_the_limit_lets_a_burst_through_then_a_request_a_second() -> None:
    limit = RequestLimit()
    assert [limit.admit('a', 0.0) for _ in range(BURST + 5)].count(True) == BURST
    assert limit.due(0.0) == [('a', 5)]  # the first record at once
    assert not limit.admit('a', 0.5) and limit.admit('a', 1.5)  # one a second after that
    assert limit.admit('b', 0.5)  # another publisher is not held back
    limit.refuse('a', 100)  # lost behind the flood, before they were read
    assert limit.due(5.0) == []  # at most one record per period
    assert limit.due(REPORT_EVERY + 0.1) == [('a', 101)]
    assert limit.due(100.0, every_one=True) == []
    many = RequestLimit(keys=4, burst=1)
    for k in range(10):  # beyond KEYS_MAX, new publishers share their group's bucket
        many.admit(f'shelve {k}', 0.0)
    assert len(many._buckets) <= 5
    assert many.due(0.0) == [('shelve (other publishers)', 5)]


def test_a_refusal_is_recorded_answered_and_replayed_alike() -> None:
    """A Refusal: its record round-trips, the core journals and answers it (a shelving
    request's on the alarms status, at once), an acknowledgement of an unknown line is one
    too, and the twin (run_log) makes the same records."""
    import json

    import numpy as np
    from replay_data import T0_NS, dock_config

    from catenary_monitor.core.monitor.events import (
        Acknowledge,
        Refusal,
        Tick,
        event_record,
        parse_event_record,
    )
    from catenary_monitor.core.monitor.monitor_core import MonitorCore
    from catenary_monitor.core.twin.engine import run_log
    from catenary_monitor.core.twin.window import Window

    ev = Refusal(T0_NS + 5, 'shelve', 'line_01', 'over the rate limit', 'x', '/n gid 01', 42)
    assert parse_event_record(ev.stamp_ns, json.dumps(event_record(ev))) == ev
    bad = '{"kind": "refused", "request": "reboot", "reason": "r"}'
    assert parse_event_record(0, bad) is None
    config = dock_config(2)
    core = MonitorCore(config, T0_NS)
    step = core.step(ev)
    assert step.note == 'line_01: refused: over the rate limit (42 requests)'
    alarms = {st.name: dict(st.values) for st in step.snapshot.statuses}
    assert alarms['catenary_monitor: alarms']['shelve_answer'] == step.note
    assert alarms['catenary_monitor: alarms']['shelve_requests'] == '42'
    (record,) = step.alarm_events
    got = (record.kind, record.alarm, record.value, record.level)
    assert got == ('refused', 'line_01', 42.0, '')
    ack = core.step(Acknowledge(T0_NS + 6, 'nope', 'op', '/n gid 01'))
    assert ack.kind == 'refused' and ack.snapshot is None and 'unknown alarm' in ack.note
    assert ack.alarm_events[0].level == 'acknowledge'
    events = [ev, Acknowledge(T0_NS + 6, 'nope', 'op', '/n gid 01')]
    ticks = np.array([T0_NS + 10], np.int64)
    want = MonitorCore(config, T0_NS)
    journal = [e for x in [*events, Tick(int(ticks[0]))] for e in want.step(x).alarm_events]
    empty = (np.zeros(0, np.int64), np.zeros(0))
    result, _ = run_log(MonitorCore(config, T0_NS), Window([empty, empty], empty, ticks), events)
    assert sorted(result.alarm_events) == sorted(journal)


def test_a_request_id_is_applied_once_per_publisher_and_remembered_boundedly() -> None:
    from catenary_monitor.core.alarms.requests import Resends, split_id

    assert split_id('line_01 60 console op #a1b2') == ('line_01 60 console op', 'a1b2')
    assert split_id('line_01 #x') == ('line_01', 'x')
    for text in ('#x', 'line_01 60 op#x', 'line_01 60 #bad!', 'line_01 60 #' + 'a' * 33):
        assert split_id(text) == (text, ''), text
    ids = Resends(kept=2, publishers=2, keep_for=60.0)
    assert not ids.seen('a', 'r1', 0.0) and ids.seen('a', 'r1', 5.0)
    assert not ids.seen('b', 'r1', 5.0)  # another publisher's id is its own
    assert not ids.seen('a', 'r2', 6.0) and not ids.seen('a', 'r3', 7.0)
    assert not ids.seen('a', 'r1', 8.0)  # beyond the 2 kept: forgotten (taken again)
    assert ids.seen('a', 'r3', 60.0) and not ids.seen('a', 'r3', 130.0)  # kept 60 s
    ids.seen('c', 'r1', 9.0)  # a third publisher: the longest idle one ('b') forgotten
    assert len(ids._ids) == 2 and 'b' not in ids._ids


class _Publisher:
    """A request publisher whose first ``lose`` sends the flood takes; then ``answer()``."""

    def __init__(self, lose: int, answer: Any = None) -> None:
        self.sent: list[str] = []
        self.lose, self.answer = lose, answer

    def get_subscription_count(self) -> int:
        return 1

    def publish(self, msg: Any) -> None:
        self.sent.append(msg.data)
        if len(self.sent) > self.lose and self.answer is not None:
            self.answer(msg.data)


def test_the_console_resends_its_request_with_its_id_until_the_answer_shows(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A shelving request lost twice is sent a third time with the same id, and its answer
    (told apart from the flood's on the same line) is returned; an acknowledgement is resent
    while its alarm, raised as when it was sent, still waits for one, never once the alarm is
    acknowledged or raised again."""
    from types import SimpleNamespace

    from catenary_monitor.console import ros_source
    from catenary_monitor.console.frames import Status

    from catenary_monitor.console import resend

    monkeypatch.setattr(ros_source, 'RESEND_EVERY', (0.02, 0.05))
    monkeypatch.setattr(resend, 'RESEND_EVERY', (0.0, 0.0))
    source = ros_source.LiveSource(None)
    source.names = ['line_01', 'line_02']
    source._String = lambda data: SimpleNamespace(data=data)
    origin = 'console vm client 127.0.0.1'

    def answer(text: str) -> None:
        with source.cond:
            n = len(source._answers_seen)
            source._answers_seen.append((n + 1, 'line_02 shelved for 600 s by flood'))
            source._answers_seen.append((n + 2, f'line_02 shelved for 60 s by {origin}'))
            source.cond.notify_all()

    source._shelve_pub = _Publisher(2, answer)
    got = source.shelve('line_02', 'all', 60.0, origin)
    assert got['answer'] == f'line_02 shelved for 60 s by {origin}', got
    assert len(source._shelve_pub.sent) == 3 and len(set(source._shelve_pub.sent)) == 1
    assert source._shelve_pub.sent[0] == got['sent']
    assert got['sent'].startswith(f'line_02 60 {origin} #')

    values = {'acknowledged': 'false', 'alarm_raised': '100.0'}
    source.statuses = {'line_01': Status('WARN', '', values)}
    source._ack_pub = _Publisher(99)
    sent = source.acknowledge('line_01', origin)
    source._resend_acks()
    assert source._ack_pub.sent == [sent, sent]
    source.statuses = {'line_01': Status('WARN', '', {**values, 'alarm_raised': '150.0'})}
    source._resend_acks()  # raised again since: the operator has not seen that one
    assert len(source._ack_pub.sent) == 2 and not source._acks
    source.acknowledge('line_01', origin)
    source.statuses = {'line_01': Status('WARN', '', {**values, 'acknowledged': 'true'})}
    source._resend_acks()  # acknowledged: nothing more to send
    assert len(source._ack_pub.sent) == 3 and not source._acks
    source.statuses = {}
    source.acknowledge('line_02', origin)  # nothing waits for it: sent once
    assert not source._acks
    # a component status is acknowledged as a line (the tide's impossible depth), by name or all
    source.statuses = {'tide': Status('ERROR', 'impossible depth', values)}
    sent = source.acknowledge('tide', origin)
    assert sent.startswith(f'tide {origin} #') and len(source._acks) == 1
    source.acknowledge('all', origin)
    assert len(source._acks) == 2
    with pytest.raises(ros_source.AckError):
        source.acknowledge('tides', origin)


def test_an_acknowledgement_is_resent_every_second_for_8_s_at_most() -> None:
    """The harbour's and the console's: none before a second, then one a second while the
    alarm waits, none after ANSWER_WAIT; at most ACKS_MAX followed at once."""
    from catenary_monitor.console.frames import Status
    from catenary_monitor.console.resend import ACKS_MAX, ANSWER_WAIT, AckResends

    waits = {'line_01': Status('WARN', '', {'acknowledged': 'false', 'alarm_raised': '5.0'})}
    acks = AckResends()
    acks.add('line_01 op #a', ['line_01'], waits, 0.0)
    assert acks.due(waits, 0.5) == [] and acks.due(waits, 1.0) == ['line_01 op #a']
    assert acks.due(waits, 1.5) == [] and acks.due(waits, 2.0) == ['line_01 op #a']
    assert acks.due(waits, ANSWER_WAIT + 0.1) == [] and len(acks) == 0
    for k in range(ACKS_MAX + 5):
        acks.add(f'line_01 op #{k}', ['line_01'], waits, 0.0)
    assert len(acks) == ACKS_MAX


def test_a_publisher_listed_before_its_node_is_named_once_its_node_is_known() -> None:
    """The middleware lists a new publisher under a placeholder (``_NODE_NAME_UNKNOWN_``) for
    a while after discovering it: its requests are recorded by GID alone meanwhile, and by its
    node's name once the graph knows it, never under the placeholder for good (which also
    refused a console as not one where only consoles may acknowledge)."""
    from types import SimpleNamespace

    from catenary_monitor.ros.node import CatenaryMonitor

    gid = bytes(range(16))
    graph = [('_NODE_NAMESPACE_UNKNOWN_/_NODE_NAME_UNKNOWN_', gid + bytes(8))]
    fake = SimpleNamespace(_senders={}, _graph_read={}, _publishers_on=lambda topic: graph)
    publisher, node = CatenaryMonitor._sender(fake, SHELVE, gid)
    assert node is None and publisher.startswith('gid 00.01.02') and 'UNKNOWN' not in publisher
    graph[:] = [('/catenary_console_a', gid + bytes(8))]
    assert CatenaryMonitor._sender(fake, SHELVE, gid)[1] is None  # asked again at most 2 Hz
    fake._graph_read.clear()
    publisher, node = CatenaryMonitor._sender(fake, SHELVE, gid)
    assert node == '/catenary_console_a' and publisher.startswith('/catenary_console_a gid 00')


#: A publisher's GID in a record's ``publisher``: ``/NODE gid 01.0f...`` once the graph names
#: it, ``gid 01.0f... (not on the ROS graph)`` before (under load, a publisher's first messages).
_GID = re.compile(r'gid ((?:[0-9a-f]{2}\.)*[0-9a-f]{2})')


def _gid(event: object) -> str:
    """The GID of the publisher of a recorded request ('' for none), named or not yet."""
    found = _GID.search(getattr(event, 'publisher', '') or '')
    return found.group(1) if found else ''


def _own_gids(node: Any) -> set[str]:
    """The GIDs of ``node``'s request publishers, from its own participant's graph (listed at
    their creation: not waiting on discovery, as the monitor's naming of them does)."""
    name = node.get_name()
    return {
        '.'.join(f'{b:02x}' for b in info.endpoint_gid)
        for topic in (ACK, SHELVE)
        for info in node.get_publishers_info_by_topic(topic)
        if info.node_name == name
    }


def _events(log_dir: Path) -> list:
    from catenary_monitor.core.monitor.events import EVENTS_TOPIC, parse_event_record
    from catenary_monitor.io.cdr import string_text
    from catenary_monitor.io.mcap_read import iter_messages

    files = sorted(log_dir.glob('*.mcap'))
    return [
        parse_event_record(m.log_time_ns, string_text(m.data))
        for m in iter_messages(files, [EVENTS_TOPIC])
    ]


def _start_console(params: Path, out: Path, env: dict[str, str]) -> subprocess.Popen:
    """The operators' console (``catenary_monitor console``) on a free port, its output in
    ``out``."""
    with open(out, 'w') as log:
        return subprocess.Popen(
            [sys.executable, '-m', 'catenary_monitor', 'console', '--params-file', str(params),
             '--port', '0'],
            stdout=log, stderr=subprocess.STDOUT, env=env,
        )  # fmt: skip


def _console_url(proc: subprocess.Popen, out: Path, timeout: float) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = re.search(r'^console: (http://\S+/)', out.read_text(), re.M)
        if found:
            return found.group(1)
        assert proc.poll() is None, out.read_text()
        time.sleep(0.2)
    raise AssertionError(f'no console URL in {timeout} s: {out.read_text()}')


def _post(url: str, path: str, body: dict[str, Any]) -> tuple[int, dict[str, Any]]:
    """POST as the console's page does (its Origin, JSON): (status, the JSON answer)."""
    import json
    import urllib.error
    import urllib.request

    request = urllib.request.Request(
        url + path.lstrip('/'), data=json.dumps(body).encode(), method='POST',
        headers={'Origin': url.rstrip('/'), 'Content-Type': 'application/json'},
    )  # fmt: skip
    try:
        with urllib.request.urlopen(request, timeout=30) as reply:
            return reply.status, json.loads(reply.read())
    except urllib.error.HTTPError as err:
        return err.code, json.loads(err.read() or b'{}')


def _console_gids(node: Any, pid: int) -> set[str]:
    """The GIDs of the console process's request publishers, as the graph lists them."""
    return {
        '.'.join(f'{b:02x}' for b in info.endpoint_gid)
        for topic in (ACK, SHELVE)
        for info in node.get_publishers_info_by_topic(topic)
        if info.node_name == f'catenary_console_{pid}'
    }


@pytest.mark.ros
def test_a_flood_of_requests_costs_a_request_a_second_and_locks_no_operator_out(
    tmp_path: Path,
) -> None:
    """The console (a real ``catenary_monitor console``) acknowledges and shelves mid-flood:
    the flood may push a request out of the monitor's shared queue before it is read, so the
    console resends it (the same id) until the answer shows; each is applied once."""
    import rclpy
    from rclpy.qos import QoSProfile
    from std_msgs.msg import String

    from catenary_monitor.core.monitor.events import Acknowledge, Refusal, Shelve

    params = write_params(tmp_path / 'p.yaml', {'line_01': LINE, 'line_02': LINE})
    log_dir = tmp_path / 'log'
    # a ROS domain of its own: another test's monitor or recorder on the request topics never
    # takes part of the flood's requests. The session's block of 20 from its base b (conftest:
    # workers b+1.., test_harbour's docks a worker's +5, +10, +15): b+18 and b+19 under -n 2,
    # apart from both, and from the next session's block (b+20..) where sessions are 20 apart
    domain = int(os.environ['ROS_DOMAIN_ID']) + 17
    env = {**child_env(), 'ROS_DOMAIN_ID': str(domain)}
    proc = start_monitor(params, log_dir, domain_id=domain)
    console_out = tmp_path / 'console.out'
    console_proc = _start_console(params, console_out, env)
    client = Client('request_flood_client', domain_id=domain)
    tool = rclpy.create_node('request_tool', context=client.context)
    # sends each request once, without an id (as before the console resent): how many a flood
    # takes from the queue before they are read (printed, not asserted: it depends on the load)
    probe = rclpy.create_node('request_probe', context=client.context)
    flooder = None
    try:
        bad_shelve = tool.create_publisher(String, SHELVE, QoSProfile(depth=10))
        bad_ack = tool.create_publisher(String, ACK, QoSProfile(depth=10))
        probe_shelve = probe.create_publisher(String, SHELVE, QoSProfile(depth=10))
        tool_gids, probe_gids = _own_gids(tool), _own_gids(probe)
        assert len(tool_gids) == 2, tool_gids
        url = _console_url(console_proc, console_out, 90.0)
        topics = ['/mooring/line_01/tension', '/mooring/line_02/tension', '/tide/depth']
        client.wait_matched(topics, 60.0)
        for pub in (bad_shelve, bad_ack, probe_shelve):
            client.wait_for(lambda p=pub: p.get_subscription_count() > 0, 30.0, 'the monitor')
        client.feed('/tide/depth', 20.85)
        client.feed('/mooring/line_02/tension', OK_T)
        client.feed('/mooring/line_01/tension', WARN_T)
        client.wait_status('catenary_monitor: line_01', 30.0, level=1)
        # The console's request path works before the flood: an unshelve of nothing, answered
        # (a 503 while its publisher and the monitor still discover each other).
        unshelve = {'line': 'line_02', 'condition': 'all', 'seconds': 0}
        deadline = time.monotonic() + 30.0
        while _post(url, '/api/shelve', unshelve)[0] != 202:
            assert time.monotonic() < deadline, console_out.read_text()
            time.sleep(0.2)
        console_gids = client.wait_for(
            lambda: len(_console_gids(client.node, console_proc.pid)) == 2
            and _console_gids(client.node, console_proc.pid), 30.0, 'the console on the graph'
        )
        # Refused before the rules: each one recorded and answered, none silent.
        # (the first twice with one id: the second a resend of a request taken, changing nothing)
        texts = ('line_01 nan tool #r1', 'line_01 nan tool #r1', 'line_01 inf tool',
                 'line_01 -1 tool', 'nope 60 tool')  # fmt: skip
        for text in texts:
            bad_shelve.publish(String(data=text))
            time.sleep(0.3)
        for text in ('nope tool', '   '):
            bad_ack.publish(String(data=text))
            time.sleep(0.3)
        client.wait_for(lambda: output_of(proc).count('refused') >= 6, 10.0, 'the refusals')
        # The flood: a shelf toggled on and off, 1,000 requests a second for 10 s.
        flooder = subprocess.Popen(
            [sys.executable, str(HERE / 'request_flood.py'), SHELVE, '1000', '10',
             'line_01 600 flood', 'line_01 0 flood'],
            stdout=subprocess.PIPE, text=True, env=env,
        )  # fmt: skip
        assert flooder.stdout is not None and flooder.stdout.readline().strip() == 'matched'
        t0 = time.monotonic()
        lines0 = len(output_of(proc).splitlines())
        time.sleep(0.5)
        for k in range(PROBES):
            probe_shelve.publish(String(data=f'line_02.sensor_warn 0 probe {k}'))
            time.sleep(0.25)
        # The console, mid-flood: an acknowledgement (202 at once, resent until the line's
        # alarm shows it acknowledged) and a shelf (202 with the monitor's answer).
        acked = _post(url, '/api/ack', {'line': 'line_01'})
        shelved = _post(url, '/api/shelve', {'line': 'line_02', 'condition': 'anchor_margin',
                                             'seconds': 60})  # fmt: skip
        client.wait_for(
            lambda: 'ACKNOWLEDGED line_01 by console' in output_of(proc), 10.0, 'the ack'
        )
        out, _ = flooder.communicate(timeout=60)
        t1 = time.monotonic()
        sent = int(out.split()[-1])
        time.sleep(1.5)
        text = output_of(proc)
        during = text.splitlines()[lines0:]
        arrays = [t for t, _ in client.diagnostics if t0 <= t <= t1]
        answer = client.latest_status('catenary_monitor: alarms')
    finally:
        if flooder is not None and flooder.poll() is None:
            flooder.terminate()
        tool.destroy_node()
        probe.destroy_node()
        client.close()
        console_code = stop(console_proc, sig=2)
        code = stop(proc, sig=2)
    assert code == 0, output_of(proc)
    assert console_code == 0, console_out.read_text()
    seconds = t1 - t0
    print(f'{sent} requests in {seconds:.1f} s: {len(arrays)} /diagnostics arrays, '
          f'{len(during)} log lines')  # fmt: skip
    assert sent > 5000
    assert (len(arrays) - PROBES) / seconds < 5.0, len(arrays)  # 1 Hz ticks, a request a second
    assert len(during) < 60, '\n'.join(during[:80])
    # The console was heard mid-flood, named by its own GID, each request applied once
    # (a resend of one already taken changes nothing).
    assert acked[0] == 202 and acked[1]['sent'].startswith('line_01 console '), acked
    assert shelved[0] == 202, shelved
    shelf = 'line_02.anchor_margin shelved for 60 s by console '
    assert (shelved[1]['answer'] or '').startswith(shelf), (shelved, text)
    heard = [t for t in text.splitlines() if 'ACKNOWLEDGED line_01 by console' in t]
    assert len(heard) == 1 and f'(/catenary_console_{console_proc.pid} gid ' in heard[0], text
    heard = [t for t in text.splitlines() if f'SHELVE {shelf}' in t]
    assert len(heard) == 1 and f'(/catenary_console_{console_proc.pid} gid ' in heard[0], text
    # The flood's answer, and no alarm raised by it (the warning was raised once, before).
    assert answer is not None and 'over the rate limit' in answer['values']['shelve_answer']
    events = [e for e in _events(log_dir) if e is not None]
    # Each sender by its GID, named by the graph or not yet (under load the monitor may take a
    # publisher's first messages before its graph names it): the console's and the tool's from
    # their own graph, the flood's one publisher by its name; nobody else took part.
    sent_by = [e for e in events if _gid(e)]
    unnamed = sum('not on the ROS graph' in e.publisher for e in sent_by)
    print(f'{len(sent_by)} records of requests, {unnamed} of a publisher not named yet')
    flooder = {_gid(e) for e in sent_by if '/request_flooder' in e.publisher}
    names = Counter(e.publisher.partition(' gid ')[0] or 'by GID alone' for e in sent_by)
    assert len(flooder) == 1 and not flooder & (tool_gids | console_gids), (flooder, names)
    assert not any('_UNKNOWN_' in name for name in names), names  # never the placeholder
    assert {_gid(e) for e in sent_by} <= flooder | tool_gids | console_gids | probe_gids
    flood = [e for e in sent_by if isinstance(e, (Shelve, Refusal)) and _gid(e) in flooder]
    admitted = [e for e in flood if isinstance(e, Shelve)]
    refused = [e for e in flood if isinstance(e, Refusal)]
    assert BURST <= len(admitted) <= BURST + seconds + 3, len(admitted)
    assert len(refused) <= seconds / REPORT_EVERY + 3, refused
    # Every request of the flood is accounted for: taken, or refused and counted.
    assert len(admitted) + sum(e.requests for e in refused) == sent
    # The console's: its unshelve of nothing, the acknowledgement and the shelf, each once; and
    # the sends of them lost behind the flood before they were read, counted (refused).
    console_sent = Counter(type(e) for e in sent_by if _gid(e) in console_gids)
    assert console_sent[Acknowledge] == 1 and console_sent[Shelve] == 2, console_sent
    assert set(console_sent) <= {Acknowledge, Shelve, Refusal}, console_sent
    lost = sum(e.requests for e in sent_by if _gid(e) in console_gids and isinstance(e, Refusal))
    taken = sum(1 for e in sent_by if _gid(e) in probe_gids and isinstance(e, Shelve))
    print(f'the console: 2 of 2 requests applied, {lost} sends lost behind the flood and resent;'
          f' sent once without an id: {taken} of {PROBES} taken')
    # Refused before the rules: recorded as refusals (or by the rules: the unknown alarm).
    tools = [e for e in sent_by if _gid(e) in tool_gids]
    reasons = [e.reason for e in tools if isinstance(e, Refusal)]
    assert len(reasons) == 5, reasons  # nan, inf, -1, the unknown line, the empty ack
    assert any('nope' == e.alarm for e in tools if isinstance(e, Shelve))  # the rules refuse
    from catenary_monitor.replay.driver import expand, load_config, replay_log

    replay = replay_log(expand([str(log_dir)]), load_config(str(params)), ticks='log')
    journal = replay.result.alarm_events
    assert sum(1 for e in journal if e.kind == 'refused') >= 6 + len(refused)
    raised = [e for e in journal if e.kind == 'raised' and e.alarm == 'line_01']
    assert len(raised) == 1, raised

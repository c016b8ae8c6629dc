"""The harbour without ROS: ``--dock`` parsing, each dock's view from its ``/diagnostics``
(levels, the silent monitor, first out), the harbour-wide alarm list, and the HTTP server's
routes and policy (the console's: Host check, read-only, tokens) over a source fed by hand.
"""

from __future__ import annotations

import json
import subprocess
import sys
import urllib.error
import urllib.request
from typing import Any

import pytest
from ros_harness import child_env

from catenary_monitor.console.frames import Status
from catenary_monitor.console.harbour_model import (
    DockSpec,
    DockState,
    dock_view,
    harbour_alarms,
    parse_console_url,
    parse_discovery_server,
    parse_dock,
)
from catenary_monitor.console.harbour_server import HarbourServer
from catenary_monitor.console.harbour_source import HarbourSource
from catenary_monitor.console.operators import Operators

T0 = 1.8e9  # s, a wall-clock time
TOKEN = 'a1b2c3d4e5f6a7b8c9d0e1f2'


def line(level: str = 'OK', state: str = 'normal', raised: float = float('nan'), **kw: Any):
    values = {
        'uplift_force': '0.0',
        'anchor_margin': '12.5',
        'time_to_uplift': 'inf',
        'alarm_state': state,
        'alarm_raised': repr(raised),
    }
    values.update({k: str(v) for k, v in kw.items()})
    return Status(level, f'{level.lower()} message', values)


def statuses(**lines: Status) -> dict[str, Status]:
    out = dict(lines)
    out['tide'] = Status('OK', 'depth 20.85 m', {'depth': '20.85'})
    return out


@pytest.mark.parametrize(
    'text, expected',
    [
        ('north=85', DockSpec('north', 85)),
        ('n.1=0:/etc/p.yaml', DockSpec('n.1', 0, '/etc/p.yaml')),
        ('d_2=232@32.3,-64.8', DockSpec('d_2', 232, None, 32.3, -64.8)),
        ('d=7:p.yaml@-1.5,170', DockSpec('d', 7, 'p.yaml', -1.5, 170.0)),
    ],
)
def test_dock_option(text, expected):
    assert parse_dock(text) == expected


@pytest.mark.parametrize(
    'text, words',
    [
        ('north', 'NAME=DOMAIN_ID'),
        ('=5', 'NAME'),
        ('a b=5', 'NAME'),
        ('north=233', '0 to 232'),
        ('north=x', '0 to 232'),
        ('north=-1', '0 to 232'),
        ('north=5@91,0', 'latitude'),
    ],
)
def test_bad_dock_option_is_one_line(text, words):
    with pytest.raises(ValueError, match=words) as err:
        parse_dock(text)
    assert '\n' not in str(err.value)


def test_console_url_option():
    assert parse_console_url('a=https://dock-a.local:8080/') == ('a', 'https://dock-a.local:8080/')
    for bad in ('a=javascript:alert(1)', 'a=ftp://x/', 'a', 'a=http://'):
        with pytest.raises(ValueError):
            parse_console_url(bad)


def test_discovery_server_option():
    assert parse_discovery_server('a=10.0.21.5:11811') == ('a', '10.0.21.5:11811')
    assert parse_discovery_server('b=;[::1]:11812') == ('b', ';[::1]:11812')  # server id 1
    for bad in ('a', 'a=', 'a=;', 'a=x y:1', 'a=$(reboot)', '=1.2.3.4:11811'):
        with pytest.raises(ValueError):
            parse_discovery_server(bad)


def test_a_dock_never_heard_is_stale_and_says_so():
    view = dock_view(DockSpec('a', 81), DockState(T0), T0 + 4.0)
    assert view['level'] == 'STALE' and view['monitor_alive'] is False
    assert view['status_age_s'] is None and view['lines'] == []
    assert 'no /diagnostics from the monitor in domain 81' in view['message']


def test_an_ok_dock_then_a_silent_one():
    spec, state = DockSpec('a', 81), DockState(T0)
    for k in range(5):  # 2 Hz: the period is learned from the gaps (1 Hz until three came)
        state.feed(T0 + 0.5 * k, statuses(l1=line(), l2=line(anchor_margin=7.5)), 400)
    view = dock_view(spec, state, T0 + 2.1)
    assert view['level'] == 'OK' and view['monitor_alive'] is True
    assert view['status_age_s'] == pytest.approx(0.1)
    assert view['silence_limit_s'] == pytest.approx(2.0)
    assert [ln['name'] for ln in view['lines']] == ['l1', 'l2']
    assert view['worst_anchor_margin'] == 7.5 and view['worst_anchor_margin_line'] == 'l2'
    assert view['time_to_uplift'] is None and view['lines'][0]['time_to_uplift_state'] == (
        'not coming'
    )
    assert view['received'] == {'arrays': 5, 'bytes': 2000, 'first': T0}
    silent = dock_view(spec, state, T0 + 4.5)
    assert silent['level'] == 'STALE' and silent['monitor_alive'] is False
    assert silent['last_level'] == 'OK'
    assert silent['level_since'] == pytest.approx(T0 + 2.0 + 2.0)
    assert [ln['level'] for ln in silent['lines']] == ['STALE', 'STALE']
    assert [ln['last_level'] for ln in silent['lines']] == ['OK', 'OK']
    assert silent['message'].startswith('monitor silent: no /diagnostics for 2 s')
    rows = harbour_alarms([view, silent])
    assert [(r['dock'], r['state']) for r in rows] == [('a', 'monitor silent')]


def test_a_params_file_gives_the_period_and_lines(tmp_path):
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.sim.scenario import default_config_path

    config = config_from_params(load_params_file(default_config_path()))
    spec = DockSpec('a', 81, config=config)
    state = DockState(T0, spec.period)
    state.feed(T0, statuses(line_01=line()), 100)
    view = dock_view(spec, state, T0 + 0.5)
    assert view['silence_limit_s'] == 2.0 / config.alarm.diagnostic_rate + 1.0
    assert len(view['lines']) == len(config.lines)
    missing = view['lines'][1]
    assert missing['level'] == 'OK' or missing['message'] == "not in the monitor's /diagnostics"


def test_error_dock_first_out_and_returned_alarms():
    spec, state = DockSpec('b', 82), DockState(T0)
    sensors = Status('OK', 'every sensor reporting', {'alarm_state': 'returned-unacknowledged',
                                                      'alarm_raised': repr(T0 - 100)})
    lifted = line('ERROR', 'unacknowledged', T0 - 5, uplift_force=1.5e5, anchor_margin=-3.0,
                  time_to_uplift=0.0)
    warned = line('WARN', 'acknowledged', T0 - 20, anchor_margin=2.0, time_to_uplift=1800.0)
    state.feed(T0, statuses(l1=lifted, l2=warned, sensors=sensors), 900)
    view = dock_view(spec, state, T0 + 0.2)
    assert view['level'] == 'ERROR' and view['level_since'] == T0
    assert view['lines_in_alarm'] == ['l1', 'l2']
    assert view['worst_uplift_force'] == 1.5e5 and view['worst_uplift_line'] == 'l1'
    assert view['time_to_uplift'] == 0.0 and view['time_to_uplift_line'] == 'l1'
    # the earliest alarm still in alarm (l2), not the sensors' returned one
    assert view['first_out'] == 'l2' and view['first_out_source'] == 'earliest'
    assert {a['line']: a['first_out'] for a in view['alarms']} == {
        'l1': False, 'l2': True, 'sensors': False
    }
    # in a flood the monitor's own first out
    flood = Status('WARN', 'ALARM FLOOD', {'flood': 'true', 'first_out': 'l1'})
    state.feed(T0 + 0.5, statuses(l1=lifted, l2=warned, alarms=flood), 900)
    view = dock_view(spec, state, T0 + 0.6)
    assert view['first_out'] == 'l1' and view['first_out_source'] == 'flood'
    assert view['flood'] is True and view['level_since'] == T0
    quiet = DockState(T0)
    quiet.feed(T0, statuses(l1=line()), 100)
    rows = harbour_alarms([dock_view(DockSpec('a', 81), quiet, T0 + 0.1), view])
    assert (rows[0]['dock'], rows[0]['line'], rows[0]['first_out']) == ('b', 'l1', True)


def test_a_component_status_is_a_row_of_its_dock():
    """The tide's impossible depth (a component status, acknowledged as a line's alarm) is a
    row of the dock's alarms and of the harbour's list, with its state."""
    spec, state = DockSpec('c', 83), DockState(T0)
    tide = Status('ERROR', 'impossible depth 0.30 m', {
        'alarm_state': 'unacknowledged', 'acknowledged': 'false', 'alarm_raised': repr(T0 - 3),
    })  # fmt: skip
    state.feed(T0, dict(statuses(l1=line()), tide=tide), 300)
    view = dock_view(spec, state, T0 + 0.2)
    rows = [(r['line'], r['kind'], r['state']) for r in view['alarms']]
    assert rows == [('tide', 'component', 'unacknowledged')]
    assert view['first_out'] == 'tide' and harbour_alarms([view])[0]['line'] == 'tide'


def test_the_issue_keys_of_api_docks():
    state = DockState(T0)
    state.feed(T0, statuses(l1=line()), 100)
    view = dock_view(DockSpec('a', 81), state, T0 + 0.1)
    assert set(view) >= {
        'name', 'domain_id', 'level', 'monitor_alive', 'status_age_s', 'lines', 'alarms'
    }
    assert set(view['lines'][0]) >= {'level', 'uplift_force', 'anchor_margin', 'time_to_uplift'}


# ---------------------------------------------------------------- the server, no ROS
def _get(url: str, host: str = '') -> tuple[int, Any]:
    req = urllib.request.Request(url, headers={'Host': host} if host else {})
    try:
        with urllib.request.urlopen(req, timeout=10) as res:
            return res.status, json.loads(res.read() or b'null')
    except urllib.error.HTTPError as err:
        return err.code, json.loads(err.read())


def _post(url: str, body: dict, token: str = '') -> tuple[int, Any]:
    headers = {'Content-Type': 'application/json'}
    if token:
        headers['Authorization'] = f'Bearer {token}'
    req = urllib.request.Request(url, json.dumps(body).encode(), headers, method='POST')
    try:
        with urllib.request.urlopen(req, timeout=10) as res:
            return res.status, json.loads(res.read())
    except urllib.error.HTTPError as err:
        return err.code, json.loads(err.read())


@pytest.fixture
def fed_source() -> HarbourSource:
    source = HarbourSource([DockSpec('a', 81), DockSpec('b', 82, lat=1.0, lon=2.0)])
    source.states['a'].feed(source.started, statuses(l1=line()), 100)
    return source


def test_server_routes_and_read_only_policy(fed_source):
    server = HarbourServer(fed_source, '127.0.0.1', 0)
    server.start()
    try:
        url = server.url
        status, docks = _get(url + 'api/docks')
        assert status == 200 and [d['name'] for d in docks] == ['a', 'b']
        assert docks[1]['level'] == 'STALE' and docks[1]['position'] == {'lat': 1.0, 'lon': 2.0}
        status, config = _get(url + 'api/config')
        assert config['mode'] == 'harbour' and config['access'] == 'read-only'
        assert _get(url + 'api/alarms')[0] == 200
        assert _get(url + 'api/frame')[1]['counts']['STALE'] == 1
        with urllib.request.urlopen(url, timeout=10) as res:
            assert b'harbour.js' in res.read()
        assert _get(url + 'static/index.html')[0] == 404  # the console's page is not served
        assert _get(url + 'api/docks', host='evil.example:80')[0] == 421
        status, body = _post(url + 'api/ack', {'dock': 'a', 'line': 'l1'})
        assert status == 403 and 'read-only' in body['error']
    finally:
        server.shutdown()


def test_server_with_operators_acknowledges_through_the_source(fed_source):
    sent: list[tuple[str, str, str]] = []
    fed_source.acknowledge = lambda d, ln, o: sent.append((d, ln, o)) or f'{ln} {o}'
    server = HarbourServer(fed_source, '127.0.0.1', 0, operators=Operators({'alice': TOKEN}))
    server.start()
    try:
        url = server.url
        assert _post(url + 'api/ack', {'dock': 'a', 'line': 'l1'})[0] == 401
        assert _post(url + 'api/ack', {'dock': 'a', 'line': 'l 1'}, TOKEN)[0] == 400
        status, body = _post(url + 'api/ack', {'dock': 'a', 'line': 'l1'}, TOKEN)
        assert status == 202 and body['operator'] == 'alice'
        assert sent[0][:2] == ('a', 'l1') and sent[0][2].startswith('alice via harbour ')
    finally:
        server.shutdown()


@pytest.mark.parametrize(
    'args, words',
    [
        (['--dock', 'a=81', '--dock', 'a=82'], 'given twice'),
        (['--dock', 'a=999'], '0 to 232'),
        (['--dock', 'a=81:/nonexistent/p.yaml'], 'dock a: /nonexistent/p.yaml'),
        (['--dock', 'a=81', '--console-url', 'b=http://x/'], 'no --dock of that name'),
        (['--dock', 'a=81', '--discovery-server', 'b=1.2.3.4:11811'], 'no --dock of that name'),
        (['--dock', 'a=81', '--discovery-server', 'a=x y'], 'expected NAME=ADDRESS:PORT'),
    ],
)
def test_bad_command_lines_exit_2_with_one_line(args, words):
    p = subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'harbour', *args, '--port', '0'],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=120,
    )
    assert p.returncode == 2, p.stderr
    assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr


class _Info:
    gids = 0

    def __init__(self, name: str, namespace: str = '/') -> None:
        self.node_name, self.node_namespace = name, namespace
        _Info.gids += 1
        self.endpoint_gid = [_Info.gids] + [0] * 15  # rclpy's: a list of 16 ints


class _Graph:
    """Stands in for the dock's node: who publishes /diagnostics."""

    def __init__(self, *infos: _Info) -> None:
        self.infos = list(infos)

    def get_publishers_info_by_topic(self, topic: str) -> list[_Info]:
        assert topic == '/diagnostics'
        return self.infos


def test_two_monitors_in_one_domain_make_the_dock_stale(fed_source):
    """Two docks in one domain (or a discovery server matching across domains): their arrays
    cannot be told apart: STALE, both named, a row of its own; a driver's diagnostics and the
    harbour's own node do not count."""
    one = _Graph(_Info('catenary_monitor'), _Info('gauge_driver'), _Info('catenary_monitor', '/x'))
    fed_source.check_publishers('a', one)
    view = fed_source.docks()[0]
    assert view['level'] == 'STALE' and view['monitor_alive'] is True
    assert view['monitors'] == ['/catenary_monitor', '/x/catenary_monitor']
    assert '2 monitors publish /diagnostics in domain 81' in view['message']
    rows = fed_source.frame()['alarms']
    assert (rows[0]['dock'], rows[0]['state']) == ('a', 'monitors mixed')
    fed_source.check_publishers('a', _Graph(_Info('catenary_monitor'), _Info('gauge_driver')))
    assert fed_source.docks()[0]['level'] == 'OK'
    # two docks' monitors of the same name (the default), heard in one domain: two publishers
    fed_source.check_publishers('a', _Graph(_Info('catenary_monitor'), _Info('catenary_monitor')))
    view = fed_source.docks()[0]
    assert view['level'] == 'STALE' and view['monitors'] == ['/catenary_monitor'] * 2


def test_fleet_kpis_per_dock_and_day(tmp_path):
    """Alarms per 10 min, time in alarm and fatigue from a dataset the fleet's writers wrote;
    a dock not in it has none; a damaged file is one line, not a traceback."""
    from harbour_data import EXPECTED, write_kpi_dataset

    from catenary_monitor.console.harbour_fleet import FleetKpis, dock_kpis

    root = write_kpi_dataset(tmp_path / 'results')
    got = dock_kpis(root, 'north')
    assert [k['day'] for k in got] == [e['day'] for e in EXPECTED]
    for k, e in zip(got, EXPECTED):
        assert k == pytest.approx(e), k['day']
    assert dock_kpis(root, 'south') == []
    kpis = FleetKpis(str(root), ['north', 'south'])
    source = HarbourSource([DockSpec('north', 81), DockSpec('south', 82)], kpis=kpis)
    views = source.docks()
    assert views[0]['kpis'][-1]['alarms'] == 3 and views[1]['kpis'] == []
    bad = next((root / 'daily' / 'dock=north').glob('date=*/part-0.parquet'))
    bad.write_bytes(b'not parquet')
    error = FleetKpis(str(root), ['north'])()['north']['error']
    assert error.startswith(f'fleet dataset {root}: ') and '\n' not in error


def test_fleet_dataset_option_refuses_a_folder_that_is_not_one(tmp_path):
    p = subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'harbour', '--dock', 'a=81',
         '--fleet-dataset', str(tmp_path), '--port', '0'],
        capture_output=True, text=True, env=child_env(), timeout=120,
    )  # fmt: skip
    assert p.returncode == 2 and 'no daily/ folder there' in p.stderr

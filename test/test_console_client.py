"""Acknowledging from a program: a request with an operator's bearer token and no ``Origin``
(which every browser sends with a POST) is a program's, accepted (202) in that operator's name
on a console with a token file; without a token 401; a browser's request from another origin is
still 403. ``catenary-monitor ack`` / ``shelve`` are such programs (the button of
docs/deploy.md). The console here serves a stub source in this process; test_install.py runs the
real monitor and console from their systemd units and acknowledges through them."""

from __future__ import annotations

import json
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any, Optional

import pytest

from catenary_monitor.cli.main import main
from catenary_monitor.console.operators import load_operators
from catenary_monitor.console.server import ConsoleServer

ALICE = 'a1b2c3d4e5f6a7b8c9d0'


class Source:
    """A live source: line_11's alarm stands for ``uplift``; acknowledgements and shelving
    requests are recorded, the monitor's answer to a shelving request made up."""

    mode = 'live'

    def __init__(self) -> None:
        self.acks: list[tuple[str, str]] = []
        self.shelves: list[tuple[str, str, float, str]] = []

    def config_json(self) -> dict[str, Any]:
        return {'mode': 'live', 'lines': []}

    def frame(self, t: Optional[float] = None) -> dict[str, Any]:
        return {'now': time.time(), 'alarms': [{'line': 'line_11', 'condition': 'uplift'}]}

    def trend(self, line: str, t: Optional[float], span: float) -> dict[str, Any]:
        return {'line': line}

    def acknowledge(self, line: str, origin: str) -> str:
        self.acks.append((line, origin))
        return f'{line} {origin}'

    def shelve(self, alarm: str, condition: str, seconds: float, origin: str) -> dict[str, Any]:
        self.shelves.append((alarm, condition, seconds, origin))
        return {'sent': f'{alarm} {seconds:g} {origin}', 'answer': f'{alarm}: shelved'}

    def wait(self, version: int, timeout: float) -> int:
        time.sleep(min(timeout, 0.05))
        return version + 1


@pytest.fixture
def console(tmp_path: Path) -> Any:
    tokens = tmp_path / 'operators'
    tokens.write_text(f'alice:{ALICE}\nbob:ffeeddccbbaa99887766\n')
    tokens.chmod(0o600)
    source = Source()
    server = ConsoleServer(source, '127.0.0.1', 0, operators=load_operators(str(tokens))[0])
    server.start()
    yield server, source
    server.shutdown()


def post(url: str, path: str, body: dict[str, Any], **headers: str) -> tuple[int, Any]:
    """What curl sends: no Origin unless given."""
    request = urllib.request.Request(
        url.rstrip('/') + path, json.dumps(body).encode(),
        {'Content-Type': 'application/json', **headers},
    )  # fmt: skip
    try:
        with urllib.request.urlopen(request, timeout=10) as reply:
            return reply.status, json.loads(reply.read())
    except urllib.error.HTTPError as err:
        return err.code, json.loads(err.read())


def test_a_program_with_a_token_acts_in_its_operators_name(console):
    server, source = console
    bearer = {'Authorization': f'Bearer {ALICE}'}
    assert post(server.url, '/api/ack', {'line': 'line_11'})[0] == 401
    assert post(server.url, '/api/ack', {'line': 'line_11'},
                Authorization='Bearer wrong-token-0000000000')[0] == 401  # fmt: skip
    other = f'http://evil.example:{server.port}'
    assert post(server.url, '/api/ack', {'line': 'line_11'}, Origin=other, **bearer)[0] == 403
    assert source.acks == []
    status, answer = post(server.url, '/api/ack', {'line': 'line_11'}, **bearer)
    assert (status, answer['operator']) == (202, 'alice')
    assert source.acks == [('line_11', f'alice via console {server.hostname} client 127.0.0.1')]


def test_without_a_token_file_a_program_is_refused(tmp_path):
    source = Source()
    server = ConsoleServer(source, '127.0.0.1', 0)
    server.start()
    try:
        status, answer = post(server.url, '/api/ack', {'line': 'line_11'})
        assert status == 403 and 'Origin' in answer['error']
    finally:
        server.shutdown()
    assert source.acks == []


def _token(tmp_path: Path, text: str) -> str:
    path = tmp_path / 'button.token'
    path.write_text(text)
    path.chmod(0o600)
    return str(path)


def test_catenary_monitor_ack_and_shelve(console, tmp_path, capsys):
    server, source = console
    where = ['--console', server.url, '--token-file']
    # the token alone, or the operator's NAME:TOKEN line
    assert main(['ack', 'line_11', *where, _token(tmp_path, f'{ALICE}\n')]) == 0
    assert capsys.readouterr().out.startswith('acknowledged line_11 as alice: line_11 alice via')
    token = _token(tmp_path, '# the button\nbob:ffeeddccbbaa99887766\n')
    assert main(['ack', 'line_11', '--condition', 'uplift', *where, token]) == 0
    assert 'as bob' in capsys.readouterr().out
    assert main(['ack', 'line_11', '--condition', 'stale', *where, token]) == 1
    assert "the alarm of line_11 stands for 'uplift', not 'stale'" in capsys.readouterr().err
    assert main(['ack', 'line_03', '--condition', 'uplift', *where, token]) == 1
    assert 'line_03 has no alarm' in capsys.readouterr().err
    assert [a[0] for a in source.acks] == ['line_11', 'line_11']
    assert main(['shelve', 'line_11', '--condition', 'anchor_margin', '--minutes', '30', *where,
                 token]) == 0  # fmt: skip
    assert capsys.readouterr().out.strip() == 'shelving line_11 as bob: line_11: shelved'
    assert source.shelves[0][:3] == ('line_11', 'anchor_margin', 1800.0)
    # refusals: one line each, never the token
    assert main(['ack', 'line_11', *where, _token(tmp_path, 'wrong-token-0000000000\n')]) == 1
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'refused (401)' in err and 'wrong-token' not in err
    assert main(['ack', 'line_11', *where, str(tmp_path / 'missing')]) == 2
    assert 'cannot read the token file' in capsys.readouterr().err
    assert main(['ack', 'line_11', '--console', 'http://127.0.0.1:1/', '--token-file',
                 token]) == 1  # fmt: skip
    assert 'cannot reach the console' in capsys.readouterr().err

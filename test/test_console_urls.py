"""The console prints every URL it is reached at: bound to 0.0.0.0, this PC's loopback first, then
each interface's address (compared with what the kernel routes by and with ``hostname -I``),
and each printed URL serves the page."""

from __future__ import annotations

import re
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest
from browser_harness import stop
from ros_harness import child_env

from catenary_monitor.console.addresses import reachable_urls

ROOT = Path(__file__).resolve().parents[1]


def _outward_address() -> str | None:
    """The address this PC sends from toward another network (a UDP connect sends nothing)."""
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sock.connect(('198.51.100.1', 9))
            return str(sock.getsockname()[0])
    except OSError:
        return None


def test_bound_to_all_interfaces_every_address_is_printed_and_serves(tmp_path):
    out = tmp_path / 'console.out'
    with open(out, 'w') as log:
        proc = subprocess.Popen(
            [sys.executable, '-m', 'catenary_monitor', 'console', '--params-file',
             str(ROOT / 'config/floating_dock.yaml'), '--bind', '0.0.0.0', '--port', '0',
             '--read-only'],
            stdout=log, stderr=subprocess.STDOUT, env=child_env(),
        )  # fmt: skip
    try:
        deadline = time.monotonic() + 90.0
        while 'console: http' not in out.read_text() and time.monotonic() < deadline:
            assert proc.poll() is None, out.read_text()
            time.sleep(0.2)
        time.sleep(0.5)  # the other lines follow at once
        text = out.read_text()
        urls = re.findall(r'^console: (?:also at )?(http://\S+)', text, re.M)
        assert urls and urls[0].startswith('http://127.0.0.1:'), text
        port = int(urls[0].rstrip('/').rsplit(':', 1)[1])
        hosts = [u.split('//')[1].rsplit(':', 1)[0] for u in urls]
        assert len(set(hosts)) == len(hosts)
        outward = _outward_address()
        if outward:
            assert outward in hosts, (outward, text)
        if shutil.which('hostname'):
            listed = subprocess.run(['hostname', '-I'], capture_output=True, text=True).stdout
            for address in listed.split():
                if '.' in address:  # IPv4: what 0.0.0.0 listens on
                    assert address in hosts, (address, text)
        for url in urls:
            with urllib.request.urlopen(url, timeout=10) as reply:
                assert reply.status == 200 and b'<html' in reply.read().lower(), url
        assert urls == reachable_urls('http', '0.0.0.0', port)
    finally:
        assert stop(proc) == 0


@pytest.mark.parametrize(
    'bind, first',
    [('127.0.0.2', 'http://127.0.0.2:8080/'), ('::1', 'http://[::1]:8080/')],
)
def test_bound_to_one_address_that_one_is_the_url(bind, first):
    assert reachable_urls('http', bind, 8080) == [first]

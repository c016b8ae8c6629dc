"""The console against a hostile page and an impatient operator, in Debian's Chromium.

A page served from another localhost port, open in the operator's browser, tries to smuggle an
acknowledgement to the console (a cross-origin POST whose body ends with a whole acknowledgement
request carrying the console's own Host and Origin): nothing reaches the monitor. The console
page is reloaded 50 times (its event stream cut under the writer each time): the console process
lives on and the page still acknowledges. Then a console bound to 127.0.0.2 with a token file:
the page is read-only, an acknowledgement without a token is refused, the operator signs in
with the form and the acknowledgement reaches the monitor with the operator's name.

A ROS subscription on ``/catenary_monitor/acknowledge`` stands in for the monitor: it sees what
the console would have acknowledged.
"""

from __future__ import annotations

import threading
import time
from functools import partial
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest
from browser_harness import PARAMS, AckRecorder, browser, start_console, stop, wait_for

from catenary_monitor.core.alarms.requests import split_id

pytestmark = [pytest.mark.ros]

_EVIL = """<!DOCTYPE html><html><body><script>
const port = %(port)d, target = `http://127.0.0.1:${port}`;
const good = '{"line":"line_11"}';
const inner = `POST /api/ack HTTP/1.1\\r\\nHost: 127.0.0.1:${port}\\r\\n` +
  `Origin: http://127.0.0.1:${port}\\r\\nContent-Type: application/json\\r\\n` +
  `Content-Length: ${good.length}\\r\\n\\r\\n${good}`;
const tries = [4096, 100, 0].map((n) => fetch(`${target}/api/ack`, {
  method: 'POST', mode: 'no-cors', headers: { 'Content-Type': 'text/plain' },
  body: 'x'.repeat(n) + inner }).then(() => 'sent', (e) => String(e)));
tries.push(fetch(`${target}/api/ack`, { method: 'POST', mode: 'no-cors',
  headers: { 'Content-Type': 'application/x-www-form-urlencoded' }, body: 'line=line_11' })
  .then(() => 'sent', (e) => String(e)));
Promise.all(tries).then((r) => { document.title = 'done ' + r.join(','); });
</script></body></html>
"""


def _serve_evil(folder: Path, console_port: int) -> ThreadingHTTPServer:
    (folder / 'index.html').write_text(_EVIL % {'port': console_port})
    handler = partial(SimpleHTTPRequestHandler, directory=str(folder))
    httpd = ThreadingHTTPServer(('127.0.0.1', 0), handler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    return httpd


def _port(url: str) -> int:
    return int(url.rstrip('/').rsplit(':', 1)[1])


def _page_ready(driver: Any) -> bool:
    return bool(driver.execute_script('return !!(window.cmConsole && cmConsole.config)'))


def test_hostile_page_reloads_and_operator_sign_in(tmp_path: Path) -> None:
    recorder = AckRecorder()
    driver = browser(tmp_path)
    evil_dir = tmp_path / 'evil'
    evil_dir.mkdir()
    console, url = start_console(['--params-file', str(PARAMS)], tmp_path / 'console.out')
    tokens = tmp_path / 'operators'
    tokens.write_text('alice:a1b2c3d4e5f6a7b8c9d0\n')
    tokens.chmod(0o600)
    guarded, gurl = start_console(
        ['--params-file', str(PARAMS), '--bind', '127.0.0.2', '--token-file', str(tokens)],
        tmp_path / 'guarded.out',
    )
    evil = _serve_evil(evil_dir, _port(url))
    try:
        recorder.wait_for_publisher()
        # 1. the hostile page on another port: four tries, nothing acknowledged
        driver.get(f'http://127.0.0.1:{evil.server_address[1]}/')
        wait_for('the hostile page\'s requests', lambda: driver.title.startswith('done'), 20.0)
        time.sleep(1.0)
        assert recorder.messages == [], recorder.messages
        # 2. 50 reloads of the console page, each cutting its event stream
        driver.get(url)
        for _ in range(50):
            wait_for('the console page', lambda: _page_ready(driver), 20.0, every=0.05)
            driver.refresh()
        wait_for('the console page', lambda: _page_ready(driver), 20.0)
        assert console.poll() is None, (tmp_path / 'console.out').read_text()
        # the page acknowledges (the recorder would have seen a smuggled one)
        status = driver.execute_async_script(
            "const done = arguments[0]; act('/api/ack', {line: 'line_11'})"
            '.then((r) => done(r.status));'
        )
        assert status == 202
        recorder.wait(1)
        assert recorder.messages[0].startswith('line_11 console '), recorder.messages
        # 3. tokens: read-only until the operator signs in; then attributed
        driver.get(gurl)
        wait_for('the guarded page', lambda: _page_ready(driver), 20.0)
        button = driver.find_element('id', 'operator')
        assert button.is_displayed() and button.text == 'read-only: sign in'
        assert driver.execute_script('return canAct()') is False
        assert not driver.find_element('id', 'ack-all').is_enabled()
        status = driver.execute_async_script(
            "const done = arguments[0]; act('/api/ack', {line: 'line_11'})"
            '.then((r) => done(r.status));'
        )
        assert status == 401
        button.click()
        driver.find_element('id', 'token').send_keys('a1b2c3d4e5f6a7b8c9d0')
        driver.find_element('id', 'signin-go').click()
        wait_for('signed in', lambda: button.text == 'alice · sign out', 10.0)
        assert driver.execute_script('return canAct()') is True
        status = driver.execute_async_script(
            "const done = arguments[0]; act('/api/ack', {line: 'line_11'})"
            '.then((r) => done(r.status));'
        )
        assert status == 202
        recorder.wait(2)
        assert recorder.messages[1].startswith('line_11 alice via console '), recorder.messages
        text, rid = split_id(recorder.messages[1])  # the request's id ends it
        assert text.endswith(' client 127.0.0.1') and len(rid) == 12, recorder.messages
        assert 'a1b2c3d4' not in driver.current_url
    finally:
        evil.shutdown()
        driver.quit()
        recorder.close()
        codes = stop(console), stop(guarded)
    assert codes == (0, 0)
    for out in ('console.out', 'guarded.out'):
        text = (tmp_path / out).read_text()
        assert 'Traceback' not in text and 'a1b2c3d4' not in text, text

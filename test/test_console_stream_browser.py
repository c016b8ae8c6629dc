"""The page's live stream under attack, in Chromium: a flood of streams on the console's port
does not keep the page from its data, and whenever the stream is refused or cut the page says
so (banner, STALE tiles, the loss-of-monitoring tone) and recovers by itself once the attacker
leaves. (EventSource gave up after a 503: the page stayed at "connecting..." with no banner and
no sound, 15 s after the attacker had left.)

The page is served from the demo's state without ROS (``browser_harness.DemoSource``); a
refusal is what the console answered beyond its stream bound before the bound evicted the
oldest unauthenticated stream (503), made here on purpose.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pytest
from browser_harness import LOST, DemoSource, browser, tiles, wait_for
from test_console_limits import open_stream

from catenary_monitor.console.http_transport import HttpError, Response
from catenary_monitor.console.server import ConsoleServer

pytestmark = [pytest.mark.slow]

BANNER = "return document.getElementById('banner').textContent"
BEEPS = 'return cmConsole.beeps'


class Refusing:
    """Wraps the server's handler: while ``on``, ``/api/stream`` is refused (503)."""

    def __init__(self, server: ConsoleServer) -> None:
        self.on = False
        self.refused = 0
        self.handle = server.handle
        server.handle = self  # type: ignore[method-assign]

    def __call__(self, request: Any) -> Response:
        if self.on and request.path == '/api/stream':
            self.refused += 1
            raise HttpError(503, 'too many streams', [('Retry-After', '5')])
        return self.handle(request)


def _live(driver: Any) -> bool:
    return bool(
        driver.execute_script(
            'return !!cmConsole.frame && !cmConsole.serverLost && '
            "document.getElementById('banner').hidden"
        )
    )


def _cut_streams(server: ConsoleServer) -> None:
    for conn in list(server.transport.open_streams):
        server.transport.loop.call_soon_threadsafe(conn.abort)


def test_the_page_outlives_a_stream_flood_and_recovers_after_refusals(tmp_path: Path) -> None:
    server = ConsoleServer(DemoSource(), '127.0.0.1', 0)
    gate = Refusing(server)
    server.start()
    driver = browser(tmp_path)
    flood: list = []
    try:
        # 1. 64 streams from the page's own address, then the page: it is served at once
        flood = [open_stream(server.port) for _ in range(64)]
        driver.get(server.url)
        wait_for('the page live under the flood', lambda: _live(driver), 30.0)
        assert tiles(driver).get('line_11') == 'ERROR'
        # 2. the stream cut and refused (503) for 8 s: banner, STALE, the tone
        before = driver.execute_script(BEEPS)
        gate.on = True
        _cut_streams(server)
        wait_for('the lost banner', lambda: driver.execute_script(LOST), 10.0)
        assert set(tiles(driver).values()) == {'STALE'}
        wait_for('the loss tone', lambda: driver.execute_script(BEEPS) > before, 10.0)
        wait_for('the refusal named', lambda: '503' in driver.execute_script(BANNER), 10.0)
        time.sleep(6.0)
        assert gate.refused >= 3  # it kept trying, backing off
        assert gate.refused <= 12  # not hammering the server
        # 3. the attacker leaves: the page recovers by itself
        gate.on = False
        for sock in flood:
            sock.close()
        t0 = time.monotonic()
        wait_for('the page live again', lambda: _live(driver), 15.0)
        recovered = time.monotonic() - t0
        assert tiles(driver).get('line_11') == 'ERROR', recovered
        # 4. a page opened while the stream is refused: no frame yet, and it says so
        gate.on = True
        _cut_streams(server)
        driver.get(server.url)
        banner = wait_for(
            'NO LIVE DATA', lambda: driver.execute_script(LOST) and driver.execute_script(BANNER),
            10.0,
        )  # fmt: skip
        assert 'NO LIVE DATA' in banner and '503' in banner, banner
        wait_for('the loss tone', lambda: driver.execute_script(BEEPS) > 0, 10.0)
        gate.on = False
        wait_for('the new page live', lambda: _live(driver), 15.0)
    finally:
        for sock in flood:
            sock.close()
        driver.quit()
        server.shutdown()

"""The console page in Debian's Chromium: on real screen sizes, when its server dies, without
``--params-file``, and its two tide margins and time to uplift (unknown is not "not coming").

* Screens: the demo's storm (``browser_harness.DemoSource``: a long monitor message, every
  optional value, a load cell's channel rows) at 1280x720, 1366x768, 1920x937 and 2560x1440;
  read from the DOM: no text clipped, no two panels or tiles overlapping, every panel usable
  and reachable; at 1920x937 every tile's level and the alarm list in the window without
  scrolling.
* Server loss: the console process killed (SIGKILL) under the page; the banner shows, a tile's
  age and the clock keep counting by the browser's clock.
* No ``--params-file``: the page loaded before the monitor is heard shows each line as soon as
  ``/diagnostics`` names it, without reload.
"""

from __future__ import annotations

import re
import signal
from pathlib import Path
from typing import Any

import pytest

from browser_harness import (
    LOST,
    PARAMS,
    SCREENS,
    SHOTS,
    DemoSource,
    DiagnosticsPublisher,
    browser,
    layout_problems,
    set_viewport,
    start_console,
    stop,
    tiles,
    wait_for,
)

pytestmark = [pytest.mark.slow]

AGE = "return document.querySelector('.tile[data-line=\"line_01\"] .foot').textContent"
CLOCK = "return document.getElementById('clock').textContent"


def _age(text: str) -> float:
    """Seconds in a tile's foot, 'newest sample 3.4 s ago' (minutes too)."""
    match = re.search(r'newest sample (?:(\d+) min )?([\d.]+) s ago', text)
    assert match, text
    return 60.0 * float(match.group(1) or 0) + float(match.group(2))


@pytest.fixture
def demo_page(tmp_path: Path) -> Any:
    """The page of a console serving the demo's storm (no ROS), in Chromium."""
    from catenary_monitor.console.server import ConsoleServer

    server = ConsoleServer(DemoSource(), '127.0.0.1', 0)
    server.start()
    driver = browser(tmp_path)
    try:
        driver.get(server.url)
        wait_for('12 tiles, line_11 ERROR', lambda: tiles(driver).get('line_11') == 'ERROR', 60.0)
        wait_for(
            'the trend drawn',
            lambda: driver.execute_script("return document.querySelectorAll('#trend path').length")
            == 4,
            30.0,
        )
        yield driver
    finally:
        driver.quit()
        server.shutdown()


def test_page_fits_every_screen(demo_page: Any) -> None:
    driver = demo_page
    SHOTS.mkdir(parents=True, exist_ok=True)
    problems = {}
    for width, height in SCREENS:
        set_viewport(driver, width, height)
        wait_for(
            f'the page at {width}x{height}',
            lambda: driver.execute_script('return [innerWidth, innerHeight]') == [width, height],
            10.0,
        )
        problems[(width, height)] = layout_problems(driver, (width, height) == (1920, 937))
        driver.save_screenshot(str(SHOTS / f'console_{width}x{height}.png'))
    assert not any(problems.values()), problems
    # The tile's message is the alarm's headline (at most 100 characters), all of it shown.
    head = driver.execute_script(
        "return document.querySelector('.tile[data-line=\"line_11\"] .msg').textContent"
    )
    assert head.startswith('anchor uplift 152.3 kN > allowed 0.0 kN (+3 more): ')
    assert len(head) <= 100
    # line_05's load cell: a row per channel, named by its topic's last part, its state
    chans = driver.execute_script(
        "return [...document.querySelectorAll('.tile[data-line=\"line_05\"] .v-ch')]"
        '.map((e) => [e.previousElementSibling.textContent, e.textContent, e.className])'
    )
    assert [c[:2] for c in chans] == [
        ['channel a', 'ok'], ['channel b', 'silent'], ['channel c', 'ok']
    ]  # fmt: skip
    assert 'warn' in chans[1][2] and 'warn' not in chans[0][2]


FIRST_SCREEN = """
const H = innerHeight, W = innerWidth;
const inside = (e) => { const b = e.getBoundingClientRect();
  return b.top >= 0 && b.bottom <= H + 0.5 && b.left >= 0 && b.right <= W + 0.5; };
const rows = [...document.querySelectorAll('#alarms tbody tr')];
const lh = (e) => parseFloat(getComputedStyle(e).fontSize) * 1.6;
return {
  rows: rows.length,
  rows_inside: rows.every(inside),
  one_line: rows.every((r) => r.getBoundingClientRect().height <= lh(r) + 8),
  plan_inside: inside(document.getElementById('plan')),
  response_inside: inside(document.getElementById('response')),
  first_tiles: [...document.querySelectorAll('.tile .badge')].filter(inside).length,
  response: document.querySelector('#response .r-text').textContent,
  response_line: document.getElementById('response').dataset.line,
};
"""


def test_plan_tiles_and_alarm_list_share_the_first_screen(demo_page: Any) -> None:
    """At 1280x720 (a control room's laptop) and 1920x1080: every alarm row one line and in
    the window, the whole dock plan and the first tiles on the first screen without
    scrolling; the selected alarm's response text under the list (a click selects another);
    the ERROR on a dynamic uplift shows that uplift on its tile."""
    driver = demo_page
    for width, height in ((1280, 720), (1920, 1080)):
        set_viewport(driver, width, height)
        wait_for(
            f'the page at {width}x{height}',
            lambda: driver.execute_script('return [innerWidth, innerHeight]') == [width, height],
            10.0,
        )
        seen = driver.execute_script(FIRST_SCREEN)
        # line_11, line_07, line_08, line_10, line_12 and the intake's WARN (a component)
        assert seen['rows'] == 6 and seen['rows_inside'], (width, seen)
        assert seen['plan_inside'] and seen['first_tiles'] >= 3, (width, seen)
        assert seen['response_inside'], (width, seen)
        if width == 1280:
            assert seen['one_line'], seen
        assert seen['response_line'] == 'line_11', seen  # the list's first, unacknowledged
        assert seen['response'].startswith('Cause: the chain pulls its anchor upward'), seen
        assert not layout_problems(driver, width == 1920)
    set_viewport(driver, 1280, 720)
    driver.execute_script(
        "document.querySelector('#alarms tr[data-line=\"line_07\"] td.msg-cell').click()"
    )
    wait_for(
        'line_07 selected',
        lambda: driver.execute_script(FIRST_SCREEN)['response_line'] == 'line_07',
        10.0,
    )
    detail = driver.execute_script(
        "return document.querySelector('#response .r-detail').textContent"
    )
    assert 'warning held' in detail  # the held conditions: in the detail, not the headline
    # line_07's ERROR is on its dynamic uplift: the tile shows it (not the quasi-static 0.0 kN)
    uplift = driver.execute_script(
        "const t = document.querySelector('.tile[data-line=\"line_07\"]');"
        "return [t.querySelector('.k-uplift').textContent,"
        " t.querySelector('.v-uplift').textContent]"
    )
    assert uplift == ['uplift, wave peak', '1.2 kN'], uplift


def test_tide_margins_and_time_to_uplift_on_the_tiles(demo_page: Any) -> None:
    """'tide to lift, R held' (tide_margin) on every tile; 'tide to lift, chain length held'
    (tide_margin_at_length) beside it where finite (line_01 has none). The time to uplift:
    unknown (NaN: the live start's even lines) reads "unknown", "trend not known yet" in its
    title, never "not coming" (inf, the other OK lines); a forecast names the chain-length
    view; a lifted anchor reads "lifted"."""
    rows = demo_page.execute_script(
        "return [...document.querySelectorAll('.tile')].map(t => [t.dataset.line,"
        " [...t.querySelectorAll('.vals dt')].filter(e => e.offsetParent)"
        ".map(e => e.textContent + ' = ' + e.nextElementSibling.textContent)])"
    )
    vals = {line: shown for line, shown in rows}
    assert 'tide to lift, R held = 4.68 m' in vals['line_02']
    assert 'tide to lift, chain length held = 1.05 m' in vals['line_02']
    assert 'tide to lift, R held = -2.10 m' in vals['line_11']
    assert 'tide to lift, chain length held = -0.40 m' in vals['line_11']
    assert 'tide to lift, R held = 4.68 m' in vals['line_01']
    assert not [v for v in vals['line_01'] if 'chain length' in v], vals['line_01']
    order = [v.split(' = ')[0] for v in vals['line_02']]
    beside = order.index('tide to lift, R held') + 1
    assert order.index('tide to lift, chain length held') == beside
    ttu = dict(
        demo_page.execute_script(
            "return [...document.querySelectorAll('.tile')].map(t => [t.dataset.line,"
            " t.querySelector('.v-ttu').textContent + ' | ' + t.querySelector('.v-ttu').title])"
        )
    )
    unknown = 'unknown | time to uplift unknown, trend not known yet: '
    assert ttu['line_02'].startswith(unknown), ttu  # NaN
    assert ttu['line_01'] == 'not coming | time to uplift', ttu  # inf, without chain_length
    assert ttu['line_03'] == 'not coming | time to uplift, chain length held', ttu
    assert ttu['line_10'] == '42 min 0 s (chain length) | time to uplift, chain length held', ttu
    assert ttu['line_11'].startswith('lifted | '), ttu


@pytest.mark.ros
def test_ages_and_clock_keep_counting_when_the_server_dies(tmp_path: Path) -> None:
    publisher = DiagnosticsPublisher([f'line_{k:02d}' for k in range(1, 13)])
    console, url = start_console(['--params-file', str(PARAMS)], tmp_path / 'console.out')
    driver = browser(tmp_path)
    try:
        driver.get(url)
        wait_for('line_01 OK', lambda: tiles(driver).get('line_01') == 'OK', 60.0)
        assert _age(driver.execute_script(AGE)) < 2.5  # fresh while the server serves
        console.send_signal(signal.SIGKILL)
        console.wait(30)
        wait_for('the lost-connection banner', lambda: driver.execute_script(LOST), 20.0)
        first, clock = _age(driver.execute_script(AGE)), driver.execute_script(CLOCK)
        wait_for(
            "line_01's age growing with the server gone",
            lambda: _age(driver.execute_script(AGE)) > first + 2.0,
            20.0,
        )
        assert driver.execute_script(CLOCK) != clock
        assert 'UNREACHABLE' in driver.find_element('id', 'banner').text
        assert set(tiles(driver).values()) == {'STALE'}
    finally:
        driver.quit()
        stop(console)
        publisher.close()


@pytest.mark.ros
def test_lines_learned_from_diagnostics_appear_without_reload(tmp_path: Path) -> None:
    console, url = start_console([], tmp_path / 'console.out')
    driver = browser(tmp_path)
    publisher = None
    try:
        driver.get(url)
        framed = 'return !!cmConsole.frame'
        wait_for('a frame on the page', lambda: driver.execute_script(framed), 60.0)
        assert tiles(driver) == {}
        names = ['bow_port', 'bow_starboard', 'stern']
        publisher = DiagnosticsPublisher(names)
        seen = wait_for(
            'a tile per line named on /diagnostics',
            lambda: tiles(driver) == {n: 'OK' for n in names} and tiles(driver),
            60.0,
        )
        assert list(seen) == names
        plan = driver.execute_script(
            "return [...document.querySelectorAll('[data-plan-line]')]"
            '.map(g => g.dataset.planLine)'
        )
        picker = driver.execute_script(
            "return [...document.getElementById('trend-line').options].map(o => o.value)"
        )
        assert plan == names and picker == names
    finally:
        driver.quit()
        stop(console)
        if publisher is not None:
            publisher.close()

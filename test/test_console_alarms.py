"""Alarm management on the console's page, in Chromium: the monitor's flood banner naming the
first out, the chattering and first-out marks, the shelved list (apart from the active one,
unshelve), the shelve control (through the same policy as an acknowledgement: refused from
another origin) and the monitor's refusal shown to the operator.

The page is served from the demo's storm without ROS (``browser_harness.DemoSource``: line_11
lifted and first out of a flood, line_10 chattering, line_09 shelved); the live path to the
monitor is test_console_browser.py's. A component status leaving OK (the tide's impossible
depth) is listed, its ERROR beeps until an operator acknowledges it, on a quiet dock of its own
(:class:`TideSource`).
"""

from __future__ import annotations

import json
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

import pytest
from browser_harness import DemoSource, browser, rows, tiles, wait_for

pytestmark = [pytest.mark.slow]


@pytest.fixture
def page(tmp_path: Path) -> Any:
    from catenary_monitor.console.server import ConsoleServer

    source = DemoSource()
    server = ConsoleServer(source, '127.0.0.1', 0)
    server.start()
    driver = browser(tmp_path)
    try:
        driver.get(server.url)
        wait_for('12 tiles, line_11 ERROR', lambda: tiles(driver).get('line_11') == 'ERROR', 60.0)
        yield driver, source, server
    finally:
        driver.quit()
        server.shutdown()


def _js(driver: Any, script: str) -> Any:
    return driver.execute_script(script)


def test_flood_first_out_chattering_and_the_shelved_list(page: Any) -> None:
    driver, source, server = page
    script = (
        "const b = document.getElementById('flood-banner');"
        'return !b.hidden && b.dataset.flood && b.textContent'
    )
    banner = wait_for('the flood banner', lambda: _js(driver, script), 20.0)
    assert 'ALARM FLOOD' in banner and 'first out: line_11' in banner
    marks = _js(
        driver,
        "return [...document.querySelectorAll('#alarms tr[data-line]')]"
        '.map(r => [r.dataset.line, r.dataset.firstOut, r.dataset.chattering])',
    )
    assert ['line_11', 'true', 'false'] in marks and ['line_10', 'false', 'true'] in marks
    row = "return document.querySelector('#alarms tr[data-line=\"line_11\"]').textContent"
    assert 'FIRST OUT' in _js(driver, row)
    # A shelved alarm is not in the active list (no sound, not at its top), but listed apart.
    assert 'line_09' not in rows(driver)
    tile = "return document.querySelector('.tile[data-line=\"line_09\"]').dataset.shelved"
    assert _js(driver, tile) == 'true'
    driver.find_element('id', 'tab-shelved').click()
    script = (
        "return [...document.querySelectorAll('#shelved tr[data-shelved-line]')]"
        '.map(r => r.dataset.shelvedLine)'
    )
    shelved = wait_for('the shelved list', lambda: _js(driver, script), 10.0)
    assert shelved == ['line_09']
    assert 'console dockpc' in _js(driver, "return document.getElementById('shelved').textContent")
    # The row is updated in place as frames come (its message changes every frame): the button
    # under the operator's pointer stays the same element (it was rebuilt, and a click lost).
    button = driver.find_element('css selector', '[data-unshelve="line_09"]')
    time.sleep(2.5)
    assert driver.execute_script('return document.contains(arguments[0])', button)
    button.click()
    wait_for('the unshelve request', lambda: source.shelves, 10.0)
    alarm, condition, seconds, origin = source.shelves[-1]
    assert (alarm, condition, seconds) == ('line_09', 'all', 0.0)
    assert origin.startswith('console ') and '127.0.0.1' in origin


def test_shelve_control_sends_what_the_operator_picked_and_shows_refusals(page: Any) -> None:
    driver, source, server = page
    from selenium.webdriver.support.ui import Select

    go = driver.find_element('id', 'shelve-go')
    wait_for('the shelve control enabled', lambda: not go.get_property('disabled'), 20.0)
    # The monitor's rules on the control: its unshelvable condition cannot be picked, and the
    # durations stop at its shelve_max (8 h here).
    uplift = driver.find_element('css selector', '#shelve-condition option[value="uplift"]')
    assert uplift.get_property('disabled') and 'never shelved' in uplift.text
    options = Select(driver.find_element('id', 'shelve-duration')).options
    assert [o.get_attribute('value') for o in options][-1] == '28800'
    # A row's Shelve button picks its alarm and condition; the operator picks 30 min.
    driver.find_element('css selector', '[data-shelve="line_12"]').click()
    Select(driver.find_element('id', 'shelve-duration')).select_by_value('1800')
    driver.find_element('id', 'shelve-go').click()
    wait_for('the shelve request', lambda: source.shelves, 10.0)
    assert source.shelves[-1][:3] == ('line_12', 'anchor_margin', 1800.0)
    box = driver.find_element('id', 'shelve-answer')
    wait_for('the answer', lambda: 'line_12.anchor_margin shelved' in box.text, 10.0)
    # The frames that follow, which still carry the monitor's older answer (its request count
    # not yet moved past ours), leave it on the page.
    time.sleep(2.5)
    assert 'line_12.anchor_margin shelved' in box.text, box.text
    # Shelving the lifted line as a whole: the monitor refuses, the page says why.
    Select(driver.find_element('id', 'shelve-line')).select_by_value('line_11')
    Select(driver.find_element('id', 'shelve-condition')).select_by_value('all')
    driver.find_element('id', 'shelve-go').click()
    answer = wait_for(
        'the refusal on the page',
        lambda: 'refused' in (t := driver.find_element('id', 'shelve-answer').text) and t,
        10.0,
    )
    assert 'the uplift ERROR cannot be shelved' in answer and '409' in answer
    assert 'refused' in driver.find_element('id', 'shelve-answer').get_attribute('class')


def test_a_shelve_request_from_another_origin_is_refused(page: Any) -> None:
    """The same policy as an acknowledgement: another site's page cannot shelve an alarm."""
    driver, source, server = page
    body = json.dumps({'line': 'line_12', 'condition': 'all', 'seconds': 600}).encode()
    request = urllib.request.Request(
        f'{server.url}api/shelve',
        data=body,
        headers={'Content-Type': 'application/json', 'Origin': 'http://evil.example'},
        method='POST',
    )
    with pytest.raises(urllib.error.HTTPError) as err:
        urllib.request.urlopen(request, timeout=10)
    assert err.value.code == 403
    assert not source.shelves
    # And a malformed body is a 400, never a traceback.
    own = {'Content-Type': 'application/json', 'Origin': server.url.rstrip('/')}
    for bad in (b'{"line": "line_12", "seconds": "soon"}', b'{"line": "line_12"}', b'[1]'):
        request = urllib.request.Request(
            f'{server.url}api/shelve', data=bad, headers=own, method='POST'
        )
        with pytest.raises(urllib.error.HTTPError) as err:
            urllib.request.urlopen(request, timeout=10)
        assert err.value.code == 400, bad


class TideSource(DemoSource):
    """A quiet dock (every line OK, nothing else to say) whose tide status the test sets;
    an acknowledgement of the tide (or of all) acknowledges it, as the monitor does."""

    def __init__(self) -> None:
        from catenary_monitor.console.frames import History, Status

        super().__init__()
        self.history = History()
        self.tide = Status('OK', 'depth 21.95 m', {'depth': '21.95', 'alarm_state': 'normal'})
        self.acks: list[str] = []

    def frame(self, t: Any = None) -> dict[str, Any]:
        from catenary_monitor.console.frames import Status, build_frame

        now = time.time()
        line = {'alarm_state': 'normal', 'top_tension': '900000.0', 'anchor_margin': '20.0'}
        statuses = {name: Status('OK', 'ok', line) for name in self.names}
        statuses['tide'] = self.tide
        statuses['logger'] = Status('OK', 'writing', {})
        sample_t = {name: now - 0.4 for name in self.names}
        return build_frame(now, self.names, now - 0.3, statuses, {}, sample_t, None, [], 3.0)

    def acknowledge(self, line: str, origin: str) -> str:
        from catenary_monitor.console.frames import Status

        self.acks.append(line)
        v = self.tide.values
        if line in ('tide', 'all') and v.get('alarm_state') == 'unacknowledged':
            v = dict(v, alarm_state='acknowledged', acknowledged='true', acknowledged_by=origin)
            self.tide = Status(self.tide.level, self.tide.message, v)
        return f'{line} {origin}'


def test_a_tide_error_beeps_until_acknowledged_and_clears(tmp_path: Path) -> None:
    """A quiet dock: no row, no beep. The tide's impossible depth (ERROR, unacknowledged): a
    row of kind ``component`` with Ack (no Shelve: a component is not shelvable), "Ack all"
    enabled; it beeps at once and again (REPEAT_S 5 s) as an unacknowledged ERROR does. Ack on
    the row acknowledges it at the monitor: the row says acknowledged, the beeps stop while the
    ERROR stands. From a monitor that publishes no alarm state for it (``active``): no button,
    "clears itself". Back at OK the row goes."""
    from catenary_monitor.console.frames import Status
    from catenary_monitor.console.server import ConsoleServer

    source = TideSource()
    server = ConsoleServer(source, '127.0.0.1', 0)
    server.start()
    driver = browser(tmp_path)
    beeps = 'return cmConsole.beeps'
    row = "return document.querySelector('#alarms tr[data-line=\"tide\"]')"
    try:
        driver.get(server.url)
        wait_for('12 OK tiles', lambda: set(tiles(driver).values()) == {'OK'}, 60.0)
        time.sleep(1.5)
        assert rows(driver) == {} and _js(driver, beeps) == 0
        text = 'depth 0.300 m impossible: outside the chart 18.0-26.0 m: check the depth gauge'
        values = {
            'alarm_state': 'unacknowledged',
            'acknowledged': 'false',
            'alarm_raised': repr(time.time()),
            'conditions': 'tide',
            'response': 'Cause: a gauge',
        }
        source.tide = Status('ERROR', text, values)
        wait_for('the tide row', lambda: rows(driver).get('tide') == 'unacknowledged', 10.0)
        seen = _js(
            driver,
            row.replace('return ', 'const r = ')
            + ';return [r.dataset.kind, r.className, r.textContent,'
            ' [...r.querySelectorAll("button")].filter(b => !b.hidden).map(b => b.textContent),'
            ' document.getElementById("ack-all").disabled, r.querySelector(".clears").hidden]',
        )
        assert seen[0] == 'component' and 'lvl-ERROR' in seen[1], seen
        assert 'impossible' in seen[2] and seen[5], seen  # "clears itself" hidden
        assert seen[3] == ['Ack'] and seen[4] is False, seen
        wait_for('the tide ERROR beeps', lambda: _js(driver, beeps) >= 1, 5.0)
        wait_for('and beeps again', lambda: _js(driver, beeps) >= 2, 8.0)
        _js(driver, row.replace('return ', 'return (') + ').querySelector("button").click()')
        wait_for('acknowledged', lambda: rows(driver).get('tide') == 'acknowledged', 10.0)
        assert source.acks == ['tide']
        quiet = _js(driver, beeps)
        time.sleep(6.0)  # longer than REPEAT_S: an acknowledged ERROR never beeps again
        assert _js(driver, beeps) == quiet
        assert _js(driver, row.replace('return ', 'return (') + ').querySelector("button").hidden')
        # a monitor that publishes no alarm state for it: listed active, clears itself
        source.tide = Status('WARN', 'depth sensor stuck', {'alarm_state': 'active'})
        wait_for('the tide row active', lambda: rows(driver).get('tide') == 'active', 10.0)
        seen = _js(
            driver,
            row.replace('return ', 'const r = ')
            + ';return [r.querySelector(".clears").hidden,'
            ' [...r.querySelectorAll("button")].filter(b => !b.hidden).length]',
        )
        assert seen == [False, 0], seen
        source.tide = Status('OK', 'depth 21.95 m', {'alarm_state': 'normal'})
        wait_for('the tide row gone', lambda: 'tide' not in rows(driver), 10.0)
    finally:
        driver.quit()
        server.shutdown()

"""Shared pieces of the console's browser tests: the headless Chromium, polling, the console as
a process, a demo-like page state served without ROS, a ``/diagnostics`` publisher and the page
layout check (what is clipped or overlapping, read from the DOM).

Waits are bounded and generous (the machine is shared); nothing is skipped: without the browser
the tests fail with the command that installs it.
"""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

import pytest
from ros_harness import child_env

from catenary_monitor_study.bench_console import CHROMEDRIVER, CHROMIUM, headless_chromium

ROOT = Path(__file__).resolve().parents[1]
PARAMS = ROOT / 'config' / 'floating_dock.yaml'
HOW_TO = (
    'the browser tests need Debian\'s Chromium and its driver: '
    'apt-get install -y chromium chromium-driver (and pip install selenium)'
)
SHOTS = Path(os.environ.get('CATENARY_CONSOLE_SHOTS', '') or ROOT / 'build' / 'console_shots')
#: Screens the page must serve (CSS px): a laptop, a small monitor, a maximized 1080p browser
#: window, a 1440p screen.
SCREENS = ((1280, 720), (1366, 768), (1920, 937), (2560, 1440))


def browser(tmp: Path, width: int = 1920, height: int = 1080) -> Any:
    """A headless Chromium with a ``width`` x ``height`` viewport (fails with the how-to when
    it is not installed)."""
    if not (os.access(CHROMIUM, os.X_OK) and os.access(CHROMEDRIVER, os.X_OK)):
        pytest.fail(HOW_TO, pytrace=False)
    try:
        import selenium  # noqa: F401 - the how-to when it is missing
    except ImportError:
        pytest.fail(HOW_TO, pytrace=False)
    driver = headless_chromium(str(tmp / 'chromium-profile'), width, height)
    driver.set_script_timeout(30)
    return driver


def set_viewport(driver: Any, width: int, height: int) -> None:
    """Emulate a ``width`` x ``height`` CSS px viewport (device scale 1)."""
    driver.execute_cdp_cmd(
        'Emulation.setDeviceMetricsOverride',
        {'width': width, 'height': height, 'deviceScaleFactor': 1, 'mobile': False},
    )


def wait_for(what: str, check: Callable[[], Any], timeout: float, every: float = 0.25) -> Any:
    """Poll ``check`` until it returns something true; fail naming ``what`` after ``timeout``."""
    deadline = time.monotonic() + timeout
    last: Any = None
    while time.monotonic() < deadline:
        try:
            last = check()
        except Exception as exc:  # noqa: BLE001 - a page being rebuilt: try again
            last = exc
        if last and not isinstance(last, Exception):
            return last
        time.sleep(every)
    raise AssertionError(f'{what}: not seen within {timeout:g} s (last: {last!r})')


TILES = (
    "return [...document.querySelectorAll('.tile[data-line][data-level]')]"
    '.map(t => [t.dataset.line, t.dataset.level])'
)
ROWS = (
    "return [...document.querySelectorAll('tr[data-line][data-alarm-state]')]"
    '.map(r => [r.dataset.line, r.dataset.alarmState])'
)
LOST = "return !!document.querySelector('[data-connection=\"lost\"]:not([hidden])')"


def tiles(driver: Any) -> dict[str, str]:
    return dict(driver.execute_script(TILES))


def rows(driver: Any) -> dict[str, str]:
    return dict(driver.execute_script(ROWS))


def start_console(args: list[str], out: Path) -> tuple[subprocess.Popen, str]:
    """``catenary-monitor console ARGS --port 0``; (process, URL) once it listens."""
    log = open(out, 'w+')
    proc = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'console', *args, '--port', '0'],
        stdout=log,
        stderr=subprocess.STDOUT,
        env=child_env(),
    )

    def url() -> Any:
        assert proc.poll() is None, out.read_text()
        match = re.search(r'console: (http://\S+)', out.read_text())
        return match.group(1) if match else None

    return proc, wait_for('the console URL', url, 90.0)


def stop(proc: subprocess.Popen, sig: int = signal.SIGINT) -> int:
    if proc.poll() is None:
        proc.send_signal(sig)
    try:
        return proc.wait(30)
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.wait(10)


# ---------------------------------------------------------------- the layout check
#: The layout check (a function body: ``arguments[0]`` says whether every tile's level and the
#: alarm list must be in the window without scrolling); it returns sentences, empty when none.
LAYOUT_JS = (Path(__file__).with_name('console_layout.js')).read_text(encoding='utf-8')


def layout_problems(driver: Any, in_window: bool) -> list[str]:
    """What is clipped, overlapping, too small or out of reach on the page now
    (:data:`LAYOUT_JS`); with ``in_window`` also the levels and alarms out of the window."""
    return list(driver.execute_script(LAYOUT_JS, in_window))


# ---------------------------------------------------------------- a demo-like state, no ROS
_LONG = (
    'anchor uplift 152.3 kN > allowed 0.0 kN; anchor margin -12.40 m < 5.00 m; uplift possible '
    'within the sensors\' accuracy: bound 210.2 kN, nominal 152.3 kN; drag margin 120.5 kN '
    'below 200.0 kN: check the anchor and the chain on the seabed'
)
#: What the live storm's dynamic uplift ERROR says while its warnings are held (the live
#: demo's longest messages: every alarm row carries one).
_HELD = (
    'anchor uplift 1.2 kN > allowed 0.0 kN at the wave peak (quasi-static '
    '0.0 kN); anchor margin 5.06 m, warning held (clears after 6 s at >= 6.00 m); tide margin '
    '1.93 m, warning held (clears after 6 s at >= 1.20 m); uplift possible within sensor '
    'accuracy: up to 5.6 kN > allowed 0.0 kN (nominal 0.0 kN)'
)


def demo_statuses(names: Sequence[str], now: float) -> dict[str, Any]:
    """The demo's storm as the monitor publishes it: line_11 lifted (ERROR, unacknowledged, a
    long message), line_07 ERROR acknowledged on its dynamic uplift and dragging (the live
    storm's longest message), line_08 WARN unacknowledged with a message as long, line_10 WARN
    unacknowledged and chattering, line_12 WARN acknowledged, line_09 WARN shelved, the rest OK
    (half of them with no tide trend yet), every optional value set (bound, drag margin and drag
    state, tide margin at length but on line_01, wave tension, fatigue, the span from the dock
    estimate; line_05 a load cell of three channels, one silent), the intake WARN, and an
    alarm flood whose first out is line_11."""
    from catenary_monitor.console.frames import Status
    from catenary_monitor.core.alarms.texts import status_texts

    out: dict[str, Any] = {}
    for k, name in enumerate(names):
        level, state, msg = 'OK', 'normal', 'ok'
        if name == 'line_11':
            level, state, msg = 'ERROR', 'unacknowledged', _LONG
        elif name == 'line_07':
            level, state, msg = 'ERROR', 'acknowledged', _HELD
        elif name == 'line_08':
            level, state, msg = 'WARN', 'unacknowledged', _HELD.replace('anchor uplift', 'uplift')
        elif name in ('line_09', 'line_10', 'line_12'):
            level, msg = 'WARN', 'anchor margin 3.10 m < 5.00 m; anchor uplift in 42 min if the '
            msg += 'tide keeps rising 0.31 m/h'
            state = {'line_09': 'shelved', 'line_10': 'unacknowledged'}.get(name, 'acknowledged')
        lifted = name == 'line_11'
        ttu = 0.0 if lifted else (2520.0 if level == 'WARN' else math.inf)
        values = {
            'top_tension': 2.4e6 if lifted else 0.9e6 + 4e4 * k,
            'anchor_margin': -12.4 if lifted else 20.0 - k,
            'uplift_force': 152.3e3 if lifted else 0.0,
            'safety_factor': 2.01 if lifted else 5.3,
            'tide_margin': -2.1 if lifted else 4.68,
            # the live start: no tide trend yet (unknown, NaN) on the even lines that are OK
            'time_to_uplift': math.nan if (level == 'OK' and k % 2) else ttu,
            'time_to_uplift_view': 'none' if k == 0 else 'chain length held',
            'uplift_force_upper': 210.2e3 if lifted else 0.0,
            'drag_margin': 120.5e3 if lifted else (-35.2e3 if name == 'line_07' else 1.8e6),
            'drag_state': 2 if name == 'line_07' else 0,
            # line_01 without chain_length: no tide margin at length (nan)
            'tide_margin_at_length': -0.4 if lifted else (math.nan if k == 0 else 1.05),
            'wave_tension': 38.5e3 + 1e3 * k,
            # the span solved at: the dock estimate's (moved) on all but line_01 (installed)
            'span': 121.06 + (0.0 if k == 0 else 0.39 + 0.01 * k),
            'span_source': 'installed' if k == 0 else 'dock_estimate',
            # line_07's ERROR is on its dynamic uplift (the quasi-static one is 0)
            'dynamic_uplift': 161.0e3 if lifted else (1.2e3 if name == 'line_07' else 0.0),
            'fatigue_damage': 3.2e-4 * (k + 1),
            'fatigue_life_left': 2.7e9 / (k + 1),
            'tension_age': 0.4,
            'alarm_state': state,
            'alarm_raised': repr(now - 95.0 - k),
            'alarm_condition': 'uplift' if name in ('line_07', 'line_11') else 'anchor_margin',
            'acknowledged_by': 'console dockpc' if state == 'acknowledged' else '',
            'acknowledged_at': repr(now - 30.0),
            'model': 'elastic catenary',
            'sensor_state': 'ok',
            'shelved': 'true' if name == 'line_09' else 'false',
            'shelved_until': repr(now + 1800.0) if name == 'line_09' else 'nan',
            'shelved_condition': 'all' if name == 'line_09' else '',
            'shelved_by': 'console dockpc client 127.0.0.1' if name == 'line_09' else '',
            'chattering': 'true' if name == 'line_10' else 'false',
        }
        if name == 'line_05':  # a load cell of three channels, the second silent
            values.update(channels_healthy=2.0, channel_states=5.0)
        # as the monitor publishes it: the headline, the full text and the response apart
        condition = str(values['alarm_condition']) if level != 'OK' else 'none'
        head, texts = status_texts(msg, level == 'OK', condition)
        values.update(texts)
        out[name] = Status(level, head, {k: str(v) for k, v in values.items()})
    out['tide'] = Status('OK', 'depth 21.95 m', {'depth': '21.95', 'rate': repr(0.31 / 3600)})
    out['logger'] = Status('OK', 'writing /var/log/catenary_monitor/2026-12-02.mcap', {})
    out['intake'] = Status(
        'WARN', 'node cannot keep up: 312 samples dropped in the last 60 s (queue 50)', {}
    )
    out['alarms'] = Status(
        'WARN',
        'ALARM FLOOD: 14 alarms raised in the last 600 s (more than 10); first out: line_11',
        {
            'flood': 'true',
            'alarms_in_window': '14',
            'flood_since': repr(now - 80.0),
            'first_out': 'line_11',
            'first_out_at': repr(now - 95.0),
            'shelve_max': '28800.0',
            'unshelvable_conditions': 'uplift',
            'shelve_answer': 'line_09 shelved for 1800 s by console dockpc client 127.0.0.1',
            'shelve_requests': '1',
        },
    )
    return out


class DemoSource:
    """A console data source (:class:`catenary_monitor.console.server.Source`) that always
    shows the demo's storm (:func:`demo_statuses`), a history and trends: the page's fullest
    state, without ROS."""

    mode = 'live'

    def __init__(self) -> None:
        from catenary_monitor.console.frames import History
        from catenary_monitor.core.config.parameters import config_from_params, load_params_file

        flat = load_params_file(PARAMS)
        for name in flat['lines']:
            flat[f'{name}.tension_accuracy'] = 20e3
            flat[f'{name}.anchor_holding'] = 1.5e6
        flat['line_05.tension_topics'] = ['/cell05/a', '/cell05/b', '/cell05/c']
        self.config = config_from_params(flat)
        self.names = [line.name for line in self.config.lines]
        self.version = 0
        self.shelves: list[tuple[str, str, float, str]] = []  # the requests the page sent
        self.history = History()
        t0 = time.time()
        self.history.feed(t0 - 200.0, demo_statuses(self.names, t0 - 200.0), self.names)
        self.history.feed(t0 - 100.0, demo_statuses(self.names, t0), self.names)

    def config_json(self) -> dict[str, Any]:
        from catenary_monitor.console.frames import console_config

        return console_config(self.config, self.names, 'live', host='dockpc')

    def frame(self, t: Optional[float] = None) -> dict[str, Any]:
        from catenary_monitor.console.frames import build_frame, tide_trend

        now = time.time()
        statuses = demo_statuses(self.names, now)
        sample_t = {name: now - 0.4 for name in self.names}
        return build_frame(
            now,
            self.names,
            now - 0.3,
            statuses,
            {},
            sample_t,
            tide_trend(statuses),
            self.history.entries,
            3.0,
            started=now - 600.0,
        )

    def trend(self, line: str, t: Optional[float], span: float) -> dict[str, Any]:
        now = time.time()
        ts = [now - span + span * k / 200 for k in range(201)]
        wave = [math.sin(k / 9.0) for k in range(201)]
        series = {
            't': ts,
            'tension_max': [1.6e6 + 6e5 * w for w in wave],
            'uplift_max': [max(0.0, 1.5e5 * w) for w in wave],
            'margin_min': [5.0 - 15.0 * w for w in wave],
        }
        depth = {'t': ts, 'depth_max': [21.0 + k * 0.005 for k in range(201)]}
        return {'line': line, 'lo': now - span, 'hi': now, 'series': series, 'depth': depth}

    def acknowledge(self, line: str, origin: str) -> str:
        return f'{line} {origin}'

    def shelve(self, alarm: str, condition: str, seconds: float, origin: str) -> dict[str, Any]:
        """Take a shelving request as the monitor would answer it (no state changes)."""
        self.shelves.append((alarm, condition, seconds, origin))
        target = alarm if condition == 'all' else f'{alarm}.{condition}'
        if condition == 'uplift' or (alarm == 'line_11' and condition == 'all'):
            from catenary_monitor.console.frames import AckError

            raise AckError(f'{target}: refused: {alarm}: the uplift ERROR cannot be shelved', 409)
        return {'sent': f'{target} {seconds:g} {origin}', 'answer': f'{target} shelved'}

    def wait(self, version: int, timeout: float) -> int:
        time.sleep(min(timeout, 0.5))
        self.version += 1
        return self.version


# ---------------------------------------------------------------- test nodes on /diagnostics
class _TestNode:
    """A test node spun in a daemon thread (rclpy initialised once per test process)."""

    def __init__(self, name: str) -> None:
        import rclpy

        if not rclpy.ok():
            rclpy.init()
        self.node = rclpy.create_node(f'{name}_{os.getpid()}')
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._spin, daemon=True)

    def _spin(self) -> None:
        import rclpy

        while not self.stop.is_set() and rclpy.ok():
            rclpy.spin_once(self.node, timeout_sec=0.1)

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)
        self.node.destroy_node()


class DiagnosticsWatcher(_TestNode):
    """Keeps line_11's newest (level, acknowledged) from /diagnostics."""

    def __init__(self) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.qos import QoSProfile

        super().__init__('console_test')
        self.seen: list[tuple[int, str]] = []
        self.node.create_subscription(
            DiagnosticArray, '/diagnostics', self._on, QoSProfile(depth=50)
        )
        self.thread.start()

    def _on(self, msg: Any) -> None:
        for st in msg.status:
            if st.name == 'catenary_monitor: line_11':
                values = {kv.key: kv.value for kv in st.values}
                self.seen.append((st.level[0], values.get('acknowledged', '')))


class DiagnosticsPublisher(_TestNode):
    """Publishes, at 2 Hz, a monitor's ``/diagnostics`` array for ``names`` (every line OK, a
    tension sample 0.2 s old), as a monitor started on those lines does."""

    def __init__(self, names: Sequence[str]) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.qos import QoSProfile

        super().__init__('console_diag')
        self.names = list(names)
        self.pub = self.node.create_publisher(DiagnosticArray, '/diagnostics', QoSProfile(depth=9))
        self.node.create_timer(0.5, self._tick)
        self.thread.start()

    def _tick(self) -> None:
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        msg = DiagnosticArray()
        msg.header.stamp = self.node.get_clock().now().to_msg()
        values = {
            'top_tension': '900000.0',
            'anchor_margin': '20.0',
            'tension_age': '0.2',
            'alarm_state': 'normal',
            'model': 'elastic catenary',
        }
        for name in self.names + ['tide']:
            st = DiagnosticStatus(name=f'catenary_monitor: {name}', message='ok')
            st.level = DiagnosticStatus.OK
            st.values = [KeyValue(key=k, value=v) for k, v in values.items()]
            msg.status.append(st)
        self.pub.publish(msg)


class AckRecorder(_TestNode):
    """Stands in for the monitor on ``/catenary_monitor/acknowledge``: keeps every message's
    text (what would be acknowledged), so a console that refuses publishes nothing here."""

    def __init__(self) -> None:
        from rclpy.qos import QoSProfile
        from std_msgs.msg import String

        from catenary_monitor.core.alarms.acknowledge import ACKNOWLEDGE_TOPIC

        super().__init__('ack_recorder')
        self.messages: list[str] = []
        self.node.create_subscription(
            String, ACKNOWLEDGE_TOPIC, lambda m: self.messages.append(m.data), QoSProfile(depth=50)
        )
        self.thread.start()

    def wait_for_publisher(self, timeout: float = 30.0) -> None:
        """Until a console's acknowledgement publisher has matched this subscription."""
        from catenary_monitor.core.alarms.acknowledge import ACKNOWLEDGE_TOPIC

        wait_for(
            'the console\'s acknowledgement publisher',
            lambda: self.node.count_publishers(ACKNOWLEDGE_TOPIC) > 0,
            timeout,
        )
        time.sleep(0.5)  # matched both ways

    def wait(self, count: int, timeout: float = 10.0) -> None:
        wait_for(f'{count} acknowledgement messages', lambda: len(self.messages) >= count, timeout)

"""``catenary-monitor bench-console``: latency from a published hook tension to the console page.

The monitor (floating_dock.yaml) and the console run as their own processes and a headless
Chromium shows the page (``?bench=1``: the page logs each render's time and tensions). This
process publishes every line's tension at ``--rate`` with values that are never repeated, and
the depth; it subscribes to the monitor's outputs too, which gives the baseline measured in the
same run: published tension -> the monitor's output message (DDS, the monitor). For every
published value: when the page first rendered it (its DOM updated: ``performance.timeOrigin +
performance.now()``, the same wall clock as ``time.time()`` here). Values the page never shows
(a newer one came within the console's 50 ms frame interval) are counted, not timed.
Reports median and p99 of both latencies.
"""

from __future__ import annotations

import functools
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from typing import Any

import numpy as np

__all__ = ['run_bench', 'register', 'headless_chromium']

CHROMIUM, CHROMEDRIVER = '/usr/bin/chromium', '/usr/bin/chromedriver'


def headless_chromium(profile: str, width: int = 1920, height: int = 1080) -> Any:
    """Debian's Chromium, headless, through its chromedriver: a ``width`` x ``height`` CSS px
    viewport, sound allowed without a click, its profile in the directory ``profile``."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in (
        '--headless',
        '--no-sandbox',
        '--disable-gpu',
        '--disable-quic',
        '--no-first-run',
        '--disable-background-networking',
        '--disable-component-update',
        '--disable-sync',
        '--autoplay-policy=no-user-gesture-required',
        f'--user-data-dir={profile}',
    ):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    driver.execute_cdp_cmd(
        'Emulation.setDeviceMetricsOverride',
        {'width': width, 'height': height, 'deviceScaleFactor': 1, 'mobile': False},
    )
    return driver


def _stats(ms: list[float]) -> dict[str, Any]:
    if not ms:
        return {'n': 0, 'median_ms': None, 'p99_ms': None}
    a = np.asarray(ms)
    return {
        'n': int(a.size),
        'median_ms': round(float(np.median(a)), 2),
        'p99_ms': round(float(np.percentile(a, 99)), 2),
    }


def run_bench(rate: float = 10.0, duration: float = 20.0, json_out: bool = False) -> int:
    """Run the benchmark; print a table (or JSON); 0 on success, 2 without the browser."""
    if not (os.access(CHROMIUM, os.X_OK) and os.access(CHROMEDRIVER, os.X_OK)):
        print(
            'bench-console: needs Debian\'s chromium and chromium-driver '
            '(apt-get install -y chromium chromium-driver) and selenium (pip)',
            file=sys.stderr,
        )
        return 2
    import rclpy
    from rclpy.qos import QoSProfile, qos_profile_sensor_data
    from std_msgs.msg import Float64, Float64MultiArray

    from catenary_monitor.cli.demo import child_env, start_console
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.sim.scenario import default_config_path

    params = default_config_path()
    config = config_from_params(load_params_file(params))
    names = [line.name for line in config.lines]
    env = child_env(domain_base=140)
    os.environ['ROS_DOMAIN_ID'] = env['ROS_DOMAIN_ID']
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    tmp = tempfile.mkdtemp(prefix='bench_console_')
    monitor = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.ros.node', '--ros-args', '--params-file']
        + [params, '-p', f'log_dir:={tmp}/log'],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
    )
    console, url = start_console(params, env, port=0)
    if console is None:
        print(f'bench-console: the console did not start: {url}', file=sys.stderr)
        monitor.kill()
        return 1
    rclpy.init()
    node = rclpy.create_node('bench_console')
    pubs = [
        node.create_publisher(Float64, line.tension_topic, qos_profile_sensor_data)
        for line in config.lines
    ]
    depth_pub = node.create_publisher(Float64, config.depth_topic, qos_profile_sensor_data)
    sent: dict[tuple[int, float], float] = {}
    got: dict[tuple[int, float], float] = {}

    def on_output(k: int, msg: Any) -> None:
        key = (k, float(msg.data[0]))
        got.setdefault(key, time.time())

    for k, name in enumerate(names):
        node.create_subscription(
            Float64MultiArray,
            f'/catenary_monitor/{name}/outputs',
            functools.partial(on_output, k),
            QoSProfile(depth=100),
        )
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            rclpy.spin_once(node, timeout_sec=0.05)

    spinner = threading.Thread(target=spin, daemon=True)
    spinner.start()
    driver = headless_chromium(f'{tmp}/profile')
    try:
        driver.get(url + '?bench=1')
        deadline = time.monotonic() + 60.0
        while time.monotonic() < deadline and not all(p.get_subscription_count() for p in pubs):
            time.sleep(0.1)
        counter = 0
        t_end = time.monotonic() + duration + 3.0
        next_depth = 0.0
        while time.monotonic() < t_end:
            now = time.monotonic()
            if now >= next_depth:
                depth_pub.publish(Float64(data=20.85))
                next_depth = now + 0.5
            measuring = now > t_end - duration  # the first 3 s warm up
            for k, pub in enumerate(pubs):
                counter += 1
                value = 380e3 + counter + 0.125  # never repeated, exact in JSON
                if measuring:
                    sent[(k, value)] = time.time()
                pub.publish(Float64(data=value))
            time.sleep(max(1.0 / rate - (time.monotonic() - now), 0.0))
        time.sleep(2.0)
        renders = driver.execute_script('return window.cmConsole.bench')
    finally:
        driver.quit()
        stop.set()
        spinner.join(2)
        node.destroy_node()
        rclpy.try_shutdown()
        for proc in (console, monitor):
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(15)
            except subprocess.TimeoutExpired:
                proc.kill()
    shown: dict[tuple[int, float], float] = {}
    for stamp_ms, tensions in renders:
        for k, value in enumerate(tensions):
            if value is not None:
                shown.setdefault((k, float(value)), stamp_ms / 1e3)
    page = [1e3 * (shown[key] - t) for key, t in sent.items() if key in shown]
    monitor_ms = [1e3 * (got[key] - t) for key, t in sent.items() if key in got]
    result: dict[str, Any] = {
        'published': len(sent),
        'rate_per_line_hz': rate,
        'lines': len(names),
        'to_monitor_output': _stats(monitor_ms),
        'to_page': _stats(page),
        'superseded_before_shown': len(sent) - len(page),
        'renders': len(renders),
    }
    if json_out:
        print(json.dumps(result))
        return 0
    print(
        f'bench-console: {len(names)} lines at {rate:g} Hz for {duration:g} s, '
        f'{result["published"]} tensions published'
    )
    for label, key in (
        ('published -> monitor output (baseline)', 'to_monitor_output'),
        ('published -> console page (DOM updated)', 'to_page'),
    ):
        s = result[key]
        print(f'  {label:42s} median {s["median_ms"]} ms  p99 {s["p99_ms"]} ms  (n = {s["n"]})')
    print(
        f'  values superseded by a newer one before a frame: {result["superseded_before_shown"]}'
        f' (the console sends at most 20 frames/s); {result["renders"]} renders'
    )
    return 0


def register(sub: Any) -> None:
    """Add ``bench-console``."""
    p = sub.add_parser(
        'bench-console',
        help='latency from a published tension to the console page (headless chromium)',
        description='Monitor and console as processes, the page in headless chromium: '
        'published tension -> page render latency (median, p99), with the '
        'published -> monitor output latency of the same run as baseline.',
    )
    p.add_argument('--rate', type=float, default=10.0, help='rate per line [Hz] (default 10)')
    p.add_argument('--duration', type=float, default=20.0, help='measuring time [s]')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(
        func=lambda args: run_bench(rate=args.rate, duration=args.duration, json_out=args.json)
    )


if __name__ == '__main__':  # pragma: no cover
    sys.exit(run_bench())

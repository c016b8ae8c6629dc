"""The alarm report on a month of generated logs (catenary_monitor_study.bench_replay's
generate_month: one file a day, a storm mid-month): streamed in bounded memory (the month's
peak RSS within a few MB of three days'), a progress line, the chart and the page.

Sparse samples (one per line every 100 s) and ticks every 100 s keep the test short; the full
month at 1 Hz is measured in docs/alarm_report.md.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from ros_harness import child_env

from catenary_monitor_study.bench_replay import dock_config, generate_month

#: The command in a child process, then its peak RSS (VmHWM) on stderr.
CHILD = (
    'import sys\n'
    'from catenary_monitor.cli.main import main\n'
    'code = main(sys.argv[1:])\n'
    'sys.stdout.flush()\n'
    'hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")]\n'
    'sys.stderr.write(hwm[0] if hwm else "")\n'
    'sys.exit(code)\n'
)


@pytest.fixture(scope='module')
def month(tmp_path_factory: Any) -> tuple[Path, Path]:
    from catenary_monitor.core.config.parameters import config_to_params, params_file_text

    tmp = tmp_path_factory.mktemp('month')
    base = dock_config()
    alarm = dataclasses.replace(
        base.alarm, diagnostic_rate=0.01, tension_timeout=300.0, depth_timeout=1200.0
    )
    config = dataclasses.replace(base, alarm=alarm)
    generate_month(tmp / 'logs', config, days=30.0, rate=0.01, depth_rate=0.002)
    params = tmp / 'params.yaml'
    params.write_text(params_file_text(config_to_params(config)))
    return tmp, params


def _run(args: list[str]) -> tuple[dict, str, float]:
    done = subprocess.run(
        [sys.executable, '-c', CHILD, 'alarms', *args, '--json'],
        capture_output=True, text=True, env=child_env(), timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    hwm = [ln for ln in done.stderr.splitlines() if ln.startswith('VmHWM:')]
    return json.loads(done.stdout), done.stderr, int(hwm[-1].split()[1]) / 1024.0


def test_a_month_of_logs_in_bounded_memory_with_progress_and_chart(month: Any) -> None:
    tmp, params = month
    logs = tmp / 'logs'
    files = sorted(logs.glob('*.mcap'))
    assert len(files) == 30
    three = tmp / 'three'
    three.mkdir()
    for f in files[:3]:
        (three / f.name).symlink_to(f)
    common = ['--params-file', str(params), '--window-messages', '4096']
    small, _, rss_three = _run([str(three), *common, '--quiet'])
    chart, page = tmp / 'month.png', tmp / 'month.html'
    report, err, rss_month = _run(
        [str(logs), *common, '--progress', '--plot', str(chart), '--html', str(page)]
    )
    # Ten times the logs, the same memory (matplotlib for the chart aside: a few MB).
    assert rss_month < rss_three + 40.0, (rss_three, rss_month)
    progress = [ln for ln in err.splitlines() if ln.startswith('alarms: ')]
    assert progress[-1].startswith('alarms: done'), err
    assert report['logs']['files'] == 30 and report['logs']['messages'] > 0
    # A month of 10-minute periods (ticks every 100 s: every period has some).
    assert report['periods'] == pytest.approx(30 * 24 * 6, abs=2)
    per_alarm = [a['annunciated'] for a in report['lines'].values()]
    per_alarm += [a['annunciated'] for a in report['components'].values()]
    assert report['annunciated'] == sum(per_alarm) + report['sensors']['annunciated'] > 0
    assert report['per_10min_mean'] == pytest.approx(report['annunciated'] / report['periods'])
    assert set(report['lines']) == {f'line_{k:02d}' for k in range(1, 13)}
    assert small['periods'] == pytest.approx(3 * 24 * 6, abs=2)
    assert chart.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n' and chart.stat().st_size > 10_000
    assert 'data:image/png;base64,' in page.read_text()

"""``catenary-monitor alarms LOG|DIR ... [--json] [--plot FILE] [--html FILE]``: the alarm
report (docs/alarm_report.md).

The logs are replayed window by window by the one replay driver (bounded memory on a month of
logs) and the monitor core decides every alarm again; the report counts what it decided
(:mod:`catenary_monitor.replay.alarm_report`). A table by default, one JSON object with
``--json``; a progress line on stderr for logs of more than 8 MB (``--progress`` always,
``--quiet`` never). Exit 2 with one line for a missing or unreadable log or a bad params file,
3 for a log without input messages.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import sys
from pathlib import Path
from typing import Any, Optional

__all__ = ['register', 'cmd_alarms']


def _time(text: str) -> float:
    """A period bound: Unix seconds, or an ISO 8601 date/time (UTC unless it says)."""
    try:
        return float(text)
    except ValueError:
        pass
    try:
        when = _dt.datetime.fromisoformat(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f'not a time: {text!r} (Unix seconds or ISO 8601, e.g. 2026-12-01T00:00)'
        ) from None
    if when.tzinfo is None:
        when = when.replace(tzinfo=_dt.timezone.utc)
    return when.timestamp()


def register(sub: Any) -> None:
    """Add ``alarms`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'alarms',
        help='the alarm report over logs: rates per 10 min, floods, chattering, standing, '
        'time to acknowledge, time shelved (ISA-18.2, EEMUA 191)',
        description='Replay MCAP logs (files or folders) and report how the alarm system '
        'performed: alarms raised per 10 minutes (mean, peak), the share of 10-minute periods '
        'in flood, the most frequent alarms, chattering and standing alarms, time to '
        'acknowledge and time shelved, per line and overall, against the ISA-18.2 / EEMUA 191 '
        'targets. The alarms are those the monitor core decides again from the recorded '
        'inputs and operator events (docs/alarm_report.md).',
    )
    p.add_argument('logs', nargs='+', metavar='LOG', help='MCAP files or folders of them')
    p.add_argument(
        '--params-file',
        metavar='FILE',
        help='ROS 2 params YAML of the monitor; default: the parameters recorded in the log',
    )
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.add_argument('--plot', metavar='FILE.png', help='write the chart (PNG)')
    p.add_argument('--html', metavar='FILE.html', help='write the report as one HTML page')
    p.add_argument('--since', type=_time, metavar='T', help='count from T (s or ISO 8601)')
    p.add_argument('--until', type=_time, metavar='T', help='count until T (s or ISO 8601)')
    p.add_argument('--top', type=int, default=10, metavar='N', help='most frequent alarms shown')
    p.add_argument('--quiet', action='store_true', help='no progress on stderr')
    p.add_argument(
        '--progress',
        action='store_true',
        help='show progress on stderr even for short logs (default: logs > 8 MB)',
    )
    p.add_argument(
        '--window-messages',
        type=int,
        default=None,
        metavar='M',
        help='input messages per replay window: the memory bound (default 131072)',
    )
    p.set_defaults(func=cmd_alarms)


def _fail(message: str, code: int = 2) -> int:
    print(f'catenary-monitor alarms: {message}', file=sys.stderr)
    return code


def cmd_alarms(args: argparse.Namespace) -> int:
    """Replay the logs into the alarm report; print it (table or JSON), write the files."""
    from catenary_monitor.cli.allocator import keep_freed_memory
    from catenary_monitor.cli.replay import Progress
    from catenary_monitor.replay.driver import (
        WINDOW_MESSAGES,
        ReplayError,
        drive,
        expand,
        stamp_figures,
    )

    keep_freed_memory()
    try:
        paths = expand(args.logs)
        config = _config(paths, args.params_file)
        size = sum(p.stat().st_size for p in paths)
        progress = Progress(args.progress or (not args.quiet and size > 8_000_000))
        progress.line.prefix = 'alarms: '
        report, state, _ = drive(
            paths,
            config,
            lambda _: _report(config, args),
            window_messages=args.window_messages or WINDOW_MESSAGES,
            progress=progress.stream,
            on_restart=lambda why: None if args.quiet else print(
                f'catenary-monitor alarms: cannot stream this log ({why}); replaying it as '
                'one window', file=sys.stderr),  # fmt: skip
        )
        progress.done()
    except ReplayError as err:
        return _fail(str(err), err.code)
    figures = report.figures()  # type: ignore[attr-defined]
    figures['logs'] = {'files': len(paths), 'bytes': size, 'messages': state.messages}
    figures['logs'].update(stamp_figures(state))
    try:
        _write_files(figures, args)
    except OSError as err:
        return _fail(f'cannot write {err.filename}: {err.strerror}')
    text = json.dumps(_finite(figures), allow_nan=False) if args.json else _text(figures, args)
    try:
        print(text)
        sys.stdout.flush()
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


def _report(config: Any, args: argparse.Namespace) -> Any:
    from catenary_monitor.replay.alarm_report import AlarmReport

    return AlarmReport(config, top=args.top, since=args.since, until=args.until)


def _config(paths: list[Path], params_file: Optional[str]) -> Any:
    """The monitor configuration: the params file's, else the one recorded in the log."""
    from catenary_monitor.core.config.parameters import ConfigError, config_from_params
    from catenary_monitor.replay.driver import ReplayError, load_config, log_parameters

    if params_file:
        return load_config(params_file)
    recorded = log_parameters(paths)
    if recorded is None:
        raise ReplayError(
            '--params-file is required: the log holds no catenary_monitor parameters'
        )
    try:
        return config_from_params(recorded[1])
    except ConfigError as err:
        raise ReplayError(
            f'the parameters recorded in the log are invalid: {err}; give --params-file'
        ) from err


def _write_files(figures: dict[str, Any], args: argparse.Namespace) -> None:
    from catenary_monitor.replay.alarm_report_chart import chart_png, write_html

    if not (args.plot or args.html):
        return
    png = chart_png(figures)
    if args.plot:
        Path(args.plot).write_bytes(png)
    if args.html:
        write_html(figures, Path(args.html), png)


def _text(figures: dict[str, Any], args: argparse.Namespace) -> str:
    from catenary_monitor.replay.alarm_report import report_text

    from catenary_monitor.replay.driver import stamp_lines

    text = '\n'.join([report_text(figures), *stamp_lines(figures.get('logs', {}))])
    files = [f for f in (args.plot, args.html) if f]
    return text + (f'\nwritten: {", ".join(files)}' if files else '')


def _finite(value: Any) -> Any:
    """JSON-ready: non-finite floats as None (JSON has no NaN)."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value

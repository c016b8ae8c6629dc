"""``catenary-monitor replay``: recompute a recorded MCAP log offline, or play it onto ROS.

Offline (no ROS graph)::

    catenary-monitor replay LOG.mcap [LOG2.mcap ...] --params-file FILE
        [--out RESULTS.mcap] [--csv RESULTS.csv] [--plot CHART.png] [--json] [--quiet]

reads the tension and depth topics named by the params file from any ROS 2-profile MCAP (the
node's own logs, rosbag2 recordings; a rotated set or a directory), recomputes every update with
the live node's schedule and alarm logic (the replay driver, :mod:`catenary_monitor.replay.driver`,
over the core's vectorized twin), writes the chosen outputs
(:mod:`catenary_monitor.replay.outputs`) window by window and prints a summary (``--json``: one
JSON object). Every step is redone as the node made it: the node records its ticks, its start and
its logger and parameter changes on ``/catenary_monitor/events``; a log without that channel (a
rosbag2 recording of the sensors) is stepped on a grid of ticks at ``diagnostic_rate``.

Playback::

    catenary-monitor replay LOG.mcap --publish [--params-file FILE] [--rate X] [--loop]

publishes the recorded inputs (as recorded: ``std_msgs/Float64``, ``WrenchStamped``,
``FluidPressure``, ``Range``) on their topics with their recorded timing scaled by X, and
``/clock`` with the log's time, which a node with ``use_sim_time`` follows
(:mod:`catenary_monitor.ros.playback`, needs rclpy).

Exit status: 0 done; 2 bad arguments, params file, missing file, not MCAP, or a topic with an
unexpected type (one line naming it); 3 no message on any requested topic (empty log).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

from catenary_monitor.cli.table import json_ready
from catenary_monitor.cli.status_line import StatusLine
from catenary_monitor.core.config.parameters import (
    ConfigError,
    MonitorConfig,
    config_from_params,
    config_hash,
    resolve_topic,
)
from catenary_monitor.core.monitor.events import EVENTS_TOPIC
from catenary_monitor.core.twin.window import COLUMNS
from catenary_monitor.io.mcap_read import (
    EmptyLogError,
    TopicTypeError,
    iter_windows,
    not_mcap,
)
from catenary_monitor.io.mcap_scan import McapReadError, ReadReport
from catenary_monitor.replay.driver import (
    EXIT_EMPTY,
    ReplayError,
    drive,
    expand,
    input_topics,
    load_config,
    log_parameters,
    stamp_figures,
)

__all__ = ['register', 'cmd_replay']


class Progress:
    """Stage progress on stderr for long logs (cli.status_line: in place on a terminal)."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.line = StatusLine('replay: ')
        self.tty = self.line.tty
        self.shown = False
        self.start = time.monotonic()

    def __call__(self, stage: str, fraction: float = 0.0) -> None:
        if not self.enabled:
            return
        text = f'{stage} {100 * fraction:3.0f}% ({time.monotonic() - self.start:.1f} s)'
        if 0.0 < fraction < 1.0:
            self.line(text)
            return
        self.line.show(text)
        if fraction >= 1.0:
            self.line.end()

    def stream(self, state: Any) -> None:
        """A streamed replay's progress: share of the files' bytes walked, with an ETA."""
        if not (self.enabled and self.line.due()):
            return
        total = max(state.bytes_total, 1)
        fraction = min(state.bytes_done / total, 1.0)
        elapsed = time.monotonic() - self.start
        eta = f', ETA {elapsed * (1 - fraction) / fraction:.0f} s' if fraction > 0 else ''
        self.line.show(
            f'{100 * fraction:3.0f}% of {total / 1e6:.0f} MB, '
            f'{state.messages / 1e6:.1f} M messages ({elapsed:.0f} s{eta})'
        )
        self.shown = True

    def done(self) -> None:
        if not self.enabled:
            return
        if self.shown or not self.tty:
            self.line.show(f'done ({time.monotonic() - self.start:.1f} s)')
        self.line.end()


def _publish_messages(
    paths: Sequence[Path], config: Optional[MonitorConfig]
) -> tuple[dict[str, tuple[np.ndarray, list[bytes], str]], ReadReport]:
    """What ``--publish`` plays (topic -> (log times, CDR payloads, type)) and the read
    report: the params file's tension and depth topics with their configured types, or every
    topic of an input type without a params file."""
    from catenary_monitor.ros.playback import input_topics_of_log

    if config is not None:  # every channel of a load cell (NAME.tension_topics) too
        _, depth_topic = input_topics(config)
        types = {
            resolve_topic(topic): line.tension_type
            for line in config.lines
            for topic in line.topics
        }
        types[depth_topic] = config.depth_type
    else:
        types = input_topics_of_log(paths)
        if not types:
            raise ReplayError('empty log: no input topic (Float64, WrenchStamped, '
                              'FluidPressure, Range) to publish', EXIT_EMPTY)  # fmt: skip
    report = ReadReport()
    try:
        window = next(iter_windows(paths, [], [], None, report, typed=types))
    except TopicTypeError as err:
        raise ReplayError(f'unexpected message type: {err} (check the params file topics)')
    except EmptyLogError as err:
        raise ReplayError(f'empty log: {err}', EXIT_EMPTY) from err
    except McapReadError as err:
        raise ReplayError(str(err)) from err
    out = {}
    for topic, type_name in types.items():
        times, payloads = window.raw.get(topic, (np.zeros(0, np.int64), []))
        out[topic] = (times, payloads, type_name)
    return out, report


def cmd_replay(args: argparse.Namespace) -> int:
    """Entry point of ``catenary-monitor replay``."""
    try:
        if args.publish:
            from catenary_monitor.ros.playback import publish

            paths = expand(args.logs)
            config = load_config(args.params_file) if args.params_file else None
            messages, report = _publish_messages(paths, config)
            return publish(
                messages,
                report,
                rate=args.rate,
                loop=args.loop,
                wait=args.wait_subscribers,
                quiet=args.quiet,
            )
        return _offline(args)
    except ReplayError as err:
        print(f'catenary-monitor replay: {err}', file=sys.stderr)
        return err.code


def _offline(args: argparse.Namespace) -> int:
    from catenary_monitor.cli.allocator import keep_freed_memory
    from catenary_monitor.replay import outputs as out

    keep_freed_memory()  # a batch job on large arrays (see cli.allocator)
    paths = expand(args.logs)
    foreign = [why for why in map(not_mcap, paths) if why]
    if len(foreign) == len(paths):  # nothing to read: say so before asking for parameters
        raise ReplayError(foreign[0])
    if all(p.stat().st_size == 0 for p in paths):
        raise ReplayError(f'empty log: {paths[0]} holds no bytes; nothing to replay', EXIT_EMPTY)
    recorded = log_parameters(paths)
    if args.params_file:
        config = load_config(args.params_file)
        source = args.params_file
    elif recorded is not None:
        try:
            config = config_from_params(recorded[1])
        except ConfigError as err:
            raise ReplayError(
                f'the parameters recorded in the log are invalid: {err}; give ' '--params-file'
            ) from err
        source = 'recorded in the log'
    else:
        raise ReplayError(
            '--params-file is required: the log holds no catenary_monitor '
            'parameters (it names the topics and the lines)'
        )
    params = {
        'source': source,
        'config_hash': config_hash(config),
        'recorded_config_hash': recorded[0] if recorded else None,
    }
    params['same_as_recorded'] = None if recorded is None else params['config_hash'] == recorded[0]
    csv_columns = _csv_columns(args.csv_columns)
    size = sum(p.stat().st_size for p in paths)
    progress = Progress(args.progress or (not args.quiet and size > 8_000_000))
    follow = params['same_as_recorded'] is not False
    params['follows_recorded_changes'] = follow
    t_start = time.perf_counter()
    sinks, state, report = _stream_outputs(args, config, paths, csv_columns, follow, progress)
    outputs = sinks.close()
    progress.done()
    timing = dict(sinks.timing)
    timing['total_s'] = time.perf_counter() - t_start
    summary = out.summary_dict(
        sinks.tally,
        report,
        {
            'parameters': params,
            'outputs': outputs,
            'streaming': {
                'streamed': sinks.window_messages is not None,
                'windows': state.windows,
                'window_messages': sinks.window_messages,
                'jobs': args.jobs,
            },
            'timing': {k: round(v, 3) for k, v in timing.items()},
            **stamp_figures(state),
        },
    )
    text = (
        json.dumps(json_ready(summary), allow_nan=False, default=_json_default)
        if args.json
        else out.summary_text(summary)
    )
    try:
        print(text)
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. piped into head: the reader has what it wanted
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


def _stream_outputs(
    args: argparse.Namespace,
    config: MonitorConfig,
    paths: Sequence[Path],
    csv_columns: Sequence[str],
    follow: bool,
    progress: Progress,
) -> tuple['_Sinks', Any, ReadReport]:
    """Stream the replay into the outputs; a log that cannot be streamed is replayed again
    as one window (one line on stderr says so)."""
    from catenary_monitor.replay.driver import WINDOW_MESSAGES
    from catenary_monitor.replay.line_split import default_processes
    from catenary_monitor.replay.outputs import SUMMARY_VALUES

    # --out builds every diagnostic snapshot: about 2.5 times the memory per message
    window: Optional[int] = args.window_messages or (
        WINDOW_MESSAGES // 2 if args.out else WINDOW_MESSAGES
    )

    # two line processes by default for a summary only: with --csv every value of the worker's
    # lines comes back (3e6 log: 252 MiB summed, slower; docs/benchmarks.md)
    summary_only = not (args.csv or args.plot or args.out)

    def restart(why: str) -> None:
        if not args.quiet:
            print(
                f'catenary-monitor replay: cannot stream this log ({why}); replaying it '
                'as one window (memory grows with the log)',
                file=sys.stderr,
            )

    sinks, state, report = drive(
        paths,
        config,
        lambda window: _Sinks(args, config, paths, csv_columns, window),
        ticks=args.ticks,
        follow_log=follow,
        snapshots=COLUMNS if args.out else False,
        window_messages=window,
        jobs=args.jobs,
        progress=progress.stream,
        on_restart=restart,
        line_processes=args.line_processes or (default_processes() if summary_only else 1),
        value_keys=SUMMARY_VALUES if summary_only else None,
    )
    assert isinstance(sinks, _Sinks)
    return sinks, state, report


class _Sinks:
    """The outputs of a streamed replay, written window by window: the summary tally, CSV
    rows, the results MCAP and the plot envelopes (files opened with the first window)."""

    def __init__(
        self,
        args: argparse.Namespace,
        config: MonitorConfig,
        paths: Sequence[Path],
        csv_columns: Sequence[str],
        window_messages: Optional[int],
    ) -> None:
        from catenary_monitor.replay import outputs as out

        self.out = out
        self.args, self.config, self.paths = args, config, paths
        self.csv_columns = csv_columns
        self.window_messages = window_messages
        names = [line.name for line in config.lines]
        self.names = names
        self.tally = out.Tally(names)
        self.plot = out.PlotData(names) if args.plot else None
        self.files: list[_OutputFile] = []
        self.csv: Any = None
        self.mcap: Any = None
        self.rows = 0
        self.header_done = False
        self.timing: dict[str, float] = {}
        if args.csv:
            self.timing['csv_s'] = 0.0
        if args.out:
            self.timing['mcap_s'] = 0.0
        self.opened = False

    def _open(self) -> None:
        self.opened = True
        if self.args.csv:
            f = _OutputFile(self.args.csv)
            self.csv = f.__enter__()
            self.files.append(f)
        if self.args.out:
            f = _OutputFile(self.args.out)
            self.files.append(f)
            topics, depth_topic = input_topics(self.config)
            self.mcap = self.out.McapSink(
                f.__enter__(),
                self.config,
                self.names,
                topics,
                depth_topic,
                [str(p) for p in self.paths],
            )

    def __call__(self, result: Any, window: Any) -> None:
        if not self.opened:
            self._open()
        self.tally.add(result)
        if self.csv is not None:
            t0 = time.perf_counter()
            self.rows += self.out.write_csv(
                self.csv, result, None, self.csv_columns, header=not self.header_done
            )
            self.header_done = True
            self.timing['csv_s'] += time.perf_counter() - t0
        if self.mcap is not None:
            t0 = time.perf_counter()
            tensions = {name: col for name, col in zip(self.names, window.tensions)}
            self.mcap.write(result, tensions, window.depth)
            self.timing['mcap_s'] += time.perf_counter() - t0
        if self.plot is not None:
            self.plot.add(result, window.depth)

    def close(self) -> dict[str, Any]:
        """Finish the files and draw the charts; returns the summary's ``outputs``."""
        outputs: dict[str, Any] = {}
        if not self.opened:
            self._open()
        if self.csv is not None:
            outputs['csv'] = f'{self.args.csv} ({self.rows} rows)'
        if self.mcap is not None:
            t0 = time.perf_counter()
            n = self.mcap.finish()
            self.timing['mcap_s'] += time.perf_counter() - t0
            outputs['mcap'] = f'{self.args.out} ({n} messages)'
        for f in self.files:
            f.__exit__(None, None, None)
        if self.plot is not None:
            t0 = time.perf_counter()
            files = self.out.draw_plots(Path(self.args.plot), self.config, self.plot)
            self.timing['plot_s'] = time.perf_counter() - t0
            outputs['plots'] = ' '.join(str(p) for p in files)
        return outputs

    def abandon(self) -> None:
        """Close and remove what was written (the replay is redone or failed)."""
        for f in self.files:
            f.__exit__(None, None, None)
            try:
                os.unlink(f.path)
            except OSError:
                pass
        self.files = []


def _csv_columns(text: str) -> Sequence[str]:
    from catenary_monitor.replay.outputs import CSV_ALL, CSV_COLUMNS

    if not text:
        return CSV_COLUMNS
    if text == 'all':
        return [name for name, _ in CSV_ALL]
    names = [t.strip() for t in text.split(',') if t.strip()]
    unknown = [n for n in names if n not in {name for name, _ in CSV_ALL}]
    if unknown:
        raise ReplayError(
            f'--csv-columns: unknown column {unknown[0]!r}; known: '
            + ', '.join(name for name, _ in CSV_ALL)
        )
    return names


def _json_default(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f'not JSON serializable: {type(value).__name__}')


class _OutputFile:
    """Open an output file for writing; a failure is a one-line ReplayError."""

    def __init__(self, path: str) -> None:
        self.path = path

    def __enter__(self) -> Any:
        try:
            parent = os.path.dirname(self.path)
            if parent:
                os.makedirs(parent, exist_ok=True)
            self.f = open(self.path, 'wb', buffering=1 << 20)
        except OSError as err:
            raise ReplayError(f'cannot write {self.path}: {err}') from err
        return self.f

    def __exit__(self, *exc: Any) -> None:
        self.f.close()


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number: {text!r}') from None
    if not value > 0 or value == float('inf'):
        raise argparse.ArgumentTypeError(f'must be a positive number, got {text!r}')
    return value


def count_arg(text: str) -> int:
    """An argparse type: a whole number of at least 1 (jobs, workers)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not an integer: {text!r}') from None
    if value < 1:
        raise argparse.ArgumentTypeError(f'must be at least 1, got {text!r}')
    return value


def register(sub: Any) -> None:
    """Add the ``replay`` sub-command to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'replay',
        help='recompute a recorded MCAP log offline, or play it onto ROS',
        description='Recompute every update of a recorded log with the live node\'s alarm '
        'logic (vectorized), write MCAP/CSV/PNG results and print a summary; or, '
        'with --publish, publish the recorded inputs with their recorded timing.',
    )
    p.add_argument(
        'logs',
        nargs='+',
        metavar='LOG.mcap',
        help='MCAP file(s) (a rotated set) or directories of *.mcap',
    )
    p.add_argument(
        '--params-file',
        metavar='FILE',
        help='ROS 2 params YAML of the monitor (lines, topics, alarm settings); '
        'default: the parameters the node recorded in the log',
    )
    p.add_argument(
        '--out',
        metavar='RESULTS.mcap',
        help='write inputs, per-line outputs and /diagnostics as a ROS 2 MCAP log',
    )
    p.add_argument(
        '--csv', metavar='RESULTS.csv', help='write one CSV row per tension message, in time order'
    )
    p.add_argument(
        '--plot',
        metavar='CHART.png',
        help='write an overview PNG and one PNG per line (CHART_<line>.png)',
    )
    p.add_argument(
        '--csv-columns',
        metavar='LIST',
        default='',
        help='comma-separated CSV columns, or "all" (default: time, line, '
        'top_tension, depth, min_anchor_distance, anchor_margin, uplift_force, '
        'level); also horizontal_tension, tide_margin, load_margin, safety_factor, '
        'time_to_uplift, the bounds, the holding values, tide_margin_at_length, '
        'wave_tension, peak_tension, dynamic_uplift, time_to_uplift_view, '
        'sensor_state, status, model '
        '(docs/replay.md)',
    )
    p.add_argument(
        '--jobs',
        type=count_arg,
        default=1,
        metavar='N',
        help='decode the files of a rotated set or directory in N processes (the alarm '
        'logic stays serial: results are those of a serial run; default 1)',
    )
    p.add_argument(
        '--line-processes',
        type=count_arg,
        default=None,
        metavar='N',
        help='recompute the lines of each window in N processes (1 or 2: a worker process '
        'takes 7 of 12 lines; the results are those of one process; not with --out or '
        '--jobs; default for a summary alone, without --csv or --plot: 2 where two CPUs are '
        'usable and the load average leaves one idle, else 1)',
    )
    p.add_argument(
        '--window-messages',
        type=count_arg,
        default=None,
        metavar='M',
        help='input messages per replay window: the memory bound (default 131072; 65536 with '
        '--out)',
    )
    p.add_argument('--json', action='store_true', help='print the summary as one JSON object')
    p.add_argument('--quiet', action='store_true', help='no progress on stderr')
    p.add_argument(
        '--progress',
        action='store_true',
        help='show progress on stderr even for a short log (default: logs > 8 MB)',
    )
    p.add_argument(
        '--ticks',
        choices=('auto', 'log', 'grid'),
        default='auto',
        help='periodic alarm steps: the ticks the node recorded on its events channel '
        f'({EVENTS_TOPIC}; auto: if present) or a grid at diagnostic_rate',
    )
    p.add_argument(
        '--publish',
        action='store_true',
        help='publish the recorded inputs onto ROS instead (needs rclpy)',
    )
    p.add_argument(
        '--rate',
        type=_positive,
        default=1.0,
        metavar='X',
        help='--publish: play X times faster than recorded (default 1)',
    )
    p.add_argument('--loop', action='store_true', help='--publish: start again at the end')
    p.add_argument(
        '--wait-subscribers',
        type=float,
        default=0.0,
        metavar='S',
        help='--publish: wait up to S s until every topic has a subscriber (and /clock its '
        'listed ones)',
    )
    p.set_defaults(func=cmd_replay, long_running=lambda a: bool(a.publish))

"""``catenary-monitor replay LOG --publish``: play recorded inputs onto ROS (rclpy), with /clock.

Publishes every recorded input message (the params file's tension and depth topics, each of
its configured type; without a params file, every topic of a type the monitor reads:
``std_msgs/msg/Float64``, ``geometry_msgs/msg/WrenchStamped``, ``sensor_msgs/msg/FluidPressure``,
``sensor_msgs/msg/Range``) on its topic, as recorded (the CDR bytes, header stamps
included), in log-time order, at its recorded time offset divided by ``--rate``: a live node
can be tested against a real log on a machine without rosbag2. Publishers are reliable,
keep-last 100 (they match the node's best-effort sensor-data subscriptions too).

``/clock`` (``rosgraph_msgs/msg/Clock``, as ``ros2 bag play --clock``) carries the log's time:
the recorded log time of each message just before it is published, and in between, every
:data:`CLOCK_PERIOD` s of wall time, the log time the playback has reached (start + elapsed x
rate). A node started with ``use_sim_time`` then judges the playback in log time: at ``--rate
10`` its timeouts, hold times and trends run ten times faster, as they ran in the recording.
The clock never goes backwards within a pass; ``--loop`` starts it again at the log's start.

ROS 2 time ends in 2038: ``builtin_interfaces/msg/Time`` is ``int32 sec`` + ``uint32 nanosec``
(the message definition; ROS 1's ``uint32`` ran to 2106). rclpy's setter takes any integer and
the serializer keeps its low 32 bits: 2**31 s (2038-01-19T03:14:08Z) arrives as -2**31 (1901),
2**32 s (2106) as 0 (1970), so /clock goes backwards; and rclpy's TimeSource raises
``ValueError`` on negative seconds, in every ``use_sim_time`` node it reaches. Shifting the
clock would misplace everything the log's time decides (tide tables, days, header stamps).
So the messages recorded at or past :data:`CLOCK_END_NS` are left out, counted and named in
one line (the offline replay reads any time); a log with nothing before it is refused (exit 2).

Timing: a wall-clock schedule (``time.monotonic``) fixed at the start of each pass, so a late
message does not delay the following ones; the lateness is reported at the end (median, p99,
max). ``--loop`` starts the next pass one median message gap after the last message.
SIGINT/SIGTERM stop playback between two messages; exit 0.

The command line (:mod:`catenary_monitor.cli.replay`) picks and reads the messages; this module
only plays them (the ROS layer imports nothing from the command line).
"""

from __future__ import annotations

import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

from catenary_monitor.io.mcap_scan import ReadReport
from catenary_monitor.io.mcap_summary import channels_of

__all__ = [
    'CLOCK_END_NS',
    'CLOCK_PERIOD',
    'INPUT_TYPES',
    'CLOCK_TOPIC',
    'input_topics_of_log',
    'publish',
]

#: Wall time between two /clock messages while no input message is due [s] (40 Hz, as
#: ``ros2 bag play --clock``'s default).
CLOCK_PERIOD = 0.025
SETTLE = 0.3  # s the readers found must stay matched before the playback begins
CLOCK_TOPIC = '/clock'
#: The first log time (ns) /clock cannot carry: 2**31 s, 2038-01-19T03:14:08Z (int32 seconds).
CLOCK_END_NS = 2**31 * 10**9
#: The types the monitor reads, which playback publishes.
INPUT_TYPES = (
    'std_msgs/msg/Float64',
    'geometry_msgs/msg/WrenchStamped',
    'sensor_msgs/msg/FluidPressure',
    'sensor_msgs/msg/Range',
)

Messages = dict[str, tuple[np.ndarray, list[bytes], str]]  # topic -> (log ns, CDR, type)


def input_topics_of_log(paths: Sequence[Path]) -> dict[str, str]:
    """Every topic of an input type (:data:`INPUT_TYPES`) -> its type (the summary if the file
    has one, else the reader's walk of its channels; bounded either way)."""
    topics: dict[str, str] = {}
    for path in paths:
        for channel in channels_of(path).values():
            if channel.schema_name in INPUT_TYPES:
                topics.setdefault(channel.topic, channel.schema_name)
    return topics


def _message_class(type_name: str) -> Any:
    """The rclpy message class of an input type, or of ``rosgraph_msgs/msg/Clock``."""
    package, _, name = type_name.split('/')
    module = __import__(f'{package}.msg', fromlist=[name])
    return getattr(module, name)


def publish(
    messages: Messages,
    report: ReadReport,
    *,
    rate: float = 1.0,
    loop: bool = False,
    wait: float = 0.0,
    quiet: bool = False,
) -> int:
    """Play ``messages`` (topic -> (log times ns, CDR payloads, type name)) read with
    ``report``, with /clock; returns the exit status (see :mod:`catenary_monitor.cli.replay`).
    Messages at or past :data:`CLOCK_END_NS` are left out (one line); none before it: 2.
    """
    messages, late, first_late = _before_clock_end(messages)
    topics = [t for t, (ts, _, _) in messages.items() if len(ts)]
    if late:
        what = 'every message is' if not topics else f'{late} message(s)'
        print(
            f'replay --publish: {what} recorded from {_utc(first_late)} on: ROS 2\'s /clock '
            'cannot carry a time past 2038-01-19T03:14:07Z (builtin_interfaces/Time: int32 '
            + ('seconds): nothing to publish' if not topics else 'seconds): left out')
            + ' (replay the log without --publish to read them)',
            file=sys.stderr,
        )
    if not topics:
        return 2
    types = [messages[t][2] for t in topics]
    t_ns = np.concatenate([messages[t][0] for t in topics])
    which = np.concatenate([np.full(len(messages[t][0]), k) for k, t in enumerate(topics)])
    payloads_all = [p for t in topics for p in messages[t][1]]
    order = np.argsort(t_ns, kind='stable')
    t_ns, which = t_ns[order], which[order]
    payloads = [payloads_all[i] for i in order.tolist()]
    offsets = (t_ns - t_ns[0]) * 1e-9 / rate
    if not quiet:
        skipped = '' if report.complete else f'; damaged input, skipped: {len(report.skips)}'
        print(
            f'replay --publish: {len(t_ns)} messages on {len(topics)} topic(s), '
            f'{offsets[-1]:.1f} s at rate {rate:g}, /clock from the log{skipped}',
            file=sys.stderr,
        )
    return _play(topics, types, which, t_ns, offsets, payloads, rate, loop, wait, quiet)


def _before_clock_end(messages: Messages) -> tuple[Messages, int, int]:
    """The messages /clock can carry, how many were left out and the first of those (ns)."""
    kept: Messages = {}
    late, first = 0, 0
    for topic, (ts, payloads, type_name) in messages.items():
        ts = np.asarray(ts, dtype=np.uint64)
        ok = ts < np.uint64(CLOCK_END_NS)
        if not ok.all():
            late += int((~ok).sum())
            lowest = int(ts[~ok].min())
            first = lowest if not first else min(first, lowest)
            payloads = [p for p, keep in zip(payloads, ok.tolist()) if keep]
            ts = ts[ok]
        kept[topic] = (ts.astype(np.int64), payloads, type_name)
    return kept, late, first


def _utc(t_ns: int) -> str:
    import datetime as _dt

    epoch = _dt.datetime(1970, 1, 1, tzinfo=_dt.timezone.utc)
    return (epoch + _dt.timedelta(microseconds=t_ns // 1000)).strftime('%Y-%m-%dT%H:%M:%SZ')


def _play(
    topics: list[str],
    types: list[str],
    which: np.ndarray,
    t_ns: np.ndarray,
    offsets: np.ndarray,
    payloads: list[bytes],
    rate: float,
    loop: bool,
    wait: float,
    quiet: bool,
) -> int:
    import rclpy
    from rclpy.qos import QoSProfile
    from rclpy.signals import SignalHandlerOptions
    from rosgraph_msgs.msg import Clock

    stop = threading.Event()

    def handler(signum: int, frame: Any) -> None:
        stop.set()

    signal.signal(signal.SIGINT, handler)
    signal.signal(signal.SIGTERM, handler)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node('catenary_monitor_replay')
    try:
        qos = QoSProfile(depth=100)
        pubs = [node.create_publisher(_message_class(ty), t, qos) for t, ty in zip(topics, types)]
        clock_pub = node.create_publisher(Clock, CLOCK_TOPIC, qos)
        clock = Clock()

        def tick(log_ns: int) -> None:
            clock.clock.sec, clock.clock.nanosec = divmod(int(log_ns), 1_000_000_000)
            clock_pub.publish(clock)

        _wait_for_readers(node, pubs, clock_pub, stop, wait)
        gap = float(np.median(np.diff(offsets))) if len(offsets) > 1 else 0.0
        which_l, offsets_l, times_l = which.tolist(), offsets.tolist(), t_ns.tolist()
        first = times_l[0]
        passes = 0
        late: list[float] = []
        while not stop.is_set():
            start = time.monotonic()
            tick(first)
            for k, off, log_ns, data in zip(which_l, offsets_l, times_l, payloads):
                due = start + off
                if _wait_ticking(stop, start, due, first, rate, tick):
                    break
                tick(log_ns)
                pubs[k].publish(data)
                late.append(time.monotonic() - due)
            passes += 1
            if not loop:
                break
            stop.wait(gap)
        if not quiet and late:
            lat = np.array(late) * 1e3
            print(
                f'replay --publish: {passes} pass(es), {len(late)} messages published; '
                f'lateness median {np.median(lat):.2f} ms, p99 {np.percentile(lat, 99):.2f} '
                f'ms, max {lat.max():.2f} ms',
                file=sys.stderr,
            )
        # Give reliable transport a moment to deliver the last messages before tear-down.
        time.sleep(0.2)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def _wait_for_readers(
    node: Any, pubs: list[Any], clock_pub: Any, stop: threading.Event, wait: float
) -> None:
    """Wait up to ``wait`` s until every data topic has a matched reader and every reader the
    graph already lists (on /clock too) is matched, and that has held for :data:`SETTLE` s
    (a participant's readers are discovered one by one: its data reader matched first once,
    its /clock reader 1.6 s of log time later), so a sim-time node's /clock reader found with
    its data readers sees the first tick."""
    deadline = time.monotonic() + wait
    every = [*pubs, clock_pub]
    since: Optional[float] = None
    while wait > 0 and not stop.is_set() and time.monotonic() < deadline:
        if all(p.get_subscription_count() > 0 for p in pubs) and all(
            p.get_subscription_count() >= node.count_subscribers(p.topic_name) for p in every
        ):
            since = time.monotonic() if since is None else since
            if time.monotonic() - since >= SETTLE:
                return
        else:
            since = None
        stop.wait(0.05)


def _wait_ticking(
    stop: threading.Event, start: float, due: float, first_ns: int, rate: float, tick: Any
) -> bool:
    """Wait until ``due`` (monotonic s), publishing /clock every :data:`CLOCK_PERIOD` at the
    log time reached (``first_ns`` + elapsed x ``rate``); True when stopped meanwhile."""
    while True:
        now = time.monotonic()
        if now >= due:
            return False
        if stop.wait(min(due - now, CLOCK_PERIOD)):
            return True
        now = min(time.monotonic(), due)
        tick(first_ns + int((now - start) * rate * 1e9))

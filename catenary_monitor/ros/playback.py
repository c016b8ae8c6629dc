"""``catenary-monitor replay LOG --publish``: play recorded inputs onto ROS (rclpy).

Publishes every recorded ``std_msgs/msg/Float64`` input (the params file's tension and depth
topics, or, without a params file, every Float64 topic of the log) on its topic, in log-time
order, at its recorded time offset divided by ``--rate``: a live node can be tested against a
real log on a machine without rosbag2. Publishers are reliable, keep-last 100 (they match the
node's best-effort sensor-data subscriptions too). The payload is the recorded value re-encoded
as CDR (12 bytes), published as serialized bytes.

Timing: a wall-clock schedule (``time.monotonic``) fixed at the start of each pass, so a late
message does not delay the following ones; the lateness is reported at the end (median, p99,
max). ``--loop`` starts the next pass one median message gap after the last message.
SIGINT/SIGTERM stop playback between two messages; exit 0.

The command line (:mod:`catenary_monitor.cli.replay`) picks and reads the columns; this module
only plays them (the ROS layer imports nothing from the command line).
"""

from __future__ import annotations

import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from catenary_monitor.io.cdr import float64_payloads
from catenary_monitor.io.mcap_read import FLOAT64_TYPE, ReadReport, iter_messages

__all__ = ['float64_topics', 'publish']


def float64_topics(paths: Sequence[Path]) -> list[str]:
    """Every topic logged as ``std_msgs/msg/Float64`` (summary if present, else a scan)."""
    from mcap.reader import make_reader

    topics: list[str] = []
    for path in paths:
        summary = None
        try:
            with open(path, 'rb') as f:
                summary = make_reader(f).get_summary()
        except Exception:  # noqa: BLE001 - damaged file: scan it
            summary = None
        if summary is not None and summary.channels:
            for ch in summary.channels.values():
                schema = summary.schemas.get(ch.schema_id)
                if schema is not None and schema.name == FLOAT64_TYPE and ch.topic not in topics:
                    topics.append(ch.topic)
            continue
        for msg in iter_messages(path, None, ReadReport()):
            if msg.schema_name == FLOAT64_TYPE and msg.topic not in topics:
                topics.append(msg.topic)
    return topics


def publish(
    columns: dict[str, tuple[np.ndarray, np.ndarray]],
    report: ReadReport,
    *,
    rate: float = 1.0,
    loop: bool = False,
    wait: float = 0.0,
    quiet: bool = False,
) -> int:
    """Play the input ``columns`` (topic -> (log times ns, values)) read with ``report``;
    returns the exit status (see :mod:`catenary_monitor.cli.replay`)."""
    topics = [t for t, (ts, _) in columns.items() if len(ts)]
    t_ns = np.concatenate([columns[t][0] for t in topics])
    which = np.concatenate([np.full(len(columns[t][0]), k) for k, t in enumerate(topics)])
    values = np.concatenate([columns[t][1] for t in topics])
    order = np.argsort(t_ns, kind='stable')
    t_ns, which, values = t_ns[order], which[order], values[order]
    offsets = (t_ns - t_ns[0]) * 1e-9 / rate
    payloads = [bytes(row) for row in float64_payloads(values)]
    if not quiet:
        skipped = '' if report.complete else f'; damaged input, skipped: {len(report.skips)}'
        print(
            f'replay --publish: {len(t_ns)} messages on {len(topics)} topic(s), '
            f'{offsets[-1]:.1f} s at rate {rate:g}{skipped}',
            file=sys.stderr,
        )
    return _play(topics, which, offsets, payloads, loop, wait, quiet)


def _play(
    topics: list[str],
    which: np.ndarray,
    offsets: np.ndarray,
    payloads: list[bytes],
    loop: bool,
    wait: float,
    quiet: bool,
) -> int:
    import rclpy
    from rclpy.qos import QoSProfile
    from rclpy.signals import SignalHandlerOptions
    from std_msgs.msg import Float64

    stop = threading.Event()

    def handler(signum: int, frame: Any) -> None:
        stop.set()

    signal.signal(signal.SIGINT, handler)
    signal.signal(signal.SIGTERM, handler)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node('catenary_monitor_replay')
    try:
        qos = QoSProfile(depth=100)
        pubs = [node.create_publisher(Float64, t, qos) for t in topics]
        deadline = time.monotonic() + wait
        while wait > 0 and not stop.is_set() and time.monotonic() < deadline:
            if all(p.get_subscription_count() > 0 for p in pubs):
                break
            stop.wait(0.05)
        gap = float(np.median(np.diff(offsets))) if len(offsets) > 1 else 0.0
        which_l = which.tolist()
        offsets_l = offsets.tolist()
        passes = 0
        late: list[float] = []
        while not stop.is_set():
            start = time.monotonic()
            for k, off, data in zip(which_l, offsets_l, payloads):
                due = start + off
                now = time.monotonic()
                if due > now and stop.wait(due - now):
                    break
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

"""The replay console's data: a recorded log recomputed by the monitor's own replay.

:func:`load_log` is the one place the console calls the replay machinery
(:func:`catenary_monitor.replay.driver.replay_log` with every snapshot); :class:`ReplaySource`
answers the page at any time ``t`` of the log with what the live console would have shown then:
the newest ``/diagnostics`` array at or before ``t`` (levels, messages, alarm states and the
acknowledgements the node recorded), the newest outputs, the alarm history up to ``t`` and the
trends. A gap in the arrays (the monitor was down) shows as the lost-connection banner.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

import numpy as np

from catenary_monitor.console.frames import (
    AckError,
    History,
    Status,
    bucket,
    build_frame,
    console_config,
    silence_limit,
    statuses_by_name,
    tide_trend,
)
from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.monitor.state import VALUE_FIELDS, output_values
from catenary_monitor.core.monitor.status import Snapshot
from catenary_monitor.core.twin.engine import ReplayResult

__all__ = ['LOG_STATUSES', 'LogError', 'load_log', 'max_snapshots', 'ReplaySource']


class LogError(Exception):
    """A log the console cannot show: ``str()`` is one line; ``code`` the exit status."""

    def __init__(self, message: str, code: int = 2) -> None:
        super().__init__(message)
        self.code = code


#: The diagnostic statuses the log view holds at most (every snapshot's, about 2 kB each with
#: its history): about 200 MB beside the interpreter's 90 MB.
LOG_STATUSES = 100_000


def max_snapshots(config: MonitorConfig) -> int:
    """How many snapshots (ticks) of ``config``'s monitor the log view holds at most: a longer
    log is refused in one line (a line and the tide, sensors, alarms, logger statuses each;
    a dock's and the guards' too)."""
    return LOG_STATUSES // (len(config.lines) + 7)


def load_log(
    logs: Sequence[str],
    params_file: Optional[str],
    on_damage: Optional[Callable[[str], None]] = None,
) -> tuple[MonitorConfig, ReplayResult, tuple[np.ndarray, np.ndarray], list[Path]]:
    """(configuration, every step with its snapshots, the depth column, the files) of a log:
    the params file's configuration, else the one the node recorded. ``on_damage`` gets one
    line when parts of the log were skipped (damaged, or crafted: the reader's bounds), and
    one on bad stamps left out and on silences not ticked through. A log of more ticks than
    :func:`max_snapshots` is refused (LogError)."""
    from catenary_monitor.core.config.parameters import ConfigError, config_from_params
    from catenary_monitor.io.mcap_read import expand_paths
    from catenary_monitor.replay.driver import (
        ReplayError,
        load_config,
        log_parameters,
        replay_log,
    )

    try:
        paths = expand_paths(list(logs))
        if not paths:
            raise LogError(f'no *.mcap file in {", ".join(logs)}')
        if params_file:
            config = load_config(params_file)
            follow = True
        else:
            recorded = log_parameters(paths)
            if recorded is None:
                raise LogError('the log holds no catenary_monitor parameters: give --params-file')
            config = config_from_params(recorded[1])
            follow = True
        notes: list[str] = []
        result, _, depth, report = replay_log(
            paths,
            config,
            follow_log=follow,
            snapshots=True,
            max_ticks=max_snapshots(config),
            notes=notes,
        )
    except FileNotFoundError as err:
        raise LogError(str(err)) from None
    except ReplayError as err:
        raise LogError(str(err), err.code) from None
    except ConfigError as err:
        raise LogError(f'the parameters recorded in the log are invalid: {err}') from None
    if on_damage is not None:
        for note in notes:
            on_damage(note)
    if report.skips and on_damage is not None:
        first = report.skips[0]
        on_damage(
            f'damaged log: {len(report.skips)} part(s) skipped, everything readable is shown '
            f'(first: {first.path} @{first.offset}: {first.kind}: {first.reason})'
        )
    return config, result, depth, paths


def _statuses(snapshot: Snapshot) -> dict[str, Status]:
    return statuses_by_name(
        (st.name, int(st.level), st.message, st.values) for st in snapshot.statuses
    )


class ReplaySource:
    """The console over a recorded log (read-only: acknowledgements are the recorded ones)."""

    mode = 'replay'

    def __init__(
        self,
        config: MonitorConfig,
        result: ReplayResult,
        depth: tuple[np.ndarray, np.ndarray],
        files: Sequence[Path] = (),
    ) -> None:
        self.config = config
        self.names = [line.name for line in config.lines]
        self.result = result
        self.files = [str(f) for f in files]
        self.limit = silence_limit(config.alarm.diagnostic_rate)
        # replay_log(snapshots=True) gives Snapshots only (no SnapshotColumns)
        self.snapshots = [s for s in result.snapshots if isinstance(s, Snapshot)]
        self.snap_t = np.array([s.stamp_ns for s in self.snapshots], np.int64) * 1e-9
        self.history = History()
        for snap in self.snapshots:
            self.history.feed(snap.stamp_ns * 1e-9, _statuses(snap), self.names)
        self.hist_t = np.array([e['time'] for e in self.history.entries])
        self.lines = {r.name: r for r in result.lines}
        self.line_t = {r.name: r.t_ns * 1e-9 for r in result.lines}
        self.sample_times = {r.name: r.t_ns[r.tension_rows] * 1e-9 for r in result.lines}
        self.depth_t, self.depth_v = depth[0] * 1e-9, depth[1]
        self.t_start = result.start_ns * 1e-9
        # The slider reaches the newest snapshot too: an acknowledgement recorded after the last
        # input (the monitor stopped before its next tick) is still shown.
        self.t_end = max(result.end_ns * 1e-9, float(self.snap_t[-1]) if len(self.snap_t) else 0)
        self.version = 0

    def config_json(self) -> dict[str, Any]:
        return console_config(
            self.config,
            self.names,
            'replay',
            t_start=self.t_start,
            t_end=self.t_end,
            files=self.files,
        )

    def wait(self, version: int, timeout: float) -> int:
        time.sleep(timeout)
        return version

    def _clamp(self, t: Optional[float]) -> float:
        return self.t_end if t is None else min(max(t, self.t_start), self.t_end)

    def frame(self, t: Optional[float] = None) -> dict[str, Any]:
        now = self._clamp(t)
        i = int(np.searchsorted(self.snap_t, now, 'right')) - 1
        statuses = _statuses(self.snapshots[i]) if i >= 0 else {}
        outputs: dict[str, tuple[float, list[float]]] = {}
        sample_t: dict[str, float] = {}
        for name in self.names:
            r = self.lines[name]
            j = int(np.searchsorted(self.line_t[name], now, 'right')) - 1
            if j >= 0:
                values = [float(r.values[k][j]) for k in VALUE_FIELDS]
                outputs[name] = (
                    float(self.line_t[name][j]),
                    list(output_values(values, float(r.status[j]), float(r.level[j]))),
                )
            times = self.sample_times[name]
            m = int(np.searchsorted(times, now, 'right')) - 1
            if m >= 0:
                sample_t[name] = float(times[m])
        h = int(np.searchsorted(self.hist_t, now, 'right'))
        return build_frame(
            now,
            self.names,
            float(self.snap_t[i]) if i >= 0 else None,
            statuses,
            outputs,
            sample_t,
            tide_trend(statuses),
            self.history.entries[:h],
            self.limit,
            t_start=self.t_start,
            t_end=self.t_end,
        )

    def trend(self, line: str, t: Optional[float], span: float) -> dict[str, Any]:
        now = self._clamp(t)
        lo = now - span
        series: dict[str, Any] = {}
        r = self.lines.get(line)
        if r is not None:
            series = bucket(
                self.line_t[line],
                {
                    'tension_max': r.values['top_tension'],
                    'uplift_max': r.values['uplift_force'],
                    'margin_min': r.values['anchor_margin'],
                },
                lo,
                now,
            )
        depth = bucket(
            self.depth_t, {'depth_max': self.depth_v, 'depth_min': self.depth_v}, lo, now
        )
        return {'line': line, 'lo': lo, 'hi': now, 'series': series, 'depth': depth}

    def acknowledge(self, line: str, origin: str) -> str:
        raise AckError(
            'replay is read-only: the acknowledgements shown are the recorded ones', 409
        )

    def shelve(self, alarm: str, condition: str, seconds: float, origin: str) -> dict[str, Any]:
        raise AckError('replay is read-only: the shelves shown are the recorded ones', 409)

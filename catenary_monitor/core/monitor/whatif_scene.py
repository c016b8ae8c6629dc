"""What-if: every line's margins, uplift, holding and time to uplift for one chosen scene.

:func:`whatif` runs the monitor core itself
(:class:`~catenary_monitor.core.monitor.monitor_core.MonitorCore`) on that scene, so a what-if
answer is the live monitor's decision for those readings:

* the configuration with the given anchor distances (``anchor_distances``, m; the others keep
  their ``NAME.anchor_distance``);
* the depth ``depth`` (m, the tide at the hooks; each line adds its ``hook_height``); with a
  ``tide_rate`` (m/s) the depth samples of one ``tide_trend_window`` before the scene rise at
  that rate and reach ``depth`` at the scene, so the core's tide trend is that rate and
  ``time_to_uplift`` follows it (without it the trend is unknown and ``time_to_uplift`` is
  NaN, the core's rule for an unknown trend: unknown, not "never");
* each line's hook tension (N) at the scene, and again ``on_delay`` before it (the scene has
  held long enough for a condition to raise);
* a tick at the scene: the levels and messages are the core's after it.

A line not given a tension hangs as installed, where the params file says how: with its
``NAME.chain_length`` its tension is that chain's at its anchor distance and this depth in still
water (problem 5, :func:`~catenary_monitor.core.physics.fixed_length.statics_at_span`, EA
included); each line says where its tension came from (``source``: ``given`` or ``hanging``; the
command adds ``log``). A line with neither is a ValueError naming it.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Mapping, NamedTuple, Optional

from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.monitor.events import Depth, Event, Tension, Tick
from catenary_monitor.core.monitor.monitor_core import MonitorCore

__all__ = [
    'LineScene',
    'Scene',
    'whatif',
    'hanging_tensions',
    'unhung_reason',
    'with_distances',
    'scene_dict',
]


class LineScene(NamedTuple):
    """One line in the scene: its name, tension (N), anchor distance (m), level name and
    message, and its outputs (:data:`OUTPUT_FIELDS` -> float, SI)."""

    line: str
    tension: float
    anchor_distance: float
    level: str
    message: str
    values: dict[str, float]
    source: str = 'given'


class Scene(NamedTuple):
    """The scene's depth (m), tide rate (m/s, NaN: none) and every line."""

    depth: float
    tide_rate: float
    lines: tuple[LineScene, ...]


def with_distances(config: MonitorConfig, distances: Mapping[str, float]) -> MonitorConfig:
    names = {line.name for line in config.lines}
    unknown = sorted(set(distances) - names)
    if unknown:
        raise ValueError(f'unknown line {unknown[0]!r} (lines: {", ".join(sorted(names))})')
    lines = tuple(
        (
            dataclasses.replace(line, anchor_distance=float(distances[line.name]))
            if line.name in distances
            else line
        )
        for line in config.lines
    )
    return dataclasses.replace(config, lines=lines)


def _events(
    config: MonitorConfig, depth: float, tensions: list[float], tide_rate: float
) -> tuple[list[Event], int]:
    """The scene's events and its stamp (ns)."""
    alarm = config.alarm
    window = alarm.tide_trend_window
    ramp = math.isfinite(tide_rate)
    lead = (1.1 * window if ramp else 0.0) + alarm.on_delay
    scene_ns = int(round((lead + 1.0) * 1e9))
    events: list[Event] = []
    if ramp:
        step = min(window / 120.0, alarm.depth_timeout / 2.0)
        n = int(1.1 * window / step)
        for k in range(n, 0, -1):
            ago = k * step
            if ago <= alarm.on_delay:
                continue
            events.append(Depth(scene_ns - int(round(ago * 1e9)), depth - tide_rate * ago))
    before = scene_ns - int(round(alarm.on_delay * 1e9))
    stamps = sorted({before, scene_ns})
    for stamp in stamps:
        events.append(Depth(stamp, depth - (tide_rate * (scene_ns - stamp) * 1e-9 if ramp else 0)))
        events += [Tension(stamp + 1 + k, k, t) for k, t in enumerate(tensions)]
    events.append(Tick(scene_ns + len(tensions) + 1))
    return sorted(events, key=lambda e: e.stamp_ns), scene_ns


def whatif(
    config: MonitorConfig,
    depth: float,
    tensions: Mapping[str, float],
    anchor_distances: Optional[Mapping[str, float]] = None,
    tide_rate: float = math.nan,
) -> Scene:
    """Every line's outputs, level and message for hook ``tensions`` (line name -> N, every
    line), ``depth`` (m), ``anchor_distances`` (line name -> m, the others installed) and a
    ``tide_rate`` (m/s, NaN: no trend), as the monitor core decides them (module docstring).
    ValueError names an unknown or missing line."""
    cfg = with_distances(config, dict(anchor_distances or {}))
    names = [line.name for line in cfg.lines]
    unknown = sorted(set(tensions) - set(names))
    if unknown:
        raise ValueError(f'unknown line {unknown[0]!r} (lines: {", ".join(names)})')
    hanging = hanging_tensions(cfg, float(depth), [n for n in names if n not in tensions])
    missing = [n for n in names if n not in tensions and n not in hanging]
    if missing:
        raise ValueError(
            f'no tension for line {missing[0]!r}: {unhung_reason(cfg, depth, missing[0])}'
        )
    values = [float(tensions[n]) if n in tensions else hanging[n] for n in names]
    events, _ = _events(cfg, float(depth), values, float(tide_rate))
    core = MonitorCore(cfg, 0)
    for event in events:
        core.step(event)
    lines = []
    for k, line in enumerate(core.state.lines):
        out = dict(zip(OUTPUT_FIELDS, core.output(k).values))
        lines.append(
            LineScene(
                line.config.name,
                values[k],
                line.config.anchor_distance,
                line.state.level.name,
                line.state.message,
                out,
                'given' if line.config.name in tensions else 'hanging',
            )
        )
    return Scene(float(depth), float(tide_rate), tuple(lines))


def hanging_tensions(config: MonitorConfig, depth: float, names: list[str]) -> dict[str, float]:
    """Hook tension (N) of each named line with a ``chain_length`` hanging at its anchor
    distance in still water at ``depth`` (m, plus its ``hook_height``); lines without one, or
    whose chain cannot reach (taut), are left out."""
    from catenary_monitor.core.physics.fixed_length import statics_at_span
    from catenary_monitor.core.physics.solve import solve

    out: dict[str, float] = {}
    for line in config.lines:
        if line.name not in names or line.chain_length is None:
            continue
        ea = math.inf if line.ea is None else line.ea
        if line.point_loads is not None:  # problem 5 with the clumps and buoys
            tension = float(
                solve(
                    line.weight,
                    depth + line.hook_height,
                    chain_length=line.chain_length,
                    anchor_distance=line.anchor_distance,
                    point_loads=line.point_loads,
                ).top_tension
            )
        else:
            state = statics_at_span(
                line.weight, depth + line.hook_height, line.chain_length, line.anchor_distance, ea
            )
            tension = float(state.top_tension)
        if math.isfinite(tension):
            out[line.name] = tension
    return out


def unhung_reason(config: MonitorConfig, depth: float, name: str) -> str:
    """Why line ``name`` has no tension from :func:`hanging_tensions` at ``depth`` (m)."""
    line = next(ln for ln in config.lines if ln.name == name)
    if line.chain_length is None:
        return 'no chain_length to hang it as installed'
    h = depth + line.hook_height
    reach = math.hypot(line.anchor_distance, h)
    return (
        f'its chain ({line.chain_length:g} m) cannot hang as installed at depth {h:g} m: '
        f'it is taut, shorter than the straight line to the anchor ({reach:g} m)'
        if line.chain_length <= reach
        else f'its chain ({line.chain_length:g} m) gives no finite tension at depth {h:g} m'
    )


def scene_dict(scene: Scene) -> dict[str, Any]:
    """The scene as plain data (SI; NaN and infinities as None, ``time_to_uplift`` None when
    not known or not coming: ``uplift_coming`` says which)."""

    def finite(v: float) -> Optional[float]:
        return v if math.isfinite(v) else None

    return {
        'depth': scene.depth,
        'tide_rate': finite(scene.tide_rate),
        'lines': [
            {
                'line': ls.line,
                'tension': ls.tension,
                'tension_source': ls.source,
                'anchor_distance': ls.anchor_distance,
                'level': ls.level,
                'message': ls.message,
                'uplift_coming': (
                    None
                    if math.isnan(ls.values['time_to_uplift'])
                    else not math.isinf(ls.values['time_to_uplift'])
                ),
                **{key: finite(v) for key, v in ls.values.items() if key != 'level'},
            }
            for ls in scene.lines
        ],
    }

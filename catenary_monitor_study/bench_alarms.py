"""``catenary-monitor bench-alarms``: the alarm system on days of a dock's normal operation and
on injected faults, counted as the operator hears it.

Generates (:mod:`catenary_monitor_study.normal_days`, seeded) days of the dock's normal
operation read by each kind of tide gauge (a 1 cm radar, a 1 mm pressure gauge with 2 mm
noise, an ideal 1 mm gauge), then shorter scenes each with one fault (a load-cell gateway
silent for 15 s, one silent load cell, a silent gauge, daN on an N line and tonnes-force on a
kN line while a storm lifts that line's anchor and no other, a parted chain, a pressure gauge
stepping to 0.3 m of depth); replays each log once with the replay driver into two sinks:

* the annunciations of the snapshots the monitor publishes on ``/diagnostics`` (every status
  that leaves OK or rises, :mod:`catenary_monitor_study.annunciations`): what ``replay --out``
  records and the operator hears;
* the alarm report (:class:`~catenary_monitor.replay.alarm_report.AlarmReport`): what
  ``catenary-monitor alarms --json`` counts.

It reports, beside the ISA-18.2 / EEMUA 191 targets: annunciations per 10 minutes on normal
days (mean, peak) and by class (status, level, cause), both counts and their gap; per fault,
the annunciations in its window (count, the causes named, the first-out: the first one heard
in the window, and whether it names the fault's cause) and those outside it. A units fault's
cause is named by a "wrong units?" naming a right factor (x10 or x9.81, which its text names
together) or no factor (the unit unsure), never by one naming a wrong factor; its storm is
:func:`~catenary_monitor_study.normal_days.isolating_storm`'s (the line, direction and
centre that lift one end line's anchor by 5 kN at the peak while the other lines keep the
largest anchor margin), the line the fault's. A table by default, ``--json`` one object;
progress on stderr (``--quiet`` none). ``--keep DIR`` keeps
the logs and params files (``catenary-monitor replay LOG --params-file LOG.yaml --out ...``
replays any of them).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import shutil
import sys
import tempfile
import time
from collections import Counter as Tally
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np

from catenary_monitor.cli.table import json_ready
from catenary_monitor_study.annunciations import Counter, family
from catenary_monitor_study.normal_days import (
    FAULT_KINDS,
    GAUGES,
    Fault,
    Scene,
    drawn_scene,
    isolating_storm,
    paper_scene,
    scene_margins,
    storm_line,
    truth_statics,
)
from catenary_monitor_study.normal_days_log import write_scene

__all__ = ['register', 'run', 'plan', 'replay_counts', 'EXPECTED']

#: What each fault must be annunciated as: (status family, a word the cause must hold).
EXPECTED = {
    'gateway_drop': ('sensors', 'silent'),
    'silent_cell': ('line', 'stale'),
    'silent_gauge': ('sensors', 'depth'),
    'units_dan': ('line', 'units'),
    'units_tf': ('line', 'units'),
    'parted': ('line', 'parted'),
    'pressure_step': ('tide', 'depth'),
}
#: The normal scenes' gauges by default: one of each kind.
NORMAL_GAUGES = ('radar_1cm', 'pressure_1mm', 'exact_1mm')
#: The fault scenes' gauge (the others read by the radar).
FAULT_GAUGE = {'pressure_step': 'pressure_1mm'}
TARGET_MEAN = 'about 1 per 10 min acceptable, 2 the most manageable (ISA-18.2 / EEMUA 191)'
TARGET_PEAK = 'at most 10 in any 10 min (more is a flood)'
TARGET_FAULT = 'one annunciation naming the cause (at most two in its window), first-out right'


def plan(
    dock: str,
    days: float,
    hours: float,
    gauges: list[str],
    faults: list[str],
    seed: int,
    settings: Optional[dict[str, Any]] = None,
) -> list[tuple[str, Scene]]:
    """The scenes: ('normal', scene) per gauge, then (fault kind, scene) per fault."""

    def make(gauge: str, span: float, fs: tuple[Fault, ...] = ()) -> Scene:
        if dock == 'paper':
            return paper_scene(gauge, days=span, faults=fs, seed=seed, settings=settings)
        return drawn_scene(int(dock.split(':', 1)[1]), gauge, days=span, faults=fs,
                           settings=settings)  # fmt: skip

    out = [('normal', make(g, days)) for g in gauges]
    if not faults:
        return out
    probe = make('radar_1cm', hours / 24.0)
    names = [line.name for line in probe.config.lines]
    storm = storm_line(probe)
    lifting = isolating_storm(probe) if {'units_dan', 'units_tf'} & set(faults) else None
    lifted = lifting.line if lifting is not None else None
    mid = 0.5 * hours * 3600.0
    for kind in faults:
        fault = {
            'gateway_drop': Fault('gateway_drop', mid, 15.0),
            'silent_cell': Fault('silent_cell', mid, 1800.0, names[len(names) // 4]),
            'silent_gauge': Fault('silent_gauge', mid, 1800.0),
            'units_dan': Fault('units_dan', 0.0, math.inf, lifted),
            'units_tf': Fault('units_tf', 0.0, math.inf, lifted),
            'parted': Fault('parted', mid, math.inf, storm, 12.0),
            'pressure_step': Fault('pressure_step', mid, 1800.0, None, 0.3),
        }[kind]
        scene = make(FAULT_GAUGE.get(kind, 'radar_1cm'), hours / 24.0, (fault,))
        if kind in ('units_dan', 'units_tf'):  # the storm that lifts that line alone
            scene = replace(scene, weather=replace(scene.weather, storm=lifting))
        out.append((kind, scene))
    return out


def replay_counts(
    log: Path, params: Path, progress: Optional[Callable[[float], None]] = None
) -> tuple[Counter, dict[str, Any]]:
    """Replay ``log`` once into the annunciation counter and the alarm report; both."""
    from catenary_monitor.core.twin.window import COLUMNS
    from catenary_monitor.replay.alarm_report import AlarmReport
    from catenary_monitor.replay.driver import drive, load_config

    config = load_config(str(params))
    counter = Counter()
    report = AlarmReport(config)

    class Both:
        def __call__(self, result: Any, window: Any) -> None:
            counter(result, window)
            report(result, window)

        def abandon(self) -> None:
            counter.abandon()
            report.abandon()

    def tell(state: Any) -> None:
        if progress is not None:
            progress(min(state.bytes_done / max(state.bytes_total, 1), 1.0))

    drive([log], config, lambda _: Both(), snapshots=COLUMNS, progress=tell)
    return counter, report.figures()


def _period_stats(events: list[Any], start: float, end: float) -> tuple[float, int]:
    """Mean and peak annunciations per 10-minute period over ``[start, end]`` [s]."""
    periods = max(1, int(math.ceil((end - start) / 600.0)))
    bins = Tally(int((a.time - start) // 600.0) for a in events)
    return len(events) / periods, max(bins.values(), default=0)


def _summary(kind: str, scene: Scene, counter: Counter, figures: dict[str, Any]) -> dict:
    start = scene.start_s
    end = start + scene.seconds
    heard = counter.heard()
    out: dict[str, Any] = {
        'scene': scene.name,
        'kind': kind,
        'gauge': scene.gauge.key,
        'port': scene.port.name,
        'lines': len(scene.config.lines),
        'mean_depth': scene.mean_depth,
        'hours': scene.seconds / 3600.0,
        'diagnostics_annunciations': len(heard),
        'hidden': len([a for a in counter.events if a.hidden]),
        'alarms_report_annunciations': figures['annunciated'],
        'gap': len(heard) - figures['annunciated'],
        'alarms_report_per_10min_mean': figures['per_10min_mean'],
        'flood_share': figures['flood_share'],
    }
    fault = scene.faults[0] if scene.faults else None
    lo, hi = (-math.inf, -math.inf) if fault is None else fault.window(scene.seconds)
    inside = [a for a in heard if lo <= a.time - start < hi]
    outside = [a for a in heard if not lo <= a.time - start < hi]
    mean, peak = _period_stats(outside, start, end)
    verdict = 'acceptable' if mean <= 1.0 else 'manageable' if mean <= 2.0 else 'over-demanding'
    out['outside'] = {
        'annunciations': len(outside),
        'per_10min_mean': mean,
        'per_10min_peak': peak,
        'verdict': 'quiet' if not outside else verdict,
        'by_class': _classes(counter, outside),
    }
    if fault is not None:
        fam, word = EXPECTED[fault.kind]
        named = [a for a in inside if family(a.status) == fam and word in a.message.lower()
                 and _factor_right(fault.kind, a.message)]
        first = inside[0] if inside else None
        out['fault'] = {
            'kind': fault.kind,
            'line': fault.line,
            'window_s': [lo, hi],
            'annunciations': len(inside),
            'causes': _classes(counter, inside),
            'first_out': None if first is None else {
                'at_s': first.time - start, 'status': first.status, 'message': first.message},
            'first_out_right': bool(first is not None and named and first == named[0]),
            'cause_named': bool(named),
            'expected': f'{fam}: {word}',
            'flood_first_out': [m.group(1) for a in inside if a.status == 'alarms'
                                for m in [re.search(r'first out: (\S+)', a.message)] if m],
        }  # fmt: skip
        f = out['fault']
        f['met'] = bool(f['cause_named'] and f['first_out_right'] and len(inside) <= 2)
        if fault.line is not None:
            out['fault']['line_view'] = _line_view(scene, counter, fault.line)
    return out


#: The factors a units fault's "wrong units?" may name: the true one, or the one 2 % from it
#: that its text names beside it (daN x10 and tonnes-force x9.81 on kN); or none.
UNIT_FACTORS_RIGHT = {'units_dan': (10.0, 9.80665), 'units_tf': (9.80665, 10.0)}


def _factor_right(kind: str, message: str) -> bool:
    """Whether a units fault's annunciation names a right factor (``reading xF``) or none
    (``reading far below``: the unit unsure); True for the other faults."""
    right = UNIT_FACTORS_RIGHT.get(kind)
    if right is None or 'reading far below' in message:
        return True
    m = re.search(r'reading x([0-9.]+)', message)
    return m is not None and any(abs(float(m.group(1)) / f - 1.0) < 0.01 for f in right)


def _line_view(scene: Scene, counter: Counter, line: str) -> dict[str, Any]:
    """What the faulty line showed: seconds at each level over the scene, and while its
    anchor truly lifted (the truth's quasi-static uplift > 0), how long it read OK."""
    t, r = truth_statics(scene)
    k = [x.name for x in scene.config.lines].index(line)
    level = counter.level_at(line, scene.start_s + t)
    step = float(t[1] - t[0]) if len(t) > 1 else 0.0
    words = {-1: 'unseen', 0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}
    with np.errstate(invalid='ignore'):
        lifted = np.asarray(r.uplift_force[:, k] > 0.0)
    return {
        'seconds_at': {words[v]: float(np.sum(level == v) * step) for v in np.unique(level)},
        'truly_lifted_s': float(lifted.sum() * step),
        'ok_while_lifted_s': float(np.sum(lifted & (level == 0)) * step),
        'true_uplift_max_kN': float(np.nanmax(r.uplift_force[:, k])) / 1e3
        if np.any(np.isfinite(r.uplift_force[:, k])) else None,
    }


def _classes(counter: Counter, events: list[Any]) -> list[dict[str, Any]]:
    return [
        {'status': f, 'level': lv, 'cause': c, 'count': n}
        for (f, lv, c), n in counter.by_cause(events).most_common()
    ]


def run(
    dock: str = 'paper',
    days: float = 2.0,
    hours: float = 6.0,
    gauges: Optional[list[str]] = None,
    faults: Optional[list[str]] = None,
    seed: int = 1,
    keep: Optional[str] = None,
    quiet: bool = False,
    settings: Optional[dict[str, Any]] = None,
) -> dict[str, Any]:
    """Generate, replay and count every scene; the figures (JSON-ready)."""
    gauges = list(NORMAL_GAUGES) if gauges is None else gauges
    faults = list(FAULT_KINDS) if faults is None else faults
    folder = Path(keep) if keep else Path(tempfile.mkdtemp(prefix='bench_alarms_'))
    say = _Say(quiet)
    scenes = plan(dock, days, hours, gauges, faults, seed, settings)
    results = []
    t0 = time.monotonic()
    try:
        for k, (kind, scene) in enumerate(scenes):
            tag = f'[{k + 1}/{len(scenes)}] {scene.name}'
            facts = write_scene(scene, folder, lambda x: say(f'{tag}: writing {100 * x:.0f} %'))
            counter, figures = replay_counts(
                facts.log, facts.params, lambda x: say(f'{tag}: replaying {100 * x:.0f} %')
            )
            row = _summary(kind, scene, counter, figures)
            row['margins'] = scene_margins(scene)
            row['log'] = str(facts.log) if keep else None
            row['log_bytes'] = facts.bytes
            results.append(row)
            say(f'{tag}: {row["diagnostics_annunciations"]} annunciations', final=True)
    finally:
        if not keep:
            shutil.rmtree(folder, ignore_errors=True)
    return {
        'dock': dock,
        'seed': seed,
        'seconds': time.monotonic() - t0,
        'targets': {'per_10min_mean': TARGET_MEAN, 'per_10min_peak': TARGET_PEAK,
                    'fault': TARGET_FAULT},  # fmt: skip
        'scenes': results,
    }


class _Say:
    """Progress on stderr: one line rewritten (at most every 0.5 s), kept when final."""

    def __init__(self, quiet: bool) -> None:
        self.quiet, self.last = quiet, 0.0

    def __call__(self, text: str, final: bool = False) -> None:
        if self.quiet:
            return
        now = time.monotonic()
        if not final and now - self.last < 0.5:
            return
        self.last = now
        sys.stderr.write(f'\r\x1b[K{text}' + ('\n' if final else ''))
        sys.stderr.flush()


def table(figures: dict[str, Any]) -> str:
    """The report as text."""
    rows = [
        f'bench-alarms: dock {figures["dock"]}, seed {figures["seed"]} '
        f'({figures["seconds"]:.0f} s)',
        f'targets: normal days {TARGET_MEAN}; peak {TARGET_PEAK}; each fault {TARGET_FAULT}',
        '',
        f'{"scene":<44} {"hours":>5} {"heard":>6} {"/10min":>7} {"peak":>5} '
        f'{"alarms":>7} {"gap":>6}  verdict',
    ]
    for r in figures['scenes']:
        o = r['outside']
        verdict = o['verdict']
        if r.get('fault'):
            verdict += ' / fault ' + ('met' if r['fault']['met'] else 'not met')
        rows.append(
            f'{r["scene"]:<44} {r["hours"]:>5.1f} {r["diagnostics_annunciations"]:>6} '
            f'{o["per_10min_mean"]:>7.2f} {o["per_10min_peak"]:>5} '
            f'{r["alarms_report_annunciations"]:>7} {r["gap"]:>6}  {verdict}'
        )
    rows += ['', '("heard": every status leaving OK on /diagnostics; "alarms": what '
             '`catenary-monitor alarms --json` counts; /10min and peak outside the faults)']
    for r in figures['scenes']:
        f = r.get('fault')
        if f is None:
            continue
        first = f['first_out']
        rows += [
            '',
            f'fault {f["kind"]}{" on " + f["line"] if f["line"] else ""} '
            f'(scene {r["scene"]}): {f["annunciations"]} annunciations in its window, cause '
            f'named: {"yes" if f["cause_named"] else "NO"} (expected {f["expected"]}), '
            f'first-out {"right" if f["first_out_right"] else "WRONG"}',
        ]
        if first:
            rows.append(f'  first-out: {first["status"]}: {first["message"][:110]}')
        if f['flood_first_out']:
            rows.append(f'  flood banner first-out: {", ".join(f["flood_first_out"])}')
        view = f.get('line_view')
        if view:
            at = ', '.join(f'{k} {v:.0f} s' for k, v in view['seconds_at'].items())
            rows.append(f'  {f["line"]} showed: {at}; its anchor truly lifted '
                        f'{view["truly_lifted_s"]:.0f} s (up to '
                        f'{view["true_uplift_max_kN"] or 0:.0f} kN), read OK for '
                        f'{view["ok_while_lifted_s"]:.0f} s of them')  # fmt: skip
        for c in f['causes'][:6]:
            rows.append(f'  {c["count"]:>5}  {c["status"]} {c["level"]}: {c["cause"][:90]}')
    for r in figures['scenes']:
        rows += ['', f'{r["scene"]}: outside the faults, by class:']
        for c in r['outside']['by_class'][:12]:
            rows.append(f'  {c["count"]:>5}  {c["status"]} {c["level"]}: {c["cause"][:90]}')
    return '\n'.join(rows)


def register(sub: Any) -> None:
    """Add ``bench-alarms`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'bench-alarms',
        help='annunciations on normal days and per injected fault, against ISA-18.2 targets',
        description='Generate days of a dock\'s normal operation (a real port\'s tide, wind '
        'drift, waves, load cells and tide gauges as their drivers publish them) and scenes '
        'with one injected fault each, replay them, and report the annunciations an operator '
        'hears (every /diagnostics status leaving OK) per 10 minutes, by class, per fault '
        '(count, causes, first-out), beside what `catenary-monitor alarms` counts and the '
        'ISA-18.2 / EEMUA 191 targets.',
    )
    p.add_argument('--dock', default='paper',
                   help='paper (config/floating_dock.yaml) or drawn:SEED (a dock drawn from '
                   'SEED: another geometry, chain, depth, port and weather; default: paper)')
    p.add_argument('--days', type=float, default=2.0,
                   help='length of each normal scene [days] (default: 2)')
    p.add_argument('--hours', type=float, default=6.0,
                   help='length of each fault scene [h], the fault half-way (default: 6)')
    p.add_argument('--gauges', default=','.join(NORMAL_GAUGES),
                   help=f'the normal scenes\' gauges, of {",".join(GAUGES)} (default: '
                   f'{",".join(NORMAL_GAUGES)})')
    p.add_argument('--faults', default=','.join(FAULT_KINDS),
                   help='the faults, comma-separated, or none (default: all: '
                   f'{",".join(FAULT_KINDS)})')
    p.add_argument('--seed', type=int, default=1, help='the scenes\' seed (default: 1)')
    p.add_argument('--set', action='append', default=[], metavar='NAME=VALUE',
                   help='a monitor parameter for every scene (e.g. depth_resolution=0.01)')
    p.add_argument('--keep', metavar='DIR', help='write and keep the logs and params files in DIR')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.add_argument('--quiet', action='store_true', help='no progress on stderr')
    p.set_defaults(func=_command)  # fmt: skip


def _setting(text: str) -> tuple[str, Any]:
    name, _, value = text.partition('=')
    try:
        return name, json.loads(value)
    except ValueError:
        return name, value


def _command(args: argparse.Namespace) -> int:
    gauges = [g for g in args.gauges.split(',') if g]
    faults = [] if args.faults in ('', 'none') else args.faults.split(',')
    bad = [g for g in gauges if g not in GAUGES] + [f for f in faults if f not in FAULT_KINDS]
    if bad:
        print(f'catenary-monitor bench-alarms: unknown gauge or fault: {", ".join(bad)}',
              file=sys.stderr)  # fmt: skip
        return 2
    if args.dock != 'paper' and not args.dock.startswith('drawn:'):
        print('catenary-monitor bench-alarms: --dock is paper or drawn:SEED', file=sys.stderr)
        return 2
    figures = run(args.dock, args.days, args.hours, gauges, faults, args.seed, args.keep,
                  args.quiet, dict(_setting(s) for s in args.set) or None)  # fmt: skip
    print(json.dumps(json_ready(figures)) if args.json else table(figures))
    return 0

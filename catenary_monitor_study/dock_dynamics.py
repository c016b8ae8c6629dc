"""``catenary-monitor bench-dynamics --dock``: the paper's dock, one body with its twelve chains
in MoorDyn, through a tide rise and a storm with waves, against the monitor's replay.

The dock's motion is prescribed (:func:`catenary_monitor_study.moordyn_scene.storm_motion`):
the tide rising, the dock drifting to starboard as the storm builds, a beam sea swaying it.
MoorDyn gives every hook's tension and every anchor's vertical force; the tensions (10 Hz) and
the hooks' depth (1 Hz) go through the monitor's replay
(:func:`~catenary_monitor.core.twin.engine.recompute`: the node's decisions on the same samples)
with the params' lines, MoorDyn's chain stiffness and an allowed uplift. Per line:

* ``dyn_peak_kN``, ``qs_peak_kN``, ``bound_peak_kN``: the largest anchor force, quasi-static
  uplift and ``uplift_force_upper``; ``peak_ratio`` the bound's over the anchor's;
* ``held_bound``, ``held_qs``: the share of samples with the anchor force above 1 kN where the
  bound (the quasi-static uplift: the baseline) holds it;
* ``crossing_s``, ``error_s``: when the anchor force first exceeds the allowed uplift and when
  the line's first ERROR came (s; null: never); ``span_error_m``: the largest difference
  between the span solved at and MoorDyn's.

And the dock estimate: its sway against the prescribed one, before the waves and in them.
"""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

__all__ = ['DockScene', 'run_dock_scene', 'dock_table', 'plot_dock']

T0_NS = 1_763_900_000_000_000_000


class DockScene:
    """The scene's settings (SI): duration, tide, drift, waves, allowed uplift, segments."""

    def __init__(
        self,
        duration: float = 300.0,
        depth: float = 20.85,
        rise: float = 0.0025,
        drift: float = -0.6,
        drift_time: float = 120.0,
        amplitude: float = 0.4,
        period: float = 9.0,
        waves_from: float = 20.0,
        allowed: float = 20e3,
        segments: int = 20,
    ) -> None:
        self.duration, self.depth, self.rise = duration, depth, rise
        self.drift, self.drift_time = drift, drift_time
        self.amplitude, self.period, self.waves_from = amplitude, period, waves_from
        self.allowed, self.segments = allowed, segments


def _config(params_file: str, allowed: float, ea: float) -> Any:
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file

    flat = load_params_file(params_file)
    for name in flat['lines']:
        flat[f'{name}.ea'] = ea
        flat[f'{name}.allowed_uplift'] = allowed
    return config_from_params(flat)


def run_dock_scene(params_file: str, scene: DockScene) -> dict[str, Any]:
    """MoorDyn and the monitor's replay on one scene: the figures (module docstring), and the
    series the chart takes (``series``: not JSON)."""
    from catenary_monitor.core.body.dock_model import DockModel
    from catenary_monitor.core.twin.engine import recompute
    from catenary_monitor_study.moordyn_scene import PAPER_CHAIN, Chain, run_dock, storm_motion

    config = _config(params_file, scene.allowed, PAPER_CHAIN.ea)
    motion = storm_motion(
        scene.depth,
        scene.rise,
        (0.0, scene.drift),
        scene.drift_time,
        scene.amplitude,
        scene.period,
        scene.waves_from,
    )
    rec = run_dock(
        DockModel.from_config(config), motion, scene.duration, Chain(segments=scene.segments)
    )
    t_ns = T0_NS + np.rint(rec.t * 1e9).astype(np.int64)
    tensions = {
        line.name: (t_ns + 1000 * k, rec.tension[:, k]) for k, line in enumerate(config.lines)
    }
    depth = (t_ns[::10] - 50_000_000, rec.depth[::10])
    result = recompute(config, tensions, depth, snapshots=True)
    lines = [_line_figures(rec, result.lines[k], k, scene.allowed) for k in range(len(tensions))]
    for row, line in zip(lines, config.lines):
        row['line'] = line.name
    dock = _dock_figures(rec, result.snapshots, result.tick_ns, scene.waves_from)
    return {
        'scene': vars(scene).copy(),
        'lines': lines,
        'dock': {k: v for k, v in dock.items() if k != 'series'},
        'series': {'rec': rec, 'result': result, 'dock': dock['series']},
    }


def _first(t: np.ndarray, mask: np.ndarray) -> Optional[float]:
    return float(t[np.argmax(mask)]) if mask.any() else None


def _line_figures(rec: Any, r: Any, k: int, allowed: float) -> dict[str, Any]:
    rows = r.tension_rows
    dyn = rec.uplift[:, k]
    qs = r.values['uplift_force'][rows]
    upper = r.values['uplift_force_upper'][rows]
    lifted = dyn > 1e3

    def held(v: np.ndarray) -> Optional[float]:
        return float(np.mean(v[lifted] >= dyn[lifted])) if lifted.any() else None

    source = r.values['span_source'][rows] == 1.0
    error = np.abs(r.values['span'][rows] - rec.span[:, k])
    return {
        'dyn_peak_kN': float(dyn.max()) / 1e3,
        'qs_peak_kN': float(np.nanmax(qs)) / 1e3,
        'bound_peak_kN': float(np.nanmax(upper)) / 1e3,
        'peak_ratio': float(np.nanmax(upper) / dyn.max()) if dyn.max() > 1e3 else None,
        'held_bound': held(upper),
        'held_qs': held(qs),
        'crossing_s': _first(rec.t, dyn > allowed),
        'error_s': _first(rec.t, r.level[rows] == 2),
        'span_error_m': float(error[source].max()) if source.any() else None,
    }


def _dock_figures(
    rec: Any, snapshots: list[Any], ticks: np.ndarray, waves_from: float
) -> dict[str, Any]:
    est = []
    at_tick = set(np.asarray(ticks).tolist())
    for snap in (s for s in snapshots if s.stamp_ns in at_tick):
        values = {st.name: dict(st.values) for st in snap.statuses}.get('catenary_monitor: dock')
        if values is not None and values['offset_y'] != 'nan':
            est.append(((snap.stamp_ns - T0_NS) * 1e-9, float(values['offset_y'])))
    t, y = np.array(est).T if est else (np.zeros(0), np.zeros(0))
    truth = np.interp(t, rec.t, rec.offset[:, 1])
    calm = t < waves_from
    err = np.abs(y - truth)

    def worst(mask: np.ndarray) -> Optional[float]:
        return float(err[mask].max()) if mask.any() else None

    return {
        'ticks': int(t.size),
        'sway_error_calm_m': worst(calm),
        'sway_error_waves_m': worst(~calm),
        'sway_rms_waves_m': float(np.sqrt(np.mean(err[~calm] ** 2))) if (~calm).any() else None,
        'series': (t, y),
    }


def _fmt(v: Optional[float], spec: str) -> str:
    """``v`` formatted, or '-' in the same width for None."""
    width = int(spec.split('.')[0] or 0)
    return '-'.rjust(width) if v is None else format(v, spec)


def dock_table(out: dict[str, Any]) -> str:
    """The figures as a table: a row per line, then the dock estimate."""
    s = out['scene']
    head = (
        f"dock scene: {s['duration']:g} s, tide +{s['rise'] * 3600:g} m/h from {s['depth']:g} m, "
        f"drift {s['drift']:+g} m over {s['drift_time']:g} s, beam sea {s['amplitude']:g} m at "
        f"{s['period']:g} s, allowed uplift {s['allowed'] / 1e3:g} kN, {s['segments']} segments"
    )
    rows = [
        head,
        f'{"line":8} {"dyn kN":>7} {"qs kN":>7} {"bd kN":>7} {"bd/dyn":>6} {"held qs":>7} '
        f'{"held bd":>7} {"cross s":>7} {"ERROR s":>7} {"span m":>6}',
    ]
    for r in out['lines']:
        rows.append(
            f'{r["line"]:8} {r["dyn_peak_kN"]:7.1f} {r["qs_peak_kN"]:7.1f} '
            f'{r["bound_peak_kN"]:7.1f} {_fmt(r["peak_ratio"], "6.2f")} '
            f'{_fmt(r["held_qs"], "7.2f")} {_fmt(r["held_bound"], "7.2f")} '
            f'{_fmt(r["crossing_s"], "7.1f")} {_fmt(r["error_s"], "7.1f")} '
            f'{_fmt(r["span_error_m"], "6.3f")}'
        )
    d = out['dock']
    rows.append(
        f"dock estimate: {d['ticks']} ticks; sway error before the waves "
        f"{_fmt(d['sway_error_calm_m'], '.3f')} m, in them {_fmt(d['sway_error_waves_m'], '.3f')}"
        f" m (rms {_fmt(d['sway_rms_waves_m'], '.3f')} m)"
    )
    return '\n'.join(rows)


def plot_dock(out: dict[str, Any], path: str) -> None:
    """The line that lifts most (MoorDyn's anchor force, the monitor's uplift and bound, the
    crossing and the first ERROR) and the dock estimate's sway against the prescribed one."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    rec, result = out['series']['rec'], out['series']['result']
    k = int(np.argmax([r['dyn_peak_kN'] for r in out['lines']]))
    figures, line = out['lines'][k], result.lines[k]
    rows = line.tension_rows
    fig, (a, b) = plt.subplots(2, 1, figsize=(8.0, 6.0), sharex=True)
    a.plot(rec.t, rec.uplift[:, k] / 1e3, lw=0.8, color='k', label='MoorDyn anchor force')
    a.plot(rec.t, line.values['uplift_force'][rows] / 1e3, lw=0.8, label='uplift (quasi-static)')
    upper = line.values['uplift_force_upper'][rows] / 1e3
    a.plot(rec.t, upper, lw=0.8, label='uplift_force_upper')
    a.axhline(out['scene']['allowed'] / 1e3, color='grey', ls=':', lw=0.8, label='allowed')
    for key, style in (('crossing_s', '--'), ('error_s', '-')):
        if figures[key] is not None:
            a.axvline(figures[key], color='r', ls=style, lw=0.8)
    a.set_ylabel(f'{figures["line"]} [kN]')
    a.legend(fontsize=7, loc='upper left')
    a.grid(alpha=0.3)
    t, y = out['series']['dock']
    b.plot(rec.t, rec.offset[:, 1], lw=0.8, color='k', label='the dock (MoorDyn, prescribed)')
    b.plot(t, y, '.', ms=3, label='dock estimate (each tick)')
    b.set_ylabel('sway offset_y [m]')
    b.set_xlabel('time [s]')
    b.legend(fontsize=7)
    b.grid(alpha=0.3)
    fig.suptitle('The paper\'s dock in MoorDyn: tide rise, storm drift, beam sea')
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def finite(value: Any) -> Any:
    """JSON-safe: NaN as None, inside lists and dicts."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [finite(v) for v in value]
    return value

"""The alarm report's chart (PNG) and its page (one self-contained HTML file).

The chart: alarms raised per 10-minute period over the report's span (periods in flood in
red), with the standards' lines (1 and 2 per 10 min, the flood count), and each alarm's raises
beside. The page: the figures, each against its target, the per-alarm table, the most frequent
alarms and the chart, with no file or network access besides itself (the PNG is inline).
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
from pathlib import Path
from typing import Any, Optional

from catenary_monitor.core.alarms.acknowledge import SENSORS

__all__ = ['draw_chart', 'chart_png', 'write_html']


def chart_png(figures: dict[str, Any]) -> bytes:
    """The chart as PNG bytes (matplotlib, Agg)."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    period = figures['period_s']
    starts, peaks, means, flood, bucket = _buckets(figures['per_10min'], period)
    limit = figures['flood_rule']['flood_count']
    fig, (ax, bx) = plt.subplots(
        1, 2, figsize=(12, 4.2), gridspec_kw={'width_ratios': [3.2, 1]}, squeeze=True
    )
    width = _dt.timedelta(seconds=bucket)
    colors = ['tab:red' if f else 'tab:blue' for f in flood]
    if starts:
        label = None if bucket == period else f'peak 10 min of each {_span(bucket)}'
        ax.bar(starts, peaks, width=width, align='edge', color=colors, linewidth=0, label=label)
        if bucket != period:
            mid = [t + width / 2 for t in starts]
            ax.plot(
                mid, means, color='k', lw=1, label=f'mean per 10 min over each {_span(bucket)}'
            )
    ax.axhline(1.0, color='tab:green', ls='--', lw=1, label='1 per 10 min: acceptable')
    ax.axhline(2.0, color='tab:orange', ls='--', lw=1, label='2 per 10 min: manageable')
    ax.axhline(limit, color='tab:red', ls=':', lw=1, label=f'flood: more than {limit:g}')
    ax.set_ylabel(f'alarms raised per {period / 60:g} min')
    ax.set_xlabel('time (UTC)')
    ax.grid(alpha=0.3)
    ax.legend(loc='upper left', fontsize=8)
    share = figures['flood_share']
    mean = figures['per_10min_mean']
    ax.set_title(
        f'{figures["annunciated"]} alarms raised; mean {_num(mean)} per 10 min, peak '
        f'{figures["per_10min_peak"]}; {"-" if share is None else f"{100 * share:.2f}"} % of '
        'periods in flood (red)',
        fontsize=10,
    )
    fig.autofmt_xdate()
    rows = dict(figures['lines'])
    rows[SENSORS] = figures['sensors']
    names = list(rows)
    bx.barh(names, [rows[n]['annunciated'] for n in names], color='tab:blue')
    chatter = [n for n in names if rows[n]['chattering']]
    bx.barh(chatter, [rows[n]['annunciated'] for n in chatter], color='tab:purple',
            label='chattered')  # fmt: skip
    bx.invert_yaxis()
    bx.set_xlabel('alarms raised')
    bx.set_title('per alarm', fontsize=10)
    bx.tick_params(axis='y', labelsize=8)
    bx.grid(alpha=0.3, axis='x')
    if chatter:
        bx.legend(loc='lower right', fontsize=8)
    fig.tight_layout()
    out = io.BytesIO()
    fig.savefig(out, format='png', dpi=80)
    plt.close(fig)
    return out.getvalue()


#: Bars the chart draws at most: longer spans show each bucket's peak 10-minute count.
MAX_BARS = 400


def _buckets(
    series: dict[str, list[Any]], period: float
) -> tuple[list[_dt.datetime], list[int], list[float], list[bool], float]:
    """The 10-minute counts as at most :data:`MAX_BARS` buckets of a whole number of periods
    (an hour, 6 h, a day, ...): each bucket's start, peak count, mean count per period and
    whether any period in it was in flood; and the bucket's length [s]."""
    starts, counts, flood = series['start'], series['count'], series['flood']
    if not starts:
        return [], [], [], [], period
    span = starts[-1] - starts[0] + period
    bucket = period
    for hours in (1, 3, 6, 12, 24, 24 * 7, 24 * 30):
        if span / bucket <= MAX_BARS:
            break
        bucket = max(period, hours * 3600.0)
    keys = [int((t - starts[0]) // bucket) for t in starts]
    out: dict[int, list[Any]] = {}
    for k, c, f in zip(keys, counts, flood):
        b = out.setdefault(k, [0, 0, 0, False])
        b[0], b[1], b[2], b[3] = max(b[0], c), b[1] + c, b[2] + 1, b[3] or f
    order = sorted(out)
    t0 = starts[0]
    return (
        [_dt.datetime.fromtimestamp(t0 + k * bucket, _dt.timezone.utc) for k in order],
        [out[k][0] for k in order],
        [out[k][1] / out[k][2] for k in order],
        [out[k][3] for k in order],
        bucket,
    )


def _span(seconds: float) -> str:
    return f'{seconds / 86400:g} d' if seconds >= 86400 else f'{seconds / 3600:g} h'


def draw_chart(figures: dict[str, Any], path: Path) -> Path:
    """Write the chart to ``path`` (PNG)."""
    path = Path(path)
    path.write_bytes(chart_png(figures))
    return path


def _num(value: Optional[float], digits: int = 2) -> str:
    return '-' if value is None else f'{value:.{digits}f}'


def _when(t: Optional[float]) -> str:
    if t is None:
        return '-'
    return _dt.datetime.fromtimestamp(t, _dt.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')


def write_html(figures: dict[str, Any], path: Path, png: Optional[bytes] = None) -> Path:
    """Write the report page to ``path``: figures, targets, per-alarm table, most frequent
    alarms and the chart (``png``; drawn when None)."""
    e = html.escape
    f = figures
    png = chart_png(f) if png is None else png
    image = base64.b64encode(png).decode('ascii')
    share = f['flood_share']
    summary = [
        ('alarms raised (annunciated)', str(f['annunciated']), ''),
        ('per 10 min, mean', _num(f['per_10min_mean']), 'per_10min_mean'),
        ('per 10 min, peak', str(f['per_10min_peak']), 'per_10min_peak'),
        (
            'periods in flood',
            '-' if share is None else f'{100 * share:.2f} % ({f["floods"]} floods)',
            'flood_share',
        ),
        ('chattering alarms', str(f['chattering_alarms']), 'chattering'),
        ('standing alarms (active > 24 h)', str(f['standing_alarms']), 'standing'),
    ]
    rows = []
    for label, value, key in summary:
        target = f['targets'].get(key, {}) if key else {}
        verdict = target.get('verdict') or ''
        rows.append(
            f'<tr><th>{e(label)}</th><td>{e(value)}</td><td class="v {e(verdict)}">'
            f'{e(verdict)}</td><td>{e(target.get("target", ""))}</td></tr>'
        )
    alarms = dict(f['lines'])
    alarms[SENSORS] = f['sensors']
    per = []
    for name, a in alarms.items():
        per.append(
            '<tr>'
            + ''.join(
                f'<td>{e(str(v))}</td>'
                for v in (
                    name,
                    a['annunciated'],
                    _num(a['per_10min_mean']),
                    a['per_10min_peak'],
                    a['chattering'],
                    a['standing'],
                    a['acknowledged'],
                    _num(a['mean_time_to_acknowledge'], 1),
                    a['shelved'],
                    _num(a['shelved_s'] / 3600.0),
                )
            )
            + '</tr>'
        )
    frequent = ''.join(
        f'<tr><td>{m["count"]}</td><td>{e(m["alarm"])}</td><td>{e(m["condition"])}</td>'
        f'<td>{e(m["level"])}</td></tr>'
        for m in f['most_frequent']
    )
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>catenary_monitor alarm report</title>
<style>
body {{ font: 14px system-ui, sans-serif; margin: 24px; color: #222; }}
table {{ border-collapse: collapse; margin: 8px 0 20px; }}
th, td {{ border: 1px solid #ccc; padding: 3px 8px; text-align: left; }}
td.v.met, td.v.acceptable {{ background: #d8f0d8; }}
td.v.manageable {{ background: #fff1c8; }}
td.v.not.met, td.v.over-demanding {{ background: #f6d0d0; }}
img {{ max-width: 100%; }}
</style></head><body>
<h1>Alarm report</h1>
<p>{e(_when(f['start']))} .. {e(_when(f['end']))}: {f['periods']} periods of
{f['period_s'] / 60:g} min monitored. A flood is more than {f['flood_rule']['flood_count']:g}
alarms raised within {f['flood_rule']['flood_window']:g} s (the monitor's own status).</p>
<table><tr><th>figure</th><th>value</th><th>verdict</th><th>target (ISA-18.2, EEMUA 191)</th></tr>
{''.join(rows)}</table>
<img alt="alarms raised per 10 minutes" src="data:image/png;base64,{image}">
<h2>Per alarm</h2>
<table><tr><th>alarm</th><th>raised</th><th>per 10 min</th><th>peak</th><th>chattering</th>
<th>standing</th><th>acknowledged</th><th>mean time to acknowledge [s]</th><th>shelved</th>
<th>time shelved [h]</th></tr>
{''.join(per)}</table>
<h2>Most frequent alarms</h2>
<table><tr><th>raised</th><th>alarm</th><th>condition</th><th>level</th></tr>{frequent}</table>
</body></html>
"""
    path = Path(path)
    path.write_text(page, encoding='utf-8')
    return path

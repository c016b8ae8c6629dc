"""The uplift envelope as a polar PNG chart (matplotlib, Agg backend)."""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

__all__ = ['envelope_chart']

_LABELS = ['bow\n0', '45', 'stbd 90', '135', 'stern\n180', '225', 'port 270', '315']


def envelope_chart(
    path: str, results: Sequence[tuple[float, Sequence[Any]]], wind: bool, title: str
) -> None:
    """Polar charts, one row per depth: the force (kN) and, if computed, the wind speed (m/s)
    from each direction at which the first anchor lifts; linear radial scales (zero at the
    centre), each panel its own; the weakest direction marked with its line.

    Directions are where the load comes from, clockwise from the bow (bow at the top).
    """
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    panels = [('force', 1e-3, 'force [kN]', 'force_line')]
    if wind:
        panels.append(('wind', 1.0, 'wind speed [m/s]', 'wind_line'))
    rows = len(results)
    fig, axes = plt.subplots(
        rows,
        len(panels),
        subplot_kw={'projection': 'polar'},
        figsize=(5.2 * len(panels), 5.0 * rows),
        squeeze=False,
    )
    for (depth, data), row in zip(results, axes):
        for ax, (key, scale, label, line_key) in zip(row, panels):
            _panel(ax, data, key, scale, line_key)
            ax.set_title(f'depth {depth:g} m: lifting {label}', pad=16, fontsize=10)
    fig.suptitle(
        f'Uplift envelope ({title}): the load from each direction at which the first anchor '
        'lifts',
        fontsize=11,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def _panel(ax: Any, rows: Sequence[Any], key: str, scale: float, line_key: str) -> None:
    ax.set_theta_zero_location('N')
    ax.set_theta_direction(-1)
    theta = np.radians([r.direction_deg for r in rows] + [rows[0].direction_deg])
    values = [getattr(r, key) * scale for r in rows]
    values.append(values[0])
    ax.plot(theta, values, marker='o', ms=3, color='tab:blue')
    ax.fill(theta, values, color='tab:blue', alpha=0.12)
    finite = [(v, r) for v, r in zip(values, rows) if math.isfinite(v)]
    if finite:
        v, r = min(finite, key=lambda p: p[0])
        ax.plot([math.radians(r.direction_deg)], [v], 'o', color='tab:red')
        ax.annotate(
            f'{v:.3g} from {r.direction_deg:g} deg\n({getattr(r, line_key)} lifts)',
            (math.radians(r.direction_deg), v),
            color='tab:red',
            fontsize=8,
            xytext=(6, -14),
            textcoords='offset points',
        )
        ax.set_ylim(0, max(p[0] for p in finite) * 1.08)
    ax.set_xticks(np.radians(np.arange(0, 360, 45)))
    ax.set_xticklabels(_LABELS, fontsize=8)
    ax.tick_params(axis='y', labelsize=7)
    ax.set_rlabel_position(112.5)

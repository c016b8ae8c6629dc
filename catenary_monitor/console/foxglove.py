"""A Foxglove / Lichtblick layout for the monitor's topics (File > Import layout from file).

Panels: Diagnostics - Summary and Detail on ``/diagnostics`` (every line, the tide, the
logger); a Plot of a chosen line's hook tension, uplift force and anchor margin from its
numeric ``/catenary_monitor/NAME/outputs`` (``data[0]``, ``data[5]``, ``data[4]``: the order of
:data:`~catenary_monitor.core.monitor.state.OUTPUT_FIELDS`) and of the depth; a State
Transitions panel of every line's ``DiagnosticStatus.level`` (OK, WARN, ERROR, STALE labels).
Generated from a configuration (``catenary-monitor console --foxglove-layout OUT.json``); the
package ships the one of config/floating_dock.yaml in ``share/catenary_monitor/foxglove``.
"""

from __future__ import annotations

from typing import Any, Optional

from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.monitor.events import NODE_NAME
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS

__all__ = ['layout']


def _path(value: str, label: str) -> dict[str, Any]:
    return {'value': value, 'enabled': True, 'timestampMethod': 'receiveTime', 'label': label}


def layout(config: MonitorConfig, focus: Optional[str] = None) -> dict[str, Any]:
    """The layout (a JSON-ready dict) for ``config``'s lines; the plot shows ``focus``
    (default line_11 when there is one, else the first line)."""
    names = [line.name for line in config.lines]
    line = focus or ('line_11' if 'line_11' in names else names[0])
    out = f'/{NODE_NAME}/{line}/outputs.data'
    idx = {k: i for i, k in enumerate(OUTPUT_FIELDS)}
    hardware = config.line(line).tension_topic
    return {
        'configById': {
            'DiagnosticSummary!cm1': {
                'topicToRender': '/diagnostics',
                'minLevel': 0,
                'pinnedIds': [],
                'hardwareIdFilter': '',
                'sortByLevel': True,
            },
            'DiagnosticStatusPanel!cm2': {
                'topicToRender': '/diagnostics',
                'selectedHardwareId': hardware,
                'selectedName': f'{NODE_NAME}: {line}',
                'collapsedSections': [],
            },
            'Plot!cm3': {
                'title': f'{line}: hook tension, uplift [N]; anchor margin, depth [m]',
                'paths': [
                    _path(f'{out}[{idx["top_tension"]}]', f'{line} hook tension [N]'),
                    _path(f'{out}[{idx["uplift_force"]}]', f'{line} uplift force [N]'),
                    _path(f'{out}[{idx["anchor_margin"]}]', f'{line} anchor margin [m]'),
                    _path(f'{out}[{idx["depth"]}]', f'{line} depth at hook [m]'),
                ],
                'showXAxisLabels': True,
                'showYAxisLabels': True,
                'showLegend': True,
                'legendDisplay': 'floating',
                'isSynced': True,
                'xAxisVal': 'timestamp',
            },
            'StateTransitions!cm4': {
                'paths': [
                    _path(f'/diagnostics.status[:]{{name=="{NODE_NAME}: {n}"}}.level', n)
                    for n in names
                ],
                'isSynced': True,
            },
        },
        'globalVariables': {},
        'userNodes': {},
        'playbackConfig': {'speed': 1.0},
        'layout': {
            'direction': 'row',
            'first': {
                'direction': 'column',
                'first': 'DiagnosticSummary!cm1',
                'second': 'DiagnosticStatusPanel!cm2',
                'splitPercentage': 55,
            },
            'second': {
                'direction': 'column',
                'first': 'Plot!cm3',
                'second': 'StateTransitions!cm4',
                'splitPercentage': 50,
            },
            'splitPercentage': 35,
        },
    }

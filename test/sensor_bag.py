"""rosbag2 recordings of the sensor topics (std_msgs/Float64), written by rosbags (not by us),
and the replay command run on them as a user runs it."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
from replay_data import params_yaml

from catenary_monitor.cli.main import main
from catenary_monitor.core.config.parameters import MonitorConfig


def write_bag(
    folder: Path,
    config: MonitorConfig,
    tensions: dict[str, tuple[np.ndarray, np.ndarray]],
    depth: tuple[np.ndarray, np.ndarray],
) -> Path:
    """A rosbag2 bag (MCAP storage, metadata.yaml) of the tension and depth topics."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    msg = store.types['std_msgs/msg/Float64']
    topics = [(line.tension_topic, *tensions[line.name]) for line in config.lines]
    topics.append((config.depth_topic, *depth))
    with Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = [
            writer.add_connection(name, 'std_msgs/msg/Float64', typestore=store)
            for name, _, _ in topics
        ]
        t = np.concatenate([tt for _, tt, _ in topics])
        v = np.concatenate([vv for _, _, vv in topics])
        k = np.concatenate([np.full(len(tt), i) for i, (_, tt, _) in enumerate(topics)])
        for i in np.argsort(t, kind='stable').tolist():
            data = store.serialize_cdr(msg(data=float(v[i])), 'std_msgs/msg/Float64')
            writer.write(conns[int(k[i])], int(t[i]), data)
    return folder


def replay_csv(tmp: Path, config: MonitorConfig, bag: Path) -> list[dict[str, Any]]:
    """``catenary-monitor replay BAG --params-file F --csv OUT --csv-columns all``: its rows."""
    params = params_yaml(config, tmp / 'params.yaml')
    out = tmp / 'out.csv'
    code = main(['replay', str(bag), '--params-file', str(params), '--csv', str(out)]
                + ['--csv-columns', 'all'])  # fmt: skip
    assert code == 0
    with open(out, newline='') as f:
        return list(csv.DictReader(f))


def column(rows: list[dict[str, Any]], key: str, line: str) -> np.ndarray:
    """One line's column as floats (``time`` in s)."""
    return np.array([float(r[key]) for r in rows if r['line'] == line])

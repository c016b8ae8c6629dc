"""The log folder as a rosbag2 bag: ``metadata.yaml`` in rosbag2's (Jazzy) version 9 format.

rosbag2 (``ros2 bag info/play``) and ``rosbags.highlevel.AnyReader`` open a folder through its
``metadata.yaml``. This module writes one for a folder of MCAP files, the way rosbag2's
``YAML::convert<BagMetadata>::encode`` does (same keys, same order, yaml-cpp's block style):
``version: 9``, ``storage_identifier: mcap``, bag ``duration``/``starting_time``/
``message_count``, ``topics_with_message_count`` (``topic_metadata`` with ``name``, ``type``,
``serialization_format``, ``offered_qos_profiles`` as a YAML list (version 9) and
``type_description_hash``), ``compression_format``/``compression_mode`` (empty: the chunks are
compressed inside MCAP, C16), ``relative_file_paths``, ``files`` (per file ``path``,
``starting_time``, ``duration``, ``message_count``), ``custom_data`` and ``ros_distro``.

Facts come from each finished file's summary (Statistics, Channels, Schemas), read with the
``mcap`` library; an unfinished file has none and is left out (recover it first:
:mod:`catenary_monitor.io.mcap_recover`). The file is replaced atomically (temporary file in
the folder, fsync, rename, fsync of the folder).
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

import yaml

__all__ = [
    'FileInfo',
    'TopicInfo',
    'METADATA_NAME',
    'file_info',
    'folder_files',
    'qos_list',
    'render',
    'write_folder_metadata',
    'write_metadata',
]

METADATA_NAME = 'metadata.yaml'
#: rosbag2's bag format version in Jazzy.
VERSION = 9
#: The distribution the node's message types come from (the ``ros-jazzy-*`` wheels).
ROS_DISTRO = 'jazzy'
_PLAIN = re.compile(r'^[A-Za-z0-9_/.][A-Za-z0-9_/.:-]*$')


@dataclass
class TopicInfo:
    """One topic of a bag: rosbag2's ``topic_metadata`` and its ``message_count``."""

    name: str
    type: str
    serialization_format: str = 'cdr'
    offered_qos_profiles: list[Any] = field(default_factory=list)
    type_description_hash: str = ''
    message_count: int = 0


@dataclass
class FileInfo:
    """One file of a bag: name (relative to the folder), times (ns) and counts."""

    path: str
    starting_time_ns: int = 0
    duration_ns: int = 0
    message_count: int = 0
    topics: dict[str, TopicInfo] = field(default_factory=dict)


def qos_list(text: str | None) -> list[Any]:
    """The channel's ``offered_qos_profiles`` YAML string as a list ([] if absent or bad)."""
    if not text:
        return []
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        return []
    return value if isinstance(value, list) else []


def file_info(path: str | os.PathLike[str]) -> FileInfo | None:
    """Facts of a finished MCAP file from its summary (read within bounds:
    :func:`catenary_monitor.io.mcap_summary.read_summary`); None if it has none or cannot be
    read."""
    from catenary_monitor.io.mcap_summary import read_summary

    path = Path(path)
    summary = read_summary(path)
    if summary is None or not summary.has_statistics:
        return None
    info = FileInfo(path.name, message_count=summary.message_count)
    if summary.message_count:
        info.starting_time_ns = summary.start_ns
        info.duration_ns = max(0, summary.end_ns - summary.start_ns)
    for cid, channel in summary.channels.items():
        topic = info.topics.setdefault(
            channel.topic,
            TopicInfo(
                channel.topic,
                channel.schema_name,
                channel.encoding,
                qos_list(channel.metadata.get('offered_qos_profiles')),
                channel.metadata.get('topic_type_hash', ''),
            ),
        )
        topic.message_count += summary.channel_counts.get(cid, 0)
    return info


def _scalar(value: Any) -> str:
    """One YAML scalar as yaml-cpp writes it (strings plain when safe, else double-quoted)."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, int):
        return str(value)
    if value is None:
        return '~'
    text = str(value)
    if text and _PLAIN.match(text) and text not in ('true', 'false', 'null', '~'):
        return text
    return json.dumps(text)


def _block(value: Any, indent: int) -> list[str]:
    """Lines of a mapping or sequence in yaml-cpp's block style (sequences indented 2)."""
    pad = ' ' * indent
    lines: list[str] = []
    if isinstance(value, dict):
        for key, item in value.items():
            if isinstance(item, (dict, list)) and item:
                lines.append(f'{pad}{key}:')
                lines.extend(_block(item, indent + 2))
            elif isinstance(item, (dict, list)):
                lines.append(f'{pad}{key}: {"{}" if isinstance(item, dict) else "[]"}')
            else:
                lines.append(f'{pad}{key}: {_scalar(item)}')
    else:
        for item in value:
            if isinstance(item, (dict, list)) and item:
                inner = _block(item, indent + 2)
                lines.append(f'{pad}- {inner[0].lstrip()}')
                lines.extend(inner[1:])
            else:
                lines.append(f'{pad}- {_scalar(item)}')
    return lines


def render(files: Iterable[FileInfo], ros_distro: str = ROS_DISTRO) -> str:
    """The ``metadata.yaml`` text of a bag made of ``files`` (in the order given)."""
    files = list(files)
    topics: dict[tuple[str, str], TopicInfo] = {}
    for f in files:
        for t in f.topics.values():
            known = topics.get((t.name, t.type))
            if known is None:
                topics[(t.name, t.type)] = TopicInfo(
                    t.name,
                    t.type,
                    t.serialization_format,
                    t.offered_qos_profiles,
                    t.type_description_hash,
                    t.message_count,
                )
            else:
                known.message_count += t.message_count
    timed = [f for f in files if f.message_count]
    start = min((f.starting_time_ns for f in timed), default=0)
    end = max((f.starting_time_ns + f.duration_ns for f in timed), default=0)
    info = {
        'version': VERSION,
        'storage_identifier': 'mcap',
        'duration': {'nanoseconds': end - start},
        'starting_time': {'nanoseconds_since_epoch': start},
        'message_count': sum(f.message_count for f in files),
        'topics_with_message_count': [
            {
                'topic_metadata': {
                    'name': t.name,
                    'type': t.type,
                    'serialization_format': t.serialization_format,
                    'offered_qos_profiles': t.offered_qos_profiles,
                    'type_description_hash': t.type_description_hash,
                },
                'message_count': t.message_count,
            }
            for t in topics.values()
        ],
        'compression_format': '',
        'compression_mode': '',
        'relative_file_paths': [f.path for f in files],
        'files': [
            {
                'path': f.path,
                'starting_time': {'nanoseconds_since_epoch': f.starting_time_ns},
                'duration': {'nanoseconds': f.duration_ns},
                'message_count': f.message_count,
            }
            for f in files
        ],
        'custom_data': None,
        'ros_distro': ros_distro,
    }
    lines = ['rosbag2_bagfile_information:'] + _block(info, 2)
    # yaml-cpp writes empty strings as "" (json.dumps gives the same).
    return '\n'.join(lines) + '\n'


def write_metadata(folder: str | os.PathLike[str], files: Iterable[FileInfo]) -> Path:
    """Write ``folder/metadata.yaml`` atomically; return its path. Raises OSError."""
    folder = Path(folder)
    target = folder / METADATA_NAME
    tmp = folder / f'.{METADATA_NAME}.tmp'
    text = render(files)
    with open(tmp, 'w', encoding='utf-8') as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, target)
    fsync_dir(folder)
    return target


def folder_files(
    folder: str | os.PathLike[str], cache: dict[str, FileInfo | None] | None = None
) -> list[FileInfo]:
    """Facts of the finished ``*.mcap`` files in ``folder``, sorted by name.

    ``cache`` (name -> FileInfo or None) is consulted and filled, so that a writer that keeps
    it reads each file's summary once; names no longer in the folder are dropped from it.
    """
    folder = Path(folder)
    cache = {} if cache is None else cache
    names = sorted(p.name for p in folder.glob('*.mcap'))
    for gone in set(cache) - set(names):
        del cache[gone]
    out = []
    for name in names:
        if name not in cache or cache[name] is None:
            cache[name] = file_info(folder / name)
        found = cache[name]
        if found is not None:
            out.append(found)
    return out


def write_folder_metadata(
    folder: str | os.PathLike[str],
    extra: Iterable[FileInfo] = (),
    cache: dict[str, FileInfo | None] | None = None,
) -> Path:
    """Write ``metadata.yaml`` for the finished files of ``folder`` plus ``extra`` (e.g. the
    file being written, by name); return its path. Raises OSError."""
    extra = list(extra)
    names = {f.path for f in extra}
    files = [f for f in folder_files(folder, cache) if f.path not in names] + extra
    files.sort(key=lambda f: f.path)
    return write_metadata(folder, files)


def fsync_dir(folder: Path) -> None:
    """fsync a directory (its entries), where the platform allows it."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)

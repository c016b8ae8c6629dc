"""ROS 2 message definitions and channel metadata in the form rosbag2 writes them to MCAP.

Pure file and string handling: nothing here imports rclpy.

* :func:`message_definition` returns the ``ros2msg`` schema text for a type such as
  ``diagnostic_msgs/msg/DiagnosticArray``: the root ``.msg`` file followed by each dependency,
  recursively and without repeats, as ``"\\n" + "=" * 80 + "\\nMSG: pkg/Type\\n" + text``. This
  mirrors ``LocalMessageDefinitionSource::get_full_text`` in rosbag2_cpp (CONVENTIONS C12):
  dependencies are visited in sorted order per file and named without ``/msg/``.
* :func:`type_description_hash` returns the ``RIHS01_...`` hash that rosbag2 stores in the channel
  metadata key ``topic_type_hash``, read from the ``.json`` file the ROS wheels install beside
  the ``.msg`` file.
* :func:`offered_qos_profiles_yaml` renders a QoS profile in the YAML that rosbag2 stores in the
  channel metadata key ``offered_qos_profiles`` (CONVENTIONS C13).

The ``.msg`` files are found under ``share/<pkg>/msg/`` through the ament index
(``ament_index_python``, which needs ``AMENT_PREFIX_PATH``), then under ``$AMENT_PREFIX_PATH``
entries, ``sys.prefix`` and ``sys.base_prefix`` (a pip-installed venv puts them in
``<venv>/share``).
"""

from __future__ import annotations

import functools
import json
import os
import re
import sys
from pathlib import Path
from typing import Callable, Optional

__all__ = [
    'SchemaNotFoundError',
    'message_definition',
    'type_description_hash',
    'offered_qos_profiles_yaml',
    'QOS_LATCHED',
    'QOS_SENSOR_DATA',
    'QOS_DEFAULT',
    'DELIMITER',
]

#: Line of 80 ``=`` that separates definitions in the concatenated ``ros2msg`` text.
DELIMITER = '=' * 80

# Same pattern as rosbag2_cpp MSG_FIELD_TYPE_REGEX: a field type at the start of a line,
# optionally followed by an array suffix, then whitespace.
_MSG_FIELD_TYPE = re.compile(r'(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+')
_PRIMITIVES = frozenset(
    {
        'bool',
        'byte',
        'char',
        'float32',
        'float64',
        'int8',
        'uint8',
        'int16',
        'uint16',
        'int32',
        'uint32',
        'int64',
        'uint64',
        'string',
    }
)
_ROS_NAME = r'[a-zA-Z][a-zA-Z0-9_]*'
_TYPE_NAME = re.compile(rf'^({_ROS_NAME})/(?:({_ROS_NAME})/)?({_ROS_NAME})$')


class SchemaNotFoundError(LookupError):
    """A message definition file could not be found or the type name is malformed."""

    def __init__(self, type_name: str, detail: str) -> None:
        super().__init__(f'no ROS 2 message definition for {type_name!r}: {detail}')
        self.type_name = type_name


def _split_type(type_name: str) -> tuple[str, str, str]:
    """Split ``pkg/msg/Type`` or ``pkg/Type`` into ``(pkg, 'msg', Type)``."""
    match = _TYPE_NAME.match(type_name)
    if match is None:
        raise SchemaNotFoundError(type_name, "expected 'pkg/msg/Type' or 'pkg/Type'")
    package, namespace, name = match.groups()
    return package, namespace or 'msg', name


def _candidate_prefixes() -> list[Path]:
    prefixes = [Path(p) for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    prefixes += [Path(sys.prefix), Path(sys.base_prefix)]
    unique: list[Path] = []
    for prefix in prefixes:
        if prefix not in unique:
            unique.append(prefix)
    return unique


@functools.lru_cache(maxsize=None)
def _share_dir(package: str) -> Path:
    """Return the ``share/<package>`` directory of an installed ROS package."""
    lookup: Optional[Callable[[str], str]]
    try:
        from ament_index_python.packages import get_package_share_directory
    except ImportError:  # pragma: no cover - the ROS wheels ship ament_index_python
        lookup = None
    else:
        lookup = get_package_share_directory
    if lookup is not None:
        try:
            return Path(lookup(package))
        except (LookupError, OSError, ValueError):
            pass  # no AMENT_PREFIX_PATH or package not indexed: fall back to a file search
    for prefix in _candidate_prefixes():
        candidate = prefix / 'share' / package
        if candidate.is_dir():
            return candidate
    raise LookupError(
        f'share directory of package {package!r} not found via the ament index or under '
        + ', '.join(str(p / 'share') for p in _candidate_prefixes())
    )


@functools.lru_cache(maxsize=None)
def _read_msg(package: str, namespace: str, name: str) -> str:
    try:
        return (_share_dir(package) / namespace / f'{name}.msg').read_text(encoding='utf-8')
    except (LookupError, OSError) as exc:
        raise SchemaNotFoundError(f'{package}/{namespace}/{name}', str(exc)) from exc


def _dependencies(text: str, package: str) -> list[str]:
    """Return the sorted, de-duplicated non-primitive field types of a ``.msg`` text."""
    deps: set[str] = set()
    for match in _MSG_FIELD_TYPE.finditer(text):
        field_type = match.group(1)
        if field_type in _PRIMITIVES:
            continue
        deps.add(field_type if '/' in field_type else f'{package}/{field_type}')
    return sorted(deps)  # rosbag2 keeps them in a std::set (byte-wise sorted)


@functools.lru_cache(maxsize=None)
def message_definition(type_name: str) -> str:
    """Return the full ``ros2msg`` schema text for ``type_name``, as rosbag2 writes it.

    Parameters
    ----------
    type_name
        ROS 2 type, e.g. ``'std_msgs/msg/Float64'`` (``'std_msgs/Float64'`` is accepted too).

    Returns
    -------
    str
        Root ``.msg`` text, then each dependency (depth first, sorted per file, no repeats)
        as ``"\\n" + "=" * 80 + "\\nMSG: pkg/Type\\n" + text``.

    Raises
    ------
    SchemaNotFoundError
        If the type name is malformed or a ``.msg`` file cannot be found.
    """
    seen: set[str] = set()
    _split_type(type_name)  # reject malformed names before any file access

    def append(dep_name: str, depth: int) -> str:
        if depth <= 0:
            raise SchemaNotFoundError(type_name, 'maximum recursion depth reached')
        package, namespace, name = _split_type(dep_name)
        text = _read_msg(package, namespace, name)
        result = text
        for dep in _dependencies(text, package):
            if dep not in seen:
                seen.add(dep)
                result += f'\n{DELIMITER}\nMSG: {dep}\n' + append(dep, depth - 1)
        return result

    try:
        return append(type_name, 50)
    except SchemaNotFoundError as exc:
        if exc.type_name == type_name:
            raise
        raise SchemaNotFoundError(type_name, f'dependency: {exc}') from exc


@functools.lru_cache(maxsize=None)
def type_description_hash(type_name: str) -> str | None:
    """Return the ``RIHS01_<sha256>`` type hash of ``type_name``, or None if not installed.

    Read from ``share/<pkg>/msg/<Type>.json`` (generated by rosidl for Iron and later).
    """
    try:
        package, namespace, name = _split_type(type_name)
        path = _share_dir(package) / namespace / f'{name}.json'
        with open(path, encoding='utf-8') as handle:
            hashes = json.load(handle).get('type_hashes', [])
    except (LookupError, OSError, ValueError):
        return None
    full_name = f'{package}/{namespace}/{name}'
    for entry in hashes:
        if entry.get('type_name') == full_name:
            return str(entry.get('hash_string'))
    return None


# rmw "infinite" duration as rosbag2 serializes it (RMW_DURATION_INFINITE = INT64_MAX ns).
_INFINITE_SEC = 9223372036
_INFINITE_NSEC = 854775807


def offered_qos_profiles_yaml(
    *,
    history: str = 'keep_last',
    depth: int = 10,
    reliability: str = 'reliable',
    durability: str = 'volatile',
    liveliness: str = 'automatic',
) -> str:
    """Render one offered QoS profile in rosbag2's ``offered_qos_profiles`` YAML (version 9).

    The text matches ``YAML::Dump`` of ``rosbag2_storage::serialize_rclcpp_qos_vector`` for a
    single profile with infinite deadline, lifespan and liveliness lease duration.

    Parameters
    ----------
    history
        ``'keep_last'``, ``'keep_all'``, ``'system_default'`` or ``'unknown'``.
    depth
        History depth (messages).
    reliability
        ``'reliable'``, ``'best_effort'``, ``'system_default'`` or ``'unknown'``.
    durability
        ``'volatile'``, ``'transient_local'``, ``'system_default'`` or ``'unknown'``.
    liveliness
        ``'automatic'``, ``'manual_by_topic'``, ``'system_default'`` or ``'unknown'``.
    """
    if depth < 0:
        raise ValueError(f'depth must be >= 0, got {depth}')
    infinite = f'\n    sec: {_INFINITE_SEC}\n    nsec: {_INFINITE_NSEC}'
    return (
        f'- history: {history}\n'
        f'  depth: {int(depth)}\n'
        f'  reliability: {reliability}\n'
        f'  durability: {durability}\n'
        f'  deadline:{infinite}\n'
        f'  lifespan:{infinite}\n'
        f'  liveliness: {liveliness}\n'
        f'  liveliness_lease_duration:{infinite}\n'
        f'  avoid_ros_namespace_conventions: false'
    )


#: Latched alarm/state topics (CONVENTIONS C6): reliable, transient_local, depth 1.
QOS_LATCHED = offered_qos_profiles_yaml(depth=1, durability='transient_local')
#: ``qos_profile_sensor_data``: keep last 5, best effort, volatile.
QOS_SENSOR_DATA = offered_qos_profiles_yaml(depth=5, reliability='best_effort')
#: rclpy's default publisher profile: keep last 10, reliable, volatile.
QOS_DEFAULT = offered_qos_profiles_yaml()

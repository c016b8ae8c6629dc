"""Params files read as rcl reads them: rules, glibc number parsing, agreement with rcl itself.

* unit tests of the scalar typing and the structure rules of ``core.config.params_file``;
* hypothesis: the Python ``strtol``/``strtod`` against glibc's (ctypes), the scalar typing against
  rcl's own ``get_value`` and whole generated files against ``rcl_parse_yaml_file`` (ctypes, the
  library rclpy loads; skipped where it is not found);
* a corpus of files through the real rcl + rclpy (one subprocess, one ``rclpy.init`` per file) and
  through ``load_params_file``: accepted by both or refused by both, same names, types, values;
  except that the monitor refuses a file giving a parameter of the node twice (rcl takes the
  later value: ``GIVEN_TWICE``).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import json
import math
import os
import random
import subprocess
import sys
from pathlib import Path
from typing import Any, Optional

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from catenary_monitor.core.config.parameters import (
    ConfigError,
    config_from_params,
    load_params_file,
)
from catenary_monitor.core.config.params_file import (
    ParamsFileError,
    c_strtod,
    c_strtol,
    parameters_for_node,
    parse_params,
    rcl_scalar,
)

ROOT = Path(__file__).resolve().parents[1]
DOCK_YAML = ROOT / 'config' / 'floating_dock.yaml'
H = 'catenary_monitor:\n  ros__parameters:\n'
ALPHABET = '0123456789+-.eExXabfinINFtrueyesnoY_ p()'
NODE = 'catenary_monitor'


def _params(text: str, namespace: str = '/') -> dict[str, Any]:
    return parameters_for_node(parse_params(text.encode()), NODE, namespace)


def _refused(text: str | bytes) -> str:
    with pytest.raises(ParamsFileError) as info:
        parse_params(text.encode() if isinstance(text, str) else text)
    assert '\n' not in str(info.value)
    return str(info.value)


# --- scalar typing ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    'text, expected',
    [
        ('5.17e6', 5.17e6),
        ('1e6', 1e6),
        ('1e+06', 1e6),
        ('1300', 1300),
        ('0x10', 16),
        ('0X1A', 26),
        ('010', 8),
        ('-0x10', -16),
        ('+5', 5),
        ('-0', 0),
        ('08', 8.0),
        ('1.', 1.0),
        ('.5', 0.5),
        ('inf', math.inf),
        ('infinity', math.inf),
        ('-.INF', -math.inf),
        ('+.Inf', math.inf),
        ('0x1p3', 8.0),
        ('99999999999999999999', 1e20),
        ('-9223372036854775808', -(2**63)),
        ('-9223372036854775809', -9.223372036854775809e18),
        ('0x1p-1074', 5e-324),
        ('yes', True),
        ('Yes', True),
        ('ON', True),
        ('y', True),
        ('N', False),
        ('off', False),
        ('1_000', '1_000'),
        ('~', '~'),
        ('null', 'null'),
        ('tRUE', 'tRUE'),
        ('1e6x', '1e6x'),
        ('0b11', '0b11'),
        ('1e400', '1e400'),
        ('1e-400', '1e-400'),
        ('4e-320', '4e-320'),
        ('.Nan', '.Nan'),
        ('-.nan', '-.nan'),
        ('12e', '12e'),
        ('0x', '0x'),
        ('5\n', '5\n'),
        (' 5', 5),
        ('\n5', 5),
        ('5 ', '5 '),
    ],
)
def test_plain_scalar_typing(text: str, expected: Any) -> None:
    kind, value = rcl_scalar(text)
    assert type(value) is type(expected) and value == expected, (kind, value)


@pytest.mark.parametrize('text', ['nan', '.nan', '.NaN', '.NAN', '-nan', 'NAN', 'nan(12)'])
def test_nans_are_doubles(text: str) -> None:
    kind, value = rcl_scalar(text)
    assert kind == 'double' and math.isnan(value)


def test_negative_zero_keeps_its_sign() -> None:
    assert math.copysign(1.0, rcl_scalar('-0.0')[1]) == -1.0


@pytest.mark.parametrize(
    'text, style, tag',
    [
        ('5', "'", None),
        ('yes', '"', None),
        ('5', '', 'tag:yaml.org,2002:str'),
        ('1e6', '|', 'tag:yaml.org,2002:str'),
    ],
)
def test_quoted_and_str_tagged_are_strings(text: str, style: str, tag: Optional[str]) -> None:
    assert rcl_scalar(text, style, tag) == ('string', text)


def test_other_tags_are_ignored_and_c_strings_end_at_nul() -> None:
    assert rcl_scalar('1', '', 'tag:yaml.org,2002:float') == ('int', 1)
    assert rcl_scalar('x\0y', '"') == ('string', 'x')
    assert rcl_scalar('5\0x') == ('int', 5)


def test_block_scalars_are_typed_like_plain_ones() -> None:
    assert _params(H + '    a: |\n      5\n    b: |-\n      5\n    c: >-\n      1e3\n') == {
        'a': '5\n',
        'b': 5,
        'c': 1000.0,
    }


# --- structure --------------------------------------------------------------------------------


def test_nested_maps_flatten_and_dotted_keys_are_the_same_name() -> None:
    assert _params(
        H + '    line_01.weight: 1\n    line_01:\n      weight: 2\n' '    a: {b: {c: 1}, d: 2}\n'
    ) == {'line_01.weight': 2, 'a.b.c': 1, 'a.d': 2}


def test_closing_a_map_cuts_the_name_at_its_last_dot() -> None:
    """rcl's quirk: ``x: {a.b: {c: 1}, d: 2}`` gives ``x.a.d``, not ``x.d``."""
    assert _params(H + '    x:\n      a.b:\n        c: 1\n      d: 2\n') == {
        'x.a.b.c': 1,
        'x.a.d': 2,
    }


@pytest.mark.parametrize(
    'text, needle',
    [
        (
            H + '    mbl: 4.8e6\n    w: 1\n    mbl: 1\n',
            "'mbl' is given twice, at line 3 and line 5",
        ),
        (
            H + '    line_01:\n      mbl: 4.8e6\n      w: 1\n      mbl: 1\n',
            "'line_01.mbl' is given twice, at line 4 and line 6",
        ),
        (
            H + '    line_01.mbl: 4.8e6\n    line_01:\n      mbl: 1.0\n',
            "'line_01.mbl' is given twice, at line 3 and line 5",
        ),
        (H + '    a: [1.0]\n    a: [2.0, 3.0]\n', "'a' is given twice, at line 3 and line 4"),
        (H + '    a: 1\n' + H + '    a: 1\n', "'a' is given twice, at line 3 and line 6"),
    ],
)
def test_a_parameter_given_twice_is_refused_naming_it_and_both_lines(
    tmp_path: Path, text: str, needle: str
) -> None:
    path = tmp_path / 'p.yaml'
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_params_file(path)
    assert needle in str(info.value) and '\n' not in str(info.value)


def test_other_nodes_sections_and_overrides_across_sections_are_not_duplicates(
    tmp_path: Path,
) -> None:
    path = tmp_path / 'p.yaml'
    path.write_text('other:\n  ros__parameters:\n    a: 1\n' + H + '    a: 2\n    b: [1, [2]]\n')
    assert load_params_file(path) == {'a': 2, 'b': [2]}
    assert load_params_file(path, 'other') == {'a': 1}
    path.write_text('/**:\n  ros__parameters:\n    a: 1\n' + H + '    a: 2\n')  # rclpy's override
    assert load_params_file(path) == {'a': 2}


def test_duplicates_later_wins_within_a_type_first_type_wins_across() -> None:
    """What rcl does with a parameter given twice (parse_params is rcl's walk; the monitor's
    read_params_file refuses such files)."""
    assert _params(H + '    a: 1\n    a: 2\n') == {'a': 2}
    assert _params(H + '    a: 1\n    a: 2.0\n    b: x\n    b: 2.5\n    c: [x]\n    c: 1\n') == {
        'a': 1,
        'b': 2.5,
        'c': 1,
    }


def test_sequences() -> None:
    assert _params(
        H + '    a: [true, false]\n    b: [1.5, 2e3]\n    c: []\n    d: [[1]]\n'
        '    e: [1, [2]]\n    f: "[1,2]"\n'
    ) == {'a': [True, False], 'b': [1.5, 2000.0], 'c': None, 'd': [1], 'e': [2], 'f': '[1,2]'}


def test_empty_map_is_not_set_and_ends_ros_parameters() -> None:
    assert _params(H + '    b: 2\n    a: {}\n') == {'b': 2, 'a': None}
    assert 'Cannot have a value' in _refused(H + '    a: {}\n    b: 2\n')


def test_keys_are_text_and_documents_merge() -> None:
    assert _params(H + '    3: 4\n    "x": 1\n    ? y\n    : 2\n---\n' + H + '    z: 5\n') == {
        '3': 4,
        'x': 1,
        'y': 2,
        'z': 5,
    }


@pytest.mark.parametrize(
    'text, expected',
    [
        ('', {}),
        ('# nothing\n', {}),
        ('5\n', {}),
        ('other:\n  ros__parameters:\n    a: 1\n', {}),
        ('catenary_monitor:\n  ros__parametersXYZ:\n    a: 1\n', {'a': 1}),
        ('/:\n  catenary_monitor:\n    ros__parameters:\n      a: 1\n', {'a': 1}),
        ('"/**":\n  ros__parameters:\n    a: 1\n', {'a': 1}),
        ('/**/*:\n  ros__parameters:\n    a: 1\n', {'a': 1}),
    ],
)
def test_sections(text: str, expected: dict[str, Any]) -> None:
    assert _params(text) == expected


def test_matching_and_order_of_sections() -> None:
    text = ''.join(
        f'{name}:\n  ros__parameters:\n    {key}: 1\n'
        for name, key in [
            ('/**', 'a'),
            ('/**/catenary_monitor', 'b'),
            ('/*/catenary_monitor', 'c'),
            ('/catenary_monitor', 'd'),
            ('other', 'e'),
            ('/ns/catenary_monitor', 'f'),
            ('/*', 'g'),
            (NODE, 'h'),
        ]
    )
    assert set(_params(text)) == set('abdgh')
    assert set(_params(text, '/ns')) == set('abcf')
    # entries in order of first appearance; a repeated name merges into its first entry
    assert _params(H + '    a: 1\n/**:\n  ros__parameters:\n    a: 2.0\n' + H + '    a: 3\n') == {
        'a': 2.0
    }
    assert _params(
        H + '    a: 1\n/**:\n  ros__parameters:\n    a: 2\n'
        '/catenary_monitor:\n  ros__parameters:\n    a: 3\n'
    ) == {'a': 3}


@pytest.mark.parametrize(
    'text, rule',
    [
        (H + '    a: [1, 2.0]\n', 'Sequence should be of same type'),
        (H + '    a: [a, 1]\n', 'Sequence should be of same type'),
        (H + '    a:\n', 'No value (line 3)'),
        (H + '    "": 1\n', 'No key'),
        ('[1, 2]\n', 'Sequences cannot be key'),
        (H + '    a: [[1], [2]]\n', 'Sequences cannot be key'),
        (H + '    a: &x 1\n    b: *x\n', 'Will not support aliasing'),
        ('catenary_monitor:\n  other: 1\n  ros__parameters:\n    a: 1\n', 'Cannot have a value'),
        ('catenary_monitor: 5\n', 'Cannot have a value'),
        ('catenary_monitor:\n  ros__parameters: 5\n', 'Cannot have a value'),
        ('catenary_monitor:\n  ros__parameters:\n  a: 1\n', 'Cannot have a value'),
        ('ros__parameters: {}\n', 'There are no node names before'),
        ('1abc:\n  ros__parameters:\n    a: 1\n', 'must not start with a number'),
        ('cat*:\n  ros__parameters:\n    a: 1\n', 'other than alphanumerics'),
        (
            'ns:\n  /**:\n    ros__parameters:\n      a: 1\n',
            '/ns// contains repeated forward slash',
        ),
        ('/:\n  ros__parameters:\n    a: 1\n', 'node name must not be empty'),
        ('a' * 256 + ':\n  ros__parameters:\n    a: 1\n', "should not exceed '255'"),
        ('/' + 'b' * 245 + '/n:\n  ros__parameters:\n    a: 1\n', 'namespace should not exceed'),
        (H + '    ? {x: 1}\n    : 2\n', 'Internal error creating param namespace'),
        (H + '    a: [\n', 'YAML syntax'),
        (b'\xff\xfe\x00', 'YAML syntax'),
        (H.encode() + b'    a: \xff\xfe\n', 'YAML syntax'),
        (bytes(range(256)), 'YAML syntax'),
    ],
)
def test_refused(text: str | bytes, rule: str) -> None:
    assert rule in _refused(text)


@pytest.mark.parametrize(
    'refused, accepted',
    [
        ('%YAML 1.2\n---\n', '%YAML 1.1\n---\n'),
        ('    a: [x:y]\n', '    a: [x: y]\n'),
        ('    a: [x ?y]\n', '    a: [x y]\n'),
        ('    a: "\\/"\n', '    a: "/"\n'),
        ('    a: [!!str, x]\n', '    a: [!!str "", x]\n'),
    ],
)
def test_libyaml_versions_disagree_so_refused(refused: str, accepted: str) -> None:
    """ROS 2's pip wheels link libyaml 0.1.7, Jazzy's debs 0.2.5: accept only what both accept."""

    def text(part: str) -> str:
        return part + _p('a: 1') if part.startswith('%') else H + part

    assert 'libyaml 0.1.7' in _refused(text(refused))
    parse_params(text(accepted).encode())


def test_utf16_with_bom_is_read() -> None:
    assert parameters_for_node(parse_params((H + '    a: 1\n').encode('utf-16')), NODE) == {'a': 1}


# --- through config ---------------------------------------------------------------------------


def test_config_errors_are_one_line(tmp_path: Path) -> None:
    path = tmp_path / 'p.yaml'
    for data in (b'', bytes(range(256)), (H + '    a: [1, x]\n').encode(), b'\x00\x01'):
        path.write_bytes(data)
        try:
            flat = load_params_file(path)
        except ConfigError as err:
            assert str(err).startswith("parameter '--params-file': ") and '\n' not in str(err)
            continue
        assert flat == {}
        with pytest.raises(ConfigError, match="'lines': missing required"):
            config_from_params(flat)


def test_namespace_argument(tmp_path: Path) -> None:
    path = tmp_path / 'p.yaml'
    path.write_text('/ns/catenary_monitor:\n  ros__parameters:\n    a: 1\n')
    assert load_params_file(path) == {}
    assert load_params_file(path, node_namespace='/ns') == {'a': 1}
    assert load_params_file(path, node_namespace='ns') == {'a': 1}


# --- glibc strtol / strtod (ctypes) -----------------------------------------------------------


def _libc() -> Optional[ctypes.CDLL]:
    try:
        libc = ctypes.CDLL(ctypes.util.find_library('c') or 'libc.so.6', use_errno=True)
        getattr(libc, 'gnu_get_libc_version')  # glibc only: the rules mirrored are glibc's
    except (OSError, AttributeError):
        return None
    libc.strtol.restype = ctypes.c_long
    libc.strtol.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_char_p), ctypes.c_int]
    libc.strtod.restype = ctypes.c_double
    libc.strtod.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_char_p)]
    return libc


LIBC = _libc()
needs_glibc = pytest.mark.skipif(
    LIBC is None or ctypes.sizeof(ctypes.c_long) != 8, reason='glibc with a 64-bit long needed'
)


def _c_call(name: str, text: str) -> tuple[Any, int, bool]:
    buf = ctypes.create_string_buffer(text.encode('ascii'))
    end = ctypes.c_char_p()
    ctypes.set_errno(0)
    args = (buf, ctypes.byref(end), 0) if name == 'strtol' else (buf, ctypes.byref(end))
    value = getattr(LIBC, name)(*args)
    erange = ctypes.get_errno() == 34  # ERANGE
    consumed = ctypes.cast(end, ctypes.c_void_p).value - ctypes.addressof(buf)
    return value, consumed, erange


def _same_double(a: float, b: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)


EDGE_NUMBERS = [
    '2.2250738585072011e-308',
    '2.2250738585072013e-308',
    '2.225073858507201e-308',
    '0x1.fffffffffffffp-1023',
    '0x1.fffffffffffff8p-1023',
    '0x0.fffffffffffff8p-1022',
    '0x1p-1075',
    '0x1.8p-1075',
    '0x1.0000000000001p-1075',
    '4.9406564584124654e-324',
    '2.4703282292062327e-324',
    '2.4703282292062328e-324',
    '1.7976931348623158e308',
    '1.7976931348623159e308',
    '0x1.fffffffffffff8p1023',
    '1e-99999999999',
    '0e-400',
    'nan(0x12)',
    'nan(',
    'infinit',
    '0x.8',
    '0x.p1',
    '0X1P',
    '-0x8000000000000000',
    '0x8000000000000000',
    '0777777777777777777777',
    '1' * 400,
    '.' + '0' * 400 + '1',
]


@needs_glibc
@settings(max_examples=3000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(ALPHABET, max_size=14))
def test_strtol_and_strtod_match_glibc(text: str) -> None:
    _check_against_libc(text)


@needs_glibc
@pytest.mark.parametrize('text', EDGE_NUMBERS)
def test_strtod_edges_match_glibc(text: str) -> None:
    _check_against_libc(text)


def _check_against_libc(text: str) -> None:
    assert c_strtol(text) == _c_call('strtol', text)
    ours, theirs = c_strtod(text), _c_call('strtod', text)
    assert ours[1:] == theirs[1:] and _same_double(ours[0], theirs[0]), (ours, theirs)


# --- rcl itself through ctypes ----------------------------------------------------------------


def _ros_library(stem: str) -> Optional[ctypes.CDLL]:
    """A ROS 2 shared library from LD_LIBRARY_PATH, this venv's lib/ or the ament prefixes."""
    dirs = (
        ['']
        + [str(Path(sys.prefix) / 'lib')]
        + [
            str(Path(p) / 'lib')
            for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep)
            if p
        ]
    )
    for directory in dirs:
        try:
            return ctypes.CDLL(os.path.join(directory, f'lib{stem}.so'))
        except OSError:
            continue
    return None


class _Alloc(ctypes.Structure):
    _fields_ = [
        (n, ctypes.c_void_p)
        for n in ('allocate', 'deallocate', 'reallocate', 'zero_allocate', 'state')
    ]


class _Array(ctypes.Structure):
    _fields_ = [('values', ctypes.c_void_p), ('size', ctypes.c_size_t)]


class _StringArray(ctypes.Structure):
    _fields_ = [
        ('size', ctypes.c_size_t),
        ('data', ctypes.POINTER(ctypes.c_char_p)),
        ('allocator', _Alloc),
    ]


class _Variant(ctypes.Structure):
    _fields_ = [
        ('bool', ctypes.POINTER(ctypes.c_bool)),
        ('int', ctypes.POINTER(ctypes.c_int64)),
        ('double', ctypes.POINTER(ctypes.c_double)),
        ('string', ctypes.c_char_p),
        ('bytes', ctypes.POINTER(_Array)),
        ('bools', ctypes.POINTER(_Array)),
        ('ints', ctypes.POINTER(_Array)),
        ('doubles', ctypes.POINTER(_Array)),
        ('strings', ctypes.POINTER(_StringArray)),
    ]


class _NodeParams(ctypes.Structure):
    _fields_ = [
        ('names', ctypes.POINTER(ctypes.c_char_p)),
        ('values', ctypes.POINTER(_Variant)),
        ('num', ctypes.c_size_t),
        ('capacity', ctypes.c_size_t),
    ]


class _Params(ctypes.Structure):
    _fields_ = [
        ('names', ctypes.POINTER(ctypes.c_char_p)),
        ('params', ctypes.POINTER(_NodeParams)),
        ('num', ctypes.c_size_t),
        ('capacity', ctypes.c_size_t),
        ('allocator', _Alloc),
    ]


class Rcl:
    """rcl_yaml_param_parser through ctypes (Jazzy's struct layout, rcl/types.h)."""

    def __init__(self, parser: ctypes.CDLL, rcutils: ctypes.CDLL) -> None:
        self.parser, self.rcutils = parser, rcutils
        rcutils.rcutils_get_default_allocator.restype = _Alloc
        parser.rcl_yaml_node_struct_init.restype = ctypes.POINTER(_Params)
        parser.rcl_yaml_node_struct_init.argtypes = [_Alloc]
        parser.rcl_parse_yaml_file.restype = ctypes.c_bool
        parser.rcl_parse_yaml_file.argtypes = [ctypes.c_char_p, ctypes.POINTER(_Params)]
        parser.rcl_yaml_node_struct_fini.argtypes = [ctypes.POINTER(_Params)]
        parser.get_value.restype = ctypes.c_void_p
        parser.get_value.argtypes = [
            ctypes.c_char_p,
            ctypes.c_int,
            ctypes.c_char_p,
            ctypes.POINTER(ctypes.c_int),
            _Alloc,
        ]

    def scalar(self, text: str, style: int = 1, tag: Optional[str] = None) -> tuple[str, Any]:
        """rcl's get_value (style: libyaml's, 1 plain 2 single 3 double 4 literal)."""
        kind = ctypes.c_int()
        allocator = self.rcutils.rcutils_get_default_allocator()
        ptr = self.parser.get_value(
            text.encode(), style, tag and tag.encode(), ctypes.byref(kind), allocator
        )
        ctype = {1: ctypes.c_bool, 2: ctypes.c_int64, 3: ctypes.c_double}.get(kind.value)
        value = (
            ctypes.string_at(ptr).decode()
            if ctype is None
            else ctypes.cast(ptr, ctypes.POINTER(ctype))[0]
        )
        return ['', 'bool', 'int', 'double', 'string'][kind.value], value

    def parse(self, path: Path) -> Optional[list[tuple[str, dict[str, Any]]]]:
        """Node entries as parse_params gives them, or None if rcl refuses the file."""
        allocator = self.rcutils.rcutils_get_default_allocator()
        params = self.parser.rcl_yaml_node_struct_init(allocator)
        try:
            if not self.parser.rcl_parse_yaml_file(str(path).encode(), params):
                self.rcutils.rcutils_reset_error()
                return None
            return [
                (params[0].names[i].decode(), self._node(params[0].params[i]))
                for i in range(params[0].num)
            ]
        finally:
            self.parser.rcl_yaml_node_struct_fini(params)

    def _node(self, node: _NodeParams) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for j in range(node.num):
            out[node.names[j].decode()] = self._value(node.values[j])
        return out

    @staticmethod
    def _value(v: _Variant) -> Any:
        """rclpy's reading order of an rcl_variant_t."""
        for name in ('bool', 'int', 'double'):
            if getattr(v, name):
                return getattr(v, name)[0]
        if v.string is not None:
            return v.string.decode()
        for name, ctype in (
            ('bools', ctypes.c_bool),
            ('ints', ctypes.c_int64),
            ('doubles', ctypes.c_double),
        ):
            if getattr(v, name):
                array = getattr(v, name)[0]
                return [
                    ctypes.cast(array.values, ctypes.POINTER(ctype))[k] for k in range(array.size)
                ]
        if v.strings:
            return [v.strings[0].data[k].decode() for k in range(v.strings[0].size)]
        return None


def _rcl() -> Optional[Rcl]:
    parser, rcutils = _ros_library('rcl_yaml_param_parser'), _ros_library('rcutils')
    if parser is None or rcutils is None:
        return None
    try:
        return Rcl(parser, rcutils)
    except AttributeError:
        return None


RCL = _rcl()
needs_rcl = pytest.mark.skipif(RCL is None, reason='librcl_yaml_param_parser not found')


def _tagged(value: Any) -> Any:
    """JSON-safe value with its type, NaN equal to NaN."""
    if isinstance(value, list):
        return ['list', [_tagged(v) for v in value]]
    if isinstance(value, float):
        return ['float', 'nan' if math.isnan(value) else repr(value)]
    return [type(value).__name__, value]


@needs_rcl
@settings(max_examples=3000, deadline=None)
@given(
    st.text(ALPHABET, max_size=12),
    st.sampled_from(
        [
            (1, None),
            (2, None),
            (3, None),
            (4, None),
            (1, 'tag:yaml.org,2002:str'),
            (1, 'tag:yaml.org,2002:int'),
        ]
    ),
)
@example('.NaN', (1, None))
@example('-.INF', (1, None))
@example('Yes', (1, None))
@example('Yes', (2, None))
def test_scalar_typing_matches_rcl_get_value(
    text: str, style_tag: tuple[int, Optional[str]]
) -> None:
    style, tag = style_tag
    kind, value = rcl_scalar(text, {1: '', 2: "'", 3: '"', 4: '|'}[style], tag)
    rcl_kind, rcl_value = RCL.scalar(text, style, tag)
    assert (kind, _tagged(value)) == (rcl_kind, _tagged(rcl_value))


# whole files: generated from the constructs rcl handles, none where libyaml versions disagree
_KEYS = [
    'a',
    'b',
    'c',
    'a.b',
    'line_01',
    'weight',
    'x.y',
    '3',
    '"a"',
    '~',
    'ros__parameters',
    'ros__parametersX',
] * 3 + ['""', '"\\0"']
_NODES = [
    NODE,
    NODE,
    '/catenary_monitor',
    '/**',
    '/**',
    '/*',
    '/**/catenary_monitor',
    'other',
    'a/b',
    '"/**"',
    '"*"',
    'ns/**',
    '1abc',
    'cat*',
    'ros__parameters',
    '""',
]
_SCALARS = [
    '1',
    '0x10',
    '010',
    '08',
    '1e6',
    '1.',
    'inf',
    '.nan',
    '-.INF',
    'yes',
    'ON',
    'tRUE',
    '~',
    '1_000',
    '1e400',
    '"5"',
    "'x'",
    '!!str 5',
    '!!float 1',
    '"\\0"',
    '""',
    '|-\n{i}5',
    '|\n{i}x',
    'é',
    '1',
    'x',
    '2.5',
    'true',
] * 2 + ['&an 1', '*an', '""']


def _scalar(draw: Any, indent: int) -> str:
    if draw(st.booleans()):
        text = draw(st.text(ALPHABET.replace('(', '').replace(')', ''), min_size=1, max_size=8))
        return text.strip() if text.strip() and text.strip()[0] not in '-?' else '1'
    return draw(st.sampled_from(_SCALARS)).replace('{i}', ' ' * (indent + 2))


def _value(draw: Any, indent: int, depth: int) -> str:
    kind = draw(st.sampled_from('sssssssqqqmmmeE' if depth < 3 else 's'))
    if kind == 's':
        return ' ' + _scalar(draw, indent)
    if kind == 'q':
        items = [
            _scalar(draw, indent).split('\n')[0].replace('|-', '1').replace('|', '1')
            for _ in range(draw(st.integers(0, 3)))
        ]
        nested = ['[' + i + ']' for i in items[:1]] if draw(st.booleans()) else []
        return ' [' + ', '.join(items + nested) + ']'
    if kind in 'eE':
        return ' {}' if kind == 'e' else ' []'
    return '\n' + _mapping(draw, indent + 2, depth + 1)


def _mapping(draw: Any, indent: int, depth: int) -> str:
    keys = draw(st.lists(st.sampled_from(_KEYS), min_size=1, max_size=4))
    return '\n'.join(' ' * indent + k + ':' + _value(draw, indent, depth) for k in keys)


@st.composite
def params_files(draw: Any) -> str:
    sections = []
    for _ in range(draw(st.integers(0, 3))):
        name, body = draw(st.sampled_from(_NODES)), ''
        for _ in range(draw(st.sampled_from([1] * 9 + [2]))):
            key = draw(st.sampled_from(['ros__parameters'] * 9 + ['other']))
            value = (
                _value(draw, 2, 0) if draw(st.integers(0, 9)) == 0 else '\n' + _mapping(draw, 4, 1)
            )
            body += f'  {key}:{value}\n'
        sections.append(f'{name}:\n{body}')
    docs = draw(st.sampled_from([1] * 4 + [2]))
    return draw(st.sampled_from([''] * 4 + ['---\n'])) + '---\n'.join(
        ''.join(sections[i::docs]) for i in range(docs)
    )


@needs_rcl
@settings(
    max_examples=600,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(params_files())
def test_generated_files_match_rcl_parse_yaml_file(tmp_path: Path, text: str) -> None:
    path = tmp_path / 'p.yaml'
    path.write_text(text)
    theirs = RCL.parse(path)
    try:
        ours: Optional[list[tuple[str, dict[str, Any]]]] = parse_params(text.encode())
    except ParamsFileError:
        ours = None
    assert _entries(ours) == _entries(theirs), text


def _entries(entries: Optional[list[tuple[str, dict[str, Any]]]]) -> Optional[list[Any]]:
    if entries is None:
        return None
    return [[name, [[k, _tagged(v)] for k, v in params.items()]] for name, params in entries]


# --- the corpus, through rclpy ----------------------------------------------------------------


def _p(*lines: str) -> str:
    '''A catenary_monitor section with these lines under ros__parameters.'''
    return H + ''.join(f'    {line}\n' for line in lines)


def _sections(*names_keys: tuple[str, str]) -> str:
    return ''.join(f'{n}:\n  ros__parameters:\n    {k}: 1\n' for n, k in names_keys)


SCALARS = [
    '5.17e6',
    '1e6',
    '1300',
    '0x10',
    '010',
    '.inf',
    'nan',
    "'x'",
    'yes',
    '"5"',
    '1_000',
    '1e400',
    '99999999999999999999',
    '+5',
    '1.',
    'inf',
    '0x1p3',
    '4e-320',
    '!!str 5',
    '~',
    'null',
    '1e-400',
    '1e+06',
    '0b11',
    '1e6x',
    '" 5"',
    '-0x10',
    '0.0e0',
    '-.inf',
    '.NaN',
    'Yes',
    'TRUE',
    'tRUE',
    '1.5E3',
    '0X1A',
    '1e3.5',
    '12e',
    'infinity',
    '-nan',
    '0x',
    '08',
    '-0',
    '-0.0',
    '0x1p-1074',
    '-9223372036854775809',
    '!!float 1',
    '!!int "3"',
    '.Nan',
    'N',
    'Off',
    'ON',
    'y',
    'YES',
    'no',
    'False',
]
WILD = [
    ('/**', 'a'),
    (NODE, 'a'),
    ('/**/catenary_monitor', 'b'),
    ('/*/catenary_monitor', 'c'),
    ('/catenary_monitor', 'd'),
    ('other', 'e'),
    ('/ns/catenary_monitor', 'f'),
    ('/*', 'g'),
]
WILD_NS = [
    ('/**', 'a'),
    (NODE, 'b'),
    ('/*/catenary_monitor', 'c'),
    ('/ns/catenary_monitor', 'd'),
    ('/*', 'e'),
    ('/ns/*', 'f'),
    ('/**/*', 'g'),
    ('ns/catenary_monitor', 'h'),
]
LONG_NS = '/' + 'b' * 244

CORPUS: list[tuple[str, str | bytes, str]] = [
    ('scalars', _p(*(f'k{i}: {v}' for i, v in enumerate(SCALARS))), '/'),
    ('blocks', _p('a: |', '  text', 'b: |-', '  5', 'c: >-', '  1e3', 'd: |2-', '    7'), '/'),
    (
        'lists',
        _p(
            'a: [true, false]',
            'b: [1.5, 2e3]',
            'c: "[1,2]"',
            'd: [a, b]',
            'e: []',
            'f: [[1]]',
            'g: [1, [2]]',
            'h: [1, [2.0]]',
            'i: [{b: 1}]',
        ),
        '/',
    ),
    ('list_mixed_float', _p('a: [1, 2.0]'), '/'),
    ('list_mixed_str', _p('a: [a, 1]'), '/'),
    ('list_mixed_empty_str', _p('a: [1, ""]'), '/'),
    ('nested_list_then_key', _p('a: [[1], 2]', 'b: 3'), '/'),
    ('nested_lists', _p('a: [[1], [2]]'), '/'),
    ('wildcards', _sections(*WILD), '/'),
    ('wildcards_in_ns', _sections(*WILD_NS), '/ns'),
    ('order_first_appearance', _p('a: 1') + _sections(('/**', 'a')) + _p('a: 3'), '/'),
    (
        'order_distinct_names',
        _p('a: 2')
        + _sections(('/**', 'a'))
        + '/catenary_monitor:\n  ros__parameters:\n    a: 3\n',
        '/',
    ),
    (
        'order_root_ns',
        '/:\n  catenary_monitor:\n    ros__parameters:\n      a: 3\n'
        + _sections(('/**', 'a'))
        + '/catenary_monitor:\n  ros__parameters:\n    a: 2\n',
        '/',
    ),
    (
        'wildcard_after_specific',
        '/**/catenary_monitor:\n  ros__parameters:\n    a: 2\n' + _sections(('/**', 'a')),
        '/',
    ),
    ('root_namespace_key', '/:\n  catenary_monitor:\n    ros__parameters:\n      a: 1\n', '/'),
    (
        'nested_namespaces',
        '/:\n  ns:\n    catenary_monitor:\n      ros__parameters:\n'
        '        a: 1\n  catenary_monitor:\n    ros__parameters:\n      b: 2\n',
        '/ns',
    ),
    ('quoted_wildcard', '"/**":\n  ros__parameters:\n    a: 1\n', '/'),
    ('star_names', _sections(('"*"', 'a'), ('"**"', 'b'), ('/**/**', 'c'), ('/**/*', 'd')), '/'),
    ('no_matching_section', _sections(('other', 'a')), '/'),
    ('empty_file', '', '/'),
    ('comments_only', '# nothing here\n', '/'),
    ('scalar_document', '5\n', '/'),
    ('empty_first_document', '---\n---\n' + _p('a: 1'), '/'),
    ('multi_document', _p('a: 1') + '---\n' + _p('b: 1') + '...\n', '/'),
    (
        'dotted_and_nested',
        _p('line_01.weight: 1', 'line_01:', '  weight: 2', 'a.b: 1', 'a:', '  c: 2'),
        '/',
    ),
    (
        'nested_quirks',
        _p(
            'x:',
            '  a.b:',
            '    c: 1',
            '  d: 2',
            'e:',
            '  f: 1',
            'e:',
            '  f: 2.0',
            'g:',
            '  h:',
            '    i: 1',
            '  j: 2',
        ),
        '/',
    ),
    (
        'duplicates',
        _p(
            'a: 1',
            'a: 2',
            'b: 1',
            'b: 2.0',
            'c: x',
            'c: 2',
            'd: 2.0',
            'd: true',
            'e: 1',
            'e: [1]',
            'f: [x]',
            'f: [1]',
            'g: [true]',
            'g: [1]',
        ),
        '/',
    ),
    ('empty_map_last', _p('b: 2', 'a: {}'), '/'),
    ('empty_map_then_key', _p('a: {}', 'b: 2'), '/'),
    (
        'keys',
        _p(
            '"a": 1',
            '? b',
            ': 2',
            '3: 4',
            '~: 5',
            'é: "ü"',
            'ros__parameters: 6',
            'ros__parametersX: 7',
            '"\\0": 8',
        ),
        '/',
    ),
    ('prefix_of_ros_parameters', 'catenary_monitor:\n  ros__parametersXYZ:\n    a: 1\n', '/'),
    ('flow_style', '{catenary_monitor: {ros__parameters: {a: 1, b: [1, 2], c: {d: x}}}}\n', '/'),
    ('crlf_and_tabs', _p('a:\t1').replace('\n', '\r\n'), '/'),
    (
        'strings',
        _p(
            'a: "x\\0y"',
            'b: ""',
            'c: !!str ""',
            'd: "\\xff"',
            'e: !<tag:yaml.org,2002:str> 5',
            'f: !foo 3',
        ),
        '/',
    ),
    ('anchor_without_alias', _p('a: &x 1'), '/'),
    ('alias', _p('a: &x 1', 'b: *x'), '/'),
    ('no_value', _p('a:'), '/'),
    ('no_value_tagged', _p('a: !!str'), '/'),
    ('no_value_in_list', _p('a:', '  -'), '/'),
    ('no_key', _p('"": 1'), '/'),
    ('flow_map_key', _p('? {x: 1}', ': 2'), '/'),
    ('sequence_document', '[1, 2]\n', '/'),
    ('sequence_at_node_level', 'catenary_monitor: [1]\n', '/'),
    ('value_before_params', 'catenary_monitor:\n  other: 1\n  ros__parameters:\n    a: 1\n', '/'),
    ('value_after_params', _p('a: 1') + '  extra: 2\n', '/'),
    ('scalar_node', 'catenary_monitor: 5\n', '/'),
    ('scalar_params', 'catenary_monitor:\n  ros__parameters: 5\n', '/'),
    ('list_params', 'catenary_monitor:\n  ros__parameters:\n    - 1\n', '/'),
    ('dedented_params', 'catenary_monitor:\n  ros__parameters:\n  a: 1\n', '/'),
    ('null_section', 'foo:\n', '/'),
    ('params_twice', _p('a: 2') + '  ros__parameters:\n    b: 1\n', '/'),
    (
        'params_twice_in_ns',
        'ns:\n  catenary_monitor:\n    ros__parameters:\n      a: 1\n'
        '    ros__parameters:\n      b: 1\n',
        '/',
    ),
    (
        'stale_index_list',
        _p('a: 1', 'b: 2') + '---\ncatenary_monitor:\n  ros__parameters: [5]\n',
        '/',
    ),
    ('only_params_key', 'ros__parameters: {}\n', '/'),
    ('digit_node', _sections(('1abc', 'a')), '/'),
    ('star_in_name', _sections(('cat*', 'a')), '/'),
    ('wildcard_under_ns', 'ns:\n  /**:\n    ros__parameters:\n      a: 1\n', '/'),
    ('root_node', _sections(('/', 'a')), '/'),
    ('trailing_slash', _sections(('catenary_monitor/', 'a')), '/'),
    ('double_slash', _sections(('//catenary_monitor', 'a')), '/'),
    ('tilde_ns', _sections(('~/catenary_monitor', 'a')), '/'),
    ('digit_ns', _sections(('/ns/1x/catenary_monitor', 'a')), '/'),
    ('unicode_node', _sections(('caténary', 'a')), '/'),
    ('node_255', _sections(('a' * 255, 'a')), '/'),
    ('node_256', _sections(('a' * 256, 'a')), '/'),
    ('ns_token_244', _sections((LONG_NS + '/catenary_monitor', 'a')), '/'),
    ('ns_token_245', _sections((LONG_NS + 'b/catenary_monitor', 'a')), '/'),
    ('nul_node', _sections(('"\\0x"', 'a')), '/'),
    (
        'nul_section_without_params',
        '"\\0x": {}\ncatenary_monitor: {ros__parameters: {a: 1}}\n',
        '/',
    ),
    ('yaml_error', _p('a: ['), '/'),
    ('yaml_error_indent', _p('a: 1') + '   b: 2\n', '/'),
    ('document_end_then_content', _p('a: 1') + '...\nb: 2\n', '/'),
    ('utf16_bom', _p('a: 1').encode('utf-16'), '/'),
    ('utf8_bom', b'\xef\xbb\xbf' + _p('a: 1').encode(), '/'),
    ('utf16_no_bom', _p('a: 1').encode('utf-16-le'), '/'),
    ('invalid_utf8', H.encode() + b'    a: \xff\xfe\n', '/'),
    ('binary', bytes(range(256)), '/'),
    ('yaml_1_1', '%YAML 1.1\n---\n' + _p('a: 1'), '/'),
    ('floating_dock', DOCK_YAML.read_bytes(), '/'),
]

# libyaml 0.1.7 (pip wheels) and 0.2 (debs, PyYAML) disagree: refused here, see params_file.
# The bool is what rcl with libyaml 0.1.7 does (True: accepts).
DIVERGENT: list[tuple[str, str, bool]] = [
    ('yaml_1_2', '%YAML 1.2\n---\n' + _p('a: 1'), False),
    ('colon_in_flow_plain', _p('a: [x:y]'), False),
    ('question_in_flow_plain', _p('a: [x ?y]'), False),
    ('slash_escape', _p('a: "\\/"'), False),
    ('quote_escape', _p('a: "x\\\'y"'), True),
    ('tag_with_comma', _p('a: !e,x 1'), True),
    ('tag_before_comma', _p('a: [!!str, x]'), True),
]

Results = tuple[Optional[str], dict[str, dict[str, Any]]]  # libyaml version, per file

RCLPY_SCRIPT = r'''
import ctypes, json, math, sys
import rclpy
from rclpy.node import Node

def tagged(v: object) -> object:
    if isinstance(v, list):
        return ['list', [tagged(x) for x in v]]
    if isinstance(v, float):
        return ['float', 'nan' if math.isnan(v) else repr(v)]
    return [type(v).__name__, v]

def libyaml_version() -> "str | None":
    for line in open('/proc/self/maps'):
        path = line.split()[-1]
        if '/libyaml' in path and '.so' in path:
            lib = ctypes.CDLL(path)
            lib.yaml_get_version_string.restype = ctypes.c_char_p
            return lib.yaml_get_version_string().decode()
    return None

print(json.dumps({'libyaml': libyaml_version()}), flush=True)
for path, namespace in json.loads(sys.argv[1]):
    try:
        rclpy.init(args=['x', '--ros-args', '--params-file', path])
    except Exception as err:
        print(json.dumps({'file': path, 'error': ' '.join(str(err).split())[:300]}), flush=True)
        continue
    try:
        node = Node('catenary_monitor', namespace=namespace,
                    automatically_declare_parameters_from_overrides=False)
        params = [[k, tagged(p.value)] for k, p in node._parameter_overrides.items()]
        print(json.dumps({'file': path, 'params': params}), flush=True)
        node.destroy_node()
    except Exception as err:
        print(json.dumps({'file': path, 'node_error': str(err)[:300]}), flush=True)
    finally:
        rclpy.shutdown()
'''


def _run_rclpy(files: list[tuple[str, str]]) -> Results:
    """Run the real rcl + rclpy on each file in one child process: (libyaml version, results)."""
    env = dict(
        os.environ,
        ROS_DOMAIN_ID=str(random.randint(100, 200)),
        ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
    )
    proc = subprocess.run(
        [sys.executable, '-c', RCLPY_SCRIPT, json.dumps(files)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith('{')]
    assert lines and proc.returncode == 0, proc.stderr[-3000:]
    return lines[0]['libyaml'], {r.pop('file'): r for r in lines[1:]}


def _ours(path: str, namespace: str) -> dict[str, Any]:
    try:
        flat = load_params_file(path, node_namespace=namespace)
    except ConfigError as err:
        return {'error': str(err)}
    return {'params': [[k, _tagged(v)] for k, v in flat.items()]}


@pytest.fixture(scope='module')
def rclpy_results(tmp_path_factory: pytest.TempPathFactory) -> Results:
    pytest.importorskip('rclpy')
    directory = tmp_path_factory.mktemp('corpus')
    files = []
    for name, content, namespace in CORPUS + [(n, t, '/') for n, t, _ in DIVERGENT]:
        path = directory / f'{name}.yaml'
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
        files.append((str(path), namespace))
    return _run_rclpy(files)


def test_corpus_is_big_enough() -> None:
    assert len(CORPUS) >= 40 and len({name for name, _, _ in CORPUS}) == len(CORPUS)


# Files that give one of the node's parameters twice: rcl takes them (the later value of a
# type wins), the monitor refuses them (read_params_file, check_given_once).
GIVEN_TWICE = {
    'order_first_appearance': "'a' is given twice, at line 3 and line 9",
    'order_root_ns': "'a' is given twice, at line 4 and line 10",
    'dotted_and_nested': "'line_01.weight' is given twice, at line 3 and line 5",
    'nested_quirks': "'e.f' is given twice, at line 8 and line 10",
    'duplicates': "'a' is given twice, at line 3 and line 4",
}


@pytest.mark.parametrize('name, namespace', [(n, ns) for n, _, ns in CORPUS])
def test_corpus_agrees_with_rclpy(rclpy_results: Results, name: str, namespace: str) -> None:
    _, results = rclpy_results
    path = next(p for p in results if Path(p).stem == name)
    theirs, ours = results[path], _ours(path, namespace)
    if name in GIVEN_TWICE:
        assert 'params' in theirs, theirs  # rcl takes it; the monitor does not
        assert GIVEN_TWICE[name] in ours.get('error', ''), ours
        return
    assert ('params' in ours) == ('params' in theirs), (theirs, ours)
    assert ours.get('params') == theirs.get('params')


@pytest.mark.parametrize('name, accepted_by_017', [(n, a) for n, _, a in DIVERGENT])
def test_libyaml_divergences_are_refused(
    rclpy_results: Results, name: str, accepted_by_017: bool
) -> None:
    version, results = rclpy_results
    path = next(p for p in results if Path(p).stem == name)
    assert 'error' in _ours(path, '/')
    if version and version.startswith('0.1.'):  # this machine: what rcl itself does
        assert ('params' in results[path]) == accepted_by_017


def test_written_params_files_read_back_to_the_same_values(tmp_path: Path) -> None:
    """core.config.params_file_text (the demo's merged file, the tests' params files): every
    kind of value comes back with its type, read by rcl's rules."""
    from catenary_monitor.core.config.parameters import (
        config_hash,
        config_to_params,
        params_file_text,
    )

    flat = {
        'lines': ['a', 'b'],
        'x': 1300.0,
        'tiny': 1e-300,
        'huge': 1e200,
        'big': 5.17e6,
        'n': 3,
        'flag': True,
        'off': False,
        'topic': '/tide/depth',
        'odd': 'say "hi": yes',
        'nan': math.nan,
        'inf': -math.inf,
        'fs': [1.5, 2.0],
    }
    path = tmp_path / 'p.yaml'
    path.write_text(params_file_text(flat))
    back = load_params_file(path)
    assert set(back) == set(flat)
    for key, want in flat.items():
        got = back[key]
        assert type(got) is type(want), key
        assert got == want or (want != want and got != got), key
    dock = config_from_params(load_params_file(DOCK_YAML))
    path.write_text(params_file_text(config_to_params(dock)))
    assert config_hash(config_from_params(load_params_file(path))) == config_hash(dock)

"""ROS 2 params files read the way the live node reads them: rcl's parser, then rclpy's matching.

No rclpy here. The live node gets its parameters from ``rcl_yaml_param_parser`` (C, on libyaml
events) and rclpy's ``Node``; :func:`read_params_file` mirrors both, so that a file is accepted
here exactly when rcl accepts it, and gives the values and types of ``node._parameter_overrides``
-- with one departure: a file that gives one of the node's parameters twice within a section is
refused (:func:`check_given_once`), where rcl silently takes the later value.

**rcl (parse.c, rules of ROS 2 Jazzy, rcl 9.2).** One walk over the YAML events with rcl's state:

* Keys above ``ros__parameters`` (any key *starting* with it counts) are joined with ``/`` into a
  node name (no ``/`` is added after a trailing one, so ``/: {n: ...}`` is ``/n``); at
  ``ros__parameters`` the name is validated (node name: ASCII letters, digits, ``_``, not
  starting with a digit, at most 255; each ``/token`` of the namespace likewise, at most 245,
  ``//`` refused; the tokens ``*`` / ``**`` and the names ``/*`` / ``/**`` allowed) and becomes
  a node entry; a
  name seen before merges into its first entry. A value or sequence above ``ros__parameters``, a
  sequence as a key, an empty key, an empty plain value (``a:``) and any alias are errors.
* Under ``ros__parameters`` nested maps give dotted names: the key owning a map is *renamed* to
  ``key.child`` by the map's first key and later keys append new entries, and closing a map cuts
  the name at its last dot (so ``x: {a.b: {c: 1}, d: 2}`` gives ``x.a.b.c`` and ``x.a.d``, as
  rcl does). An empty map leaves its key NOT_SET (None) and, as in rcl, ends ``ros__parameters``.
* A scalar is a string if quoted or tagged ``!!str`` (other tags are ignored); else a bool if
  exactly one of ``Y y yes Yes YES true True TRUE on On ON`` / ``N n no No NO false False FALSE
  off Off OFF``; else an int if glibc ``strtol(s, &end, 0)`` takes all of it without ERANGE
  (``0x10`` 16, ``010`` 8); else a double for ``.nan .NaN .NAN .inf .Inf .INF`` (signed inf too)
  or if ``strtod`` takes all of it without ERANGE (``1e6``, ``08``, ``0x1p3``, ``inf``, ``nan``;
  ``1e400`` and inexact subnormals set ERANGE); else a string. C strings end at a NUL.
* Each parameter slot keeps one value per rcl type; a later scalar of another type does not erase
  the first, and rclpy reads the slot in the order bool, int, double, string, then the arrays in
  the same order (``a: 1`` then ``a: 2.0`` gives 1). A sequence restarts the array of its first
  element's type; other element types are an error; ``[]`` is NOT_SET; a nested sequence restarts
  the array and its end makes the next scalar a key (``[1, [2]]`` gives ``[2]``).
* Documents of one stream continue the same walk; an empty stream gives no entries.

**rclpy (Jazzy).** Entries are applied in file order of first appearance, later values winning,
when the entry name (with a leading ``/`` added if missing) fully matches the node's fully
qualified name after replacing ``/*`` by ``(/\\w+)`` (so ``/**`` matches any namespace and ``/*``
one token). No matching entry gives ``{}``.

**YAML syntax** is libyaml's, through PyYAML's binding (its pure-Python parser only where PyYAML
was built without libyaml). ROS 2's pip wheels link libyaml 0.1.7, Jazzy's Debian packages 0.2.5
and PyYAML 0.2.6, and 0.1.7 differs, measured: it refuses ``%YAML 1.2``, ``:`` or ``?`` inside a
plain scalar in a flow collection (``[a:b]``) and the escape ``\\/``; it accepts ``\\'`` in
double quotes and reads ``,[]`` right after a tag as part of it (``[!!str, x]`` is one scalar).
A file is accepted here only if both versions read it alike, so the node accepts it whichever
build runs it; all of these are refused.

**Numbers.** :func:`c_strtol` and :func:`c_strtod` re-implement glibc's ``strtol`` (base 0,
64-bit) and ``strtod`` (C locale, round to nearest even, ERANGE on overflow and on an inexact
result below the smallest normal double, tininess after rounding) in Python, checked against the
C functions in the tests. Python rather than ctypes: the loader stays pure and deterministic on
every platform (the host libc elsewhere is not the glibc the robot runs), and the rules are short.
"""

from __future__ import annotations

import math
import re
import stat
from dataclasses import dataclass, field
from decimal import Decimal
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

__all__ = [
    'ParamsFileError',
    'c_strtol',
    'c_strtod',
    'rcl_scalar',
    'check_section_name',
    'parse_params',
    'fully_qualified_name',
    'parameters_for_node',
    'read_params_file',
    'check_given_once',
    'section_applies',
]

PARAMS_KEY = 'ros__parameters'
_NODE_LEVEL, _PARAMS_LEVEL = 1, 2
_STR_TAG = 'tag:yaml.org,2002:str'
_TYPES = ('bool', 'int', 'double', 'string')
_TRUE = frozenset('Y y yes Yes YES true True TRUE on On ON'.split())
_FALSE = frozenset('N n no No NO false False FALSE off Off OFF'.split())
_YAML_FLOATS = {
    '.nan': math.nan,
    '.NaN': math.nan,
    '.NAN': math.nan,
    **{
        f'{s}.{i}': (-math.inf if s == '-' else math.inf)
        for s in ('', '+', '-')
        for i in ('inf', 'Inf', 'INF')
    },
}
_C_SPACE = ' \t\n\v\f\r'
_INT64_MAX = 2**63 - 1
_DBL_MIN = Fraction(1, 2**1022)
_NODE_NAME_MAX, _NAMESPACE_MAX = 255, 245
_NAME_CHARS = re.compile(r'[A-Za-z0-9_]*\Z')
_INFNAN = re.compile(r'infinity|inf|nan(?:\([A-Za-z0-9_]*\))?', re.IGNORECASE | re.ASCII)
_HEXFLOAT = re.compile(
    r'0[xX](?P<m>[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)' r'(?:[pP](?P<e>[+-]?[0-9]+))?'
)
_DECFLOAT = re.compile(r'(?P<m>[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE](?P<e>[+-]?[0-9]+))?')
_YAML_SPACE = ' \t\r\n#'
_ANCHOR_CHARS = frozenset('ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-')
_TAG_CHARS = _ANCHOR_CHARS | frozenset(";/?:@&=+$.!~*'()%")
_DIGITS = {8: '01234567', 10: '0123456789', 16: '0123456789abcdefABCDEF'}


class ParamsFileError(ValueError):
    """A params file rcl (or one of its libyaml builds) refuses; ``str(err)`` is one line."""

    def __init__(self, reason: str, line: int | None = None, syntax: bool = False) -> None:
        text = ' '.join(str(reason).split())
        self.syntax = syntax  # a YAML syntax error (else a rule of rcl's)
        super().__init__(text if line is None else f'{text} (line {line})')


# --- glibc strtol / strtod ---------------------------------------------------------------------


def _skip_space(text: str) -> int:
    i = 0
    while i < len(text) and text[i] in _C_SPACE:
        i += 1
    return i


def _sign(text: str, i: int) -> tuple[int, int]:
    """(index after an optional sign, -1 or 1)."""
    if text[i : i + 1] in ('+', '-'):
        return i + 1, -1 if text[i] == '-' else 1
    return i, 1


def _run(text: str, i: int, chars: str | frozenset[str]) -> int:
    while i < len(text) and text[i] in chars:
        i += 1
    return i


def c_strtol(text: str) -> tuple[int, int, bool]:
    """glibc ``strtol(text, &end, 0)`` on 64-bit Linux: ``(value, end index, ERANGE)``.

    Leading C whitespace and a sign are skipped; ``0x`` + a hex digit selects base 16, a leading
    ``0`` base 8, else base 10. No digits gives ``(0, 0, False)``; out of int64 saturates with
    ERANGE.
    """
    i, sign = _sign(text, _skip_space(text))
    base, start = 10, i
    if text[i : i + 1] == '0':
        base = 8
        if (
            text[i + 1 : i + 2] in ('x', 'X')
            and text[i + 2 : i + 3]
            and text[i + 2] in _DIGITS[16]
        ):
            base, start = 16, i + 2
    end = _run(text, start, _DIGITS[base])
    if end == start:
        return 0, 0, False
    digits = text[start:end].lstrip('0') or '0'
    magnitude = int(digits, base) if len(digits) <= 40 else 2**64
    if magnitude > _INT64_MAX + (sign < 0):
        return (-_INT64_MAX - 1 if sign < 0 else _INT64_MAX), end, True
    return sign * magnitude, end, False


def _round_to_double(exact: Fraction) -> tuple[float, bool]:
    """glibc's double for an exact magnitude > 0 and whether it sets ERANGE."""
    try:
        value = exact.numerator / exact.denominator  # correctly rounded, half to even
    except OverflowError:
        return math.inf, True
    if exact >= _DBL_MIN:
        return value, False
    return value, _tiny_after_rounding(exact) and Fraction(value) != exact


def _tiny_after_rounding(exact: Fraction) -> bool:
    """Whether ``exact`` rounded to 53 bits with an unbounded exponent is below DBL_MIN."""
    num, den = exact.numerator, exact.denominator
    exp = num.bit_length() - den.bit_length()
    if (num << max(0, -exp)) < (den << max(0, exp)):
        exp -= 1  # now 2**exp <= exact < 2**(exp + 1)
    if exp != -1023:
        return exp < -1022
    q, r = divmod(num << (52 - exp), den)
    return q + (2 * r > den or (2 * r == den and q % 2 == 1)) < 2**53


def _exponent(text: str | None) -> int:
    """Decimal exponent text as an int, clamped to +-10**9 (beyond any double)."""
    if not text:
        return 0
    digits = text.lstrip('+-').lstrip('0') or '0'
    value = int(digits) if len(digits) <= 9 else 10**9
    return -value if text.startswith('-') else value


def _finish(exact: Fraction | None, log2: float) -> tuple[float, bool]:
    """Magnitude and ERANGE from an exact value (None: zero) and a rough base-2 logarithm."""
    if exact is None:
        return 0.0, False
    if log2 > 1100:
        return math.inf, True
    if log2 < -1200:
        return 0.0, True
    return _round_to_double(exact)


def _hex_double(match: re.Match[str]) -> tuple[float, bool]:
    mantissa = match['m']
    whole, _, frac = mantissa.partition('.')
    digits = int(whole + frac or '0', 16)
    exp = _exponent(match['e']) - 4 * len(frac)
    if digits == 0:
        return _finish(None, 0.0)
    log2 = digits.bit_length() - 1 + exp
    return _finish(
        Fraction(digits) * Fraction(2) ** exp if abs(log2) < 1300 else Fraction(1), log2
    )


def _dec_double(match: re.Match[str]) -> tuple[float, bool]:
    whole, _, frac = match['m'].partition('.')
    digits = (whole + frac).lstrip('0')
    if not digits:
        return _finish(None, 0.0)
    exp10 = _exponent(match['e']) - len(frac)
    log10 = len(digits) - 1 + exp10
    if abs(log10) > 400:
        return _finish(Fraction(1), log10 * 3.33)
    return _finish(Fraction(Decimal(f'{digits}e{exp10}')), log10 * 3.33)


def c_strtod(text: str) -> tuple[float, int, bool]:
    """glibc ``strtod(text, &end)`` in the C locale: ``(value, end index, ERANGE)``.

    Skips C whitespace and a sign, then reads ``inf``/``infinity``/``nan``/``nan(chars)`` (any
    case), a hex float (``0x1.8p3``) or a decimal one (``1.5e3``, ``.5``, ``1.``). No number gives
    ``(0.0, 0, False)``.
    """
    i, sign = _sign(text, _skip_space(text))
    special = _INFNAN.match(text, i)
    if special:
        value = math.nan if special[0][0] in 'nN' else math.inf
        return math.copysign(value, sign), special.end(), False
    for pattern, convert in ((_HEXFLOAT, _hex_double), (_DECFLOAT, _dec_double)):
        match = pattern.match(text, i)
        if match:
            magnitude, erange = convert(match)
            return math.copysign(magnitude, sign), match.end(), erange
    return 0.0, 0, False


# --- scalar typing (parse.c get_value) ---------------------------------------------------------


def _c_string(text: str) -> str:
    """The text as C sees it: up to the first NUL."""
    return text.split('\0', 1)[0]


def _whole(parsed: tuple[Any, int, bool], text: str) -> bool:
    """Whether a strtol/strtod result took all of a non-empty ``text`` without ERANGE."""
    return bool(text) and parsed[1] == len(text) and not parsed[2]


def rcl_scalar(text: str, style: str | None = None, tag: str | None = None) -> tuple[str, Any]:
    """``(rcl type, value)`` of one scalar: ``bool``, ``int``, ``double`` or ``string``.

    ``style`` is PyYAML's (``'`` and ``"`` quoted; ``''``/None plain; ``|``/``>`` block), ``tag``
    the resolved tag (only ``!!str`` counts).
    """
    text = _c_string(text)
    if tag == _STR_TAG or style in ("'", '"'):
        return 'string', text
    if text in _TRUE or text in _FALSE:
        return 'bool', text in _TRUE
    as_int = c_strtol(text)
    if _whole(as_int, text):
        return 'int', as_int[0]
    if text in _YAML_FLOATS:
        return 'double', _YAML_FLOATS[text]
    as_double = c_strtod(text)
    if _whole(as_double, text):
        return 'double', as_double[0]
    return 'string', text


# --- node names (parse.c _validate_name, rmw validators) ---------------------------------------


def _check_node_name(name: str) -> None:
    if not name:
        raise ParamsFileError('node name must not be empty')
    if not _NAME_CHARS.match(name):
        raise ParamsFileError(
            "node name must not contain characters other than alphanumerics " "or '_'"
        )
    if name[0].isdigit():
        raise ParamsFileError('node name must not start with a number')
    if len(name) > _NODE_NAME_MAX:
        raise ParamsFileError(f"node name length should not exceed '{_NODE_NAME_MAX}'")


def _check_namespace_token(token: str) -> None:
    """One ``/token`` of a namespace, as rmw_validate_namespace sees it."""
    if not _NAME_CHARS.match(token[1:]):
        raise ParamsFileError(
            "namespace must not contain characters other than alphanumerics, " "'_', or '/'"
        )
    if token[1:2].isdigit():
        raise ParamsFileError('namespace must not have a token that starts with a number')
    if len(token) > _NAMESPACE_MAX:
        raise ParamsFileError(f"namespace should not exceed '{_NAMESPACE_MAX}'")


def _check_namespace(namespace: str) -> None:
    """``namespace`` ends with ``/``; its tokens ``/*`` and ``/**`` are allowed."""
    start = 0
    end = namespace.find('/', 1)
    while end >= 0:
        token = namespace[start:end]
        if token == '/':
            raise ParamsFileError(f'{namespace} contains repeated forward slash')
        if token not in ('/*', '/**'):
            _check_namespace_token(token)
        start, end = end, namespace.find('/', end + 1)


def check_section_name(name: str) -> None:
    """Raise ParamsFileError unless rcl accepts ``name`` (the keys above ros__parameters)."""
    if name in ('/*', '/**'):
        return
    slash = name.rfind('/')
    if slash >= 0:
        namespace = name[: slash + 1]
        _check_namespace(namespace if namespace.startswith('/') else '/' + namespace)
    node = name[slash + 1 :]
    if node not in ('*', '**'):
        _check_node_name(node)


# --- the event walk (parse.c parse_file_events) ------------------------------------------------


@dataclass
class _Slot:
    """One rcl_variant_t: at most one value per rcl type, scalars and arrays apart."""

    scalars: dict[str, Any] = field(default_factory=dict)
    arrays: dict[str, list[Any]] = field(default_factory=dict)

    def value(self) -> Any:
        """What rclpy makes of the slot (None: NOT_SET)."""
        for kind in _TYPES:
            if kind in self.scalars:
                return self.scalars[kind]
        for kind in _TYPES:
            if kind in self.arrays:
                return list(self.arrays[kind])
        return None


@dataclass
class _Node:
    """rcl_node_params_t: names in order (duplicates possible), value slots by index."""

    names: list[str] = field(default_factory=list)
    slots: dict[int, _Slot] = field(default_factory=dict)

    def find(self, name: str) -> int:
        """Index of the first parameter called ``name``, appended if there is none."""
        if name in self.names:
            return self.names.index(name)
        self.names.append(name)
        return len(self.names) - 1

    def slot(self, index: int) -> _Slot:
        return self.slots.setdefault(index, _Slot())

    def parameters(self) -> dict[str, Any]:
        return {name: self.slot(i).value() for i, name in enumerate(self.names)}


@dataclass
class _Namespace:
    """rcl's namespace tracker: a joined name and how many names went into it."""

    sep: str
    text: str | None = None
    count: int = 0

    def add(self, name: str) -> None:
        if self.count == 0 or self.text is None:
            self.text = name
        elif self.text.endswith(self.sep):
            self.text += name
        else:
            self.text += self.sep + name
        self.count += 1

    def remove(self) -> None:
        """Drop the last name: cut at the last separator (rem_name_from_ns)."""
        if self.count == 1:
            self.text = None
        elif self.count > 1 and self.text is not None and self.sep in self.text:
            self.text = self.text[: self.text.rfind(self.sep)]
        self.count = max(0, self.count - 1)

    def replace(self, text: str, count: int) -> None:
        self.text, self.count = text, count


class _Walk:
    """The state of rcl's parse_file_events, fed one PyYAML event at a time."""

    def __init__(self) -> None:
        self.is_key, self.is_seq, self.new_map = True, False, False
        self.seq_type: str | None = None
        self.level, self.depth = _NODE_LEVEL, 0
        self.node_ns, self.param_ns = _Namespace('/'), _Namespace('.')
        self.nodes: dict[str, _Node] = {}
        self.node: _Node | None = None
        self.section = ''
        self.index = 0
        self.line = 0
        self.key_line = 0  # line of the last parameter key not given its value yet (0: none)
        # (section, parameter, line of its key) each time a parameter key is given a value
        self.given: list[tuple[str, str, int]] = []

    def feed(self, event: Any) -> None:
        self.line = event.start_mark.line + 1
        handler = _HANDLERS.get(type(event).__name__)
        if handler is not None:
            handler(self, event)

    # scalars
    def scalar(self, event: Any) -> None:
        if self.is_key:
            self.key(event.value)
            self.is_key = False
            return
        if self.level < _PARAMS_LEVEL or self.node is None or not self.node.names:
            raise ParamsFileError(f'Cannot have a value before {PARAMS_KEY}', self.line)
        self.value(event)
        if not self.is_seq:
            self.is_key = True

    def key(self, raw: str) -> None:
        if not raw:
            raise ParamsFileError('No key', self.line)
        name = _c_string(raw)
        if self.level == _PARAMS_LEVEL:
            self.key_line = self.line
            self.parameter_key(name)
        elif not name.startswith(PARAMS_KEY):
            self.node_ns.add(name)
        else:
            self.enter_node()

    def enter_node(self) -> None:
        if self.node_ns.count == 0 or self.node_ns.text is None:
            raise ParamsFileError(f'There are no node names before {PARAMS_KEY}', self.line)
        name = self.node_ns.text
        check_section_name(name)
        self.node = self.nodes.setdefault(name, _Node())
        self.section = name
        self.node_ns.remove()
        self.level += 1

    def parameter_key(self, name: str) -> None:
        assert self.node is not None
        if self.new_map:
            if self.index >= len(self.node.names):
                raise ParamsFileError('Internal error creating param namespace', self.line)
            self.param_ns.replace(self.node.names[self.index], self.param_ns.count + 1)
            self.new_map = False
        prefix = self.param_ns.text
        if prefix is None:
            self.index = self.node.find(name)
        else:
            self.index = self.node.find(prefix)
            self.node.names[self.index] = f'{prefix}.{name}'

    def value(self, event: Any) -> None:
        assert self.node is not None
        if event.style not in ("'", '"') and not event.value:
            raise ParamsFileError('No value', self.line)
        kind, value = rcl_scalar(event.value, event.style, event.tag)
        slot = self.node.slot(self.index)
        if self.key_line and self.index < len(self.node.names):
            self.given.append((self.section, self.node.names[self.index], self.key_line))
        self.key_line = 0
        if not self.is_seq:
            slot.scalars[kind] = value
            return
        if self.seq_type is None:
            self.seq_type = kind
            slot.arrays[kind] = []
        elif self.seq_type != kind:
            raise ParamsFileError(
                f"Sequence should be of same type. Value type '{kind}' do not " 'belong', self.line
            )
        slot.arrays[kind].append(value)

    # collections
    def sequence_start(self, event: Any) -> None:
        if self.is_key:
            raise ParamsFileError('Sequences cannot be key', self.line)
        if self.level < _PARAMS_LEVEL:
            raise ParamsFileError('Sequences can only be values and not keys in params', self.line)
        self.is_seq, self.seq_type = True, None

    def sequence_end(self, event: Any) -> None:
        self.is_seq, self.is_key = False, True

    def mapping_start(self, event: Any) -> None:
        self.depth += 1
        self.new_map = not (
            self.level == _PARAMS_LEVEL and self.depth - (self.node_ns.count + 1) == 2
        )
        self.is_key = True

    def mapping_end(self, event: Any) -> None:
        if self.level == _PARAMS_LEVEL:
            if self.param_ns.count > 0:
                self.param_ns.remove()
            else:
                self.level -= 1
        elif self.depth == self.node_ns.count + 1:
            self.node_ns.remove()
        self.depth -= 1

    def alias(self, event: Any) -> None:
        raise ParamsFileError('Will not support aliasing', self.line)

    def entries(self) -> list[tuple[str, dict[str, Any]]]:
        return [(name, node.parameters()) for name, node in self.nodes.items()]


_HANDLERS: dict[str, Callable[[_Walk, Any], None]] = {
    'ScalarEvent': _Walk.scalar,
    'SequenceStartEvent': _Walk.sequence_start,
    'SequenceEndEvent': _Walk.sequence_end,
    'MappingStartEvent': _Walk.mapping_start,
    'MappingEndEvent': _Walk.mapping_end,
    'AliasEvent': _Walk.alias,
}


# --- YAML events and the libyaml 0.1.7 / 0.2 differences ---------------------------------------


def _decode(data: bytes) -> str:
    """The text libyaml reads (its BOM detection: UTF-16 LE/BE with BOM, else UTF-8)."""
    for bom, codec in (
        (b'\xff\xfe', 'utf-16-le'),
        (b'\xfe\xff', 'utf-16-be'),
        (b'\xef\xbb\xbf', 'utf-8'),
    ):
        if data.startswith(bom):
            return data[len(bom) :].decode(codec, 'replace')
    return data.decode('utf-8', 'replace')


def _tag_end(text: str, start: int) -> int:
    """Index after the tag among the node properties (``&anchor``, ``!tag``) at ``start``."""
    i = start
    for _ in range(2):
        while i < len(text) and text[i] in _YAML_SPACE:
            i = text.find('\n', i) if text[i] == '#' else i + 1
            i = len(text) if i < 0 else i
        if text.startswith('&', i):
            i = _run(text, i + 1, _ANCHOR_CHARS)
        elif text.startswith('!<', i):
            return -1  # verbatim: the same in both versions
        elif text.startswith('!', i):
            return _run(text, i + 1, _TAG_CHARS)
    return -1


def _has_slash_escape(source: str) -> bool:
    """Whether a double-quoted scalar's source holds the escape ``\\/``."""
    i = source.find('\\')
    while 0 <= i < len(source) - 1:
        if source[i + 1] == '/':
            return True
        i = source.find('\\', i + 2)
    return False


class _LibyamlCompat:
    """Refuses what libyaml 0.1.7 and 0.2 read differently (see the module docstring).

    0.1.7 also refuses ``[?]`` (a flow pair with neither key nor value before ``]``), which rcl
    refuses anyway for its empty key.
    """

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.text: str | None = None
        self.flow = 0

    def check(self, event: Any) -> None:
        name = type(event).__name__
        line = event.start_mark.line + 1
        if name == 'DocumentStartEvent' and getattr(event, 'version', None) not in (None, (1, 1)):
            raise ParamsFileError('%YAML 1.2 is refused by libyaml 0.1.7 (ROS 2 pip wheels)', line)
        if getattr(event, 'tag', None) is not None:
            self.tag(event, line)
        if name in ('SequenceStartEvent', 'MappingStartEvent'):
            self.flow += 1 if self.flow or event.flow_style else 0
        elif name in ('SequenceEndEvent', 'MappingEndEvent'):
            self.flow = max(0, self.flow - 1)
        elif name == 'ScalarEvent':
            self.scalar(event, line)

    def tag(self, event: Any, line: int) -> None:
        end = _tag_end(self.decoded(), event.start_mark.index)
        if end >= 0 and self.decoded()[end : end + 1] in (',', '[', ']'):
            raise ParamsFileError(
                "a tag directly followed by ',', '[' or ']' is read differently "
                'by libyaml 0.1.7 (ROS 2 pip wheels) and 0.2',
                line,
            )

    def decoded(self) -> str:
        if self.text is None:
            self.text = _decode(self.data)
        return self.text

    def scalar(self, event: Any, line: int) -> None:
        if self.flow and event.style in (None, '') and (':' in event.value or '?' in event.value):
            raise ParamsFileError(
                "':' or '?' inside a plain scalar in a flow collection is "
                'refused by libyaml 0.1.7 (ROS 2 pip wheels)',
                line,
            )
        if event.style == '"':
            source = self.decoded()[event.start_mark.index : event.end_mark.index]
            if _has_slash_escape(source):
                raise ParamsFileError(
                    "the escape '\\/' is refused by libyaml 0.1.7 (ROS 2 pip " 'wheels)', line
                )


def _events(data: bytes) -> Iterator[Any]:
    """PyYAML's events for ``data`` (libyaml when available); YAMLError on a syntax error."""
    import yaml  # local: only params-file readers need it

    loader = getattr(yaml, 'CBaseLoader', yaml.BaseLoader)
    return yaml.parse(data, Loader=loader)


def parse_params(data: bytes) -> list[tuple[str, dict[str, Any]]]:
    """rcl's node entries of a params file: ``[(section name, {parameter: value})]`` in order.

    Raises ParamsFileError (one line) for any file rcl refuses (``syntax`` set for YAML errors).
    """
    return _walk(data).entries()


def _walk(data: bytes) -> _Walk:
    """The event walk over a whole file (ParamsFileError as :func:`parse_params`)."""
    import yaml

    walk, compat = _Walk(), _LibyamlCompat(data)
    try:
        for event in _events(data):
            compat.check(event)
            walk.feed(event)
    except yaml.YAMLError as err:
        raise ParamsFileError(f'YAML syntax: {err}', syntax=True) from None
    return walk


def check_given_once(given: Iterable[tuple[str, str, int]], sections: Iterable[str]) -> None:
    """ParamsFileError naming the first parameter that one of ``sections`` (those applying to the
    node) gives a value twice, with the lines of both: rcl takes the later value silently (per
    value type), which turned a copy-paste slip into a line monitored with an MBL of 1 N. A
    section repeated under the same name is one section (rcl merges them); a parameter set in
    two different sections (``/**`` and ``catenary_monitor``) is rclpy's override, allowed."""
    applying = set(sections)
    first: dict[tuple[str, str], int] = {}
    for section, name, line in given:
        if section not in applying:
            continue
        if (section, name) in first:
            raise ParamsFileError(
                f'parameter {name!r} is given twice, at line {first[section, name]} and line '
                f'{line} (give each parameter once)'
            )
        first[section, name] = line


# --- rclpy: which entries a node gets ----------------------------------------------------------


def _section_pattern(name: str) -> re.Pattern[str]:
    """rclpy's regex for a section name: ``/`` prepended, ``/*`` replaced by ``(/\\w+)``."""
    full = name if name.startswith('/') else '/' + name
    return re.compile(full.replace('/*', r'(/\w+)'), re.ASCII)


def fully_qualified_name(node_name: str, node_namespace: str = '/') -> str:
    """``/ns/name`` as rcl forms it (an empty or relative namespace is made absolute)."""
    namespace = node_namespace if node_namespace.startswith('/') else '/' + node_namespace
    return namespace.rstrip('/') + '/' + node_name


def parameters_for_node(
    entries: Iterable[tuple[str, dict[str, Any]]], node_name: str, node_namespace: str = '/'
) -> dict[str, Any]:
    """The parameters rclpy hands node ``node_namespace/node_name``: matching entries merged."""
    merged: dict[str, Any] = {}
    for name, parameters in entries:
        if section_applies(name, node_name, node_namespace):
            merged.update(parameters)
    return merged


def section_applies(section: str, node_name: str, node_namespace: str = '/') -> bool:
    """Whether rclpy hands section ``section``'s parameters to ``node_namespace/node_name``."""
    fqn = fully_qualified_name(node_name, node_namespace)
    return _section_pattern(section).fullmatch(fqn) is not None


#: Larger than any params file (the 12-line dock's is 4 KiB): refused rather than parsed.
MAX_PARAMS_BYTES = 16 * 1024 * 1024


def _read_bytes(path: Path) -> bytes:
    """The file's bytes; ParamsFileError (one line) for an unreadable path, a pipe or device
    (it could not be read twice, once here and once by rcl) or an implausibly large file."""
    where = repr(str(path))
    try:
        info = path.stat()
        if not stat.S_ISDIR(info.st_mode) and not stat.S_ISREG(info.st_mode):
            raise ParamsFileError(f'cannot read {where}: not a regular file (a pipe or device)')
        if info.st_size > MAX_PARAMS_BYTES:
            raise ParamsFileError(
                f'cannot read {where}: {info.st_size} bytes, more than a params file holds '
                f'({MAX_PARAMS_BYTES} at most)'
            )
        return path.read_bytes()
    except OSError as err:
        raise ParamsFileError(f'cannot read {where}: {err.strerror or err}') from None


def read_params_file(
    path: str | Path, node_name: str, node_namespace: str = '/'
) -> dict[str, Any]:
    """Flat ``{dotted name: value}`` of a params file for one node, exactly as rclpy has them.

    Values are bool, int, float, str, lists of one of those, or None (NOT_SET). Raises
    ParamsFileError (one line) for an unreadable file, one rcl refuses, or one that gives a
    parameter of the node twice (:func:`check_given_once`; rcl would take the later value).
    """
    data = _read_bytes(Path(path))
    try:
        walk = _walk(data)
        entries = walk.entries()
        mine = [name for name, _ in entries if section_applies(name, node_name, node_namespace)]
        check_given_once(walk.given, mine)
    except ParamsFileError as err:
        prefix = 'cannot read ' if err.syntax else ''
        raise ParamsFileError(f'{prefix}{str(path)!r}: {err}', syntax=err.syntax) from None
    return parameters_for_node(entries, node_name, node_namespace)

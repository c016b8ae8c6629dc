"""The numpy CSV formatter (catenary_monitor.io.csv_columns): every field parses back, with the
stated precision, and the rows are what the csv module reads."""

import csv
import io
import math

import numpy as np
import pytest

from catenary_monitor.io.csv_columns import FloatColumn, IntColumn, LabelColumn, write_rows

EDGES = [
    0.0,
    -0.0,
    0.0004,
    -0.0004,
    0.0005,
    -0.0005,
    0.0015,
    9999.9995,
    -9999.9995,
    0.9999999,
    1e-300,
    -1e-300,
    123456789012.3449,
    999999999999.999,
    1e12,
    -1e12,
    1e15,
    1.5e300,
    -2.5e-7,
    math.nan,
    math.inf,
    -math.inf,
    372000.0,
    20.85,
    -104.911612,
    5e11 + 0.25,
]


def _read(data: bytes):
    return list(csv.reader(io.StringIO(data.decode('ascii'))))


@pytest.mark.parametrize('decimals', [0, 3, 6, 9])
def test_float_columns_parse_back_within_half_a_unit(decimals):
    rng = np.random.default_rng(decimals)
    scales = 10.0 ** rng.integers(-4, 13, 20000)
    values = np.concatenate((rng.normal(0, 1, 20000) * scales, EDGES))
    other = rng.normal(0, 50, len(values))
    buf = io.BytesIO()
    write_rows(
        buf,
        [FloatColumn('x', values, decimals), FloatColumn('y', other, 3)],
        len(values),
        block=4096,
    )
    rows = _read(buf.getvalue())
    assert rows[0] == ['x', 'y'] and len(rows) == len(values) + 1
    got = np.array([float(r[0]) for r in rows[1:]])
    y = np.array([float(r[1]) for r in rows[1:]])
    limit = 10.0 ** (15 - decimals)
    fixed = np.isfinite(values) & (np.abs(values) < limit)
    # Fixed-point values: within half a unit of the last decimal (plus the product's rounding).
    err = np.abs(got[fixed] - values[fixed])
    assert np.all(err <= 0.5 * 10.0**-decimals * (1 + 1e-9) + np.abs(values[fixed]) * 4e-16)
    # The others are exact (repr), NaN and infinities included.
    np.testing.assert_array_equal(got[~fixed], values[~fixed])
    assert np.all(np.abs(y - other) <= 0.5e-3 * (1 + 1e-9) + np.abs(other) * 4e-16)
    text = [r[0] for r in rows[1:]]
    assert not any(t.startswith('-') and float(t) == 0 for t in text)  # no '-0.000'
    assert all(t == t.strip() and t for t in text)


def test_integer_time_labels_and_layout():
    t = np.array(
        [0, 1, 999_999_999, 1_000_000_000, 1_763_900_000_123_456_789, 9_223_372_036_854_775_807]
    )
    lines = ['a', 'line_11', 'x' * 9]
    levels = ['OK', 'WARN', 'ERROR', 'STALE']
    idx = np.arange(len(t))
    buf = io.BytesIO()
    n = write_rows(
        buf,
        [
            IntColumn('time', t, 9),
            LabelColumn('line', idx % 3, lines),
            FloatColumn('v', -idx * 1.5, 3),
            LabelColumn('level', idx % 4, levels),
        ],
        len(t),
    )
    data = buf.getvalue()
    assert n == len(data) and data.endswith(b'\n') and b'\0' not in data
    rows = _read(data)
    assert rows[0] == ['time', 'line', 'v', 'level']
    assert [r[0] for r in rows[1:]] == [
        '0.000000000',
        '0.000000001',
        '0.999999999',
        '1.000000000',
        '1763900000.123456789',
        '9223372036.854775807',
    ]
    assert [r[1] for r in rows[1:]] == [lines[i % 3] for i in idx]
    assert [r[2] for r in rows[1:]] == ['0.000', '-1.500', '-3.000', '-4.500', '-6.000', '-7.500']
    assert [r[3] for r in rows[1:]] == [levels[i % 4] for i in idx]


def test_column_rules():
    with pytest.raises(ValueError):
        FloatColumn('x', np.zeros(2), 2)
    with pytest.raises(ValueError):
        IntColumn('t', np.array([-1]), 0)
    with pytest.raises(ValueError):
        LabelColumn('l', np.zeros(1, int), ['a,b'])
    buf = io.BytesIO()
    assert write_rows(buf, [FloatColumn('x', np.zeros(0), 3)], 0) == 2
    assert buf.getvalue() == b'x\n'

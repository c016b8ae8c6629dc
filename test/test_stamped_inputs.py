"""Samples taken at their header stamps (core/rules/readings.py): the core against its twin,
stamps that lag arrival and come in bunches, stamps refused (ahead of the clock, backwards),
and the readings of each message type against their definitions.

The oracle of the twin is the core stepped event by event (as test_batch.py); the oracle of a
reading is the message type's own definition, built with the real ROS message classes.
"""

import math

import numpy as np
import pytest
from replay_data import T0_NS, dock_config, generate
from test_batch import assert_same_float, assert_same_state, assert_statuses_agree, ticks_for

from catenary_monitor.core.config.parameters import (
    ConfigError,
    LineConfig,
    MonitorConfig,
    config_from_params,
)
from catenary_monitor.core.rules import readings, sensor_state
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS, VALUE_FIELDS
from catenary_monitor.core.monitor.events import Depth, Tension, Tick
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.twin.window import KIND_TENSION, Window
from catenary_monitor.core.twin.engine import advance
from catenary_monitor.core.physics.result import Status
from catenary_monitor.core.physics.solve import solve

LAG_S = 2.5  # the gateway delivers each sample this long after the sensor took it, or more
BUNCH_S = 1.0  # ... in bunches, once a second


def delivered(sample_ns, k, lag=LAG_S, bunch=BUNCH_S):
    """Arrival times (ns) of samples taken at ``sample_ns``: held ``lag`` and delivered in
    bunches every ``bunch`` s, a few ns apart (input ``k`` < 16 offset so no two inputs share
    a stamp: the twin sees events of one stamp at once, test_batch.compare)."""
    due = sample_ns + int(lag * 1e9)
    arrival = (due // int(bunch * 1e9) + 1) * int(bunch * 1e9)
    return arrival + np.arange(len(sample_ns), dtype=np.int64) * 16 + k  # distinct: k < 16


def stamped_scene(seed=3, bad=True, seconds=90.0):
    """A storm's tensions and depth as (arrival, value, header stamp) columns, lagging and
    bunched; with ``bad`` two tension samples stamped 10 s ahead and one going backwards, and
    one depth sample ahead."""
    config = dock_config(3, tension_timeout=6.0, depth_timeout=8.0)
    tensions, depth = generate(config, seconds=seconds, seed=seed)
    cols = {}
    for k, (name, (t, v)) in enumerate(tensions.items()):
        stamp = t.copy()
        arrival = delivered(stamp, k)
        n = len(stamp)
        if bad and k == 1:
            stamp[n // 9] += 10_000_000_000  # 10 s ahead
            stamp[4 * n // 9] += 10_000_000_000
            stamp[6 * n // 9] = stamp[6 * n // 9 - 2] - 1  # backwards
        cols[name] = (arrival, v, stamp)
    td, dv = depth
    dstamp = td.copy()
    if bad:
        dstamp[30] += 5_000_000_000
    return config, cols, (delivered(td, 5, lag=1.0), dv, dstamp)


def events(config, cols, depth, ticks):
    out = [(int(a), 0, 0, Depth(int(a), float(v), int(s))) for a, v, s in zip(*depth)]
    for k, line in enumerate(config.lines):
        a, v, s = cols[line.name]
        out += [(int(x), 1, k, Tension(int(x), k, float(y), int(z))) for x, y, z in zip(a, v, s)]
    out += [(int(t), 2, 0, Tick(int(t))) for t in ticks]
    out.sort(key=lambda e: e[:3])
    return [e[3] for e in out]


def window(config, cols, depth, ticks, lo=None, hi=None):
    def cut(t):
        keep = np.ones(len(t), bool)
        if lo is not None:
            keep &= t >= lo
        if hi is not None:
            keep &= t < hi
        return keep

    tensions, stamps = [], []
    for line in config.lines:
        a, v, s = cols[line.name]
        m = cut(a)
        tensions.append((a[m], v[m]))
        stamps.append(s[m])
    a, v, s = depth
    m = cut(a)
    return Window(tensions, (a[m], v[m]), ticks[cut(ticks)], stamps, s[m])


def plain(cols, depth):
    return {n: (a, v) for n, (a, v, _) in cols.items()}, depth[:2]


@pytest.mark.parametrize('cuts', [(), (T0_NS + 31_000_000_000, T0_NS + 62_500_000_000)])
def test_the_twin_takes_stamped_samples_as_the_core_does(cuts):
    config, cols, depth = stamped_scene()
    ticks = ticks_for(*plain(cols, depth))
    core = MonitorCore(config, T0_NS)
    steps = [core.step(ev) for ev in events(config, cols, depth, ticks)]
    twin = MonitorCore(config, T0_NS)
    bounds = [None, *cuts, None]
    results = [
        advance(twin, window(config, cols, depth, ticks, lo, hi), snapshots=True)
        for lo, hi in zip(bounds[:-1], bounds[1:])
    ]
    for k, line in enumerate(config.lines):
        want = [(s.stamp_ns, s.kind, o.values) for s in steps for o in s.outputs if o.line == k]
        t_ns = np.concatenate([r.lines[k].t_ns for r in results])
        assert t_ns.tolist() == [w[0] for w in want], line.name
        kinds = np.concatenate([r.lines[k].kind for r in results])
        assert [('tension' if x == KIND_TENSION else 'depth') for x in kinds] == [
            w[1] for w in want
        ]
        data = np.array([w[2] for w in want]).reshape(-1, len(OUTPUT_FIELDS))
        for key in VALUE_FIELDS:
            got = np.concatenate([r.lines[k].values[key] for r in results])
            assert_same_float(got, data[:, OUTPUT_FIELDS.index(key)], f'{line.name} {key}')
        level = np.concatenate([r.lines[k].level for r in results])
        assert level.tolist() == data[:, 12].astype(int).tolist(), line.name
    want_tr = sorted(
        [c for s in steps for c in s.transitions], key=lambda c: (c.transition.time, c.component)
    )
    got_tr = sorted(
        [c for r in results for c in r.changes()], key=lambda c: (c.transition.time, c.component)
    )
    assert got_tr == want_tr
    want_sn = [s.snapshot for s in steps if s.snapshot is not None]
    got_sn = [sn for r in results for sn in r.snapshots]
    assert [s.stamp_ns for s in got_sn] == [s.stamp_ns for s in want_sn]
    for g, w in zip(got_sn, want_sn):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    assert_same_state(twin, core)
    # The refused samples made the line's bad_stamp WARN, and the depth's.
    words = {
        (st.name, dict(st.values).get('sensor_state'))
        for s in want_sn
        for st in s.statuses
        if st.name in ('catenary_monitor: line_02', 'catenary_monitor: tide')
    }
    assert ('catenary_monitor: line_02', 'bad_stamp') in words
    assert ('catenary_monitor: tide', 'bad_stamp') in words


def test_a_sample_is_taken_at_its_header_stamp():
    """The readings' stamps, not their arrivals: the age of a line's newest reading, its
    sensor memory, the tide trend's bins; no bad_stamp without a bad stamp."""
    config, cols, depth = stamped_scene(bad=False)
    ticks = ticks_for(*plain(cols, depth))
    core = MonitorCore(config, T0_NS)
    newest = {}
    for ev in events(config, cols, depth, ticks):
        step = core.step(ev)
        if isinstance(ev, Tension):
            newest[ev.line] = ev
        if isinstance(ev, Tick):
            for k, ten in newest.items():
                status = step.snapshot.statuses[k]
                values = dict(status.values)
                assert float(values['measured_tension']) == ten.value
                age = float(values['tension_age'])
                assert age == pytest.approx((ev.stamp_ns - ten.sample_ns) * 1e-9, abs=1e-6)
                assert age >= LAG_S  # the lag is seen, not hidden
                assert values['sensor_state'] != 'bad_stamp'
    assert core.state.depth_sample_ns == int(depth[2][-1])
    assert core.state.lines[0].sample_ns == int(cols['line_01'][2][-1])


def test_stamps_refused_ahead_and_backwards_are_no_reading():
    config = dock_config(1, tension_timeout=10.0, depth_timeout=10.0)
    core = MonitorCore(config, T0_NS)
    s = 1_000_000_000
    core.step(Depth(T0_NS + s, 20.85, T0_NS))
    core.step(Tension(T0_NS + 2 * s, 0, 400e3, T0_NS + s))
    before = core.state.lines[0].tension
    step = core.step(Tension(T0_NS + 3 * s, 0, 900e3, T0_NS + 5 * s))  # 2 s ahead
    assert step.outputs == () and core.state.lines[0].tension == before
    step = core.step(Tension(T0_NS + 4 * s, 0, 900e3, T0_NS))  # backwards
    assert step.outputs == () and core.state.lines[0].tension == before
    assert core.state.lines[0].stamp_refused == pytest.approx((T0_NS + 4 * s) * 1e-9)
    step = core.step(Tension(T0_NS + 5 * s, 0, 410e3, T0_NS + s))  # equal stamps: accepted
    assert step.outputs and core.state.lines[0].tension == 410e3
    step = core.step(Tick(T0_NS + 6 * s))
    line = dict(step.snapshot.statuses[0].values)
    assert line['sensor_state'] == 'bad_stamp'
    assert 'header stamps' in step.snapshot.statuses[0].message
    assert step.snapshot.statuses[0].level.name == 'WARN'
    codes = readings.stamp_faults(
        np.array([10, 20, 30, 40, 50]), np.array([5, 25 + 10**9 * 3, 15, 4, 30]), -1, 1.0
    )
    assert codes.tolist() == [0, readings.FAULT_AHEAD, 0, readings.FAULT_BACKWARDS, 0]


def test_message_types_give_the_readings_their_definitions_say():
    from geometry_msgs.msg import WrenchStamped
    from sensor_msgs.msg import FluidPressure, Range

    w = WrenchStamped()
    w.wrench.force.x, w.wrench.force.y, w.wrench.force.z = 3.0, -4.0, 12.0
    fields = {'x': w.wrench.force.x, 'y': w.wrench.force.y, 'z': w.wrench.force.z}
    for axis, want in (('x', 3e3), ('y', -4e3), ('z', 12e3), ('norm', 13e3)):
        line = LineConfig(
            'a', 1300.0, 120.0, 4.8e6, tension_type=readings.WRENCH, tension_axis=axis,
            tension_scale=1000.0,
        )  # fmt: skip
        assert readings.tension_si(line, fields) == pytest.approx(want, rel=1e-15)
    line = LineConfig('a', 1300.0, 120.0, 4.8e6)
    kw = dict(lines=(line,), water_density=1025.0, atmospheric_pressure=101325.0)
    p = FluidPressure(fluid_pressure=101325.0 + 1025.0 * 9.80665 * 19.85)
    cfg = MonitorConfig(depth_type=readings.FLUID_PRESSURE, gauge_height=1.0, **kw)
    assert readings.depth_si(cfg, {'fluid_pressure': p.fluid_pressure}) == pytest.approx(20.85)
    r = Range(range=4.15, min_range=0.3, max_range=30.0)
    cfg = MonitorConfig(depth_type=readings.RANGE, gauge_height=25.0, depth_offset=0.5, **kw)
    got = readings.depth_si(cfg, {'range': r.range, 'min_range': 0.3, 'max_range': 30.0})
    assert got == pytest.approx(25.0 - r.range + 0.5)  # the message's float32 range
    for bad in (math.inf, -math.inf, 0.1, 31.0, math.nan):
        assert math.isnan(
            readings.depth_si(cfg, {'range': bad, 'min_range': 0.3, 'max_range': 30.0})
        )
    cfg = MonitorConfig(depth_offset=-0.25, **kw)
    assert readings.depth_si(cfg, {'value': 21.1}) == pytest.approx(20.85)


def test_input_parameters_are_checked():
    base = {'lines': ['a'], 'a.weight': 1300.0, 'a.anchor_distance': 120.0, 'a.mbl': 4.8e6}
    for key, value, word in (
        ('a.tension_type', 'std_msgs/msg/Float32', 'WrenchStamped'),
        ('a.tension_axis', 'w', 'norm'),
        ('a.tension_scale', 0.0, 'not be 0'),
        ('depth_type', 'sensor_msgs/msg/Imu', 'FluidPressure'),
        ('water_density', 10.0, 'out of range'),
    ):
        with pytest.raises(ConfigError, match=word) as err:
            config_from_params({**base, key: value})
        assert key in str(err.value)


def wrong_units_scene(scale):
    """The paper's dock line read by a load cell in kN (1623.5 kN, 372 kN, 0.2 kN), scaled
    by ``scale``: the core's status and message per reading."""
    line = LineConfig('line_11', 1300.0, 121.06, 5.17e6, tension_scale=scale)
    core = MonitorCore(MonitorConfig(lines=(line,)), T0_NS)
    core.step(Depth(T0_NS + 1, 20.85))
    out = []
    for k, kn in enumerate((1623.5, 372.0, 0.2)):
        step = core.step(Tension(T0_NS + 2 + k, 0, readings.tension_si(line, {'value': kn})))
        out.append((int(step.outputs[0].values[11]), core.state.lines[0].state.message, step))
    return out


def test_a_load_cell_in_kn_without_its_scale_says_wrong_units_and_names_the_parameter():
    got = wrong_units_scene(1.0)
    for status, message, _ in got:
        assert status == Status.WRONG_UNITS
        assert 'wrong units?' in message and 'kN' in message
        assert 'line_11.tension_scale: 1000' in message
    transitions = [c for _, _, s in got for c in s.transitions]
    assert len(transitions) == 1 and 'wrong units?' in transitions[0].transition.message
    # With the scale, the same readings solve as solve() says (the last one parted/slack).
    got = wrong_units_scene(1000.0)
    r = solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=121.06, mbl=5.17e6)
    assert got[0][0] == 0 and got[0][2].outputs[0].values[5] == pytest.approx(r.uplift_force)
    assert got[1][0] == 0
    assert got[2][0] == Status.WRONG_UNITS  # 200 N: a parted chain, or units
    # 10 x MBL and beyond (a cell in N given a kN scale): the parameter named too.
    line = LineConfig('line_11', 1300.0, 121.06, 5.17e6, tension_scale=1000.0)
    core = MonitorCore(MonitorConfig(lines=(line,)), T0_NS)
    core.step(Depth(T0_NS + 1, 20.85))
    core.step(Tension(T0_NS + 2, 0, 1000.0 * 372e3))
    message = core.state.lines[0].state.message
    assert 'wrong units? check line_11.tension_scale (it is 1000' in message


def test_a_slack_chain_is_not_called_wrong_units():
    """A tension between w*h/100 and w*h whose 1000-fold exceeds the MBL stays slack (T <= w*h)."""
    line = LineConfig('a', 1300.0, 121.06, 5.17e6)
    core = MonitorCore(MonitorConfig(lines=(line,)), T0_NS)
    core.step(Depth(T0_NS + 1, 20.85))
    step = core.step(Tension(T0_NS + 2, 0, 20e3))
    assert int(step.outputs[0].values[11]) == Status.TENSION
    assert sensor_state.LINE_STATES[sensor_state.BAD_STAMP] == 'bad_stamp'


def test_node_doc_input_table_is_generated_and_the_reader_speaks_the_readings_fields():
    from pathlib import Path

    from catenary_monitor.core.config.parameters import parameters_markdown
    from catenary_monitor.io.sensor_cdr import STAMPED_TYPES

    text = (Path(__file__).resolve().parent.parent / 'docs' / 'node.md').read_text()
    begin, end = '<!-- input-parameters:begin -->\n', '<!-- input-parameters:end -->'
    assert text.split(begin, 1)[1].split(end, 1)[0] == parameters_markdown('inputs')
    for name, fields in STAMPED_TYPES.items():
        assert name in readings.STAMPED
        want = readings.TENSION_FIELDS.get(name) or readings.DEPTH_FIELDS[name]
        assert fields == want


@pytest.mark.parametrize('frame', ['', 'a', 'abc', 'load_pin_7', 'x' * 13])
def test_the_log_reader_decodes_the_stamped_types_as_rclpy_encodes_them(frame):
    from geometry_msgs.msg import WrenchStamped
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import FluidPressure, Range

    from catenary_monitor.io.sensor_cdr import decode

    w = WrenchStamped()
    w.header.frame_id, w.header.stamp.sec, w.header.stamp.nanosec = frame, 1_763_900_000, 7
    w.wrench.force.x, w.wrench.force.y, w.wrench.force.z = 1.5, -2.25, 370.125
    p = FluidPressure(fluid_pressure=301234.5, variance=4.0)
    p.header.frame_id, p.header.stamp.sec, p.header.stamp.nanosec = frame, 12, 999_999_999
    r = Range(radiation_type=1, field_of_view=0.1, min_range=0.3, max_range=30.0, range=4.25)
    r.header.frame_id, r.header.stamp.sec = frame, 5
    got = decode('geometry_msgs/msg/WrenchStamped', [serialize_message(w), b'\x00\x01'])
    assert got.ok.tolist() == [True, False]
    assert got.stamps.tolist() == [1_763_900_000 * 10**9 + 7]
    assert [got.fields[k][0] for k in 'xyz'] == [1.5, -2.25, 370.125]
    got = decode('sensor_msgs/msg/FluidPressure', [serialize_message(p)])
    assert got.stamps.tolist() == [12 * 10**9 + 999_999_999]
    assert got.fields['fluid_pressure'].tolist() == [301234.5]
    got = decode('sensor_msgs/msg/Range', [serialize_message(r)])
    assert got.stamps.tolist() == [5 * 10**9]
    want = [np.float32(4.25), np.float32(0.3), np.float32(30.0)]
    assert [got.fields[k][0] for k in ('range', 'min_range', 'max_range')] == want


def test_replay_of_a_rosbag2_recording_of_stamped_sensors_equals_the_core(tmp_path):
    """A bag written by rosbags' rosbag2 writer (MCAP storage), as ``ros2 bag record`` of the
    drivers' topics would be: WrenchStamped tensions in kN and a FluidPressure depth, received
    late and in bunches. Replay reads their types and header stamps and decides as the core
    does event by event on the same arrivals, stamps and readings."""
    from geometry_msgs.msg import WrenchStamped
    from rclpy.serialization import serialize_message
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as BagWriter
    from rosbags.typesys import Stores, get_typestore
    from sensor_msgs.msg import FluidPressure

    from catenary_monitor.replay.driver import replay_log

    base, cols, depth = stamped_scene(seed=8, seconds=40.0)
    lines = tuple(
        LineConfig(
            lc.name, lc.weight, lc.anchor_distance, lc.mbl, lc.allowed_uplift, lc.hook_height,
            tension_type=readings.WRENCH, tension_axis='y', tension_scale=1000.0,
        )
        for lc in base.lines
    )  # fmt: skip
    config = MonitorConfig(
        lines=lines, depth_type=readings.FLUID_PRESSURE, gauge_height=2.0, alarm=base.alarm
    )
    store = get_typestore(Stores.ROS2_JAZZY)
    bag = tmp_path / 'bag'
    with BagWriter(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = [
            writer.add_connection(lc.tension_topic, readings.WRENCH, typestore=store)
            for lc in lines
        ]
        dconn = writer.add_connection(
            config.depth_topic, readings.FLUID_PRESSURE, typestore=store
        )
        rows = []
        for k, lc in enumerate(lines):
            for a, v, s in zip(*cols[lc.name]):
                m = WrenchStamped()
                m.header.stamp.sec, m.header.stamp.nanosec = divmod(int(s), 10**9)
                m.header.frame_id = f'pin_{k}'
                m.wrench.force.y = float(v) / 1000.0 if math.isfinite(v) else float(v)
                rows.append((int(a), conns[k], serialize_message(m)))
        for a, v, s in zip(*depth):
            p = FluidPressure(fluid_pressure=101325.0 + 1025.0 * readings.G * (float(v) - 2.0))
            p.header.stamp.sec, p.header.stamp.nanosec = divmod(int(s), 10**9)
            rows.append((int(a), dconn, serialize_message(p)))
        for a, conn, data in sorted(rows, key=lambda r: r[0]):
            writer.write(conn, a, data)
    replay = replay_log(sorted(bag.glob('*.mcap')), config, snapshots=True)
    # The oracle: the core on the same arrivals, stamps and readings (from the messages).
    from catenary_monitor.io.sensor_cdr import decode

    ticks = replay.result.tick_ns
    evs = []
    by_topic = {}
    for a, conn, data in rows:
        by_topic.setdefault(conn.topic, []).append((a, data))
    for k, lc in enumerate(lines):
        items = sorted(by_topic[lc.tension_topic])
        d = decode(readings.WRENCH, [x for _, x in items])
        value = readings.tension_si(lc, d.fields)
        evs += [(a, 1, k, Tension(a, k, float(t), int(s)))
                for (a, _), t, s in zip(items, value, d.stamps)]  # fmt: skip
    items = sorted(by_topic[config.depth_topic])
    d = decode(readings.FLUID_PRESSURE, [x for _, x in items])
    value = readings.depth_si(config, d.fields)
    evs += [(a, 0, 0, Depth(a, float(h), int(s))) for (a, _), h, s in zip(items, value, d.stamps)]
    evs += [(int(t), 2, 0, Tick(int(t))) for t in ticks]
    evs.sort(key=lambda e: e[:3])
    core = MonitorCore(config, replay.result.started_ns)
    steps = [core.step(e[3]) for e in evs]
    want = [s.snapshot for s in steps if s.snapshot is not None]
    got = replay.result.snapshots
    assert [s.stamp_ns for s in got] == [s.stamp_ns for s in want]
    for g, w in zip(got, want):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    words = {dict(st.values).get('sensor_state') for s in want for st in s.statuses}
    assert 'bad_stamp' in words  # the refused stamps of the scene, from the bag too
    # replay --out: the results log holds the inputs as SI Float64 readings and says so in its
    # recorded parameters (scale 1, Float64), so it reads back in N, not 1000 times that.
    from replay_data import params_yaml

    from catenary_monitor.cli.main import main as cli
    from catenary_monitor.replay.driver import log_parameters, read_inputs

    out = tmp_path / 'out.mcap'
    params = params_yaml(config, tmp_path / 'dock.yaml')
    args = ['replay', str(bag), '--params-file', str(params), '--out', str(out), '--quiet']
    assert cli(args) == 0
    recorded = config_from_params(log_parameters([out])[1])
    assert {lc.tension_type for lc in recorded.lines} == {'std_msgs/msg/Float64'}
    assert recorded.lines[0].tension_scale == 1.0 and recorded.depth_type.endswith('Float64')
    tensions, depth_col, _ = read_inputs([out], recorded)
    first = lines[0].name
    want = replay.tensions[first][1]
    np.testing.assert_array_equal(tensions[first][1], want)
    assert 300e3 < np.nanmedian(want) < 2e6


@pytest.mark.parametrize('cuts', [(), (T0_NS + 31_000_000_000, T0_NS + 62_500_000_000)])
def test_the_twin_leaves_out_coalesced_stamped_samples_as_the_core_does(cuts):
    """A coalescing node's records over stamped samples (lagging, bunched): the twin leaves
    out the samples and their header stamps alike, in one window or three, as the core."""
    from catenary_monitor.core.monitor.events import Coalesced
    from catenary_monitor.core.twin.engine import run_log
    from catenary_monitor.core.twin.window import slice_window

    config, cols, depth = stamped_scene(bad=False)
    ticks = ticks_for(*plain(cols, depth))
    rng = np.random.default_rng(4)
    records = []
    arrivals = [(line.name, cols[line.name][0]) for line in config.lines] + [(None, depth[0])]
    for name, t in arrivals:
        i = 3
        while i < len(t) - 12:
            n = int(rng.integers(1, 6))
            # 8 ns before the first: the inputs' arrivals sit at offsets 0-5 of 16 ns
            records.append(Coalesced(int(t[i]) - 8, name, int(t[i + n - 1]), n))
            i += n + int(rng.integers(2, 30))
    records.sort(key=lambda e: e.stamp_ns)
    core = MonitorCore(config, T0_NS)
    merged = sorted(events(config, cols, depth, ticks) + records, key=lambda e: e.stamp_ns)
    steps = [core.step(ev) for ev in merged]
    assert sum(s.kind == 'coalesced' for s in steps) == sum(r.samples for r in records) + len(
        records
    )
    twin, bounds, got = MonitorCore(config, T0_NS), [None, *cuts, None], []
    whole = window(config, cols, depth, ticks)
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        part = [
            r
            for r in records
            if (lo is None or r.stamp_ns >= lo) and (hi is None or r.stamp_ns < hi)
        ]
        result, twin = run_log(twin, slice_window(whole, lo, hi), part, snapshots=True)
        got.append(result)
    for k, line in enumerate(config.lines):
        want = [(s.stamp_ns, o.values) for s in steps for o in s.outputs if o.line == k]
        assert np.concatenate([r.lines[k].t_ns for r in got]).tolist() == [w[0] for w in want]
        data = np.array([w[1] for w in want]).reshape(-1, len(OUTPUT_FIELDS))
        for key in ('top_tension', 'depth', 'uplift_force', 'anchor_margin'):
            values = np.concatenate([r.lines[k].values[key] for r in got])
            assert_same_float(values, data[:, OUTPUT_FIELDS.index(key)], f'{line.name} {key}')
    want_sn = [s.snapshot for s in steps if s.snapshot is not None]
    got_sn = [sn for r in got for sn in r.snapshots]
    assert [s.stamp_ns for s in got_sn] == [s.stamp_ns for s in want_sn]
    for g, w in zip(got_sn, want_sn):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    assert_same_state(twin, core)

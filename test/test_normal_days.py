"""The normal-days generator (catenary_monitor_study/normal_days*.py) and the annunciation count
of bench-alarms, against what we did not write: the ROS message definitions (rclpy's
deserialization), the monitor's own tide table and dock statics, and the /diagnostics that
``catenary-monitor replay --out`` records (decoded by mcap_ros2)."""

import math
from dataclasses import replace

import numpy as np
import pytest

from catenary_monitor.cli.main import main
from catenary_monitor.core.config.tide_constituents import parse_table
from catenary_monitor.core.rules import tide_table as monitor_tide
from catenary_monitor.io.sensor_cdr import decode
from catenary_monitor_study import normal_days as nd
from catenary_monitor_study import normal_days_log as ndl
from catenary_monitor_study.annunciations import (
    Counter,
    cause,
    decode_diagnostic_array,
    read_results,
)
from catenary_monitor_study.bench_alarms import replay_counts

CALM = nd.Weather(wind=0.0, wander=0.0, gust=0.0, current=0.0, hs=0.0, hs_per_wind=0.0,
                  residual=0.0)


@pytest.mark.parametrize('port', sorted(nd.PORTS))
def test_the_tide_is_the_monitors_tide_table_of_the_port(port):
    """The generated tide (the constituents with their equilibrium arguments) is what the
    monitor's own forecast makes of the table the params file gives it."""
    p = nd.PORTS[port]
    epoch = nd.START_NS * 1e-9
    table = parse_table(nd.tide_table(p, epoch))
    t = epoch + np.arange(0.0, 3 * 86400.0, 600.0)
    want = monitor_tide.predicted(table, t, epoch)
    got = nd.tide_level(p, t)
    assert np.max(np.abs(got - want)) < 2e-3  # the table's 4 decimals, 2 days of drift
    # the arguments advance at the constituents' speeds
    args = [nd._arguments(np.array([x]))['M2'] for x in (epoch, epoch + 3600.0)]
    rate = args[1] - args[0]
    assert rate[0] % 360.0 == pytest.approx(28.9841042, abs=1e-5)


def test_slack_water_and_range_of_pillar_point():
    t = nd.START_NS * 1e-9 + np.arange(0.0, 2 * 86400.0, 60.0)
    h = nd.tide_level(nd.PORTS['pillar_point'], t)
    assert 1.2 < np.ptp(h) < 2.6  # a mixed tide, spring range about 2 m
    rate = np.abs(np.diff(h)) / 60.0
    assert rate.min() < 2e-6 and rate.max() > 1e-4  # slack water, and a running tide


def test_the_dock_at_rest_holds_the_papers_pretension():
    """At the paper's depth, calm, each chain's hook tension is what the core's problem 5
    (a chain of given length and stiffness at its span, solve(chain_length=, ea=)) gives: the
    tensions come from the statics; near the paper's R = 372 kN (the lengths were fitted to
    it inextensible; the 81 mm chain's stretch takes a few percent off)."""
    from catenary_monitor.core.physics.solve import solve

    scene = nd.paper_scene('exact_1mm', days=0.01, weather=CALM, mean_depth=20.85)
    scene = replace(scene, port=nd.Port('flat', 'no tide', '', ()))
    c = nd.coarse(scene)
    assert np.allclose(c.offset, 0.0, atol=1e-3)  # line 11 sits 1.06 m further out
    t = nd.hook_tensions(scene, c, np.array([10.0, 20.0]))
    line = scene.config.lines[0]
    want = solve(1300.0, 20.85, chain_length=line.chain_length, anchor_distance=120.0,
                 ea=nd.PAPER_EA)  # fmt: skip
    assert np.allclose(t[:, :10], want.top_tension, rtol=1e-4)
    assert 0.9 * 372e3 < want.horizontal_tension < 372e3


def test_stamped_payloads_are_ros_messages():
    """WrenchStamped, FluidPressure and Range built in columns deserialize with rclpy to the
    values given, and the monitor's own decoder reads them alike."""
    from rclpy.serialization import deserialize_message
    from geometry_msgs.msg import WrenchStamped
    from sensor_msgs.msg import FluidPressure, Range

    stamps = np.array([1_740_787_200_123_456_789, 1_740_787_201_000_000_001])
    force = (np.array([3.5e5, 4e5]), np.array([1.0, 2.0]), np.array([-3.0, 4.0]))
    w = ndl.wrench_payloads(stamps, 'line_01_pin', force)
    m = deserialize_message(w[1].tobytes(), WrenchStamped)
    assert (m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id) == (
        1_740_787_201, 1, 'line_01_pin')
    assert (m.wrench.force.x, m.wrench.force.y, m.wrench.force.z) == (4e5, 2.0, 4.0)
    p = ndl.fluid_pressure_payloads(stamps, 'tide_pressure', np.array([1.9e5, 2e5]))
    assert deserialize_message(p[0].tobytes(), FluidPressure).fluid_pressure == 1.9e5
    r = ndl.range_payloads(stamps, 'tide_radar', np.array([8.25, 8.5], np.float32), 0.3, 40.0)
    msg = deserialize_message(r[1].tobytes(), Range)
    assert (msg.range, msg.min_range, msg.max_range) == (8.5, pytest.approx(0.3), 40.0)
    cols = decode('sensor_msgs/msg/Range', [bytes(x) for x in r])
    assert cols.fields['range'].tolist() == [8.25, 8.5] and cols.stamps.tolist() == stamps.tolist()


@pytest.fixture(scope='module')
def drop_log(tmp_path_factory):
    """Twenty minutes at the paper's dock read by a radar gauge, the load-cell gateway silent
    for 15 s at 10 min."""
    fault = nd.Fault('gateway_drop', 600.0, 15.0)
    scene = nd.paper_scene('radar_1cm', days=20 / 1440, faults=(fault,), mean_depth=18.3)
    return scene, ndl.write_scene(scene, tmp_path_factory.mktemp('drop'))


@pytest.fixture(scope='module')
def drop_counts(drop_log):
    """The drop log replayed into the bench's two sinks."""
    return replay_counts(drop_log[1].log, drop_log[1].params)


def test_the_log_holds_what_the_drivers_publish(drop_log):
    scene, facts = drop_log
    config = scene.config
    n = facts.messages
    assert n[config.depth_topic] == pytest.approx(1200, abs=2)  # 1 Hz
    for line in config.lines:  # 10 Hz, less the 15 s of the drop (and a lost one, maybe)
        assert 11840 <= n[line.tension_topic] <= 11850
    kinds = {config.lines[0].tension_type, config.lines[5].tension_type, config.depth_type}
    assert kinds == {'geometry_msgs/msg/WrenchStamped', 'std_msgs/msg/Float64',
                     'sensor_msgs/msg/Range'}


def test_annunciations_in_replay_are_those_replay_out_records(drop_log, drop_counts, tmp_path):
    """The bench's count from the replay driver's snapshots equals the /diagnostics that
    ``replay --out`` writes (decoded by mcap_ros2 and by our decoder), and the gateway's 15 s
    of silence is heard."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    scene, facts = drop_log
    counter, figures = drop_counts
    out = tmp_path / 'out.mcap'
    code = main(['replay', str(facts.log), '--params-file', str(facts.params), '--out', str(out),
                 '--quiet'])
    assert code == 0
    recorded = read_results(out)
    assert counter.events == recorded.events
    assert counter.snapshots == recorded.snapshots
    # our decoder against mcap_ros2's on every array
    with open(out, 'rb') as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for k, (_, _, msg, ros) in enumerate(
            reader.iter_decoded_messages(topics=['/diagnostics'], log_time_order=True)
        ):
            stamp, statuses = decode_diagnostic_array(msg.data)
            assert [(s[0], s[1], s[2]) for s in statuses] == [
                (st.name, int.from_bytes(st.level, 'little') if isinstance(st.level, bytes)
                 else int(st.level), st.message) for st in ros.status]
            if k > 50:
                break
    heard = counter.heard(scene.start_s + 600.0, scene.start_s + 700.0)
    assert heard, 'the gateway drop was not heard at all'
    assert figures['annunciated'] <= len(counter.heard())


def test_causes_mask_numbers():
    assert cause('depth sensor stuck at 19.91 m while the lines move: check the tide gauge') == (
        'depth sensor stuck at # m while the lines move')
    assert cause('3 of 7640 tension and depth samples dropped in the last 60 s (0.0 %)') == (
        '# of # tension and depth samples dropped in the last # s')


def test_a_drawn_dock_is_another_dock_and_normal():
    scene = nd.drawn_scene(4, 'pressure_1mm', days=0.05)
    paper = nd.paper_scene('pressure_1mm', days=0.05, mean_depth=18.3)
    assert scene.config.lines != paper.config.lines
    m = nd.scene_margins(scene)
    a = scene.config.alarm
    assert m['anchor_margin_min'] > a.anchor_margin_warn + a.anchor_margin_deadband
    assert m['uplift_max'] == 0.0 and math.isfinite(m['tide_margin_min'])


def test_counter_takes_a_status_once_it_was_ok():
    c = Counter()
    c.take_rows(1_000_000_000, [('catenary_monitor: tide', 3, 'no depth yet', {})])
    c.take_rows(2_000_000_000, [('catenary_monitor: tide', 0, 'depth 1 m', {})])
    c.take_rows(3_000_000_000, [('catenary_monitor: tide', 1, 'stuck', {})])
    c.take_rows(4_000_000_000, [('catenary_monitor: tide', 2, 'worse', {})])
    c.take_rows(5_000_000_000, [('catenary_monitor: tide', 3, 'stale', {})])
    c.take_rows(6_000_000_000, [('catenary_monitor: line_01', 0, '', {})])
    c.take_rows(7_000_000_000, [('catenary_monitor: line_01', 3, 'stale',
                                 {'alarm_state': 'suppressed'})])
    assert [(a.status, a.after, a.hidden) for a in c.events] == [
        ('tide', 1, ''), ('tide', 2, ''), ('line_01', 3, 'suppressed')]
    assert len(c.heard()) == 2


def test_the_bench_reports_a_fault_window(drop_log, drop_counts):
    """The bench's row of a fault scene: the window's annunciations, their causes, the
    first-out and whether it names the fault, both counts and their gap; and its table."""
    from catenary_monitor_study.bench_alarms import _summary, table

    scene, _ = drop_log
    counter, figures = drop_counts
    row = _summary('gateway_drop', scene, counter, figures)
    fault = row['fault']
    assert fault['window_s'] == [600.0, 735.0]
    assert fault['annunciations'] == len(counter.heard(scene.start_s + 600, scene.start_s + 735))
    assert row['gap'] == row['diagnostics_annunciations'] - row['alarms_report_annunciations']
    assert fault['first_out'] is not None and fault['causes']
    text = table({'dock': 'paper', 'seed': 1, 'seconds': 1.0, 'scenes': [row]})
    assert 'fault gateway_drop' in text and scene.name in text

"""The live node fed as a dock's drivers feed it: WrenchStamped tensions in kN (scale 1000, one
axis) whose header stamps lag arrival by seconds and come in bunches, a FluidPressure depth;
a third load cell in kN without its scale. /diagnostics against solve() at the stamped
values and ages, replay of the node's log against /diagnostics, the log read by rosbags.
"""

import math
import time

import numpy as np
import pytest
from ros_harness import Client, output_of, start_monitor, stop, write_params

from catenary_monitor.core.rules.readings import G
from catenary_monitor.core.physics.solve import solve
from catenary_monitor.replay.driver import expand, load_config, replay_log

W, X, MBL, HOOK = 1300.0, 121.06, 5.17e6, 0.5
RHO, P_ATM, GAUGE = 1025.0, 101325.0, 1.2
LAG = 2.0  # s: the oldest sample of a bunch is LAG + 0.9 s old when it arrives


def _params(tmp_path):
    line = {'weight': W, 'anchor_distance': X, 'mbl': MBL, 'hook_height': HOOK}
    wrench = {'tension_type': 'geometry_msgs/msg/WrenchStamped', 'tension_axis': 'z'}
    return write_params(
        tmp_path / 'dock.yaml',
        {
            'a': {**line, **wrench, 'tension_scale': 1000.0},
            'b': {**line, **wrench, 'tension_scale': 1000.0},
            'c': {**line, **wrench},  # a load cell in kN, its scale forgotten
        },
        depth_type='sensor_msgs/msg/FluidPressure',
        water_density=RHO,
        atmospheric_pressure=P_ATM,
        gauge_height=GAUGE,
        tension_timeout=10.0,
        depth_timeout=20.0,
        diagnostic_rate=2.0,
    )


def _stamp(msg, ns):
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(int(ns), 10**9)
    msg.header.frame_id = 'load_pin'


@pytest.mark.timeout(120)
def test_stamped_sensors_in_kn_live_and_replayed(tmp_path):
    from geometry_msgs.msg import WrenchStamped
    from sensor_msgs.msg import FluidPressure

    log = tmp_path / 'log'
    params = _params(tmp_path)
    proc = start_monitor(params, log)
    client = Client('stamped_test_client')
    sent = {}  # (line, kN) -> header stamp ns
    depths = {}  # stamp ns -> depth m
    try:
        pubs = {n: client.node.create_publisher(WrenchStamped, f'/mooring/{n}/tension', 10)
                for n in 'abc'}  # fmt: skip
        dpub = client.node.create_publisher(FluidPressure, '/tide/depth', 10)
        client.wait_for(
            lambda: all(p.get_subscription_count() for p in [*pubs.values(), dpub]),
            30.0,
            'the monitor subscribed',
        )
        rng = np.random.default_rng(5)
        for burst in range(7):
            now = time.time_ns()
            d = 20.85 + 0.01 * burst
            p = FluidPressure(fluid_pressure=P_ATM + RHO * G * (d - GAUGE), variance=0.0)
            _stamp(p, now - int(1.5e9))
            depths[now - int(1.5e9)] = d
            dpub.publish(p)
            for i in range(10):  # a bunch: 10 samples taken 0.1 s apart, LAG s ago
                ns = now - int((LAG + 0.9 - 0.1 * i) * 1e9)
                for n, base in (('a', 370.0), ('b', 1623.5), ('c', 370.0)):
                    kn = round(base + rng.normal(0, 5.0), 6)
                    m = WrenchStamped()
                    _stamp(m, ns)
                    m.wrench.force.x, m.wrench.force.y, m.wrench.force.z = 99.0, -99.0, kn
                    pubs[n].publish(m)
                    sent[(n, kn)] = ns
            time.sleep(1.0)
        client.wait_for(lambda: len(client.diagnostics) > 8, 20.0, 'diagnostics')
        time.sleep(0.6)
    finally:
        code = stop(proc)
        client.close()
    text = output_of(proc)
    assert code == 0, text
    # The load cell in kN without its scale: one log line names the units and the parameter.
    units = [ln for ln in text.splitlines() if 'wrong units?' in ln]
    assert len(units) == 1 and 'ALARM c:' in units[0] and 'c.tension_scale: 1000' in units[0]
    assert 'kN' in units[0]
    # /diagnostics: each line's values are solve() at the stamped reading, its age the stamp's.
    checked = 0
    with client.lock:
        arrays = list(zip(client.diag_stamps, [e for _, e in client.diagnostics]))
    for stamp, entry in arrays:
        tide = entry['catenary_monitor: tide']['values']
        if tide['depth'] == 'nan':
            continue
        at = stamp - float(tide['depth_age']) * 1e9  # the depth's header stamp (to float s)
        d_stamp = min(depths, key=lambda s: abs(s - at))
        assert abs(d_stamp - at) < 1e4
        assert float(tide['depth']) == pytest.approx(depths[d_stamp], abs=1e-9)
        for n in 'ab':
            v = entry[f'catenary_monitor: {n}']['values']
            if v['measured_tension'] == 'nan':
                continue
            t = float(v['measured_tension'])
            ns = sent[(n, round(t / 1000.0, 6))]
            assert float(v['tension_age']) == pytest.approx((stamp - ns) * 1e-9, abs=1e-6)
            assert float(v['tension_age']) >= LAG
            h = float(v['depth'])
            assert h == pytest.approx(float(tide['depth']) + HOOK, abs=1e-12)
            r = solve(W, h, tension=t, anchor_distance=X, mbl=MBL)
            for key in ('horizontal_tension', 'uplift_force', 'anchor_margin', 'tide_margin'):
                assert float(v[key]) == pytest.approx(getattr(r, key), rel=1e-9, abs=1e-6)
            checked += 1
        c = entry['catenary_monitor: c']
        if c['values']['measured_tension'] != 'nan':
            assert c['level'] == 2 and 'wrong units?' in c['values']['detail']
    assert checked >= 10
    # Replay of the node's log: the same levels and values at the same stamps.
    config = load_config(str(params))
    replay = replay_log(expand([str(log)]), config, snapshots=True)
    by_stamp = {s.stamp_ns: s for s in replay.result.snapshots}
    compared = 0
    for stamp, entry in arrays:
        snap = by_stamp.get(stamp)
        if snap is None:
            continue
        for st in snap.statuses:
            live = entry.get(st.name)
            if live is None or st.name.endswith(('logger', 'intake')):
                continue  # the node's own counters
            assert live['level'] == int(st.level), (stamp, st.name)
            for key, value in st.values:
                got, want = live['values'][key], value
                try:
                    assert math.isclose(float(got), float(want), rel_tol=1e-12) or (
                        math.isnan(float(got)) and math.isnan(float(want))
                    ), (st.name, key)
                except ValueError:
                    assert got == want, (st.name, key)
        compared += 1
    assert compared >= 8
    # rosbags opens the folder and reads the stamped types and their header stamps.
    from rosbags.highlevel import AnyReader

    with AnyReader([log]) as reader:
        conns = [c for c in reader.connections if c.topic == '/mooring/a/tension']
        assert conns and conns[0].msgtype == 'geometry_msgs/msg/WrenchStamped'
        stamps = [
            reader.deserialize(raw, c.msgtype).header.stamp
            for c, _, raw in reader.messages(connections=conns)
        ]
    got = [s.sec * 10**9 + s.nanosec for s in stamps]
    assert len(got) >= 50 and set(got) <= {ns for (n, _), ns in sent.items() if n == 'a'}

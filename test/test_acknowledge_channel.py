"""Who may acknowledge over ROS: the origin kept bounded, the publisher named as the middleware
sees it, and ``acknowledge_from_ros: false`` (against a monitor process, and the pure rules).

With ``acknowledge_from_ros`` false the node takes an acknowledgement only while every publisher
on ``/catenary_monitor/acknowledge`` is a console node: a message from another node (here one
claiming to be the console in its text) is refused with one warning line; the console's is
taken and recorded with the console's node name and GID.
"""

from __future__ import annotations

import time

import pytest
from ros_harness import Client, output_of, start_monitor, stop, write_params

from catenary_monitor.core.alarms.acknowledge import (
    ACKNOWLEDGE_TOPIC,
    ORIGIN_LIMIT,
    bounded_text,
    console_only_refusal,
    parse_request,
    publisher_identity,
)

GID = bytes(range(16)) + bytes(8)
HEX = '00.01.02.03.04.05.06.07.08.09.0a.0b.0c.0d.0e.0f'


def test_origin_bounded_printable_idempotent() -> None:
    """An origin of 1 MB, with control characters or line breaks, is one printable line of at
    most ORIGIN_LIMIT characters, marked cut; bounding twice changes nothing."""
    line, origin = parse_request('line_11 ' + 'x' * 1_000_000)
    assert line == 'line_11' and len(origin) == ORIGIN_LIMIT and origin.endswith('...')
    assert bounded_text(origin) == origin
    assert bounded_text('bridge\n\x1b[31mfake\tALARM\x00') == 'bridge ?[31mfake ALARM?'
    assert parse_request('all') == (None, 'ros')
    assert bounded_text('a' * ORIGIN_LIMIT) == 'a' * ORIGIN_LIMIT
    with pytest.raises(ValueError):
        parse_request(' \n ')


def test_publisher_identity_and_console_only_rule() -> None:
    """One publisher: its node and GID; several: all of them (Jazzy's rclpy gives no sender
    GID per message); the console-only rule refuses while any non-console node publishes."""
    console = ('/catenary_console_41', GID)
    other = ('/intruder', bytes(24))
    assert publisher_identity([console]) == f'/catenary_console_41 gid {HEX}'
    both = publisher_identity([console, other])
    assert both.startswith('one of 2: ') and '/intruder gid 00.00' in both
    assert publisher_identity([]).startswith('unknown')
    assert console_only_refusal([console]) is None
    assert console_only_refusal([('/dock/catenary_console_7', GID), console]) is None
    assert '/intruder' in (console_only_refusal([console, other]) or '')
    assert console_only_refusal([]) is not None


@pytest.mark.ros
def test_acknowledge_from_ros_false_takes_only_the_console(tmp_path) -> None:
    import rclpy
    from rclpy.qos import QoSProfile
    from std_msgs.msg import String

    params = write_params(
        tmp_path / 'p.yaml',
        {'line_01': dict(weight=1300.0, anchor_distance=121.06, mbl=4.827e6)},
        acknowledge_from_ros=False,
    )
    proc = start_monitor(params, tmp_path / 'log')
    client = Client('ack_channel_client')  # rclpy initialised, spun in its thread
    intruder = rclpy.create_node('intruder')
    console = rclpy.create_node('catenary_console_test')
    try:
        evil = intruder.create_publisher(String, ACKNOWLEDGE_TOPIC, QoSProfile(depth=10))
        good = console.create_publisher(String, ACKNOWLEDGE_TOPIC, QoSProfile(depth=10))
        client.wait_for(lambda: evil.get_subscription_count() > 0, 60.0, 'the monitor')
        client.wait_for(lambda: good.get_subscription_count() > 0, 10.0, 'the monitor')
        time.sleep(1.0)  # both publishers in the monitor's graph
        evil.publish(String(data='line_01 console dockpc client 127.0.0.1'))
        client.wait_for(
            lambda: 'acknowledge refused: acknowledge_from_ros is false' in output_of(proc),
            10.0,
            'the refusal',
        )
        assert '/intruder' in output_of(proc)
        intruder.destroy_node()
        client.wait_for(
            lambda: client.node.count_publishers(ACKNOWLEDGE_TOPIC) == 1, 10.0, 'intruder gone'
        )
        time.sleep(1.0)
        good.publish(String(data='line_01 console dockpc client 127.0.0.1'))
        client.wait_for(lambda: 'ACKNOWLEDGED line_01' in output_of(proc), 10.0, 'the ack')
        text = output_of(proc)
        assert '(/catenary_console_test gid ' in text, text
        assert text.count('ACKNOWLEDGED') == 1, text
    finally:
        console.destroy_node()
        client.close()
        assert stop(proc) == 0

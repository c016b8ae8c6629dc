"""Publish std_msgs/Float64 tensions on /mooring/NAME/tension for NAME in argv[1] (comma
separated) at argv[2] Hz each, and a depth at argv[4] Hz (default 10), for argv[3] s
(sensor-data QoS): a node-intake load for test_node_guard and test_log_retention. Prints ``sent
N`` at the end; SIGTERM ends it early, cleanly (its participant leaves the graph: Fast DDS
segfaulted now and then in the teardown of a monitor stopped just after a flood publisher was
SIGKILLed)."""

import signal
import sys
import threading
import time

import rclpy
from rclpy.qos import qos_profile_sensor_data
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import Float64


def main() -> None:
    names, rate, duration = sys.argv[1].split(','), float(sys.argv[2]), float(sys.argv[3])
    depth_rate = float(sys.argv[4]) if len(sys.argv) > 4 else 10.0
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node('flood_publisher')
    pubs = [
        node.create_publisher(Float64, f'/mooring/{n}/tension', qos_profile_sensor_data)
        for n in names
    ]
    depth = node.create_publisher(Float64, '/tide/depth', qos_profile_sensor_data)
    deadline = time.monotonic() + 30.0
    while any(p.get_subscription_count() == 0 for p in pubs) and time.monotonic() < deadline:
        time.sleep(0.05)
    tension, level = Float64(data=1500e3), Float64(data=20.85)
    t0, sent, k, d = time.monotonic(), 0, 0, 0
    while (now := time.monotonic() - t0) < duration and not stop.is_set():
        while k < int(now * rate):
            for p in pubs:
                p.publish(tension)
            sent, k = sent + len(pubs), k + 1
        while d < int(now * depth_rate):
            depth.publish(level)
            sent, d = sent + 1, d + 1
        time.sleep(0.0005)
    print(f'sent {sent}', flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == '__main__':
    main()

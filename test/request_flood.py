"""Publish std_msgs/String requests on argv[1] (a request topic) at argv[2] a second for argv[3]
s, the texts argv[4:] in turn, from a node named ``request_flooder`` (reliable, keep last 10):
a hostile or broken node for test_request_flood. Prints ``sent N`` at the end; SIGTERM ends it
early, cleanly."""

import signal
import sys
import threading
import time

import rclpy
from rclpy.duration import Duration
from rclpy.qos import QoSProfile
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import String


def main() -> None:
    topic, rate, duration = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
    texts = sys.argv[4:]
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node('request_flooder')
    pub = node.create_publisher(String, topic, QoSProfile(depth=10))
    deadline = time.monotonic() + 30.0
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    messages = [String(data=t) for t in texts]
    # One request first, taken alone: the monitor counts a publisher's lost requests from the
    # gaps in its sequence numbers after the first it takes (none can tell those lost before)
    pub.publish(messages[0])
    time.sleep(1.0)
    print('matched', flush=True)
    t0, sent = time.monotonic(), 1
    while (now := time.monotonic() - t0) < duration and not stop.is_set():
        while sent < 1 + int(now * rate):
            pub.publish(messages[sent % len(messages)])
            sent += 1
        time.sleep(0.0005)
    # reliable delivery of the last ones (under load it took longer than a fixed 0.5 s: the
    # monitor could not account for requests it never received)
    pub.wait_for_all_acked(Duration(seconds=10.0))
    print(f'sent {sent}', flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == '__main__':
    main()

"""ROS 2 wiring (rclpy): the live node, the dock simulator and log playback onto ROS."""

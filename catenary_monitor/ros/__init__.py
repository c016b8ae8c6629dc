"""ROS 2 wiring (rclpy): the live node, the dock simulator (the episode of
:mod:`catenary_monitor.sim` published as sensors) and log playback onto ROS."""

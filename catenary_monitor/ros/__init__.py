"""ROS 2 wiring (rclpy): the live node, the dock simulator (and its optional MoorDyn source,
moordyn_dock.py) and log playback onto ROS."""

"""Simulation without ROS: the demo's dock episode (scenario.py: the paper's dock through a
compressed storm, its tensions from the dock's equilibrium or from MoorDyn) and the dock's chains
in MoorDyn (moordyn_dock.py, optional: the ``dynamics`` extra). May import the core only (no
rclpy, no io); the dock simulator (ros/simulator.py) publishes it, the demo, the console and the
study's benchmarks use it."""

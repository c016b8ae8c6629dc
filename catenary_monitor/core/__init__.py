"""The monitor's pure core: physics, solvers, configuration, alarms and the monitor itself.

Plain Python and numpy only: nothing here imports rclpy, reads a clock or touches a file
(``config.load_params_file`` reads the one file it is handed). The node, replay and the command
line are thin shells around it.
"""

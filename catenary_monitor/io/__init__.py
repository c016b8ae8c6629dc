"""Files: MCAP logging and reading, CDR encoding, CSV writing. No rclpy, no monitor decisions."""

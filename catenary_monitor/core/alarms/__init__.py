"""Alarm management on top of the rules: :mod:`.latches` (each line's alarm: a latch per
condition, its level and message, and their column loop for the twin), :mod:`.acknowledge`
(alarm states in ISA-18.2's terms and their acknowledgement), :mod:`.shelving` (shelving an
alarm or one condition of it), :mod:`.flood` (the alarm flood and its first-out) and
:mod:`.journal` (the records of the alarm journal).

May import :mod:`catenary_monitor.core.rules`, :mod:`~catenary_monitor.core.body`,
:mod:`~catenary_monitor.core.config` and :mod:`~catenary_monitor.core.physics`.
"""

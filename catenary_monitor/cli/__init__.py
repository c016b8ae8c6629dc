"""The ``catenary-monitor`` command line: sub-commands, the demo, replay and its outputs."""

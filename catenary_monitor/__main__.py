"""``python -m catenary_monitor``: the ``catenary-monitor`` command."""

import sys

from catenary_monitor.cli.main import main

sys.exit(main())

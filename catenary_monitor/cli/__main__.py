"""``python -m catenary_monitor.cli``: the ``catenary-monitor`` command."""

import sys

from catenary_monitor.cli.main import main

sys.exit(main())

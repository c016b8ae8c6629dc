"""The operator's console: the dock at a glance in a browser (``catenary-monitor console``).

Its own process: a ROS client of the monitor (:mod:`.ros_source`: it subscribes to
``/diagnostics`` and the per-line outputs, and publishes acknowledgements, which the monitor's
core decides and records), or a viewer of a recorded log (:mod:`.log_source`, over the replay
driver). :mod:`.frames` turns what the monitor published into the page's frames;
:mod:`.server` serves the page (plain HTML, CSS and JS shipped in ``static/``: no CDN, no web
fonts) and decides who may act; :mod:`.http_transport` carries its HTTP (asyncio and h11, every
request read whole, every wait bounded); :mod:`.operators` reads the operators' token file.
Live updates go as Server-Sent Events.
:mod:`.foxglove` writes a Foxglove / Lichtblick layout for the same topics. :mod:`.command` is
the ``console`` sub-command, which the command line finds through its entry point (the console
and :mod:`catenary_monitor.cli` never import each other). See docs/console.md.
"""

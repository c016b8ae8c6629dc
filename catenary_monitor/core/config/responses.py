"""The shipped response texts: for each alarm condition, what an operator reads beside the
alarm's headline (its cause, its consequence, the action), as the defaults of the
``response_texts.<condition>`` parameters (one string each: rcl's parameters hold no nested
lists). :mod:`catenary_monitor.core.alarms.responses` looks them up for a status.

The conditions are a line's (:data:`~catenary_monitor.core.config.parameters.ALARM_CONDITIONS`)
and the monitor's own statuses (``tide``, ``sensors``, ...): one text per status name.
"""

from __future__ import annotations

__all__ = ['DEFAULT_RESPONSES', 'RESPONSE_PREFIX']

#: The parameters' prefix: ``response_texts.uplift`` holds the ``uplift`` condition's text.
RESPONSE_PREFIX = 'response_texts.'


def _text(cause: str, consequence: str, action: str) -> str:
    return f'Cause: {cause} Consequence: {consequence} Action: {action}'


#: condition -> 'Cause: ... Consequence: ... Action: ...' (the shipped defaults).
DEFAULT_RESPONSES: dict[str, str] = {
    'uplift': _text(
        'the chain pulls its anchor upward: too little chain on the seabed for this tide and '
        'load (at the waves\' peak when the alarm names the dynamic uplift).',
        'a drag anchor loses its holding when lifted; the dock may drift and load the other '
        'lines.',
        'reduce the load (mooring, ballast, traffic) or pay out chain; check the anchor\'s '
        'position; watch the neighbouring lines.',
    ),
    'input': _text(
        'a reading no mooring produces: a failed load cell or depth gauge, a cable, or wrong '
        'units or scaling (tension_scale, depth settings).',
        'the line\'s margins cannot be computed: it is not monitored until readings are sane.',
        'check the sensor, its cable and the units; correct NAME.tension_scale or the depth '
        'settings if they are wrong.',
    ),
    'anchor_margin': _text(
        'the chain on the seabed is running short: the tide is high or the load has risen.',
        'the anchor lifts when the margin reaches zero.',
        'watch the tide and the load; prepare to pay out chain or reduce the load.',
    ),
    'tide_margin': _text(
        'the tide is close to the depth at which the chain lifts its anchor.',
        'a further rise of the tide lifts the anchor.',
        'check the tide forecast; prepare to pay out chain before high water.',
    ),
    'load_margin': _text(
        'the horizontal load on the line is close to what lifts its anchor.',
        'more load (wind, current, waves) lifts the anchor.',
        'reduce the load on the dock; watch the weather; check the other lines.',
    ),
    'safety_factor': _text(
        'the line\'s tension is high against its minimum breaking load.',
        'the chain, its shackles or its hook may be overloaded.',
        'reduce the load; inspect the chain and its fittings after the event.',
    ),
    'time_to_uplift': _text(
        'at the tide\'s trend (or the tide table\'s forecast) the anchor lifts soon.',
        'the anchor lifts at the time shown unless the load or the tide changes.',
        'pay out chain or reduce the load before then; watch the forecast.',
    ),
    'inconsistent': _text(
        'the line\'s tension disagrees with the dock position the other lines agree on: '
        'sensor drift or calibration, a slipped stopper, a broken link or a dragging anchor.',
        'the line\'s own margins may be wrong.',
        'check the load cell (calibration, cable), the chain and stopper, and the anchor.',
    ),
    'uplift_possible': _text(
        'within the sensors\' accuracy the anchor may already lift.',
        'the nominal margin cannot be trusted near the limit.',
        'treat as uplift: reduce the load or pay out chain; check the sensors\' calibration.',
    ),
    'drag_margin': _text(
        'the horizontal load is close to the anchor\'s holding capacity.',
        'the anchor may start to drag.',
        'reduce the load; watch the anchor\'s position and the line\'s span.',
    ),
    'sensor_error': _text(
        'the load cell reads above the chain\'s MBL, or at or below the hanging chain\'s own '
        'weight: a parted or slack chain, or a failed sensor.',
        'a parted chain leaves the dock on fewer lines; a failed sensor leaves it unwatched.',
        'check the chain and the anchor at once, then the load cell and its cable.',
    ),
    'sensor_warn': _text(
        'the load cell is stuck or spiking: a cable, a connector, the amplifier or noise.',
        'its tension, and the margins from it, may be wrong.',
        'check the load cell, its cable, connector and amplifier.',
    ),
    'dragging': _text(
        'the load exceeds the anchor\'s holding and the chain puts the anchor beyond its '
        'installed position.',
        'the dock moves off station and loads the other lines.',
        'reduce the load at once; survey the anchor; re-tension or re-set the line.',
    ),
    'fatigue': _text(
        'the chain\'s cumulative fatigue damage (Miner\'s rule) reached its warning level.',
        'cracks may grow in the chain\'s links.',
        'plan an inspection of the chain; replace worn links.',
    ),
    'channel': _text(
        'one channel of a multi-channel load cell is silent, stuck or out of line.',
        'the tension comes from the other channels; one more failure blinds the line.',
        'check the failed channel\'s cable and amplifier.',
    ),
    'stale': _text(
        'no recent tension or depth reading: a sensor, its cable, a gateway or the network.',
        'the line is not monitored: an uplift would not be seen.',
        'check the sensor link (gateway, network, power) and watch the line by other means.',
    ),
    'tide': _text(
        'the depth gauge is silent, stuck, spiking or out of its range.',
        'every line\'s margins depend on the depth.',
        'check the tide gauge, its cable and its datum; compare with the tide table.',
    ),
    'sensors': _text(
        'inputs fell silent or never arrived: a gateway, the network, power or a driver.',
        'the lines they feed are blind: an uplift would not be seen.',
        'check the gateway, network and power of the silent sensors.',
    ),
    'alarms': _text(
        'more alarms than an operator can handle in the window (an alarm flood).',
        'important alarms may be missed.',
        'deal with the first-out alarm first; the others often follow from it.',
    ),
    'logger': _text(
        'the log cannot be written: disk full, permissions or a failed disk.',
        'the record of this period may be lost.',
        'free disk space or fix the log directory.',
    ),
    'dock': _text(
        'the dock estimate lacks readings or disagrees with them.',
        'inconsistent lines cannot be found meanwhile.',
        'restore the silent sensors; check the dock model\'s parameters.',
    ),
    'parameters': _text(
        'parameters were changed at runtime.',
        'alarms follow the new limits.',
        'confirm the change was intended; record it in the shift log.',
    ),
    'clock': _text(
        'the ROS clock jumped or stalled.',
        'timers and timeouts may misfire.',
        'check the time source (NTP, use_sim_time, the bag player).',
    ),
    'intake': _text(
        'samples were dropped or coalesced: the node cannot keep up, or the network loses '
        'messages.',
        'short events may be missed.',
        'check the node\'s CPU load and the network.',
    ),
    'fatigue_store': _text(
        'the fatigue store cannot be read or written.',
        'the chains\' cumulative damage may be lost.',
        'check the log directory and its disk.',
    ),
}

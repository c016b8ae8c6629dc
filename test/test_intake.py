"""The intake status against configured sample rates (core.monitor.monitor_core,
core.rules.health): samples that never reached the node, counted whatever the executor can
see."""

from __future__ import annotations

from replay_data import T0_NS, dock_config

from catenary_monitor.core.alarms import components
from catenary_monitor.core.rules.health import missing_samples
from catenary_monitor.core.monitor.events import Intake
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.monitor.monitor_core import MonitorCore


def _at(s: float) -> int:
    return T0_NS + int(s * 1e9)


def _status(core: MonitorCore):
    (status,) = [s for s in core.guard_components(0.0) if s.name.endswith('intake')]
    return status


def test_missing_samples_counts_a_shortfall_beyond_the_tolerance():
    assert missing_samples(0.0, 60.0, 0) == 0  # no rate: not checked
    assert missing_samples(400.0, 60.0, 24000) == 0
    assert missing_samples(400.0, 60.0, 23800) == 0  # 200 short: within 1 % (240)
    assert missing_samples(400.0, 60.0, 20880) == 3120  # 13 % short
    assert missing_samples(20.0, 1.0, 9) == 11  # 0.5 s of samples is the floor
    assert missing_samples(20.0, 1.0, 11) == 0


def test_a_shortfall_against_the_sample_rate_is_counted_per_line():
    """2 lines at a configured 400 Hz: line 1 delivers 87 %; the first report (which began
    before the first sample) is not checked; the depth has no rate and is not checked."""
    core = MonitorCore(dock_config(2, tension_sample_rate=400.0), T0_NS)
    core.step(Intake(_at(1.0), (120, 90, 1), (0, 0, 0), 0.01, 1.0))  # first: not checked
    assert core.state.intake[0] == Level.OK
    core.step(Intake(_at(11.0), (4000, 3480, 10), (0, 0, 0), 0.5, 10.0))
    status = _status(core)
    values = dict(status.values)
    assert values['line_01.messages_missing'] == '0'
    assert values['line_02.messages_missing'] == '520'
    assert values['depth.messages_missing'] == '0'
    assert values['messages_missing'] == '520' and values['messages_dropped'] == '520'
    assert status.level == Level.ERROR, status  # 520 of 8130: 6.4 %, the node idle
    assert 'missing in the last 60 s (520 of' in status.message, status.message
    assert 'a sensor slower than its sample rate, or samples lost' in status.message


def test_missing_and_counted_drops_add_without_counting_twice():
    """A sequence gap counted as dropped is not missing again."""
    core = MonitorCore(dock_config(1, tension_sample_rate=100.0), T0_NS)
    core.step(Intake(_at(1.0), (100, 1), (0, 0), 0.01, 1.0))
    core.step(Intake(_at(11.0), (950, 10), (50, 0), 9.0, 10.0))  # 1000 expected: all there
    values = dict(_status(core).values)
    assert values['messages_missing'] == '0' and values['messages_dropped'] == '50'
    core.step(Intake(_at(21.0), (800, 10), (50, 0), 9.5, 10.0))  # 150 short, 50 counted
    status = _status(core)
    values = dict(status.values)
    assert values['messages_missing'] == '150' and values['messages_dropped'] == '250'
    assert status.level == Level.ERROR and 'node cannot keep up' in status.message
    assert '150 of them missing against the sample rates' in status.message


def test_a_silent_input_is_left_to_staleness():
    """A line that sends nothing in a report period is stale, not 'missing' samples."""
    core = MonitorCore(dock_config(1, tension_sample_rate=20.0), T0_NS)
    core.step(Intake(_at(1.0), (20, 1), (0, 0), 0.01, 1.0))
    core.step(Intake(_at(11.0), (0, 10), (0, 0), 0.01, 10.0))
    values = dict(_status(core).values)
    assert values['messages_missing'] == '0' and core.state.intake[0] == Level.OK


def test_without_rates_the_values_are_as_before():
    core = MonitorCore(dock_config(1), T0_NS)
    core.step(Intake(_at(1.0), (1, 1), (0, 0), 0.01, 1.0))
    core.step(Intake(_at(11.0), (2, 10), (0, 0), 0.01, 10.0))
    keys = [k for k, _ in _status(core).values]
    assert keys == [
        'messages_dropped',
        'line_01.messages_dropped',
        'depth.messages_dropped',
        'messages_coalesced',
        'messages_handled',
        *components.KEYS,  # its alarm's (acknowledgeable)
    ]
    assert core.state.intake[0] == Level.OK
    assert dict(_status(core).values)['messages_handled'] == '14'


def test_coalesced_samples_are_dropped_from_the_decisions_and_said_so():
    """A node that coalesced (logged every sample, stepped the newest of each line): the
    samples not stepped count as dropped, per line and in the share, and the message says
    they were logged and how many were lost before the node."""
    core = MonitorCore(dock_config(2), T0_NS)
    core.step(Intake(_at(1.0), (200, 200, 1), (0, 0, 0), 0.1, 1.0))
    assert _status(core).level == Level.OK
    core.step(Intake(_at(2.0), (60, 200, 1), (0, 3, 0), 0.9, 1.0, (140, 0, 0)))
    status = _status(core)
    values = dict(status.values)
    assert status.level == Level.ERROR, status  # 143 of 805 not stepped: 18 %
    assert values['messages_dropped'] == '143'
    assert values['line_01.messages_dropped'] == '140'
    assert values['line_02.messages_dropped'] == '3'
    assert values['messages_coalesced'] == '140' and values['messages_handled'] == '662'
    assert status.message.startswith(
        'node cannot keep up: 18 % of tension and depth samples dropped in the last 60 s '
        '(143 of 805); 140 coalesced (logged, the newer sample of their input handled '
        'instead), 3 lost before the node'
    ), status.message
    assert 'none dropped' not in status.message
    core.step(Intake(_at(3.0), (200, 200, 1), (0, 0, 0), 0.1, 1.0, (0, 0, 0)))
    assert _status(core).level == Level.ERROR  # the window still holds them


def test_coalesced_samples_are_not_missing_against_the_sample_rate():
    """Samples taken and coalesced reached the node: not counted missing too."""
    core = MonitorCore(dock_config(1, tension_sample_rate=200.0), T0_NS)
    core.step(Intake(_at(1.0), (200, 1), (0, 0), 0.1, 1.0))
    core.step(Intake(_at(11.0), (500, 10), (0, 0), 9.0, 10.0, (1500, 0)))
    values = dict(_status(core).values)
    assert values['messages_missing'] == '0'
    assert values['messages_dropped'] == values['messages_coalesced'] == '1500'


def test_a_lone_lost_sample_is_counted_not_annunciated():
    """A WARN needs intake_warn_count samples AND intake_warn_share of the window's: 3 of
    7640 lost stay OK with the counts in the values and the message; 100 of 7640 (1.3 %)
    warn; 15 of 7640 (0.2 %) stay OK; ERROR from 5 % as ever."""
    from catenary_monitor.core.rules.health import intake_status

    level, text = intake_status(7637, 3, float("nan"), 60.0)
    assert level == Level.OK
    assert text == (
        '3 of 7640 tension and depth samples dropped in the last 60 s (0.0 %): below the '
        'warning (10 samples and 1 %)'
    )
    assert intake_status(7540, 100, 0.01, 60.0)[0] == Level.WARN
    assert intake_status(7625, 15, 0.01, 60.0)[0] == Level.OK
    assert intake_status(19, 1, 0.01, 60.0)[0] == Level.ERROR  # 5 %: ERROR as ever
    assert intake_status(7637, 3, 0.01, 60.0, warn_count=1, warn_share=0.0)[0] == Level.WARN
    core = MonitorCore(dock_config(1), T0_NS)
    core.step(Intake(_at(1.0), (100, 1), (0, 0), 0.01, 1.0))
    core.step(Intake(_at(11.0), (997, 10), (3, 0), 0.01, 10.0))
    status = _status(core)
    assert status.level == Level.OK and dict(status.values)['messages_dropped'] == '3'
    assert 'none dropped' not in status.message


def test_a_busy_node_says_the_smaller_loss_it_counted():
    """A node busy 70 % of the time warns that it cannot keep up; 5 of 2005 samples lost
    (below the warning) are said in that message too, with their figures, and counted in the
    values: a warning about the load never hides a loss the node has counted."""
    from catenary_monitor.core.rules.health import intake_status

    level, text = intake_status(2000, 5, 0.7, 60.0)
    assert level == Level.WARN
    assert text == (
        'node cannot keep up: busy 70 % of the last 5 s in callbacks (samples may be lost); '
        '5 of 2005 tension and depth samples dropped in the last 60 s (0.2 %): below the '
        'warning (10 samples and 1 %)'
    )
    assert 'dropped' not in intake_status(2005, 0, 0.7, 60.0)[1]  # nothing lost: not said
    core = MonitorCore(dock_config(1), T0_NS)
    core.step(Intake(_at(1.0), (100, 1), (0, 0), 0.7, 1.0))
    core.step(Intake(_at(2.0), (997, 10), (3, 0), 0.7, 1.0))
    status = _status(core)
    assert status.level == Level.WARN and dict(status.values)['messages_dropped'] == '3'
    assert status.message.startswith('node cannot keep up: busy 70 %')
    assert '3 of 1111 tension and depth samples dropped' in status.message

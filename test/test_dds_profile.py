"""The participants' announcement profile (catenary_monitor/ros/dds_profile.py): used only when
nothing else configures Fast DDS, and a profile Fast DDS reads (1 s announcements)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from catenary_monitor.ros.dds_profile import PROFILE, use_announce_profile

NS = '{http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles}'


def test_the_profile_is_set_when_nothing_configures_fast_dds(tmp_path):
    env: dict[str, str] = {'ROS_DOMAIN_ID': '7'}
    assert use_announce_profile(env, tmp_path) == str(PROFILE)
    assert env['FASTRTPS_DEFAULT_PROFILES_FILE'] == str(PROFILE)
    env = {'RMW_IMPLEMENTATION': 'rmw_fastrtps_cpp'}
    assert use_announce_profile(env, tmp_path) == str(PROFILE)


@pytest.mark.parametrize(
    'name, value',
    [
        ('FASTRTPS_DEFAULT_PROFILES_FILE', '/etc/dds/own.xml'),
        ('FASTDDS_DEFAULT_PROFILES_FILE', '/etc/dds/own.xml'),
        ('ROS_DISCOVERY_SERVER', '127.0.0.1:11811'),
        ('SKIP_DEFAULT_XML', '1'),
        ('RMW_IMPLEMENTATION', 'rmw_cyclonedds_cpp'),
        ('RMW_IMPLEMENTATION', 'rmw_zenoh_cpp'),
    ],
)
def test_a_deployments_own_settings_win(tmp_path, name, value):
    env = {name: value}
    assert use_announce_profile(env, tmp_path) is None
    assert env == {name: value}


@pytest.mark.parametrize('name', ['DEFAULT_FASTRTPS_PROFILES.xml', 'DEFAULT_FASTDDS_PROFILES.xml'])
def test_a_profile_in_the_working_folder_wins(tmp_path, name):
    (tmp_path / name).write_text('<profiles/>')
    env: dict[str, str] = {}
    assert use_announce_profile(env, tmp_path) is None and env == {}


def test_the_profile_announces_every_second_and_is_the_default():
    root = ET.parse(PROFILE).getroot()
    (participant,) = root.findall(f'{NS}participant')
    assert participant.get('is_default_profile') == 'true'
    lease = participant.find(f'{NS}rtps/{NS}builtin/{NS}discovery_config/{NS}leaseAnnouncement')
    assert lease is not None
    assert (lease.findtext(f'{NS}sec'), lease.findtext(f'{NS}nanosec')) == ('1', '0')
    # nothing else: the rmw's own settings (discovery range, transports) stay as they are
    tags = [e.tag.removeprefix(NS) for e in participant.iter()]
    assert tags == ['participant', 'rtps', 'builtin', 'discovery_config', 'leaseAnnouncement',
                    'sec', 'nanosec']  # fmt: skip

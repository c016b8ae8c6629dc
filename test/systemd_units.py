"""The systemd units of deploy/, read as systemd reads them, and their commands moved onto a test
machine's places (a venv for /opt/catenary_monitor/.venv, temporary folders for /etc, /var/lib
and /var/log)."""

from __future__ import annotations

import configparser
import re
import shlex
from pathlib import Path
from typing import Mapping

ROOT = Path(__file__).resolve().parents[1]
UNITS = ('catenary-monitor.service', 'catenary-monitor-console.service')
#: The harbour PC's unit (no monitor there).
HARBOUR_UNIT = 'catenary-monitor-harbour.service'
VENV = '/opt/catenary_monitor/.venv'
STATE = '/var/lib/catenary_monitor'
LOGS = '/var/log/catenary_monitor'
ETC = '/etc/catenary_monitor'
#: The environment systemd gives every service besides Environment= (systemd.exec(5)), for a
#: user whose home does not exist.
BASE_ENV = {
    'PATH': '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin',
    'LANG': 'C.UTF-8',
    'HOME': '/nonexistent',
    'USER': 'nobody',
    'LOGNAME': 'nobody',
    'SHELL': '/usr/sbin/nologin',
}


def read_unit(name: str) -> tuple[configparser.ConfigParser, dict[str, str]]:
    """The unit's sections and its ``Environment=`` variables, in order."""
    text = (ROOT / 'deploy' / name).read_text()
    unit = configparser.ConfigParser(strict=False, interpolation=None)
    unit.optionxform = str  # type: ignore[assignment,method-assign]
    unit.read_string(text)
    environment = dict(re.findall(r'^Environment=(\S+?)=(.*)$', text, re.M))
    return unit, environment


def moved(text: str, places: Mapping[str, str]) -> str:
    """``text`` with each of the unit's paths replaced by the test's (longest first)."""
    for old in sorted(places, key=len, reverse=True):
        text = text.replace(old, places[old])
    return text


def command(name: str, places: Mapping[str, str]) -> tuple[list[str], dict[str, str]]:
    """The unit's ``ExecStart`` and its ``Environment=`` on the test's places."""
    unit, environment = read_unit(name)
    argv = [moved(a, places) for a in shlex.split(unit['Service']['ExecStart'])]
    return argv, {k: moved(v, places) for k, v in environment.items()}

"""The participants' announcement period: every second, not Fast DDS's 3 s.

A participant that joins a domain announces itself and the others answer at once; on a busy
PC that first answer is often lost, and the newcomer then meets each peer only at the peer's
next periodic announcement: up to 3 s later with Fast DDS's default (measured here: the
harbour's first array from a dock 0.1 s or 2-3 s after its start, half the time the second).
With every participant announcing each second, the monitor and the harbour meet within a
second whichever joined last (docs/deploy.md, section 9).

:func:`use_announce_profile` points Fast DDS at the package's profile
(``fastdds_announce.xml``) before rclpy starts, only when nothing else configures Fast DDS:
no profile file in the environment or the working folder, no discovery server, the default
or a Fast DDS rmw. A deployment's own profile always wins.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import MutableMapping, Optional

__all__ = ['PROFILE', 'use_announce_profile']

#: The package's Fast DDS profile: a participant announcement every 1 s.
PROFILE = Path(__file__).with_name('fastdds_announce.xml')
#: Settings that configure Fast DDS otherwise: any of them set, the profile is not used.
_CONFIGURED = (
    'FASTRTPS_DEFAULT_PROFILES_FILE',
    'FASTDDS_DEFAULT_PROFILES_FILE',
    'ROS_DISCOVERY_SERVER',
    'SKIP_DEFAULT_XML',
)
#: The profile files Fast DDS reads from the working folder by itself.
_CWD_PROFILES = ('DEFAULT_FASTRTPS_PROFILES.xml', 'DEFAULT_FASTDDS_PROFILES.xml')
_FAST_DDS = ('', 'rmw_fastrtps_cpp', 'rmw_fastrtps_dynamic_cpp')


def use_announce_profile(
    environ: Optional[MutableMapping[str, str]] = None, cwd: Optional[Path] = None
) -> Optional[str]:
    """Set ``FASTRTPS_DEFAULT_PROFILES_FILE`` to :data:`PROFILE` in ``environ`` (this
    process's) unless Fast DDS is configured otherwise or not the rmw; the file set or None.
    Call it before ``rclpy.init``."""
    env = os.environ if environ is None else environ
    folder = Path.cwd() if cwd is None else cwd
    if any(env.get(name) for name in _CONFIGURED):
        return None
    if env.get('RMW_IMPLEMENTATION', '') not in _FAST_DDS:
        return None
    if not PROFILE.is_file() or any((folder / f).exists() for f in _CWD_PROFILES):
        return None
    env['FASTRTPS_DEFAULT_PROFILES_FILE'] = str(PROFILE)
    return str(PROFILE)

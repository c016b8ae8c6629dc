"""Shared test set-up: keep DDS discovery on this machine, one domain per test session."""

import os
import random

import pytest

os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
os.environ.setdefault('ROS_DOMAIN_ID', str(random.Random(os.getpid()).randint(100, 200)))


def _build_kernels() -> None:
    """Build core/_kernels.c in place when the tree has no up-to-date build (the tests import the
    package from this tree, not from where pip installed it); test_kernels fails if it cannot."""
    import subprocess
    import sys
    import sysconfig
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    core = root / 'catenary_monitor' / 'core'
    so = core / ('_kernels' + sysconfig.get_config_var('EXT_SUFFIX'))
    newest = max(p.stat().st_mtime for p in core.glob('_kernels*.[ch]'))
    if so.exists() and so.stat().st_mtime >= newest:
        return
    so.unlink(missing_ok=True)  # a failed build must not leave a stale kernel behind
    done = subprocess.run(
        [sys.executable, 'setup.py', '-q', 'build_ext', '--inplace'],
        cwd=root,
        capture_output=True,
        text=True,
    )
    if done.returncode:
        print(f'conftest: building core/_kernels.c failed:\n{done.stderr[-2000:]}')


_build_kernels()


def _isas() -> list:
    """The kernel's instruction sets this CPU runs, once it is built ('none': not built)."""
    from catenary_monitor.core import kernels

    return kernels.supported() or ['none']


@pytest.fixture(params=_isas())
def isa(request):
    """Each instruction set of the C kernel in turn (test_kernels, test_extremes)."""
    from catenary_monitor.core import kernels

    if request.param == 'none':
        pytest.fail('no kernel to test: python setup.py build_ext --inplace')
    before = kernels.isa()
    kernels.set_isa(request.param)
    yield request.param
    kernels.set_isa(before)

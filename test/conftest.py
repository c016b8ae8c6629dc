"""Shared test set-up: keep DDS discovery on this machine, one domain per test session."""

import os
import random

import pytest

os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')


def _domain() -> int:
    """The DDS domain of this test session: ROS_DOMAIN_ID when given, else one of its own; under
    pytest-xdist (-n N) the next ones, one per worker (the workers inherit the controller's),
    so that two workers' nodes on the same topic names never meet."""
    given = os.environ.get('ROS_DOMAIN_ID', '')
    base = int(given) if given.isdigit() else random.Random(os.getpid()).randint(100, 200)
    worker = os.environ.get('PYTEST_XDIST_WORKER', '')
    return base + 1 + int(worker[2:]) % 16 if worker[2:].isdigit() else base


os.environ['ROS_DOMAIN_ID'] = str(_domain())


#: The C accelerators (setup.py): their sources, and the built module beside them.
EXTENSIONS = {
    'catenary_monitor/core/physics/_fused_kernel': ('_fused_kernel.c', '_fused_kernel_body.h'),
    'catenary_monitor/io/_scan': ('_scan.c',),
    'catenary_monitor/core/twin/_twin_loops': ('_twin_loops.c',),
    'catenary_monitor/core/rules/_fatigue_loop': ('_fatigue_loop.c',),
    'catenary_monitor/core/rules/_wave_loop': ('_wave_loop.c',),
}


def _build_extensions() -> None:
    """Build the C accelerators in place when the tree has no up-to-date build of one (the tests
    import the package from this tree, not from where pip installed it); test_kernels,
    test_mcap_scan and test_batch_steps fail if one cannot be built. Nothing is built when
    CATENARY_MONITOR_NO_EXTENSIONS=1 (the no-compiler run, test_no_compiler.py)."""
    import fcntl
    from pathlib import Path

    if os.environ.get('CATENARY_MONITOR_NO_EXTENSIONS') == '1':
        return
    root = Path(__file__).resolve().parent.parent
    (root / 'build').mkdir(exist_ok=True)
    with open(root / 'build' / '.conftest.lock', 'w') as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # pytest-xdist's processes start together: one builds
        _build_stale(root)


def _build_stale(root) -> None:
    import subprocess
    import sys
    import sysconfig

    suffix = sysconfig.get_config_var('EXT_SUFFIX')
    stale = []
    for module, sources in EXTENSIONS.items():
        so = root / (module + suffix)
        newest = max((so.parent / name).stat().st_mtime for name in sources)
        if not so.exists() or so.stat().st_mtime < newest:
            so.unlink(missing_ok=True)  # a failed build must not leave a stale module behind
            stale.append(module)
    if not stale:
        return
    done = subprocess.run(
        [sys.executable, 'setup.py', '-q', 'build_ext', '--inplace'],
        cwd=root,
        capture_output=True,
        text=True,
    )
    if done.returncode:
        print(f'conftest: building {", ".join(stale)} failed:\n{done.stderr[-2000:]}')


_build_extensions()


def _isas() -> list:
    """The kernel's instruction sets this CPU runs, once it is built ('none': not built)."""
    from catenary_monitor.core.physics import fused_kernel

    return fused_kernel.supported() or ['none']


@pytest.fixture(params=_isas())
def isa(request):
    """Each instruction set of the C kernel in turn (test_kernels, test_extremes)."""
    from catenary_monitor.core.physics import fused_kernel

    if request.param == 'none':
        pytest.fail('no kernel to test: python setup.py build_ext --inplace')
    before = fused_kernel.isa()
    fused_kernel.set_isa(request.param)
    yield request.param
    fused_kernel.set_isa(before)


def pytest_collection_modifyitems(items):
    """A test of the C kernel's instruction sets needs the kernel: marked ``c_extension``."""
    for item in items:
        if 'isa' in getattr(item, 'fixturenames', ()):
            item.add_marker(pytest.mark.c_extension)


@pytest.fixture
def no_callback_errors():
    """A monitor that logged an exception in a callback fails the test, even if it went on (the
    node tests' modules use it: ``pytest.mark.usefixtures('no_callback_errors')``)."""
    from ros_harness import callback_errors

    callback_errors()
    yield
    errors = callback_errors()
    assert not errors, errors[:3]


@pytest.fixture(scope='module')
def client(request):
    """One test node (ros_harness.Client) per test module that asks for it, named after it."""
    from ros_harness import Client

    c = Client(f'{request.module.__name__}_client')
    yield c
    c.close()

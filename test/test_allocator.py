"""The command-line processes keep freed memory for reuse (glibc mallopt), and only they do."""

import platform
import subprocess
import sys

from catenary_monitor.cli import allocator


def test_keep_freed_memory_applies_on_glibc_and_is_a_no_op_elsewhere():
    glibc = platform.system() == 'Linux' and platform.libc_ver()[0] == 'glibc'
    assert allocator.keep_freed_memory() is glibc


def test_importing_the_library_leaves_the_allocator_alone():
    code = (
        'import catenary_monitor, catenary_monitor.core.physics.solve, '
        'catenary_monitor.core.physics.elastic, sys; '
        'sys.exit(int("catenary_monitor.cli.allocator" in sys.modules))'
    )
    assert subprocess.run([sys.executable, '-c', code]).returncode == 0

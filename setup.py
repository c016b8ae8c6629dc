"""ament_python package that also installs with plain ``pip install .``."""

import platform
import sys
from glob import glob

from setuptools import Extension, find_packages, setup

package_name = 'catenary_monitor'

# The fused problem-3/4 kernel (docs/benchmarks.md, "Where the time goes"). Vectorized with
# glibc's libmvec on x86-64 Linux; elsewhere a plain C loop. Optional: without a C compiler the
# package installs and solve() uses its numpy implementation (catenary_monitor.core.kernels).
_linux = sys.platform.startswith('linux')
_mvec = _linux and platform.machine() in ('x86_64', 'AMD64')
kernels = Extension(
    'catenary_monitor.core._kernels',
    sources=['catenary_monitor/core/_kernels.c'],
    depends=['catenary_monitor/core/_kernels_body.h'],
    extra_compile_args=[
        '-O3',
        '-fopenmp-simd',
        '-fno-math-errno',
        '-fno-trapping-math',
        '-ffp-contract=off',
        # no scalar prologue that depends on an array's address: every element takes the
        # same vector code wherever it lies (a windowed replay gives the whole log's bits)
        '--param=vect-max-peeling-for-alignment=0',
    ],
    libraries=(['mvec'] if _mvec else []) + ['m'] + (['pthread'] if _linux else []),
    optional=True,
)

# The MCAP reader's per-record loops (index check, gathers, Float64 columns). Optional too:
# without it the reader runs its numpy passes, which give the same results
# (catenary_monitor.io.mcap_read, test/test_mcap_scan.py).
scan = Extension(
    'catenary_monitor.io._scan',
    sources=['catenary_monitor/io/_scan.c'],
    extra_compile_args=['-O2'],
    optional=True,
)

# Loops of the vectorized replay (core/batch.py: the step merge, the step indexes and the
# picks; core/alarms.py: the latch; core/sensor.py: the sensor memory; core/tide_trend.py: the
# time to uplift). Optional: without it those modules run their numpy passes, which give the
# same arrays.
steps = Extension(
    'catenary_monitor.core._steps',
    sources=['catenary_monitor/core/_steps.c'],
    extra_compile_args=['-O2', '-ffp-contract=off'],
    optional=True,
)

setup(
    name=package_name,
    version='0.2.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['py.typed', 'data/*', 'console/static/*']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
        ('share/' + package_name + '/foxglove', glob('foxglove/*.json')),
    ],
    python_requires='>=3.10',
    install_requires=[
        'setuptools',
        'numpy>=1.24',
        'scipy>=1.10',
        'pyyaml',
        'matplotlib>=3.7',
        'mcap>=1.1',
        'mcap-ros2-support>=0.5',
        'ros-jazzy-rclpy[fastrtps]',
        'ros-jazzy-common-interfaces',
    ],
    extras_require={
        # The test suite also checks the peers (MoorPy, pycatenary): nothing there is skipped.
        'test': [
            'pytest>=7',
            'hypothesis>=6',
            'mpmath>=1.3',
            'flake8>=6',
            'mypy>=1.8',
            'pytest-timeout',
            # The console's browser tests drive Debian's chromium through /usr/bin/chromedriver.
            'selenium>=4.10',
            'moorpy',
            'pycatenary',
            # Independent readers of the MCAP logs and the bag folder (issue 10).
            'rosbags>=0.10',
            'pymcap-cli',
        ],
        'peers': ['moorpy', 'pycatenary'],
    },
    ext_modules=[kernels, scan, steps],
    zip_safe=False,
    maintainer='catenary_monitor developers',
    maintainer_email='catenary-monitor@example.org',
    description='Live anchor-uplift monitor for moored floating docks (ROS 2 Jazzy).',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'catenary-monitor = catenary_monitor.cli.main:main',
            'monitor = catenary_monitor.ros.node:main',
            'dock_simulator = catenary_monitor.ros.simulator:main',
        ],
        # The benchmarks and the methods study add their sub-commands through this group.
        'catenary_monitor.commands': ['study = catenary_monitor_study.commands:register'],
    },
)

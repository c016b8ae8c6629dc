"""ament_python package that also installs with plain ``pip install .``."""

import os
import platform
import sys
from glob import glob

from setuptools import Extension, find_packages, setup

package_name = 'catenary_monitor'

# Five optional C accelerators, each measured faster than the numpy code it replaces and tested
# equal to it (docs/benchmarks.md). Without a C compiler the build of each fails with a warning
# and the package installs and runs on its numpy paths, with the same results.
# CATENARY_MONITOR_NO_EXTENSIONS=1 builds none of them (what test/test_no_compiler.py installs).
_linux = sys.platform.startswith('linux')
_mvec = _linux and platform.machine() in ('x86_64', 'AMD64')

# The fused problem-3/4 kernel of solve() (core/physics/fused_kernel.py loads it). Vectorized
# with glibc's libmvec on x86-64 Linux; elsewhere a plain C loop.
fused_kernel = Extension(
    'catenary_monitor.core.physics._fused_kernel',
    sources=['catenary_monitor/core/physics/_fused_kernel.c'],
    depends=['catenary_monitor/core/physics/_fused_kernel_body.h'],
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

# The MCAP reader's per-record loops: index check, gathers, Float64 columns (io/mcap_scan.py).
scan = Extension(
    'catenary_monitor.io._scan',
    sources=['catenary_monitor/io/_scan.c'],
    extra_compile_args=['-O2'],
    optional=True,
)

# The vectorized twin's schedule loops (core/twin/schedule.py): step merge, step indexes, picks.
twin_loops = Extension(
    'catenary_monitor.core.twin._twin_loops',
    sources=['catenary_monitor/core/twin/_twin_loops.c'],
    extra_compile_args=['-O2', '-ffp-contract=off'],
    optional=True,
)

# The fatigue count's column loop (core/rules/fatigue.py): streamed rainflow and Miner's damage.
fatigue_loop = Extension(
    'catenary_monitor.core.rules._fatigue_loop',
    sources=['catenary_monitor/core/rules/_fatigue_loop.c'],
    extra_compile_args=['-O2', '-ffp-contract=off'],
    optional=True,
)
# The wave window's column loop (core/rules/wave_window.py): the window's extremes per reading.
wave_loop = Extension(
    'catenary_monitor.core.rules._wave_loop',
    sources=['catenary_monitor/core/rules/_wave_loop.c'],
    extra_compile_args=['-O2'],
    optional=True,
)
EXTENSIONS = (
    []
    if os.environ.get('CATENARY_MONITOR_NO_EXTENSIONS') == '1'
    else [
        fused_kernel,
        scan,
        twin_loops,
        fatigue_loop,
        wave_loop,
    ]
)

setup(
    name=package_name,
    version='0.2.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['py.typed', 'console/static/*', 'ros/*.xml']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
        ('share/' + package_name + '/foxglove', glob('foxglove/*.json')),
        ('share/' + package_name + '/launch', glob('launch/*.launch.xml')),
        ('share/' + package_name + '/deploy', glob('deploy/*.service')),
        # the units' Documentation=
        ('share/' + package_name + '/docs', ['docs/deploy.md']),
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
        # The MCAP reader's own chunk decompression (io/mcap_scan.py).
        'zstandard',
        'lz4',
        # The console's HTTP/1.1 framing (pure Python, no dependencies).
        'h11>=0.14',
        'ros-jazzy-rclpy[fastrtps]',
        'ros-jazzy-common-interfaces',
        # The sensors' own messages (WrenchStamped, FluidPressure, Range) and replay's /clock.
        'ros-jazzy-geometry-msgs',
        'ros-jazzy-sensor-msgs',
        'ros-jazzy-rosgraph-msgs',
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
            # Two test processes (-n 2 --dist loadfile, README): each its own DDS domain.
            'pytest-xdist>=3',
            # The console's browser tests drive Debian's chromium through /usr/bin/chromedriver.
            'selenium>=4.10',
            'moorpy',
            'pycatenary',
            # Independent readers of the MCAP logs and the bag folder.
            'rosbags>=0.10',
            'pymcap-cli',
            # Two rainflow counts (ASTM E1049-85) the streamed fatigue count is tested against.
            'rainflow>=3.2',
            'fatpack>=0.7',
            # NREL's lumped-mass mooring model: the dynamic reference (docs/dynamics.md).
            'moordyn>=2.3',
            # The fleet replay (the fleet extra) and DuckDB, which answers docs/fleet.md's
            # questions over its dataset in the tests.
            'dask[distributed]>=2024.1',
            'pyarrow>=14',
            'duckdb>=1.0',
        ],
        'peers': ['moorpy', 'pycatenary'],
        # catenary-monitor bench-dynamics and the MoorDyn scenes (docs/dynamics.md)
        'dynamics': ['moordyn>=2.3'],
        # catenary-monitor fleet: many docks' logs replayed on Dask, results as Parquet.
        'fleet': ['dask[distributed]>=2024.1', 'pyarrow>=14'],
        # catenary-monitor fuzz (docs/fuzzing.md): Hypothesis always; --atheris needs atheris
        # (libFuzzer; wheels for CPython on Linux x86_64).
        'fuzz': ['hypothesis>=6', 'atheris>=2.3'],
    },
    ext_modules=EXTENSIONS,
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
        # The console and the benchmarks add their sub-commands through this group (the
        # command line imports neither).
        'catenary_monitor.commands': [
            'console = catenary_monitor.console.command:register',
            'study = catenary_monitor_study.commands:register',
        ],
    },
)

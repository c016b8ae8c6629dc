"""Linters, ament style: flake8 over the package and the tests (config in setup.cfg)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.linter
def test_flake8():
    p = subprocess.run(
        [
            sys.executable,
            '-m',
            'flake8',
            'catenary_monitor',
            'catenary_monitor_study',
            'test',
            'tools',
            'setup.py',
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stdout + p.stderr

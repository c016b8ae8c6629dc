"""Static types: mypy over the package and the study, 0 errors (config in setup.cfg)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.linter
def test_mypy():
    # The [mypy] section of setup.cfg names the files and the strictness; no arguments here.
    p = subprocess.run(
        [sys.executable, '-m', 'mypy'], cwd=ROOT, capture_output=True, text=True, timeout=240
    )
    assert p.returncode == 0, p.stdout + p.stderr

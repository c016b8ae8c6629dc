"""CI runs the README's test command verbatim (.ci/run holds the same line)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_ci_runs_the_readme_test_command():
    readme = ROOT.joinpath('README.md').read_text(encoding='utf-8')
    block = re.search(r'# 2\..*?\n((?:#.*\n)*)(.+)\n```', readme)
    assert block, 'README command 2 not found'
    command = block.group(2).strip()
    run = ROOT.joinpath('.ci', 'run').read_text(encoding='utf-8').strip().splitlines()
    assert run[-1].strip() == command
    # the browser tests' and the JS reader tests' needs
    assert 'chromium chromium-driver nodejs npm' in command

"""A command line naming one of the commands in ``ALONE`` builds only that command's parser:
the same parser as in the whole command line, and nothing else beside ``solve`` and ``paper``."""

import argparse

import pytest

from catenary_monitor.cli import main as cli


def _same(value):
    """A value to compare: a lambda made by each registration by its code."""
    return getattr(value, '__code__', value)


def _commands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


@pytest.mark.parametrize('command', sorted(cli.ALONE))
def test_a_command_alone_has_the_parser_of_the_whole_command_line(command):
    whole, alone = _commands(cli.build_parser()), _commands(cli.build_parser(command))
    assert set(alone) == {'solve', 'paper', command}
    assert alone[command].format_help() == whole[command].format_help()
    assert {k: _same(v) for k, v in alone[command]._defaults.items()} == {
        k: _same(v) for k, v in whole[command]._defaults.items()
    }


def test_replay_parses_alike_alone_and_whole():
    argv = ['replay', 'a.mcap', '--params-file', 'p.yaml', '--quiet', '--json']
    alone = vars(cli.build_parser('replay').parse_args(argv))
    whole = vars(cli.build_parser().parse_args(argv))
    assert {k: _same(v) for k, v in alone.items()} == {k: _same(v) for k, v in whole.items()}

#!/usr/bin/env python3
"""Time two whole commands in turn (A B A B ...) and print each one's wall time, CPU time
(user + system of the finished child) and peak RSS, and the ratio A/B pair by pair.

Pairing keeps a ratio meaningful on a machine whose speed drifts; quote the median.

    python tools/pairs.py -n 5 --vs "sh -c 'cd OLD && exec CMD'" -- sh -c 'cd NEW && exec CMD'
"""
import argparse
import os
import shlex
import statistics
import subprocess
import sys
import time
from typing import Dict, List, Sequence


def run_once(cmd: Sequence[str]) -> Dict[str, float]:
    """Run `cmd` once, its output discarded: wall [s], cpu [s], peak [MiB], rc."""
    start = time.monotonic()
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.monotonic() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    return {'wall': wall, 'cpu': usage.ru_utime + usage.ru_stime,
            'peak': usage.ru_maxrss / 1024.0, 'rc': float(proc.returncode)}


def spread(values: List[float]) -> str:
    """'median (min-max)' of `values`."""
    return f'{statistics.median(values):.3f} ({min(values):.3f}-{max(values):.3f})'


def main(argv: Sequence[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('-n', type=int, default=5, help='counted runs of each command')
    parser.add_argument('--warmup', type=int, default=1, help='uncounted runs first')
    parser.add_argument('--vs', default='', help='the baseline command B, one string')
    parser.add_argument('command', nargs=argparse.REMAINDER, help='-- COMMAND A ...')
    args = parser.parse_args(argv)
    cmd_a = args.command[1:] if args.command[:1] == ['--'] else args.command
    if not cmd_a:
        parser.error('give the command to time after --')
    cmds = {'A': cmd_a, 'B': shlex.split(args.vs)} if args.vs else {'A': cmd_a}
    runs: Dict[str, List[Dict[str, float]]] = {k: [] for k in cmds}
    for i in range(args.warmup + args.n):
        for name, cmd in cmds.items():
            result = run_once(cmd)
            if i >= args.warmup:
                runs[name].append(result)
    print(f'{time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}, {os.cpu_count()} CPUs, '
          f'load {os.getloadavg()[0]:.1f}; median (min-max) of {args.n} runs')
    for name, results in runs.items():
        failed = sum(1 for r in results if r['rc'] != 0)
        note = f', {failed} failed' if failed else ''
        print(f'{name}: wall {spread([r["wall"] for r in results])} s, cpu '
              f'{spread([r["cpu"] for r in results])} s, peak '
              f'{spread([r["peak"] for r in results])} MiB{note}')
    if 'B' in runs:
        for key in ('wall', 'cpu'):
            ratios = [a[key] / b[key] for a, b in zip(runs['A'], runs['B']) if b[key] > 0]
            print(f'A/B {key}: {spread(ratios)}')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))

"""Public peers that can express our problems (optional: ``pip install .[peers]``).

Both peers solve a mooring line of *given unstretched length* L between two points; neither takes
a measured hook tension.  So we run them two ways:

* ``(L given)``: one call on the same scene, with the suspended length L of the 50-digit problem-4
  answer, compared with the 50-digit answer for that very L (``reference.given_length``).  This is
  the cost of one peer catenary evaluation, the figure the issue's 20x target is set against.
* ``MoorPy + brentq on L``: problem 4 as a MoorPy user would solve it, a brentq on L until the
  fairlead tension equals the measured T (many MoorPy calls per solve).

MoorPy needs a finite axial stiffness: we pass ``EA = 1e12 T`` (stretch ~1e-12, below what the
comparison resolves; much stiffer lines make MoorPy return an all-zero profile).  MoorPy calls
``breakpoint()`` on some error paths, so the benchmark sets ``PYTHONBREAKPOINT=0``.
"""

from __future__ import annotations

import math
import os
from typing import Any

from scipy import optimize

from .base import Method, NoConvergence

os.environ.setdefault('PYTHONBREAKPOINT', '0')


def _moorpy() -> Any:
    from moorpy.Catenary import catenary

    return catenary


def _ea(w: float, h: float, x: float, length: float) -> float:
    # hook tension is below w (a + h) with a <= span: a scale for the stiffness
    return 1e12 * w * (x + h + length)


def moorpy_given_length(w: float, h: float, x: float, length: float) -> tuple[float, float]:
    fah, fav, _, _, _ = _moorpy()(x, h, length, _ea(w, h, x, length), w)
    return float(fah), float(fav)


def moorpy_brentq(w: float, h: float, t: float, x: float) -> tuple[float, float]:
    catenary = _moorpy()
    ea = 1e12 * t

    def excess(length: float) -> float:
        _, _, fbh, fbv, _ = catenary(x, h, length, ea, w)
        return math.hypot(fbh, fbv) - t

    lo, hi = math.hypot(x, h) * (1.0 + 1e-9), x + h
    length, res = optimize.brentq(excess, lo, hi, xtol=5e-324, full_output=True, disp=False)
    if not res.converged:
        raise NoConvergence(res.flag)
    fah, fav, _, _, _ = catenary(x, h, length, ea, w)
    return float(fah), float(fav)


def pycatenary_given_length(w: float, h: float, x: float, length: float) -> tuple[float, float]:
    import pycatenary

    line = pycatenary.MooringLine(
        fairlead=[x, h], anchor=[0.0, 0.0], L=length, w=w, EA=None, floor=True
    )
    line.compute_solution()
    fx, fz = line.get_anchor_force()
    return abs(float(fx)), abs(float(fz))


PEERS = {
    'moorpy': [
        Method(
            'MoorPy catenary (L given)',
            4,
            moorpy_given_length,
            None,
            'peers',
            given='length',
            why='absolute tolerance: Tol = 1e-6 m on the line-end position, whatever the '
            'scale; no profile for very short or very long catenaries',
        ),
        Method(
            'MoorPy + brentq on L',
            4,
            moorpy_brentq,
            None,
            'peers',
            slow=True,
            why="bracket missing the root: our wrapper's [taut chord (1 + 1e-9), x + h] misses it "
            'where MoorPy\'s tension at 1e-9 stretch does not exceed the measured T (large a, '
            "and steep chains with h >> a); elsewhere MoorPy's absolute 1e-6 m tolerance, "
            'amplified by dT/dL',
        ),
    ],
    'pycatenary': [
        Method(
            'pycatenary (L given)',
            4,
            pycatenary_given_length,
            None,
            'peers',
            given='length',
            why='cancelling formulas (cosh(d/a) - 1, 2a sinh(d/2a) - chord) for a >> x: '
            'its profile '
            'test and bisection run on rounding noise ("Line is too stretched"); and a bracket '
            '[1e-2, 1e10] m that misses a < 1 cm, where it silently returns the bracket end',
        ),
    ],
}


def peer_versions() -> dict[str, str | None]:
    """Installed version of each peer, None if absent."""
    from importlib import metadata

    out: dict[str, str | None] = {}
    for name in PEERS:
        try:
            __import__(name)
            out[name] = metadata.version(name)
        except Exception:  # not installed, or installed but not importable: absent
            out[name] = None
    return out


def available_methods() -> list[Method]:
    out: list[Method] = []
    for name, methods in PEERS.items():
        try:
            __import__(name)
        except Exception:  # absent or broken: the benchmark reports it as absent
            continue
        out.extend(methods)
    return out

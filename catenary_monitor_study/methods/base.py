"""The common interface of the alternative methods (the registry is the package's)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Optional

#: An answer further than this (relative) from the 50-digit reference counts as a failure.
FAIL_RTOL = 1e-6


class NoConvergence(RuntimeError):
    """An iterative method gave up (iteration cap reached or its search lost the root)."""


@dataclass(frozen=True)
class Method:
    """One way of solving one catenary problem.

    ``scalar_fn`` takes plain floats; ``vector_fn`` (or None) takes 1-D float arrays of one length
    and returns arrays with NaN where it failed.  ``family`` names the module; ``why`` says, in one
    sentence, why the method fails where it fails (shown next to the stability map); ``slow``
    methods are run on a thinned scene set by the benchmark; ``default`` marks the project's own.
    """

    name: str
    problem: int
    scalar_fn: Callable[..., tuple[float, float]]
    vector_fn: Optional[Callable[..., tuple[Any, Any]]] = None
    family: str = ''
    why: str = ''
    slow: bool = False
    default: bool = False
    #: 'load' for the problem as stated above; 'length' for peers that need the chain length:
    #: ``fn(w, h, x, L) -> (R, F)``, compared with the reference for that same L.
    given: str = 'load'

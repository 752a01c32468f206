"""Choices between candidates that mean the same on every machine (docs/model.md,
"Near-ties").

Two machines round floating-point sums differently (another BLAS kernel, another SIMD
width), so the same cost can differ in its last digits from one machine to the next. A
choice decided by such a difference would flip between machines. Every choice of the
planner between candidates (the search's swaps and optima, the swarm's bests, the
finalists, the sweep's recommendation) therefore goes through this module: costs within
:data:`TIE_RTOL` of each other are a tie, and a tie goes to the candidate that comes first
in the order the caller gives (its index: a fixed order that does not depend on the costs).

A difference below :data:`TIE_RTOL` never decides a choice. A choice can still flip when
two costs differ by almost exactly :data:`TIE_RTOL`, to within the machines' rounding
(about 1e-12 relative here); that is as unlikely as two costs that agree to 1e-12 are
without the rule.
"""

from __future__ import annotations

import math

import numpy as np

#: costs closer than this, relative to the smaller, are a tie
TIE_RTOL = 1e-6


def _key(costs) -> np.ndarray:
    """(n,) the costs as floats, NaN as +inf (a failed candidate is never chosen)."""
    c = np.asarray(costs, dtype=float).reshape(-1)
    return np.where(np.isnan(c), np.inf, c)


def slack(cost: float) -> float:
    """How much more than ``cost`` a cost may be and still tie with it: TIE_RTOL·|cost|."""
    return TIE_RTOL * abs(cost) if math.isfinite(cost) else 0.0


def argmin(costs) -> int:
    """The index of the lowest cost, the first index among costs tied with it (module
    docstring); 0 for an all-infinite or all-NaN list. ``costs`` (n,), n ≥ 1."""
    c = _key(costs)
    if c.size == 0:
        raise ValueError("costs: expected at least one cost")
    best = float(c.min())
    return int(np.argmax(c <= best + slack(best)))


def improves(new: float, old: float) -> bool:
    """Whether ``new`` is lower than ``old`` by more than a tie: a step that a machine's
    rounding cannot decide."""
    new = math.inf if new != new else float(new)
    old = math.inf if old != old else float(old)
    return new < old - slack(old) if math.isfinite(old) else math.isfinite(new)


def order(costs) -> np.ndarray:
    """(n,) indices of ``costs`` (n,) from the lowest cost up, each tie taken in index
    order: at every step the first remaining index whose cost ties with the lowest
    remaining one (module docstring). Infinite and NaN costs come last, in index order."""
    c = _key(costs)
    left = list(np.argsort(c, kind="stable"))
    out = []
    while left:
        best = c[left[0]]
        tied = [i for i in left if c[i] <= best + slack(best)]
        first = min(tied)
        out.append(first)
        left.remove(first)
    return np.asarray(out, dtype=int)


def meets(value: float, target: float) -> bool:
    """Whether ``value`` ≤ ``target``, a value within a tie of the target counting as
    meeting it (the sweep's P95 target)."""
    return value == value and value <= target + slack(target)


def reaches(value: float, target: float) -> bool:
    """Whether ``value`` ≥ ``target``, a value within a tie of the target counting as
    reaching it (the sweep's availability and coverage targets)."""
    return value == value and value >= target - slack(target)

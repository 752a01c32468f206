"""Error statistics and DOP of simulated positions: the one home of these formulas.

The lowest layer that needs them is the simulation (:class:`simulation.Evaluation`), so
they live here; :mod:`analysis`, :mod:`placement` and the report import them from here
(docs/model.md, "Monte Carlo evaluation and error statistics" and "Dilution of
precision").

Shapes: Euclidean errors ``errors`` are (R, P) for R noise realizations at P nodes (any
shape for :func:`error_stats`), signed range errors ``range_errors`` (R, P, M) for M
anchors. Lengths in metres.

A NaN error is a node realization without a position fix (fewer than 4 anchors heard,
:func:`simulation.positioning.locate`); ±inf marks a fix that failed. Neither is dropped
silently, and no figure averages a no-fix in as a number:

* :func:`error_stats` computes every statistic over the finite errors (the fixes), reports
  how many were left out (``n_invalid``, beside ``n`` used) and the **availability**, the
  share of realizations with a fix;
* the per-node statistics (:func:`node_mean`, :func:`node_std`, :func:`node_rmse`) use a
  node's finite errors and give +inf for a node without any (its error is unbounded);
* the cost statistics :data:`STATISTICS` rank availability first (docs/model.md, "Costs
  and availability"): the statistic of the fixes when every realization has a fix, else
  :data:`NO_FIX_COST` · (1 + share without a fix) + the statistic of the fixes, so that
  no layout with full availability loses to one without; +inf when an error is ±inf or
  there is no error at all (a layout that cannot be scored).

Range errors are NaN where the receiver reported no range.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from simulation import checks

__all__ = [
    "COST_UNITS",
    "STATISTICS",
    "cost_unit",
    "axis_errors",
    "dop",
    "dop_rms",
    "error_stats",
    "euclidean_errors",
    "node_mean",
    "node_rmse",
    "node_std",
    "range_std",
    "row_statistics",
]

#: the percentile reported as "p95" (numpy's default linear interpolation)
PERCENTILE = 95


# -- errors from estimates ----------------------------------------------------------------------
def _difference(estimates, truth) -> np.ndarray:
    e = checks.reals("estimates", estimates, finite=False)
    t = checks.reals("truth", truth, finite=False)
    try:
        return e - t
    except ValueError:
        raise ValueError(
            f"estimates/truth: shapes {e.shape} and {t.shape} do not broadcast"
        ) from None


def euclidean_errors(estimates, truth) -> np.ndarray:
    """‖p̂ − p‖ over the last axis: estimates (..., P, 3), truth (P, 3) → (..., P) metres."""
    return np.linalg.norm(_difference(estimates, truth), axis=-1)


def axis_errors(estimates, truth) -> np.ndarray:
    """Absolute per-axis errors |p̂ − p|, (..., P, 3) metres (paper Fig. 3)."""
    return np.abs(_difference(estimates, truth))


# -- summary over all errors --------------------------------------------------------------------
def error_stats(errors) -> dict[str, float | int]:
    """Summary of Euclidean errors (any shape, metres) over all finite entries.

    Returns ``{"std", "mean", "p95", "rms", "median", "max", "n", "n_invalid"}``: ``std``
    is the population standard deviation (ddof = 0), the paper's σ (§V-B, Table I);
    ``mean`` the paper's μ; ``p95`` the 95th percentile (linear interpolation); ``rms`` =
    √mean e². ``n`` counts the finite errors used, ``n_invalid`` the non-finite ones
    left out (no fix, or a failed one) and ``availability`` = n / (n + n_invalid) (NaN
    without errors); without any finite error every statistic is NaN.
    """
    e = checks.reals("errors", errors, finite=False).ravel()
    v = e[np.isfinite(e)]
    out: dict[str, float | int]
    if v.size == 0:
        out = dict.fromkeys(("std", "mean", "p95", "rms", "median", "max"), math.nan)
    else:
        out = {
            "std": float(np.std(v)),
            "mean": float(np.mean(v)),
            "p95": float(np.percentile(v, PERCENTILE)),
            "rms": float(np.sqrt(np.mean(v * v))),
            "median": float(np.median(v)),
            "max": float(np.max(v)),
        }
    out["n"] = int(v.size)
    out["n_invalid"] = int(e.size - v.size)
    out["availability"] = v.size / e.size if e.size else math.nan
    return out


#: the cost statistics as reductions over an axis (None: all errors), lower is better
_REDUCTIONS: dict[str, Callable[..., np.ndarray]] = {
    "variance": lambda e, axis=None: np.var(e, axis=axis),
    "mean": lambda e, axis=None: np.mean(e, axis=axis),
    "p95": lambda e, axis=None: np.percentile(e, PERCENTILE, axis=axis),
    "rms": lambda e, axis=None: np.sqrt(np.mean(e * e, axis=axis)),
}


def _strict(name: str) -> Callable[[np.ndarray], float]:
    """The statistic ``name`` of all errors: the one-row case of :func:`row_statistics`."""

    def stat(errors) -> float:
        return float(row_statistics(name, np.asarray(errors, dtype=float).reshape(1, -1))[0])

    return stat


#: statistics of the simulated Euclidean errors (all R·P of them) usable as a cost, lower
#: is better, with availability first (module docstring). "variance" is the paper's cost
#: (σ², m², §III-B); "mean", "p95" and "rms" are in metres.
STATISTICS: dict[str, Callable[[np.ndarray], float]] = {k: _strict(k) for k in _REDUCTIONS}

#: the cost of a layout with a no-fix: NO_FIX_COST · (1 + share without a fix) + the
#: statistic of its fixes. Above any statistic of fixes: a least-squares fix started in a
#: room of at most 100 m per side lies within a few hundred metres of it, so its error
#: variance stays below 1e6 m²
NO_FIX_COST = 1e12
#: the cost of a layout below a coverage target (:func:`placement.coverage.constrain`):
#: BELOW_TARGET_COST · (1 + the share of the nodes it is short) + its cost; above every
#: cost of a layout that meets it (the costs of layouts with no-fixes stay below
#: 2·NO_FIX_COST + 1e6)
BELOW_TARGET_COST = 1e14


def penalty_text(cost) -> str | None:
    """What a penalized cost means, for a reader: "below the coverage target" or "x %
    without a fix" (:data:`BELOW_TARGET_COST`, :data:`NO_FIX_COST`); None for a cost that
    is not a penalty (its value is the figure)."""
    if cost is None or not cost >= NO_FIX_COST:
        return None
    if cost >= BELOW_TARGET_COST:
        return "below the coverage target"
    return f"{100 * (cost / NO_FIX_COST - 1):.2g} % without a fix"


def row_statistics(name: str, errors, shadow=None) -> np.ndarray:
    """(L,) the cost statistic ``name`` of :data:`STATISTICS` of each row of errors (L, n)
    at once: row l's value equals ``STATISTICS[name](errors[l])``. A row without a NaN
    (no-fix) gets the statistic; a row with some gets :data:`NO_FIX_COST` · (1 + their
    share) + the statistic of its finite errors (0 if none); a row with a ±inf error, or
    rows without errors, get +inf. ``shadow`` (h (L,), E): row l's errors stand for the
    share 1 − h[l] of the tags, the others' errors are E m (:func:`mixed_statistic`)."""
    checks.choice("statistic", name, tuple(_REDUCTIONS))
    e = np.asarray(errors, dtype=float)
    if e.ndim != 2:
        raise ValueError(f"errors: expected shape (L, n), got {e.shape}")
    out = np.full(len(e), math.inf)
    if e.shape[1] == 0:
        return out
    ok = np.all(np.isfinite(e), axis=1)
    if np.any(ok):
        out[ok] = _REDUCTIONS[name](e[ok], axis=1)
    if shadow is not None:
        h, E = shadow
        for i in np.flatnonzero(ok & (np.asarray(h) > 0)):  # layouts, not nodes: few
            out[i] = mixed_statistic(name, e[i], float(h[i]), float(E))
    nofix = np.isnan(e)
    partial = ~ok & ~np.any(np.isinf(e), axis=1)  # only NaN among the non-finite
    for i in np.flatnonzero(partial):  # layouts, not nodes: few
        fixes = e[i][~nofix[i]]
        stat = float(_REDUCTIONS[name](fixes)) if fixes.size else 0.0
        out[i] = NO_FIX_COST * (1.0 + nofix[i].mean()) + stat
    return out


def mixed_statistic(name: str, errors, h: float, E: float) -> float:
    """The statistic ``name`` of the errors of a mixture: the share 1 − h of the tags with
    the errors (n,) (each 1/n of it), the share h with the error E (m): for the mean
    (1 − h)·ē + h·E, for the RMS √((1 − h)·mean(e²) + h·E²), for the variance its second
    moment less the squared mean, for the P95 the mixture's 95th percentile."""
    e = np.asarray(errors, dtype=float)
    m1 = (1 - h) * np.mean(e) + h * E
    m2 = (1 - h) * np.mean(e * e) + h * E * E
    if name == "mean":
        return float(m1)
    if name == "rms":
        return float(np.sqrt(m2))
    if name == "variance":
        return float(max(m2 - m1 * m1, 0.0))
    q = PERCENTILE / 100  # the mixture's CDF (1 − h)·F(x) + h·[x ≥ E] first reaches q
    below = (1 - h) * np.mean(e < E)
    if below >= q:
        return float(np.percentile(e, 100 * q / (1 - h)))
    if below + h >= q:
        return float(E)
    return float(np.percentile(e, 100 * (q - h) / (1 - h)))


#: the unit of a cost by its name: the statistics above and the mean PEB ("peb", m)
COST_UNITS = {"variance": "m²", "mean": "m", "p95": "m", "rms": "m", "peb": "m"}


def cost_unit(name) -> str:
    """The unit of a cost by its name (:data:`COST_UNITS`), "" for a user's callable."""
    return COST_UNITS.get(str(name).lower(), "")


# -- per node -----------------------------------------------------------------------------------
def _per_node(errors) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(errors with non-finite entries zeroed, finite mask, finite count per node)."""
    e = checks.reals("errors", errors, finite=False)
    if e.ndim != 2:
        raise ValueError(f"errors: expected shape (R, P), got {e.shape}")
    ok = np.isfinite(e)
    return np.where(ok, e, 0.0), ok, ok.sum(axis=0)


def _node_average(total: np.ndarray, n: np.ndarray) -> np.ndarray:
    out = np.full(total.shape, np.inf)
    np.divide(total, n, out=out, where=n > 0)
    return out


def node_mean(errors) -> np.ndarray:
    """(P,) mean over the realizations of each node's finite errors (R, P); +inf if none."""
    e, _, n = _per_node(errors)
    return _node_average(e.sum(axis=0), n)


def node_rmse(errors) -> np.ndarray:
    """(P,) RMS √mean_r e_rp² over each node's finite errors (R, P); +inf if none."""
    e, _, n = _per_node(errors)
    return np.sqrt(_node_average(np.sum(e * e, axis=0), n))


def node_std(errors) -> np.ndarray:
    """(P,) population standard deviation over the realizations of each node's finite
    errors (R, P), σ^p of the paper's DOP (§V-A); +inf for a node without any."""
    e, ok, n = _per_node(errors)
    mean = _node_average(e.sum(axis=0), n)
    dev = np.where(ok, e - np.where(np.isfinite(mean), mean, 0.0), 0.0)
    return np.sqrt(_node_average(np.sum(dev * dev, axis=0), n))


def range_std(range_errors) -> np.ndarray:
    """(P,) σ_r^p: mean over the anchors of the standard deviation over the realizations
    of the range error, range_errors (R, P, M) in metres (paper §V-A). Missing ranges
    (NaN) are left out: each pair's σ is over its heard realizations, and the mean over
    the anchors heard at least once (0 at a node that hears none)."""
    r = checks.reals("range_errors", range_errors, finite=False)
    if r.ndim != 3 or 0 in r.shape:
        raise ValueError(f"range_errors: expected shape (R, P, M), none of them 0, got {r.shape}")
    if np.any(np.isinf(r)):
        raise ValueError("range_errors: must be finite or NaN (no range), got inf")
    heard = ~np.isnan(r)
    if np.all(heard):
        return np.mean(np.std(r, axis=0), axis=-1)
    n = heard.sum(axis=0)  # (P, M)
    x = np.where(heard, r, 0.0)
    mean = x.sum(axis=0) / np.maximum(n, 1)
    var = np.where(heard, (x - mean) ** 2, 0.0).sum(axis=0) / np.maximum(n, 1)
    seen = n > 0
    total = np.where(seen, np.sqrt(var), 0.0).sum(axis=-1)
    return total / np.maximum(seen.sum(axis=-1), 1)


# -- dilution of precision ----------------------------------------------------------------------
#: (m) a node whose ranges vary by at most this over the realizations has no DOP (+inf): a
#: receiver that picks the same sample every time leaves only the rounding of equal values
#: (about 1e-17 m), and a ratio to it is not a dilution of anything
RANGE_STD_FLOOR = 1e-9


def _ratio(errors, range_errors, spread: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    e = checks.reals("errors", errors, finite=False)
    r = checks.reals("range_errors", range_errors, finite=False)
    if e.ndim != 2 or r.ndim != 3 or r.shape[:2] != e.shape:
        raise ValueError(
            "errors/range_errors: expected shapes (R, P) and (R, P, M), "
            f"got {e.shape} and {r.shape}"
        )
    sigma_r = range_std(r)
    out = np.full(sigma_r.shape, np.inf)
    np.divide(spread(e), sigma_r, out=out, where=sigma_r > RANGE_STD_FLOOR)
    return out


def dop(errors, range_errors) -> np.ndarray:
    """(P,) the paper's DOP (§V-A): σ^p / σ_r^p, with σ^p the standard deviation over the
    R realizations of the Euclidean error at node p (:func:`node_std`) and σ_r^p the
    :func:`range_std`; +inf where σ_r is 0 (e.g. one realization) or within
    :data:`RANGE_STD_FLOOR` of it.

    errors (R, P) Euclidean errors, range_errors (R, P, M) signed range errors (m).
    """
    return _ratio(errors, range_errors, node_std)


def dop_rms(errors, range_errors) -> np.ndarray:
    """(P,) the RMS-based DOP: RMSE^p / σ_r^p with RMSE^p = √mean_r e_rp² (:func:`node_rmse`);
    +inf where σ_r is within :data:`RANGE_STD_FLOOR` of 0. It counts a node's mean error as
    well as its spread (RMSE² = σ² + mean², so dop_rms ≥ :func:`dop`): a steady multipath
    bias raises it, not the paper's."""
    return _ratio(errors, range_errors, node_rmse)

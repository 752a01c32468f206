"""Error statistics for analysis: the ECDF, and the formulas of :mod:`simulation.statistics`.

σ, mean, P95, RMS, per-node statistics, per-axis errors and both DOPs are computed in
:mod:`simulation.statistics` (their one home, re-exported here); this module adds the
empirical CDF used by the figures.
"""

from __future__ import annotations

import numpy as np

from simulation import checks
from simulation.statistics import (
    STATISTICS,
    axis_errors,
    dop,
    dop_rms,
    error_stats,
    euclidean_errors,
    node_mean,
    node_rmse,
    node_std,
    range_std,
)

__all__ = [
    "STATISTICS",
    "axis_errors",
    "dop",
    "dop_rms",
    "ecdf",
    "error_stats",
    "euclidean_errors",
    "node_mean",
    "node_rmse",
    "node_std",
    "range_std",
]


def ecdf(values) -> tuple[np.ndarray, np.ndarray]:
    """Empirical CDF: (sorted finite x, F) with F = i/n, i = 1…, over *all* n values.

    Non-finite values (failed fixes) are not plotted but count in n, so the CDF of a set
    with failures ends below 1 instead of hiding them.
    """
    v = checks.reals("values", values, finite=False).ravel()
    x = np.sort(v[np.isfinite(v)])
    return x, np.arange(1, x.size + 1) / max(v.size, 1)

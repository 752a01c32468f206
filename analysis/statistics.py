"""Error statistics for analysis: the ECDF, and the formulas of :mod:`simulation.statistics`.

σ, mean, P95, RMS, per-node statistics, per-axis errors and both DOPs are computed in
:mod:`simulation.statistics` (their one home, re-exported here); this module adds the
empirical CDF used by the figures.
"""

from __future__ import annotations

import numpy as np

from simulation import checks
from simulation import statistics as _statistics
from simulation.statistics import *  # noqa: F403 - the one home of the error statistics

__all__ = [*_statistics.__all__, "ecdf"]


def ecdf(values) -> tuple[np.ndarray, np.ndarray]:
    """Empirical CDF: (sorted finite x, F) with F = i/n, i = 1…, over *all* n values.

    Non-finite values (failed fixes) are not plotted but count in n, so the CDF of a set
    with failures ends below 1 instead of hiding them.
    """
    v = checks.reals("values", values, finite=False).ravel()
    x = np.sort(v[np.isfinite(v)])
    return x, np.arange(1, x.size + 1) / max(v.size, 1)

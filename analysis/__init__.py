"""Bounds and statistics: FIM, CRLB, PEB, GDOP, range-noise models, error statistics.

Imports only from :mod:`simulation` (never from :mod:`placement`).
"""

from analysis.fim import crlb, crlb_trace, fim, gdop, peb
from analysis.noise import (
    CalibratedRangeNoise,
    ConstantRangeNoise,
    MultipathRangeNoise,
    PhysicalRangeNoise,
    calibrated_sigma,
    direct_amplitude,
)
from analysis.statistics import (
    axis_errors,
    dop,
    dop_rms,
    ecdf,
    error_stats,
    euclidean_errors,
    node_mean,
    node_rmse,
    node_std,
    range_std,
)

__all__ = [
    "CalibratedRangeNoise",
    "ConstantRangeNoise",
    "MultipathRangeNoise",
    "PhysicalRangeNoise",
    "axis_errors",
    "calibrated_sigma",
    "crlb",
    "crlb_trace",
    "direct_amplitude",
    "dop",
    "dop_rms",
    "ecdf",
    "error_stats",
    "euclidean_errors",
    "fim",
    "gdop",
    "node_mean",
    "node_rmse",
    "node_std",
    "peb",
    "range_std",
]

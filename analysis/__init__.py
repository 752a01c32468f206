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
    ErrorStats,
    axis_errors,
    dop,
    ecdf,
    error_stats,
    euclidean_errors,
)

__all__ = [
    "CalibratedRangeNoise",
    "ConstantRangeNoise",
    "MultipathRangeNoise",
    "ErrorStats",
    "PhysicalRangeNoise",
    "axis_errors",
    "calibrated_sigma",
    "crlb",
    "crlb_trace",
    "direct_amplitude",
    "dop",
    "ecdf",
    "error_stats",
    "euclidean_errors",
    "fim",
    "gdop",
    "peb",
]

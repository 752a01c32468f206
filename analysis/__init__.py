"""Bounds and statistics: FIM, CRLB, PEB, GDOP, range-noise models, error statistics.

Imports only from :mod:`simulation` (never from :mod:`placement`).
"""

from analysis import statistics
from analysis.coverage import bound, coverage, covered_share, heard, heard_sigma
from analysis.fim import crlb, crlb_trace, fim, gdop, peb
from analysis.noise import (
    CalibratedRangeNoise,
    ConstantRangeNoise,
    MultipathRangeNoise,
    PhysicalRangeNoise,
    calibrated_sigma,
    direct_amplitude,
)
from analysis.statistics import *  # noqa: F403 - error statistics, DOP, ECDF

__all__ = [
    "CalibratedRangeNoise",
    "ConstantRangeNoise",
    "MultipathRangeNoise",
    "PhysicalRangeNoise",
    "bound",
    "calibrated_sigma",
    "coverage",
    "covered_share",
    "crlb",
    "crlb_trace",
    "direct_amplitude",
    "fim",
    "gdop",
    "heard",
    "heard_sigma",
    "peb",
    *statistics.__all__,
]

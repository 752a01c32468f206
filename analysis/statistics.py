"""Error statistics of position estimates: σ, mean, P95, RMS, per-axis errors, ECDF, DOP."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from simulation import checks


@dataclass(frozen=True)
class ErrorStats:
    """Summary of Euclidean errors in metres over all finite entries.

    ``std`` is the population standard deviation (ddof = 0), the paper's σ; ``n`` counts
    the finite errors used and ``n_invalid`` the non-finite ones left out.
    """

    std: float
    mean: float
    p95: float
    rms: float
    median: float
    max: float
    n: int
    n_invalid: int

    def to_dict(self) -> dict:
        return asdict(self)


def error_stats(errors) -> ErrorStats:
    """:class:`ErrorStats` of an array of Euclidean errors (any shape, metres)."""
    e = _numbers("errors", errors).ravel()
    ok = np.isfinite(e)
    v = e[ok]
    if v.size == 0:
        nan = float("nan")
        return ErrorStats(nan, nan, nan, nan, nan, nan, 0, int(e.size))
    return ErrorStats(
        std=float(np.std(v)),
        mean=float(np.mean(v)),
        p95=float(np.percentile(v, 95)),
        rms=float(np.sqrt(np.mean(v * v))),
        median=float(np.median(v)),
        max=float(np.max(v)),
        n=int(v.size),
        n_invalid=int(e.size - v.size),
    )


def _numbers(name: str, value) -> np.ndarray:
    """A float array (NaN and inf allowed: they mark failed fixes)."""
    return checks.reals(name, value, finite=False)


def _difference(estimates, truth) -> np.ndarray:
    e, t = _numbers("estimates", estimates), _numbers("truth", truth)
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


def ecdf(values) -> tuple[np.ndarray, np.ndarray]:
    """Empirical CDF of the finite values: (sorted x, F) with F = i/n, i = 1…n."""
    v = np.sort(_numbers("values", values).ravel())
    v = v[np.isfinite(v)]
    return v, np.arange(1, v.size + 1) / max(v.size, 1)


def dop(position_errors, range_errors) -> np.ndarray:
    """Per-node RMS-based DOP = σ_pos / σ_r, (P,); the paper's (§V-A) uses the std, not the RMS.

    position_errors (R, P): Euclidean errors over R realizations; σ_pos is their RMS.
    range_errors (R, P, M): signed range errors; σ_r is the mean over anchors of their
    standard deviation over realizations. Nodes with σ_r = 0 give +inf.
    """
    e = _numbers("position_errors", position_errors)
    r = _numbers("range_errors", range_errors)
    if e.ndim != 2 or r.ndim != 3 or r.shape[:2] != e.shape:
        raise ValueError(
            "position_errors/range_errors: expected shapes (R, P) and (R, P, M), "
            f"got {e.shape} and {r.shape}"
        )
    sigma_pos = np.sqrt(np.mean(e * e, axis=0))
    sigma_r = np.mean(np.std(r, axis=0), axis=-1)
    out = np.full(sigma_pos.shape, np.inf)
    np.divide(sigma_pos, sigma_r, out=out, where=sigma_r > 0)
    return out

"""Reference figures of the paper (Delabie et al., IPIN 2023) that results are compared
with."""

from __future__ import annotations

#: Table I (§V-B): σ, mean and P95 of the Euclidean error (m) of the optimized layouts
TABLE1: dict[int, dict[str, float]] = {
    4: {"std": 0.803, "mean": 0.995, "p95": 2.629},
    6: {"std": 0.691, "mean": 0.913, "p95": 2.272},
    8: {"std": 0.587, "mean": 0.797, "p95": 1.986},
    10: {"std": 0.563, "mean": 0.773, "p95": 1.876},
}

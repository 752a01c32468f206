"""Helpers shared by the benchmark scripts: timing and one JSON line per result."""

from __future__ import annotations

import json
import platform
import sys
import time
from pathlib import Path

# Run from a checkout without installing: make the top-level packages importable.
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

#: the paper's Table I (§V-B): σ, mean and P95 of the Euclidean error in metres
PAPER_TABLE1 = {
    4: {"std": 0.803, "mean": 0.995, "p95": 2.629},
    6: {"std": 0.691, "mean": 0.913, "p95": 2.272},
    8: {"std": 0.587, "mean": 0.797, "p95": 1.986},
    10: {"std": 0.563, "mean": 0.773, "p95": 1.876},
}


def best_time(fn, repeat: int = 5, number: int = 1) -> float:
    """Best wall-clock seconds per call of ``fn`` over ``repeat`` rounds of ``number`` calls."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def emit(name: str, **fields) -> None:
    """Print one JSON line: the benchmark name, its figures and the machine."""
    rec = {
        "bench": name,
        **fields,
        "python": platform.python_version(),
        "machine": platform.machine(),
    }
    print(json.dumps(rec), flush=True)

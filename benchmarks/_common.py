"""Helpers shared by the benchmark scripts: timing and one JSON line per result."""

from __future__ import annotations

import json
import platform
import statistics
import sys
import time
from pathlib import Path

# Run from a checkout without installing: make the top-level packages importable.
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from analysis.paper import TABLE1 as PAPER_TABLE1  # noqa: E402, F401  (re-exported)


def best_time(fn, repeat: int = 5, number: int = 1) -> float:
    """Best wall-clock seconds per call of ``fn`` over ``repeat`` rounds of ``number`` calls."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def spread(values) -> float:
    """The spread of values over seeds, as issue 12 measures it: (max − min) / median."""
    v = [float(x) for x in values]
    return (max(v) - min(v)) / statistics.median(v)


def emit(name: str, **fields) -> None:
    """Print one JSON line: the benchmark name, its figures and the machine."""
    rec = {
        "bench": name,
        **fields,
        "python": platform.python_version(),
        "machine": platform.machine(),
    }
    print(json.dumps(rec), flush=True)

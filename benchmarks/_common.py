"""Helpers shared by the benchmark scripts: timing and one JSON line per result."""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

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


def runs_parser(doc: str, anchors: list[int], seeds_help: str | None = None):
    """The options of a benchmark over (M, seed) runs: ``--anchors`` (default ``anchors``),
    ``--seeds`` (5: seeds 0–4), ``--workers`` (2) and ``--summary JSONL [JSONL ...]``
    (print the tables of the finished runs in those files instead of running)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--anchors", type=int, nargs="+", default=anchors)
    ap.add_argument("--seeds", type=int, default=5, help=seeds_help)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument(
        "--summary", metavar="JSONL", nargs="+", help="print the tables of finished runs"
    )
    return ap


def read_lines(paths: list[str]) -> list[dict]:
    """The JSON lines of the files ``paths``, in order."""
    rows = []
    for path in paths:
        with open(path) as f:
            rows += [json.loads(line) for line in f if line.strip()]
    return rows


def with_room_chirp(system, own):
    """``system`` with the chirp duration of the room file's system ``own`` (a long chirp
    for a large room) and its window moved by the same shift, so that it still closes where
    it did relative to the chirp's end."""
    if own.chirp.duration == system.chirp.duration:
        return system
    shift = own.chirp.duration - system.chirp.duration
    return system.with_signal(duration=own.chirp.duration, t_wake=system.receiver.t_wake + shift)


#: the field draws' seed of the benchmarks that evaluate layouts in the field (``--seed``)
FIELD_SEED = 7


def field_draws(room, anchors, system, draws: int, seed: int = FIELD_SEED) -> np.ndarray:
    """(2, 300 draws) the field errors (m) of ``anchors`` and whether each fix is verified
    (1.0, else 0.0): ``draws`` draws of the field check (300 random tags in the zones,
    anchors mounted within 3 cm, one noise realization, the streams of ``seed``;
    ``placement.validation.field_errors``)."""
    from placement.validation import field_errors

    return np.concatenate([field_errors(room, anchors, 300, 0.03, d, seed, system=system)
                           for d in range(draws)], axis=1)  # fmt: skip


def error_summary(e: np.ndarray) -> dict:
    """Median, mean, P95 and RMS (m) of the finite errors e (an empty dict: none finite)."""
    e = e[np.isfinite(e)]
    if e.size == 0:
        return {}
    return {"median": float(np.median(e)), "mean": float(e.mean()),
            "p95": float(np.percentile(e, 95)), "rms": float(np.sqrt(np.mean(e * e)))}  # fmt: skip


def emit(name: str, **fields) -> None:
    """Print one JSON line: the benchmark name, its figures and the machine."""
    rec = {
        "bench": name,
        **fields,
        "python": platform.python_version(),
        "machine": platform.machine(),
    }
    print(json.dumps(rec), flush=True)


def room_parser(doc: str) -> argparse.ArgumentParser:
    """A parser with the options of a benchmark in one room with one system: ``--room``
    (a room file) and ``--system`` (a preset or a TOML file, default recommended)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--room", required=True)
    ap.add_argument("--system", default="recommended", help="a preset or a TOML file")
    return ap


def room_and_system(args):
    """(room, system) of the parsed options of :func:`room_parser`."""
    from placement.cli.common import system_choice
    from simulation import Room

    return Room.from_toml(args.room), system_choice(args.system)


def candidates_in_sight(room, system):
    """(candidates (N, 3), sight points (Q, 3), seen (Q, N)): the search's candidate grid of
    the room, its sight points and which candidates each sees in line of sight and reach."""
    from placement.rangetable import sight, sight_points
    from placement.simselect import SearchOptions
    from placement.surfaces import candidate_grid

    cand = candidate_grid(room, SearchOptions().spacing_for(room))
    pts = sight_points(room)
    return cand, pts, sight(room, system, cand, pts)

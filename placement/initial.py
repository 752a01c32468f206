"""The swarm's starting layouts (docs/model.md, "The whole chain: seed_then_pso").

For a simulated cost they are the best distinct optima of the multi-start swap search on
the range table (:func:`search_initial`, :mod:`placement.simselect`); for a bound-driven
cost the convex relaxations, their PEB refinements and the best random layouts by mean PEB
(:func:`analytic_initial`). A finished search is saved beside the plan's checkpoint and
reused by a rerun with the same arguments.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from analysis.fim import DEFAULT_SIGMA, peb
from analysis.progress import ProgressBar
from placement import ties
from placement.serialization import fingerprint, write_json_atomic
from placement.simselect import SearchOptions
from placement.streams import phase_seed
from placement.surfaces import random_layout
from simulation import streams
from simulation.room import Room
from simulation.system import as_system

logger = logging.getLogger(__name__)

#: random layouts screened by mean PEB for the analytic starting layouts, and how many kept
RANDOM_SCREEN, RANDOM_KEEP = 512, 2


@dataclass
class InitialLayout:
    """A starting layout of the swarm: where it came from, its anchors, mean PEB (m, at the
    default range σ), the cost it scored in the swarm's first iteration and, for the
    search's optima, its cost on the range table of
    :func:`placement.simselect.simulated_select`."""

    name: str
    anchors: np.ndarray
    mean_peb: float
    cost: float = math.nan
    table_cost: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        """The layout as plain JSON types."""
        return {
            "name": self.name,
            "anchors": np.asarray(self.anchors).tolist(),
            "mean_peb": self.mean_peb,
            "cost": self.cost,
            "table_cost": self.table_cost,
        }


def analytic_initial(
    room: Room, M: int, *, sigma: float = DEFAULT_SIGMA, nodes=None, rng=None
) -> list[InitialLayout]:
    """The "auto" starting layouts of a bound-driven cost: A- and D-optimal relaxations,
    their PEB refinements, and the best random layouts by mean PEB (range σ ``sigma`` m).
    A relaxation whose solver fails is logged and skipped."""
    from placement.refine import refine_peb
    from placement.relaxation import relax_select

    nodes = room.grid() if nodes is None else nodes
    seed = streams.entropy("rng", rng)
    out: list[InitialLayout] = []

    def add(name, anchors):
        anchors = np.asarray(anchors, dtype=float)
        if any(np.allclose(anchors, s.anchors) for s in out):
            return
        value = float(np.mean(peb(anchors, nodes, sigma)))
        if math.isfinite(value):
            out.append(InitialLayout(name, anchors, value))

    for criterion in ("A", "D"):
        try:
            sel = relax_select(room, M, criterion=criterion, sigma=sigma, nodes=nodes, rng=seed)
            add(f"relax-{criterion}", sel.anchors)
            add(
                f"relax-{criterion}+refine", refine_peb(room, sel.anchors, sigma=sigma, nodes=nodes)
            )
        except Exception as exc:  # noqa: BLE001 - a failed relaxation leaves the others
            logger.warning("initial layout relax-%s failed: %s", criterion, exc)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(3,)))
    layouts = np.stack([random_layout(room, M, rng) for _ in range(RANDOM_SCREEN)])
    scores = np.mean(peb(layouts, nodes, sigma), axis=-1)
    for k, i in enumerate(ties.order(scores)[:RANDOM_KEEP]):
        add(f"random-best-{k + 1}", layouts[i])
    return out


def _search_fingerprint(room, system, M, opt: SearchOptions, statistic, nodes, entropy) -> str:
    return fingerprint(
        {
            "room": room.to_dict(),
            "system": system.to_dict(),
            "M": M,
            "search": dataclasses.asdict(opt),
            "statistic": statistic,
            "nodes": None if nodes is None else np.asarray(nodes).tolist(),
            "seed": entropy,
        }
    )


def build_table(
    room: Room, options: SearchOptions, nodes, seed: int, executor=None, progress: bool = False,
    system=None,
):  # fmt: skip
    """The range table of the run ``seed_then_pso(room, M, rng=seed, search=options,
    nodes=nodes, system=system)`` (the same for every M;
    :func:`placement.simselect.search_table` on the run's stream "table"), with a progress
    bar when ``progress``."""
    from placement.simselect import search_table

    bar = ProgressBar(progress, "range table")
    table = search_table(room, options, nodes, phase_seed(seed, "table"), executor, bar.update,
                         system=system)  # fmt: skip
    bar.close()
    return table


def search_initial(
    room: Room,
    M: int,
    *,
    statistic: str,
    options: SearchOptions,
    table,
    nodes,
    rng: int,
    sigma: float,
    executor: Executor | None,
    workers: int,
    checkpoint: Path | None = None,
    progress: bool = False,
    system=None,
) -> tuple[list[InitialLayout], dict[str, Any]]:
    """The starting layouts of a simulated cost (the ``system`` simulated, default the
    paper's): the ``options.keep_for(M)`` best distinct optima of
    :func:`placement.simselect.simulated_select` on the range table (``table``: a
    :class:`~placement.rangetable.RangeTable`, or a callable that builds it), and the
    search's summary. With a ``checkpoint``, a finished search is saved beside it
    (``<checkpoint>.search.json``) and reused by a rerun with the same arguments, without
    building the table."""
    from placement import simselect

    sidecar = None if checkpoint is None else checkpoint.with_name(checkpoint.name + ".search.json")
    seed = streams.entropy("rng", rng)
    system = as_system(system)
    origin = seed if callable(table) else [table.seed, list(table.ranges.shape)]
    print_ = _search_fingerprint(room, system, M, options, statistic, nodes, origin)
    if sidecar is not None and sidecar.exists():
        saved = _load_sidecar(sidecar)
        if saved.get("fingerprint") == print_:
            layouts = [
                InitialLayout(
                    d["name"], np.array(d["anchors"]), d["mean_peb"], table_cost=d["table_cost"]
                )
                for d in saved["initial"]
            ]
            return layouts, {**saved["summary"], "resumed": True}
    table = table() if callable(table) else table
    bar = ProgressBar(progress, "search")
    sel = simselect.simulated_select(
        room,
        M,
        statistic=statistic,
        options=options,
        table=table,
        rng=seed,
        executor=executor,
        workers=workers,
        progress=lambda stage, done, total: bar.update(done, total, stage),
    )
    bar.close()
    grid = room.grid() if nodes is None else nodes
    kept = sel.layouts(options.keep_for(M))
    layouts = [
        InitialLayout(f"search-{k + 1}", a, float(np.mean(peb(a, grid, sigma))), table_cost=c)
        for k, (a, (_, c)) in enumerate(zip(kept, sel.optima, strict=False))
    ]
    summary = sel.to_dict()
    del summary["anchors"], summary["optima"]
    if sidecar is not None:
        _write_sidecar(sidecar, print_, layouts, summary)
    return layouts, summary


def _load_sidecar(path: Path) -> dict:
    afresh = "delete it to start afresh"
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"checkpoint {path}: cannot read it ({exc}); {afresh}") from None
    if not isinstance(data, dict) or not {"fingerprint", "initial", "summary"} <= set(data):
        raise ValueError(f"checkpoint {path}: not a search checkpoint; {afresh}")
    return data


def _write_sidecar(path: Path, print_: str, layouts, summary) -> None:
    blob = {"fingerprint": print_, "initial": [s.to_dict() for s in layouts], "summary": summary}
    write_json_atomic(path, blob)

"""The finalists: the plan's candidate layouts scored on fresh draws before choosing.

The refined layouts, the swarm's best distinct layouts and the starting layouts are scored
on ``FinalistOptions.draws`` new scene draws (new noise; by default at the exact nodes),
and the lowest wins, so that a layout fitted to the draws it was optimized on does not win
by luck (docs/model.md, "The whole chain: seed_then_pso").
"""

from __future__ import annotations

import logging
import math
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any

import numpy as np

from placement import ties
from placement.costs import DrawsCost
from placement.initial import InitialLayout
from placement.pso import PSOResult
from placement.workers import run_calls
from simulation import checks

logger = logging.getLogger(__name__)

#: the most fresh draws and finalists
MAX_FINALIST_DRAWS = 1000


@dataclass(frozen=True)
class FinalistOptions:
    """The finalists' settings.

    count : how many of the swarm's best distinct layouts are scored, besides the starting
        layouts and the refined ones (1 … the swarm's particles).
    draws : the fresh scene draws each finalist is scored on (1–1000).
    exact_draws : how many of those keep the nodes and the planned points exactly (None:
        all); the others move the nodes within their cells and mount the anchors within
        the search's ``mount_tolerance``, as the range table's moved draws do.
    """

    count: int = 1
    draws: int = 12
    exact_draws: int | None = None

    def __post_init__(self) -> None:
        checks.count("count", self.count, low=1, high=MAX_FINALIST_DRAWS)
        checks.count("draws", self.draws, low=1, high=MAX_FINALIST_DRAWS)
        if self.exact_draws is not None:
            checks.count("exact_draws", self.exact_draws, low=0, high=self.draws)

    @property
    def exact(self) -> int:
        """The exact draws (``exact_draws``, or all)."""
        return self.draws if self.exact_draws is None else self.exact_draws


def _score(cost, anchors) -> float:
    try:
        return float(cost(anchors))
    except Exception as exc:  # noqa: BLE001 - a failed re-score only drops that finalist
        logger.warning("scoring a finalist failed: %s", exc)
        return math.inf


def best_distinct(res: PSOResult, count: int | None, exclude=()) -> list[int]:
    """Indices of the ``count`` best particle layouts of a swarm (None: all of them; by
    their best cost, finite only), distinct from each other and from the layouts
    ``exclude``."""
    picked: list[int] = []
    taken = [np.asarray(a, dtype=float) for a in exclude]
    for i in ties.order(res.pcost):
        if len(picked) == count or not math.isfinite(res.pcost[i]):
            break
        if not any(np.allclose(res.pbest[i], a) for a in taken):
            picked.append(int(i))
            taken.append(res.pbest[i])
    return picked


def score_finalists(
    res: PSOResult,
    initial: list[InitialLayout],
    cost: DrawsCost,
    count: int,
    executor: Executor | None = None,
    progress=None,
    refined: list[tuple[str, np.ndarray]] = (),
) -> list[dict[str, Any]]:
    """Score the ``count`` best distinct particle layouts (by swarm cost), every starting
    layout and the ``refined`` layouts (name, anchors) on the fresh draws of ``cost``;
    one dict per finalist (``source``, ``anchors``, ``pso_cost`` (NaN for refined
    layouts), ``cost``): refined layouts first, then particles in swarm-cost order, then
    the starting layouts."""
    picked: list[tuple[str, np.ndarray, float]] = [
        (name, np.asarray(a, dtype=float), math.nan) for name, a in refined
    ]
    for i in best_distinct(res, count, exclude=[a for _, a, _ in picked]):
        same = [s.name for s in initial if np.allclose(s.anchors, res.pbest[i])]
        source = same[0] if same else "swarm"
        picked.append((source, res.pbest[i].copy(), float(res.pcost[i])))
    for s in initial:
        if not any(np.allclose(s.anchors, a) for _, a, _ in picked):
            picked.append((s.name, np.asarray(s.anchors), float(s.cost)))
    values = run_calls(executor, [(_score, (cost, a)) for _, a, _ in picked], progress=progress)
    return [
        {"source": src, "anchors": a, "pso_cost": c, "cost": v}
        for (src, a, c), v in zip(picked, values, strict=True)
    ]

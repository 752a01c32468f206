"""Cost functions of a layout for the swarm (paper §III-B, §V-A; docs/model.md, "Costs").

A cost maps anchors (M, 3) and a numpy ``Generator`` (the evaluation's own noise stream)
to a float, lower is better; +inf marks a layout that cannot be scored. The paper's cost
is the variance of the Euclidean position error over the 270 grid nodes from the full
simulation.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from analysis.fim import DEFAULT_SIGMA, check_sigma, peb
from placement.coverage import CoverageTarget
from placement.rangetable import (
    check_mount_tolerance,
    range_table,
    table_cost,
    table_errors,
)
from simulation import checks, degeneracy
from simulation.room import Room, as_room
from simulation.statistics import STATISTICS
from simulation.system import System, as_system

#: statistics of the simulated Euclidean errors usable as a cost (+inf when an error is not
#: finite); one home: :data:`simulation.statistics.STATISTICS`
SIMULATED_STATISTICS = STATISTICS

COST_NAMES = (*SIMULATED_STATISTICS, "peb")
#: the planner's default cost: the paper's variance for the paper's experiment, the RMS
#: elsewhere (:func:`default_cost`)
AUTO = "auto"


def default_cost(room, system) -> str:
    """The cost the planner minimizes when given ``"auto"`` (docs/model.md, "Costs"): the
    paper's variance for the paper's experiment (the paper's system in the paper's room,
    what Table I reports), and the RMS of the error in any other room or with any other
    system. The variance rewards a layout whose every fix is off by the same metres (an
    echo that biases the ranges of a whole region); the RMS, √(mean² + σ²), does not
    (BENCHMARKS.md, "The cost in a user's room")."""
    paper = system == System() and room == Room.techtile()
    return "variance" if paper else "rms"


@dataclass(frozen=True)
class SimulatedCost:
    """A statistic of the simulated Euclidean errors: "variance" (paper), "mean", "p95", "rms".

    Each call simulates ``realizations`` noisy realizations of the full chirp pipeline
    (:func:`simulation.evaluate_layout`) on ``nodes`` (default: the room's grid) with noise
    drawn from the given generator, with the receiver DSP in ``precision`` (see
    :data:`simulation.receiver.DEFAULT_PRECISION`) and the ``system`` simulated (default
    the paper's).
    """

    room: Room = field(default_factory=Room.techtile)
    statistic: str = "variance"
    realizations: int = 1
    nodes: np.ndarray | None = None
    precision: str = "float32"
    system: System = field(default_factory=System)

    def __post_init__(self) -> None:
        checks.choice("statistic", self.statistic, SIMULATED_STATISTICS)
        checks.count("realizations", self.realizations, low=1, high=100_000)
        room = as_room(self.room)
        if self.nodes is not None:
            room.check_nodes(self.nodes)

    def __call__(self, anchors: np.ndarray, rng: np.random.Generator) -> float:
        from simulation.evaluation import evaluate_layout

        ev = evaluate_layout(
            self.room,
            anchors,
            realizations=int(self.realizations),
            rng=rng,
            nodes=self.nodes,
            precision=self.precision,
            system=self.system,
        )
        return SIMULATED_STATISTICS[self.statistic](np.asarray(ev.errors, dtype=float))


@dataclass(frozen=True)
class DrawsCost:
    """A statistic of the simulated Euclidean errors over fixed scene draws (common random
    numbers): every layout is scored on the same node sets, mounting errors and noise.

    The layout's M anchors are simulated exactly as M candidates of a range table
    (:func:`placement.rangetable.range_table`) with ``nodes`` (D, P, 3), anchor slot m
    taking the streams of candidate m: the first ``exact_draws`` draws keep the planned
    points, the others mount each anchor within ``mount_tolerance`` (m) of its planned
    point in its surface plane; positioning uses the planned points. The cost is then a
    deterministic function of the layout (the generator is ignored), so a swarm compares
    its particles without noise between them (docs/model.md, "Range tables and scene draws").
    ``system``: the system simulated (default the paper's). ``coverage_target``: a
    :class:`placement.coverage.CoverageTarget` the cost enforces at the first draw's nodes
    (:func:`placement.coverage.constrain`; None: none).
    """

    room: Room
    nodes: np.ndarray
    exact_draws: int = 1
    mount_tolerance: float = 0.0
    seed: int = 0
    statistic: str = "variance"
    precision: str = "float32"
    system: System = field(default_factory=System)
    coverage_target: CoverageTarget | None = None

    def __post_init__(self) -> None:
        checks.choice("statistic", self.statistic, SIMULATED_STATISTICS)
        room = as_room(self.room)
        nodes = checks.reals("nodes", self.nodes, shape=(None, None, 3))
        room.check_nodes(nodes.reshape(-1, 3))
        checks.count("exact_draws", self.exact_draws, low=0, high=nodes.shape[0])
        check_mount_tolerance(self.mount_tolerance)

    @property
    def draws(self) -> int:
        """D, the number of scene draws."""
        return int(np.shape(self.nodes)[0])

    def errors(self, anchors) -> np.ndarray:
        """(D · P,) Euclidean position errors (m) of the layout over every draw and node."""
        return table_errors(self._table(anchors), np.arange(len(anchors))[None])[0]

    def _table(self, anchors):
        """The range table of the layout's M anchors (its M candidates) on the draws, under
        the cost's coverage target."""
        a = np.asarray(anchors, dtype=float)
        table = range_table(
            self.room,
            a,
            self.nodes,
            exact_draws=self.exact_draws,
            mount_tolerance=self.mount_tolerance,
            rng=self.seed,
            chunk=len(a),
            precision=self.precision,
            system=self.system,
        )
        return dataclasses.replace(table, coverage_target=self.coverage_target)

    def __call__(self, anchors: np.ndarray, rng: np.random.Generator | None = None) -> float:
        if degeneracy.anchor_rank(anchors) < 2:  # collinear: the position is not determined
            return math.inf
        return table_cost(self._table(anchors), np.arange(len(anchors)), self.statistic)


@dataclass(frozen=True)
class PEBCost:
    """Mean PEB = mean over nodes of √tr J⁻¹ (metres) for a constant range σ; bound-driven.

    Deterministic: the generator is ignored. A singular node makes the cost +inf.
    """

    room: Room = field(default_factory=Room.techtile)
    sigma: float = DEFAULT_SIGMA
    nodes: np.ndarray | None = None

    def __post_init__(self) -> None:
        check_sigma(self.sigma)
        room = as_room(self.room)
        if self.nodes is not None:
            room.check_nodes(self.nodes)

    def __call__(self, anchors: np.ndarray, rng: np.random.Generator | None = None) -> float:
        nodes = self.room.grid() if self.nodes is None else self.nodes
        return float(np.mean(peb(anchors, nodes, self.sigma)))


@dataclass(frozen=True)
class CallableCost:
    """Wraps a user function ``f(anchors) -> float`` or ``f(anchors, rng) -> float``."""

    fn: Callable
    name: str = "callable"

    def __call__(self, anchors: np.ndarray, rng: np.random.Generator) -> float:
        if _takes_rng(self.fn):
            return float(self.fn(anchors, rng))
        return float(self.fn(anchors))


def _takes_rng(fn: Callable) -> bool:
    try:
        params = inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False
    return "rng" in params or len(params) >= 2


def make_cost(
    cost: str | Callable,
    room: Room,
    *,
    realizations: int = 1,
    nodes=None,
    sigma: float = DEFAULT_SIGMA,
    system=None,
) -> Callable[[np.ndarray, np.random.Generator], float]:
    """Turn a cost name or callable into a ``cost(anchors, rng) -> float`` object.

    Names: "variance" (paper default), "mean", "p95", "rms" (simulated Euclidean errors
    of ``system``, default the paper's, with ``realizations`` noise realizations per
    evaluation) and "peb" (mean PEB with constant ``sigma``). Objects that already take
    ``(anchors, rng)`` pass through.
    """
    if isinstance(cost, SimulatedCost | PEBCost | CallableCost):
        return cost
    if isinstance(cost, str):
        if cost == "peb":
            return PEBCost(room, sigma=sigma, nodes=nodes)
        if is_simulated(cost):
            return SimulatedCost(room, cost, realizations=realizations, nodes=nodes,
                                 system=as_system(system))  # fmt: skip
        raise ValueError(f"cost: unknown name {cost!r}; allowed: {list(COST_NAMES)} or a callable")
    if callable(cost):
        return CallableCost(cost, getattr(cost, "__name__", "callable"))
    raise ValueError(f"cost: expected a name in {list(COST_NAMES)} or a callable, got {cost!r}")


def is_simulated(cost) -> bool:
    """Whether ``cost`` is a simulated cost by name ("variance", "mean", "p95", "rms"):
    the planner then searches a range table and scores the swarm on scene draws ("auto"
    stands for one of them)."""
    return isinstance(cost, str) and (cost in SIMULATED_STATISTICS or cost == AUTO)


def cost_name(cost) -> str:
    """A label for reports: the statistic's name, "peb", or the callable's name."""
    if isinstance(cost, str):
        return cost
    if isinstance(cost, SimulatedCost):
        return cost.statistic
    if isinstance(cost, PEBCost):
        return "peb"
    if isinstance(cost, CallableCost):
        return cost.name
    return getattr(cost, "__name__", type(cost).__name__)

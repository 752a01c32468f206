"""The whole chain: seeds → PSO on the simulated cost → validation (docs/model.md).

``seed_then_pso(room, M=8)`` builds seed layouts in two ways: simulation-driven, a local
search over candidate mounting points on a table of simulated ranges
(:mod:`placement.simselect`), and bound-driven, the A- and D-optimal convex relaxations,
their gradient refinements and the best of many random layouts by PEB. It puts them into
the swarm beside random particles, runs the swarm on the full chirp simulation, and
validates the winner with many noise realizations.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import time
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.fim import peb
from placement.costs import SimulatedCost, cost_name, make_cost
from placement.pso import PSOOptions, PSOResult, pso
from placement.serialization import to_jsonable
from placement.surfaces import random_layout
from simulation.room import Room

logger = logging.getLogger(__name__)

#: random layouts screened by mean PEB for the "auto" seeds, and how many are kept
RANDOM_SCREEN, RANDOM_KEEP = 512, 2
#: local optima of the simulation-driven candidate search kept as "auto" seeds
SIMULATED_KEEP = 3


@dataclass
class SeedLayout:
    """A seed layout: where it came from, its anchors, mean PEB (m, σ = 0.04 m), the cost
    it scored in the swarm's first iteration and, for simulation-driven seeds, its cost on
    the range table of :func:`placement.simselect.simulated_select`."""

    name: str
    anchors: np.ndarray
    mean_peb: float
    cost: float = math.nan
    table_cost: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "anchors": np.asarray(self.anchors).tolist(),
            "mean_peb": self.mean_peb,
            "cost": self.cost,
            "table_cost": self.table_cost,
        }


@dataclass
class PlacementResult:
    """Result of :func:`seed_then_pso`.

    anchors (M, 3) the chosen layout; cost its (noisy) PSO cost; history the swarm's best
    cost per iteration (non-increasing); finalists the best distinct particle layouts with
    their PSO cost and their re-scored cost (the chosen one has the lowest re-scored cost,
    see :func:`seed_then_pso`); seeds the seed layouts with their costs; validation the
    statistics of the chosen layout over ``validate_realizations`` noise
    realizations (σ, mean, P95, RMS of the Euclidean error in m; mean PEB in m with
    σ_r = 0.04 m, PEB = √tr J⁻¹); timings in seconds.
    """

    room: Room
    anchors: np.ndarray
    cost: float
    cost_name: str
    history: list[float]
    best_anchors_history: list[np.ndarray]
    nfev: int
    nit: int
    message: str
    success: bool
    seeds: list[SeedLayout]
    validation: dict[str, Any]
    timings: dict[str, float]
    settings: dict[str, Any]
    pso: PSOResult | None = field(default=None, repr=False)
    finalists: list[dict[str, Any]] = field(default_factory=list)

    @property
    def x(self) -> np.ndarray:
        return self.anchors.ravel()

    @property
    def fun(self) -> float:
        return self.cost

    def to_dict(self) -> dict[str, Any]:
        return {
            "room": self.room.to_dict(),
            "anchors": self.anchors.tolist(),
            "cost": self.cost,
            "cost_name": self.cost_name,
            "history": list(self.history),
            "best_anchors_history": [np.asarray(a).tolist() for a in self.best_anchors_history],
            "nfev": self.nfev,
            "nit": self.nit,
            "message": self.message,
            "success": self.success,
            "seeds": [s.to_dict() for s in self.seeds],
            "finalists": self.finalists,
            "validation": self.validation,
            "timings": self.timings,
            "settings": self.settings,
            "costs": None if self.pso is None else np.asarray(self.pso.costs).tolist(),
        }

    def to_json(self, **kw) -> str:
        """Strict JSON (non-finite numbers become null)."""
        return json.dumps(to_jsonable(self.to_dict()), **kw)


def analytic_seeds(
    room: Room, M: int, *, sigma: float = 0.04, nodes=None, seed: int | None = None
) -> list[SeedLayout]:
    """The "auto" seeds: A- and D-optimal relaxations, their PEB refinements, and the
    best random layouts by mean PEB. A seed whose solver fails is logged and skipped."""
    from placement.refine import refine_peb
    from placement.relaxation import relax_select

    nodes = room.grid() if nodes is None else nodes
    out: list[SeedLayout] = []

    def add(name, anchors):
        anchors = np.asarray(anchors, dtype=float)
        if any(np.allclose(anchors, s.anchors) for s in out):
            return
        value = float(np.mean(peb(anchors, nodes, sigma)))
        if math.isfinite(value):
            out.append(SeedLayout(name, anchors, value))

    for criterion in ("A", "D"):
        try:
            sel = relax_select(room, M, criterion=criterion, sigma=sigma, nodes=nodes, seed=seed)
            add(f"relax-{criterion}", sel.anchors)
            add(
                f"relax-{criterion}+refine", refine_peb(room, sel.anchors, sigma=sigma, nodes=nodes)
            )
        except Exception as exc:  # noqa: BLE001 - a failed seed leaves the others
            logger.warning("seed relax-%s failed: %s", criterion, exc)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(3,)))
    layouts = np.stack([random_layout(room, M, rng) for _ in range(RANDOM_SCREEN)])
    scores = np.mean(peb(layouts, nodes, sigma), axis=-1)
    for k, i in enumerate(np.argsort(scores)[:RANDOM_KEEP]):
        add(f"random-best-{k + 1}", layouts[i])
    return out


def simulated_seeds(
    room: Room,
    M: int,
    *,
    statistic: str = "variance",
    sigma: float = 0.04,
    nodes=None,
    seed: int | None = None,
    executor: Executor | None = None,
    keep: int = SIMULATED_KEEP,
    **search,
) -> tuple[list[SeedLayout], dict[str, Any]]:
    """The simulation-driven "auto" seeds: the ``keep`` best local optima of
    :func:`placement.simselect.simulated_select` (``search``: its keyword arguments), and
    that search's summary (evaluations, table size, timings). A failure is logged and
    gives no seeds."""
    from placement.simselect import simulated_select

    nodes = room.grid() if nodes is None else nodes
    try:
        sel = simulated_select(
            room, M, statistic=statistic, seed=seed, nodes=nodes, executor=executor, **search
        )
    except ValueError:  # bad arguments are the caller's to fix
        raise
    except Exception as exc:  # noqa: BLE001 - the bound-driven seeds remain
        logger.warning("simulated seeds failed: %s", exc)
        return [], {"message": f"{type(exc).__name__}: {exc}"}
    out = [
        SeedLayout(
            f"simulated-{k + 1}",
            a,
            float(np.mean(peb(a, nodes, sigma))),
            table_cost=c,
        )
        for k, (a, (_, c)) in enumerate(zip(sel.layouts(keep), sel.optima, strict=False))
        if math.isfinite(c)
    ]
    summary = sel.to_dict()
    del summary["anchors"], summary["optima"]
    return out, summary


def validate_layout(
    room: Room, anchors, realizations: int, seed: int, sigma: float = 0.04, nodes=None
) -> dict[str, Any]:
    """σ, mean, P95, RMS of the simulated Euclidean error over ``realizations``, the mean
    PEB (m, √tr J⁻¹ at constant ``sigma``), per-node RMSE and DOP, and the errors (R, P)."""
    from simulation.evaluation import evaluate_layout

    nodes = room.grid() if nodes is None else nodes
    ev = evaluate_layout(room, anchors, realizations=realizations, seed=seed, nodes=nodes)
    e = np.asarray(ev.errors)
    return {
        "realizations": int(realizations),
        "seed": int(seed),
        "std": float(np.std(e)),
        "mean": float(np.mean(e)),
        "p95": float(np.percentile(e, 95)),
        "rms": float(np.sqrt(np.mean(e * e))),
        "mean_peb": float(np.mean(peb(anchors, nodes, sigma))),
        "peb_definition": f"sqrt(tr J^-1), metres, sigma_r = {sigma:g} m",
        "per_node": {"rmse": np.asarray(ev.rmse).tolist(), "dop": np.asarray(ev.dop).tolist()},
        "errors": np.round(e, 6).tolist(),
    }


def _rescore(cost: SimulatedCost, anchors: np.ndarray, seed: int) -> float:
    try:
        return float(cost(anchors, np.random.default_rng(seed)))
    except Exception as exc:  # noqa: BLE001 - a failed re-score only drops that finalist
        logger.warning("re-scoring a finalist failed: %s", exc)
        return math.inf


def rescore_finalists(
    res: PSOResult,
    cost: SimulatedCost,
    count: int,
    realizations: int,
    seed: int,
    executor: Executor | None = None,
) -> list[dict[str, Any]]:
    """Re-score the ``count`` best distinct particle layouts (by PSO cost) with
    ``realizations`` noise realizations each, all on the same noise draws (``seed``).

    The swarm ranks layouts by single noisy evaluations, so its best is partly the
    luckiest draw; a less noisy comparison on common draws picks the better layout.
    Returns one dict per finalist (anchors, pso_cost, cost), in PSO-cost order.
    """
    order = np.argsort(res.pcost, kind="stable")
    picked: list[int] = []
    for i in order:
        if len(picked) == count or not math.isfinite(res.pcost[i]):
            break
        if not any(np.allclose(res.pbest[i], res.pbest[j]) for j in picked):
            picked.append(int(i))
    scorer = dataclasses.replace(cost, realizations=int(realizations))
    if executor is None:
        values = [_rescore(scorer, res.pbest[i], seed) for i in picked]
    else:
        futures = [executor.submit(_rescore, scorer, res.pbest[i], seed) for i in picked]
        values = [f.result() for f in futures]
    return [
        {"anchors": res.pbest[i].copy(), "pso_cost": float(res.pcost[i]), "cost": v}
        for i, v in zip(picked, values, strict=True)
    ]


def seed_then_pso(
    room: Room | None = None,
    M: int = 8,
    *,
    particles: int = 15,
    iterations: int = 40,
    cost="variance",
    realizations: int = 1,
    seeds="auto",
    executor: Executor | None = None,
    seed: int | None = None,
    progress: bool = True,
    callback=None,
    checkpoint=None,
    validate_realizations: int = 100,
    options: PSOOptions | None = None,
    sigma: float = 0.04,
    nodes=None,
    search: dict[str, Any] | None = None,
    finalists: int = 4,
    finalist_realizations: int = 10,
) -> PlacementResult:
    """Plan M anchors: seeds → PSO on ``cost`` → finalists → validation.

    cost : "variance" (paper), "mean", "p95", "rms" of the simulated Euclidean error with
        ``realizations`` noise realizations per evaluation; "peb" (mean PEB); or a callable
        ``f(anchors)`` / ``f(anchors, rng)``.
    seeds : "auto" (for a simulated cost: the best layouts of a simulation-driven search
        over candidate points, :func:`simulated_seeds`; then A-/D-optimal relaxations,
        their refinements, best random layouts by PEB), None for an unseeded swarm, or an
        array of seed layouts (S, M, 3).
    executor : a ``concurrent.futures.Executor`` (``ProcessPoolExecutor``, or a Dask
        ``Client.get_executor()``) for the particle evaluations.
    seed : makes the whole run reproducible (same result serially or in parallel).
    checkpoint : a file for the PSO state after every iteration; rerunning with the same
        arguments resumes from it.
    validate_realizations : noise realizations used to validate the best layout (0: skip).
    options : further swarm settings; ``particles`` and ``iterations`` override its fields.
    search : keyword arguments of the simulation-driven seed search
        (:func:`placement.simselect.simulated_select`: ``spacing``, ``realizations``,
        ``starts``, ...; ``{"starts": 0}`` skips it) and ``keep``, the optima kept as seeds.
    finalists, finalist_realizations : for a simulated cost, the ``finalists`` best
        distinct particle layouts are re-scored with ``finalist_realizations`` common
        noise realizations and the lowest wins (:func:`rescore_finalists`); 1: the
        swarm's best as it is. Validation then uses independent noise.
    """
    room = Room.techtile() if room is None else room
    if int(M) != M or M < 4:
        raise ValueError(f"M: need an integer number of anchors >= 4 for 3D positioning, got {M}")
    for name, value in (("finalists", finalists), ("finalist_realizations", finalist_realizations)):
        if int(value) != value or value < 1:
            raise ValueError(f"{name}: must be an integer >= 1, got {value}")
    if int(validate_realizations) != validate_realizations or validate_realizations < 0:
        raise ValueError(
            f"validate_realizations: must be an integer >= 0, got {validate_realizations}"
        )
    base = options or PSOOptions()
    options = PSOOptions(
        **{**base.__dict__, "particles": int(particles), "iterations": int(iterations)}
    )
    entropy = int(seed) if seed is not None else int(np.random.SeedSequence().entropy % 2**63)
    cost_fn = make_cost(cost, room, realizations=realizations, nodes=nodes, sigma=sigma)
    timings: dict[str, float] = {}
    seed_search: dict[str, Any] = {}

    t0 = time.perf_counter()
    if isinstance(seeds, str):
        if seeds != "auto":
            raise ValueError(f"seeds: expected 'auto', None or an array of layouts, got {seeds!r}")
        seed_layouts = []
        search = dict(search or {})
        if isinstance(cost_fn, SimulatedCost) and search.get("starts", 1) > 0:
            seed_layouts, summary = simulated_seeds(
                room,
                M,
                statistic=cost_fn.statistic,
                sigma=sigma,
                nodes=nodes,
                seed=entropy,
                executor=executor,
                **search,
            )
            timings.update({f"seeding_{k}": v for k, v in summary.pop("timings", {}).items()})
            seed_search = summary
        seed_layouts += analytic_seeds(room, M, sigma=sigma, nodes=nodes, seed=entropy)
    elif seeds is None:
        seed_layouts = []
    else:
        arr = np.asarray(seeds, dtype=float).reshape(-1, M, 3)
        seed_layouts = [
            SeedLayout(
                f"user-{i + 1}",
                a,
                float(np.mean(peb(a, room.grid() if nodes is None else nodes, sigma))),
            )
            for i, a in enumerate(arr)
        ]
    # Seeds take at most half of the swarm: the random half keeps exploring.
    seed_layouts = seed_layouts[: max(0, options.particles // 2)]
    timings["seeding"] = time.perf_counter() - t0

    t1 = time.perf_counter()
    initial = np.stack([s.anchors for s in seed_layouts]) if seed_layouts else None
    res = pso(
        cost_fn,
        room,
        M,
        initial=initial,
        options=options,
        executor=executor,
        seed=entropy,
        progress=progress,
        callback=callback,
        checkpoint=checkpoint,
        cost_label=cost_name(cost),
    )
    timings["pso"] = time.perf_counter() - t1
    for i, s in enumerate(seed_layouts):
        s.cost = float(res.costs[0][i])

    t2 = time.perf_counter()
    anchors, chosen_cost, final = res.anchors, res.cost, []
    if finalists > 1 and isinstance(cost_fn, SimulatedCost) and res.success:
        fseed = int(np.random.SeedSequence(entropy, spawn_key=(5,)).generate_state(1)[0])
        final = rescore_finalists(
            res, cost_fn, int(finalists), int(finalist_realizations), fseed, executor
        )
        best = min(final, key=lambda f: f["cost"])
        if math.isfinite(best["cost"]):
            anchors, chosen_cost = best["anchors"], best["pso_cost"]
        timings["finalists"] = time.perf_counter() - t2

    t3 = time.perf_counter()
    validation: dict[str, Any] = {}
    if validate_realizations > 0 and res.success:
        vseed = int(np.random.SeedSequence(entropy, spawn_key=(4,)).generate_state(1)[0])
        validation = validate_layout(
            room, anchors, int(validate_realizations), vseed, sigma=sigma, nodes=nodes
        )
    timings["validation"] = time.perf_counter() - t3
    timings["total"] = time.perf_counter() - t0

    return PlacementResult(
        room=room,
        anchors=np.asarray(anchors),
        cost=float(chosen_cost),
        cost_name=cost_name(cost),
        history=res.history,
        best_anchors_history=res.best_anchors_history,
        nfev=res.nfev,
        nit=res.nit,
        message=res.message,
        success=res.success,
        seeds=seed_layouts,
        validation=validation,
        timings=timings,
        settings={
            "M": int(M),
            "particles": options.particles,
            "iterations": options.iterations,
            "cost": cost_name(cost),
            "realizations": int(realizations),
            "seeds": "auto" if isinstance(seeds, str) else ("none" if seeds is None else "user"),
            "seed_search": seed_search,
            "seed": entropy,
            "validate_realizations": int(validate_realizations),
            "finalists": int(finalists),
            "finalist_realizations": int(finalist_realizations),
            "sigma": sigma,
            "options": dict(options.__dict__),
        },
        pso=res,
        finalists=final,
    )

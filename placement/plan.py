"""The whole chain: search → swarm → refinement → finalists → validation (docs/model.md,
"The whole chain: seed_then_pso").

``seed_then_pso(room, M=8)`` plans M anchors for a simulated cost:

1. **Range table and search** (:mod:`placement.rangetable`, :mod:`placement.simselect`):
   every candidate mounting point is simulated at the nodes of a few scene draws (the
   exact nodes, and nodes moved within their cells with the anchors mounted within
   ``mount_tolerance``); a multi-start swap search on the table finds the seed layouts.
2. **Swarm** (:mod:`placement.pso`): the seeds and a particle started around them, in
   continuous positions on the surfaces, every particle scored on the same scene draws
   as the table (common random numbers, :class:`placement.costs.DrawsCost`); one
   iteration by default (:data:`LOCAL_SWARM`).
3. **Refinement** (:func:`placement.simselect.refine_on_table`): the swarm's best layout
   descends on finer lattices of table columns around its anchors.
4. **Finalists**: the refined layout, the swarm's best and the seeds are scored on fresh
   draws (new noise) and the lowest is chosen, so that a layout fitted to the draws it
   was optimized on does not win by luck.
5. **Validation** (:mod:`placement.validation`): the chosen layout at the evaluation nodes
   with many noise realizations (the paper's statistics), at held-out nodes, and under
   mounting error.

Bound-driven costs ("peb") and user callables skip steps 1, 3 and 4 and seed the swarm with the
convex relaxations and their refinements instead (:func:`analytic_seeds`).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import time
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from analysis.fim import peb
from placement.costs import DrawsCost, cost_name, make_cost
from placement.pso import MAX_ITERATIONS, MAX_PARTICLES, PSOOptions, PSOResult, pso
from placement.rangetable import check_mount_tolerance, node_draws
from placement.result import LayoutResult
from placement.serialization import fingerprint, to_jsonable, write_json_atomic
from placement.simselect import SearchOptions
from placement.surfaces import MAX_ANCHORS, project, random_layout
from placement.validation import ValidationOptions, validate_layout
from placement.workers import executor_workers, run_calls
from simulation import checks
from simulation.room import Room, room_or_default
from simulation.statistics import cost_unit

logger = logging.getLogger(__name__)

#: random layouts screened by mean PEB for the "auto" seeds, and how many are kept
RANDOM_SCREEN, RANDOM_KEEP = 512, 2

#: the random streams of a run (:func:`stream`): the range table (whose node sets the
#: swarm's draws share), the swarm's noise and mounting errors, the search's chains, the
#: validation, the finalists' noise and mounting errors, the finalists' node sets, and the
#: refinement's descents
STREAMS = {
    "table": 1,
    "swarm": 2,
    "search": 3,
    "validation": 4,
    "finalists": 5,
    "finalist_nodes": 6,
    "refinement": 7,
}


def stream(seed: int, name: str) -> int:
    """The int seed of the stream ``name`` (:data:`STREAMS`) of the run
    ``seed_then_pso(rng=seed)`` (``seed``: its int seed, ``settings["seed"]``)."""
    return checks.substream(seed, STREAMS[name])


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
        """The seed as plain JSON types."""
        return {
            "name": self.name,
            "anchors": np.asarray(self.anchors).tolist(),
            "mean_peb": self.mean_peb,
            "cost": self.cost,
            "table_cost": self.table_cost,
        }


#: status codes of :class:`PlacementResult`
PLACEMENT_STATUS = {
    0: "a layout was planned",
    1: "no usable layout: every candidate failed or is degenerate",
}


@dataclass(frozen=True)
class PlacementResult(LayoutResult):
    """Result of :func:`seed_then_pso` (the result convention of :mod:`placement.result`).

    anchors (M, 3) the chosen layout (m); cost (``fun``, in ``cost_unit``) its cost on the
    finalists' fresh draws (a simulated cost), or in the swarm (otherwise); history the
    swarm's best cost per iteration (non-increasing); finalists the layouts scored on
    fresh draws (``source``, ``anchors``, swarm cost ``pso_cost``, fresh-draw cost
    ``cost``; the chosen one has the lowest); seeds the seed layouts with their costs;
    validation the checks of :func:`placement.validation.validate_layout`; timings the
    seconds of every phase and ``total``; settings every setting of the run and
    ``nfev_by_phase``. ``to_dict()`` is the ``result.json`` format and
    :meth:`from_dict` reads it back.
    """

    FUN: ClassVar[str] = "cost"
    STATUS: ClassVar[dict[int, str]] = PLACEMENT_STATUS

    room: Room
    anchors: np.ndarray
    cost: float
    cost_name: str
    cost_unit: str
    history: list[float]
    best_anchors_history: list[np.ndarray]
    nfev: int
    nit: int
    success: bool
    status: int
    message: str
    seeds: list[SeedLayout]
    validation: dict[str, Any]
    timings: dict[str, float]
    settings: dict[str, Any]
    pso: PSOResult | None = field(default=None, repr=False)
    finalists: list[dict[str, Any]] = field(default_factory=list)

    @property
    def availability(self) -> float:
        """The validated share of node realizations with a position fix at the evaluation
        nodes (NaN without a validation); 1 − it is the share of the zone without a fix."""
        return float((self.validation or {}).get("availability", math.nan))

    def to_dict(self) -> dict[str, Any]:
        """The plan as plain JSON types (``kind`` "plan"); :meth:`from_dict` reads it back."""
        return {
            "kind": "plan",
            "room": self.room.to_dict(),
            "anchors": self.anchors.tolist(),
            "cost": self.cost,
            "fun": self.cost,
            "cost_name": self.cost_name,
            "cost_unit": self.cost_unit,
            "history": list(self.history),
            "best_anchors_history": [np.asarray(a).tolist() for a in self.best_anchors_history],
            "nfev": self.nfev,
            "nit": self.nit,
            "success": self.success,
            "status": self.status,
            "message": self.message,
            "seeds": [s.to_dict() for s in self.seeds],
            "finalists": [
                {**f, "anchors": np.asarray(f["anchors"]).tolist()} for f in self.finalists
            ],
            "validation": self.validation,
            "timings": self.timings,
            "settings": self.settings,
            "costs": None if self.pso is None else np.asarray(self.pso.costs).tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> PlacementResult:
        """The result read back from :meth:`to_dict` (e.g. a ``result.json``; JSON nulls
        become NaN); the swarm's full record (``pso``) is not kept."""

        def num(v):
            return math.nan if v is None else float(v)

        seeds = [
            SeedLayout(
                s["name"],
                np.asarray(s["anchors"], dtype=float),
                num(s["mean_peb"]),
                num(s.get("cost")),
                num(s.get("table_cost")),
            )
            for s in d.get("seeds", [])
        ]
        finalists = [
            {
                **f,
                "anchors": np.asarray(f["anchors"], dtype=float),
                "pso_cost": num(f.get("pso_cost")),
                "cost": num(f.get("cost")),
            }
            for f in d.get("finalists", [])
        ]
        return cls(
            room=Room.from_dict(d["room"]),
            anchors=np.asarray(d["anchors"], dtype=float),
            cost=num(d["cost"]),
            cost_name=d["cost_name"],
            cost_unit=d.get("cost_unit", cost_unit(d["cost_name"])),
            history=[num(h) for h in d.get("history", [])],
            best_anchors_history=[np.asarray(a) for a in d.get("best_anchors_history", [])],
            nfev=int(d.get("nfev", 0)),
            nit=int(d.get("nit", 0)),
            success=bool(d.get("success", True)),
            status=int(d.get("status", 0)),
            message=d.get("message", ""),
            seeds=seeds,
            validation=d.get("validation", {}),
            timings=d.get("timings", {}),
            settings=d.get("settings", {}),
            finalists=finalists,
        )

    def to_json(self, **kw) -> str:
        """Strict JSON (non-finite numbers become null)."""
        return json.dumps(to_jsonable(self.to_dict()), **kw)


def analytic_seeds(
    room: Room, M: int, *, sigma: float = 0.04, nodes=None, rng=None
) -> list[SeedLayout]:
    """The "auto" seeds: A- and D-optimal relaxations, their PEB refinements, and the
    best random layouts by mean PEB. A seed whose solver fails is logged and skipped."""
    from placement.refine import refine_peb
    from placement.relaxation import relax_select

    nodes = room.grid() if nodes is None else nodes
    seed = checks.entropy("rng", rng)
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
            sel = relax_select(room, M, criterion=criterion, sigma=sigma, nodes=nodes, rng=seed)
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


#: the swarm of ``seed_then_pso`` for a simulated cost: the seeds and a particle started
#: around them, scored on fresh draws; one iteration, what the swarm contributes
#: (docs/model.md, "Particle swarm optimization")
LOCAL_SWARM = PSOOptions(
    particles=5,
    iterations=1,
    init_spread=0.1,
    velocity_clamp=0.03,
    init_velocity=0.01,
    patience=6,
)


def _check_counts(**values) -> dict[str, Any]:
    """Validate ``name=(value, low, high)`` counts; None passes through."""
    out = {}
    for name, (value, low, high) in values.items():
        out[name] = None if value is None else checks.count(name, value, low=low, high=high)
    return out


def _swarm_options(options, particles, iterations, simulated: bool) -> PSOOptions:
    """The swarm settings: ``options`` (or the default for the cost) with ``particles`` /
    ``iterations`` when given; a clash between them is an error."""
    if options is not None and not isinstance(options, PSOOptions):
        raise ValueError(
            f"options: must be a PSOOptions (e.g. PSOOptions(**options)) or None, "
            f"got {checks.describe(options)}"
        )
    base = options or (LOCAL_SWARM if simulated else PSOOptions())
    for name, value in (("particles", particles), ("iterations", iterations)):
        if value is not None and options is not None and getattr(options, name) != value:
            raise ValueError(
                f"{name}: {value} contradicts options.{name} = {getattr(options, name)}; "
                "give one of them"
            )
    changes = {k: v for k, v in (("particles", particles), ("iterations", iterations)) if v}
    return dataclasses.replace(base, **changes)


def _search_options(search, mount_tolerance=None) -> SearchOptions:
    """The search's settings: ``search`` (SearchOptions, a dict of its fields, or None for
    the defaults) with the plan's ``mount_tolerance`` when given; a clash is an error."""
    if search is None:
        opt, given = SearchOptions(), None
    elif isinstance(search, SearchOptions):
        opt, given = search, search.mount_tolerance
    elif isinstance(search, dict):
        allowed = [f.name for f in dataclasses.fields(SearchOptions)]
        checks.known_keys("search", search, allowed)
        opt = SearchOptions(**search)
        given = opt.mount_tolerance if "mount_tolerance" in search else None
    else:
        raise ValueError(
            "search: must be a SearchOptions or a dict of its fields, "
            f"got {checks.describe(search)}"
        )
    if mount_tolerance is None:
        return opt
    tol = check_mount_tolerance(mount_tolerance)
    if given is not None and given != tol:
        raise ValueError(
            f"mount_tolerance: {tol:g} m contradicts search.mount_tolerance = {given:g} m; "
            "give one of them"
        )
    return dataclasses.replace(opt, mount_tolerance=tol)


class _Clock:
    """Seconds and cost evaluations per phase."""

    def __init__(self):
        self.t0 = self.last = time.perf_counter()
        self.seconds: dict[str, float] = {}
        self.nfev: dict[str, int] = {}

    def lap(self, phase: str, nfev: int | None = None) -> None:
        now = time.perf_counter()
        self.seconds[phase] = self.seconds.get(phase, 0.0) + now - self.last
        self.last = now
        if nfev is not None:
            self.nfev[phase] = int(nfev)

    def timings(self) -> dict[str, float]:
        return {**self.seconds, "total": time.perf_counter() - self.t0}


def _search_fingerprint(room: Room, M: int, opt: SearchOptions, statistic, nodes, entropy) -> str:
    return fingerprint(
        {
            "room": room.to_dict(),
            "M": M,
            "search": dataclasses.asdict(opt),
            "statistic": statistic,
            "nodes": None if nodes is None else np.asarray(nodes).tolist(),
            "seed": entropy,
        }
    )


def build_table(
    room: Room, options: SearchOptions, nodes, seed: int, executor=None, progress: bool = False
):
    """The range table of the run ``seed_then_pso(room, M, rng=seed, search=options,
    nodes=nodes)`` (the same for every M; :func:`placement.simselect.search_table` on the
    run's stream "table"), with a progress bar."""
    from placement.simselect import search_table

    bar = _Bar(progress, "range table")
    table = search_table(room, options, nodes, stream(seed, "table"), executor, bar.update)
    bar.close()
    return table


def search_seeds(
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
) -> tuple[list[SeedLayout], dict[str, Any]]:
    """The simulation-driven seeds: the ``options.keep`` best distinct optima of
    :func:`placement.simselect.simulated_select` on the range table (``table``: a
    :class:`~placement.rangetable.RangeTable`, or a callable that builds it), and the
    search's summary. With a ``checkpoint``, a finished search is saved beside it
    (``<checkpoint>.search.json``) and reused by a rerun with the same arguments, without
    building the table."""
    from placement import simselect

    sidecar = None if checkpoint is None else checkpoint.with_name(checkpoint.name + ".search.json")
    seed = checks.entropy("rng", rng)
    origin = seed if callable(table) else [table.seed, list(table.ranges.shape)]
    print_ = _search_fingerprint(room, M, options, statistic, nodes, origin)
    if sidecar is not None and sidecar.exists():
        saved = _load_sidecar(sidecar)
        if saved.get("fingerprint") == print_:
            seeds = [
                SeedLayout(
                    d["name"], np.array(d["anchors"]), d["mean_peb"], table_cost=d["table_cost"]
                )
                for d in saved["seeds"]
            ]
            return seeds, {**saved["summary"], "resumed": True}
    table = table() if callable(table) else table
    bar = _Bar(progress, "search")
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
    seeds = [
        SeedLayout(f"search-{k + 1}", a, float(np.mean(peb(a, grid, sigma))), table_cost=c)
        for k, (a, (_, c)) in enumerate(zip(sel.layouts(options.keep), sel.optima, strict=False))
    ]
    summary = sel.to_dict()
    del summary["anchors"], summary["optima"]
    if sidecar is not None:
        _write_sidecar(sidecar, print_, seeds, summary)
    return seeds, summary


class _Bar:
    """A tqdm progress bar fed with (done, total) reports; silent when ``progress`` is
    off."""

    def __init__(self, progress: bool, desc: str):
        self.desc, self.bar = desc, None
        self.enabled = progress

    def update(self, done: int, total: int, stage: str | None = None) -> None:
        if not self.enabled:
            return
        if self.bar is None:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=total, desc=self.desc, leave=False)
        if stage is not None:
            self.bar.set_description(f"{self.desc} ({stage})")
        self.bar.total = total
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def _load_sidecar(path: Path) -> dict:
    afresh = "delete it to start afresh"
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"checkpoint {path}: cannot read it ({exc}); {afresh}") from None
    if not isinstance(data, dict) or not {"fingerprint", "seeds", "summary"} <= set(data):
        raise ValueError(f"checkpoint {path}: not a seed-search checkpoint; {afresh}")
    return data


def _write_sidecar(path: Path, print_: str, seeds, summary) -> None:
    blob = {"fingerprint": print_, "seeds": [s.to_dict() for s in seeds], "summary": summary}
    write_json_atomic(path, blob)


def _score(cost, anchors) -> float:
    try:
        return float(cost(anchors))
    except Exception as exc:  # noqa: BLE001 - a failed re-score only drops that finalist
        logger.warning("scoring a finalist failed: %s", exc)
        return math.inf


def best_distinct(res: PSOResult, count: int, exclude=()) -> list[int]:
    """Indices of the ``count`` best particle layouts of a swarm (by their best cost,
    finite only), distinct from each other and from the layouts ``exclude``."""
    picked: list[int] = []
    taken = [np.asarray(a, dtype=float) for a in exclude]
    for i in np.argsort(res.pcost, kind="stable"):
        if len(picked) == count or not math.isfinite(res.pcost[i]):
            break
        if not any(np.allclose(res.pbest[i], a) for a in taken):
            picked.append(int(i))
            taken.append(res.pbest[i])
    return picked


def choose_finalist(
    res: PSOResult,
    seeds: list[SeedLayout],
    cost: DrawsCost,
    count: int,
    executor: Executor | None = None,
    progress=None,
    refined: list[tuple[str, np.ndarray]] = (),
) -> list[dict[str, Any]]:
    """Score the ``count`` best distinct particle layouts (by swarm cost), every seed and
    the ``refined`` layouts (name, anchors) on the fresh draws of ``cost``; returns one
    dict per finalist (``source``, ``anchors``, ``pso_cost`` (NaN for refined layouts),
    ``cost``): refined layouts first, then particles in swarm-cost order, then seeds."""
    picked: list[tuple[str, np.ndarray, float]] = [
        (name, np.asarray(a, dtype=float), math.nan) for name, a in refined
    ]
    for i in best_distinct(res, count, exclude=[a for _, a, _ in picked]):
        same = [s.name for s in seeds if np.allclose(s.anchors, res.pbest[i])]
        source = same[0] if same else "swarm"
        picked.append((source, res.pbest[i].copy(), float(res.pcost[i])))
    for s in seeds:
        if not any(np.allclose(s.anchors, a) for _, a, _ in picked):
            picked.append((s.name, np.asarray(s.anchors), float(s.cost)))
    values = run_calls(executor, [(_score, (cost, a)) for _, a, _ in picked], progress=progress)
    return [
        {"source": src, "anchors": a, "pso_cost": c, "cost": v}
        for (src, a, c), v in zip(picked, values, strict=True)
    ]


def _degenerate(anchors) -> bool:
    return checks.geometry(anchors) in ("collinear", "coincident")


def seed_then_pso(
    room: Room | None = None,
    M: int = 8,
    *,
    cost="variance",
    seeds="auto",
    search: SearchOptions | dict | None = None,
    options: PSOOptions | None = None,
    particles: int | None = None,
    iterations: int | None = None,
    mount_tolerance: float | None = None,
    finalists: int = 1,
    finalist_draws: int = 12,
    finalist_exact_draws: int | None = None,
    validation: ValidationOptions | None = None,
    validate_realizations: int | None = None,
    realizations: int = 1,
    executor: Executor | None = None,
    workers: int | None = None,
    rng=None,
    progress: bool = True,
    callback=None,
    checkpoint=None,
    sigma: float = 0.04,
    nodes=None,
    table=None,
    seed=checks.UNSET,
) -> PlacementResult:
    """Plan M anchors: range-table search → swarm → refinement → finalists → validation
    (module doc).

    room : the room (None: the embedded default, :meth:`simulation.Room.techtile`).
    cost : "variance" (the paper's), "mean", "p95" or "rms" of the simulated Euclidean
        error over the scene draws (:class:`placement.costs.DrawsCost`); "peb" (mean PEB
        with constant ``sigma``); or a callable ``f(anchors)`` / ``f(anchors, rng)``.
    seeds : "auto" (the search's optima for a simulated cost; relaxations and their
        refinements otherwise), None (an unseeded swarm: random particles, the paper's
        setting), or seed layouts (S, M, 3), projected onto the mounting surfaces.
    search : the search's settings (:class:`placement.simselect.SearchOptions` or a dict
        of its fields); its ``draws`` and ``exact_draws`` also set the swarm's draws.
    options, particles, iterations : the swarm's settings (default :data:`LOCAL_SWARM`
        for a simulated cost with seeds, the paper's ``PSOOptions()`` otherwise);
        ``particles`` and ``iterations`` set those fields, and must agree with
        ``options`` when both given.
    mount_tolerance : radius (m) of the in-plane mounting error in the table's moved draws,
        the swarm's and finalists' draws and the validation (None: the search's,
        ``SearchOptions.mount_tolerance``, 0.03 m); it must agree with ``search`` and
        ``table`` when they set one.
    finalists, finalist_draws : how many of the swarm's best distinct layouts, together
        with the seeds and the refined layout, are scored on ``finalist_draws`` fresh
        draws before choosing.
    finalist_exact_draws : how many of those draws keep the nodes and the planned points
        exactly (None: all); the others move the nodes and mount the anchors within
        ``mount_tolerance``, as the table's moved draws do.
    validation, validate_realizations : the validation's settings
        (:class:`placement.validation.ValidationOptions`); ``validate_realizations`` sets
        its ``realizations`` (0: no validation).
    realizations : noise realizations per evaluation of a user's
        :class:`placement.costs.SimulatedCost`-style cost (names use fixed draws instead).
    executor, workers : a ``concurrent.futures.Executor`` and its number of workers (the
        search splits its descents into that many jobs); results do not depend on them.
    rng : an int makes the run reproducible (the same result serially or in parallel, and
        resumable from a checkpoint); a numpy Generator is drawn once; ``seed=`` is its
        deprecated alias.
    checkpoint : a file for the swarm's state after every iteration (the search's result
        beside it); rerunning with the same arguments resumes.
    table : a range table to search instead of building one
        (:func:`placement.rangetable.range_table` with the search's spacing and draws), to
        share it between runs (e.g. :func:`placement.sweep`).
    """
    room = room_or_default(room)
    run = _prepare(room, locals())
    run["reach"] = reach_check(room, run["nodes"])
    run["lattices"] = {
        "spacing": run["search"].spacing_for(room),
        "fine_spacings": list(run["search"].fine_spacings_for(room)),
    }
    clock = _Clock()
    seed_layouts, summary = _seeds(room, run, clock)
    res = _run_swarm(room, run, seed_layouts, clock)
    refined = _refine(room, run, res, clock)
    anchors, chosen, final = _choose(room, run, res, seed_layouts, refined, clock)
    validation = _validate(room, run, anchors, res.success, clock)
    success = res.success and not _degenerate(anchors)
    message = res.message if success else "no usable layout: " + res.message
    return PlacementResult(
        room=room,
        anchors=np.asarray(anchors),
        cost=float(chosen),
        cost_name=run["label"],
        cost_unit=cost_unit(run["label"]),
        history=res.history,
        best_anchors_history=res.best_anchors_history,
        nfev=res.nfev,
        nit=res.nit,
        success=success,
        status=0 if success else 1,
        message=message,
        seeds=seed_layouts,
        validation=validation,
        timings=clock.timings(),
        settings=_settings(run, summary, clock),
        pso=res,
        finalists=final,
    )


def reach_check(room: Room, nodes=None) -> dict[str, Any]:
    """The signal's reach against the room: the reach and near limit (m,
    :class:`simulation.Signal`), and the longest and shortest distances between the nodes
    (default ``room.grid()``) and the allowed mounting points. Logs a warning when the
    room is larger than the reach (or a node nearer a mounting point than the near limit):
    anchors that far give no range, and nodes may be left without a fix."""
    from placement.surfaces import project, rectangle_corners

    grid = room.grid() if nodes is None else np.asarray(nodes, dtype=float)
    # the farthest point of a rectangle from a node is one of its corners
    corners = rectangle_corners(room).reshape(-1, 3)
    far = np.max(np.linalg.norm(grid[:, None] - corners[None], axis=-1))
    near = np.linalg.norm(grid - project(room, grid), axis=-1).min()
    out = {
        "reach_m": room.reach,
        "near_limit_m": room.near_limit,
        "farthest_m": float(far),
        "nearest_m": float(near),
    }
    out["exceeded"] = bool(out["farthest_m"] > room.reach or out["nearest_m"] < room.near_limit)
    if out["exceeded"]:
        logger.warning(
            "the room is larger than the signal's reach: mounting points lie up to %.1f m "
            "from the nodes, the signal reaches %.2f m%s (chirp %.3g ms, window %.3g ms from "
            "%.3g ms); anchors beyond it give no range, the plan scores availability first "
            "and reports the share of node realizations without a fix",
            out["farthest_m"],
            room.reach,
            f" and sees nothing nearer than {room.near_limit:.2f} m" if room.near_limit else "",
            room.signal.chirp.duration * 1e3,
            room.signal.window_span * 1e3,
            room.signal.receiver.t_wake * 1e3,
        )
    return out


def _prepare(room: Room, kw: dict) -> dict[str, Any]:
    """Check every argument before any work; returns the run's resolved settings."""
    M = checks.count("M", kw["M"], low=4, high=MAX_ANCHORS)
    counts = _check_counts(
        particles=(kw["particles"], 2, MAX_PARTICLES),
        iterations=(kw["iterations"], 1, MAX_ITERATIONS),
        finalists=(kw["finalists"], 1, 1000),
        finalist_draws=(kw["finalist_draws"], 1, 1000),
        finalist_exact_draws=(kw["finalist_exact_draws"], 0, 1000),
        validate_realizations=(kw["validate_realizations"], 0, 100_000),
        realizations=(kw["realizations"], 1, 10_000),
        workers=(kw["workers"], 1, 1024),
    )
    sigma = checks.real("sigma", kw["sigma"], low=0.0, high=10.0, low_open=True, unit="m")
    search = _search_options(kw["search"], kw["mount_tolerance"])
    tol = search.mount_tolerance
    rng = checks.rng_or_seed(kw["rng"], kw["seed"], owner="seed_then_pso")
    entropy = checks.entropy("rng", rng)
    cost = kw["cost"]
    cost_fn = make_cost(
        cost, room, realizations=counts["realizations"], nodes=kw["nodes"], sigma=sigma
    )
    simulated = isinstance(cost, str) and cost in ("variance", "mean", "p95", "rms")
    # the local swarm works around seeds; without seeds it is the paper's swarm
    local = simulated and kw["seeds"] is not None
    swarm = _swarm_options(kw["options"], counts["particles"], counts["iterations"], local)
    if counts["finalist_exact_draws"] is None:
        counts["finalist_exact_draws"] = counts["finalist_draws"]
    elif counts["finalist_exact_draws"] > counts["finalist_draws"]:
        raise ValueError(
            f"finalist_exact_draws: must be an integer in [0, {counts['finalist_draws']}] "
            f"(finalist_draws) or None, got {counts['finalist_exact_draws']}"
        )
    if counts["finalists"] > swarm.particles:
        raise ValueError(
            f"finalists: must be an integer in [1, {swarm.particles}] (the swarm's "
            f"particles), got {counts['finalists']}"
        )
    validation = kw["validation"] or ValidationOptions()
    if not isinstance(validation, ValidationOptions):
        raise ValueError(
            f"validation: must be a ValidationOptions or None, got {checks.describe(validation)}"
        )
    if counts["validate_realizations"] is not None:
        validation = dataclasses.replace(validation, realizations=counts["validate_realizations"])
    seeds = kw["seeds"]
    if isinstance(seeds, str) and seeds != "auto":
        raise ValueError(f"seeds: expected 'auto', None or an array of layouts, got {seeds!r}")
    nodes = None if kw["nodes"] is None else room.check_nodes(kw["nodes"])
    checkpoint = kw["checkpoint"]
    table = kw["table"]
    if table is not None and not hasattr(table, "ranges"):
        raise ValueError(f"table: must be a RangeTable or None, got {checks.describe(table)}")
    if table is not None and table.mount_tolerance != tol:
        raise ValueError(
            f"table: built with mount_tolerance {table.mount_tolerance:g} m, the run's is "
            f"{tol:g} m; pass mount_tolerance={table.mount_tolerance:g} or build it with {tol:g}"
        )
    return {
        "table": table,
        "M": M,
        "cost": cost,
        "cost_fn": cost_fn,
        "label": cost_name(cost),
        "simulated": simulated,
        "search": search,
        "swarm": swarm,
        "validation": validation,
        "seeds": seeds,
        "sigma": sigma,
        "mount_tolerance": tol,
        "entropy": entropy,
        "nodes": nodes,
        "finalists": counts["finalists"],
        "finalist_draws": counts["finalist_draws"],
        "finalist_exact_draws": counts["finalist_exact_draws"],
        "executor": kw["executor"],
        "workers": counts["workers"] or executor_workers(kw["executor"]),
        "progress": checks.flag("progress", kw["progress"]),
        "callback": kw["callback"],
        "checkpoint": None if checkpoint is None else checks.output_path("checkpoint", checkpoint),
        "realizations": counts["realizations"],
    }


def _draws_cost(room: Room, run: dict, draws: int, exact: int, key: str, nodes_key: str):
    """A :class:`DrawsCost` of the run's statistic over ``draws`` scene draws, its noise
    from the run's stream ``key`` and its node sets from ``nodes_key``."""
    grid = room.grid() if run["nodes"] is None else run["nodes"]
    sets = node_draws(room, grid, draws, exact, stream(run["entropy"], nodes_key))
    return DrawsCost(
        room,
        sets,
        exact_draws=exact,
        mount_tolerance=run["mount_tolerance"],
        seed=stream(run["entropy"], key),
        statistic=run["cost"],
        precision=run["search"].precision,
    )


def _table(room: Room, run: dict):
    """The run's range table: the one given, else built once (its draws' node sets are
    those of the swarm's cost: the run's stream "table")."""
    if run.get("table") is None:
        run["table"] = build_table(
            room, run["search"], run["nodes"], run["entropy"], run["executor"], run["progress"]
        )
    return run["table"]


def _seeds(room: Room, run: dict, clock: _Clock) -> tuple[list[SeedLayout], dict]:
    """The seed layouts of the run and the search's summary."""
    M, seeds, summary = run["M"], run["seeds"], {}
    out: list[SeedLayout] = []
    if isinstance(seeds, str) and run["simulated"]:
        out, summary = search_seeds(
            room,
            M,
            statistic=run["cost"],
            options=run["search"],
            nodes=run["nodes"],
            rng=stream(run["entropy"], "search"),
            sigma=run["sigma"],
            executor=run["executor"],
            workers=run["workers"],
            checkpoint=run["checkpoint"],
            progress=run["progress"],
            table=lambda: _table(room, run),
        )
        run["searched"] = True
        clock.lap("search", summary.get("nfev"))
    elif isinstance(seeds, str):
        out = analytic_seeds(room, M, sigma=run["sigma"], nodes=run["nodes"], rng=run["entropy"])
        clock.lap("seeding")
    elif seeds is not None:
        grid = room.grid() if run["nodes"] is None else run["nodes"]
        arr = checks.reals("seeds", seeds)
        if arr.ndim not in (2, 3) or arr.shape[-2:] != (M, 3):
            raise ValueError(f"seeds: expected layouts of shape (S, {M}, 3), got {arr.shape}")
        # on the mounting surfaces, as the swarm starts from them: the reported seed and
        # its PEB are the layout that is used
        for i, a in enumerate(project(room, arr.reshape(-1, M, 3))):
            out.append(SeedLayout(f"user-{i + 1}", a, float(np.mean(peb(a, grid, run["sigma"])))))
    return out[: run["swarm"].particles], summary


def _run_swarm(room: Room, run: dict, seed_layouts, clock: _Clock) -> PSOResult:
    """The swarm on the run's cost: the search's draws (common random numbers) for a
    simulated cost, seeded with ``seed_layouts``."""
    s = run["search"]
    cost = run["cost_fn"]
    if run["simulated"]:
        cost = _draws_cost(room, run, s.draws, s.exact_draws, key="swarm", nodes_key="table")
        if run.get("table") is not None:  # the table's own draws: common random numbers
            cost = dataclasses.replace(cost, nodes=run["table"].nodes)
    initial = np.stack([x.anchors for x in seed_layouts]) if seed_layouts else None
    res = pso(
        cost,
        room,
        run["M"],
        initial=initial,
        options=run["swarm"],
        executor=run["executor"],
        rng=run["entropy"],
        progress=run["progress"],
        callback=run["callback"],
        checkpoint=run["checkpoint"],
        cost_label=run["label"],
    )
    for i, x in enumerate(seed_layouts):
        x.cost = float(res.costs[0][i])
    clock.lap("pso", res.nfev)
    return res


def _refine(room: Room, run: dict, res: PSOResult, clock: _Clock) -> list:
    """The best ``fine_optima`` distinct layouts of the swarm (seeds included), each refined
    on finer lattices of the range table (:func:`placement.simselect.refine_on_table`);
    [(name, anchors)]. Simulated costs with fine spacings only."""
    opt = run["search"]
    fine = opt.fine_spacings_for(room)
    if not (run["simulated"] and res.success and fine and run.get("searched")):
        return []
    from placement.simselect import refine_on_table

    starts = [res.pbest[i] for i in best_distinct(res, opt.fine_optima)]
    bar = _Bar(run["progress"], "refinement")
    bar.update(0, len(starts))
    out, nfev = [], 0
    for k, start in enumerate(starts):
        # each on the table grown by its own lattices: another layout's columns would
        # change its descent (docs/model.md, "Refinement after the swarm")
        refined, _, n = refine_on_table(
            room,
            _table(room, run),
            [start],
            statistic=run["cost"],
            options=opt,
            rng=stream(run["entropy"], "refinement"),
            executor=run["executor"],
            workers=run["workers"],
        )
        nfev += n
        out += [(f"refined-{k + 1}", a) for a, f, _ in refined if math.isfinite(f)]
        bar.update(k + 1, len(starts))
    bar.close()
    clock.lap("refinement", nfev)
    return out


def _choose(room: Room, run: dict, res: PSOResult, seed_layouts, refined, clock: _Clock):
    """The chosen layout, its swarm cost, and the finalists (fresh draws, simulated
    costs only); a degenerate layout is never chosen."""
    anchors, chosen, final = res.anchors, res.cost, []
    if run["simulated"] and res.success and (run["finalists"] > 1 or seed_layouts or refined):
        # new noise, by default at the exact nodes: the candidates already come from a
        # search whose draws include moved ones, and the choice among near-equal optima
        # needs draws that vary little (docs/model.md, "The whole chain: seed_then_pso")
        exact = run["finalist_exact_draws"]
        fresh = _draws_cost(
            room, run, run["finalist_draws"], exact, key="finalists", nodes_key="finalist_nodes"
        )
        bar = _Bar(run["progress"], "finalists")
        final = choose_finalist(
            res, seed_layouts, fresh, run["finalists"], run["executor"], bar.update, refined
        )
        bar.close()
        usable = [f for f in final if math.isfinite(f["cost"]) and not _degenerate(f["anchors"])]
        if usable:
            best = min(usable, key=lambda f: f["cost"])
            anchors, chosen = best["anchors"], best["cost"]
        clock.lap("finalists", len(final) * run["finalist_draws"])
    return anchors, chosen, final


def _validate(room: Room, run: dict, anchors, success: bool, clock: _Clock) -> dict:
    out: dict[str, Any] = {}
    if success and run["validation"].realizations > 0:
        bar = _Bar(run["progress"], "validation")
        out = validate_layout(
            room,
            anchors,
            rng=stream(run["entropy"], "validation"),
            options=run["validation"],
            mount_tolerance=run["mount_tolerance"],
            nodes=run["nodes"],
            sigma=run["sigma"],
            executor=run["executor"],
            progress=bar.update,
        )
        bar.close()
    clock.lap("validation")
    return out


def _settings(run: dict, summary: dict, clock: _Clock) -> dict[str, Any]:
    return {
        "M": run["M"],
        "cost": run["label"],
        "seeds": "auto"
        if isinstance(run["seeds"], str)
        else ("none" if run["seeds"] is None else "user"),
        "seed": run["entropy"],
        "search": dataclasses.asdict(run["search"]),
        "search_lattices": run["lattices"],
        "seed_search": summary,
        "swarm": dataclasses.asdict(run["swarm"]),
        "particles": run["swarm"].particles,
        "iterations": run["swarm"].iterations,
        "mount_tolerance": run["mount_tolerance"],
        "finalists": run["finalists"],
        "finalist_draws": run["finalist_draws"],
        "finalist_exact_draws": run["finalist_exact_draws"],
        "validation": dataclasses.asdict(run["validation"]),
        "validate_realizations": run["validation"].realizations,
        "sigma": run["sigma"],
        "reach": run["reach"],
        "nfev_by_phase": dict(clock.nfev),
    }

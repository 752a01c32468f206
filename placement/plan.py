"""The whole chain: search → swarm → refinement → finalists → validation (docs/model.md,
"The whole chain: seed_then_pso").

``seed_then_pso(room, M=8)`` plans M anchors for a simulated cost:

1. **Range table and search** (:mod:`placement.rangetable`, :mod:`placement.initial`):
   every candidate mounting point is simulated at the nodes of a few scene draws (the
   exact nodes, and nodes moved within their cells with the anchors mounted within
   ``search.mount_tolerance``); a multi-start swap search on the table finds the swarm's
   starting layouts.
2. **Swarm** (:mod:`placement.pso`): the starting layouts and a particle started around
   them, in continuous positions on the surfaces, every particle scored on the same scene
   draws as the table (common random numbers, :class:`placement.costs.DrawsCost`); one
   iteration by default (:data:`LOCAL_SWARM`).
3. **Refinement** (:func:`placement.simselect.refine_on_table`): the swarm's best layout
   descends on finer lattices of table columns around its anchors.
4. **Finalists** (:mod:`placement.finalists`): the refined layout, the swarm's best and the
   starting layouts are scored on fresh draws (new noise) and the lowest is chosen.
5. **Validation** (:mod:`placement.validation`): the chosen layout at the evaluation nodes
   with many noise realizations (the paper's statistics), at held-out nodes, and under
   mounting error.

Bound-driven costs ("peb") and user callables skip steps 1, 3 and 4 and start the swarm
from the convex relaxations and their refinements instead
(:func:`placement.initial.analytic_initial`).

:func:`seed_then_pso` is a thin function over :class:`Planner`, whose attributes hold the
run's settings and state and whose methods are the phases, in the order above.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from concurrent.futures import Executor
from typing import Any

import numpy as np

from analysis.fim import DEFAULT_SIGMA, peb
from analysis.progress import ProgressBar, check_progress
from placement import resume, ties
from placement.costs import AUTO, DrawsCost, cost_name, default_cost, is_simulated, make_cost
from placement.coverage import CoverageTarget
from placement.effort import effort_options
from placement.finalists import FinalistOptions, best_distinct, score_finalists
from placement.initial import InitialLayout, analytic_initial, build_table, search_initial
from placement.plan_result import PlacementResult, PlanSettings
from placement.pso import PSOOptions, PSOResult, pso
from placement.rangetable import node_draws
from placement.simselect import SearchOptions
from placement.streams import phase_seed
from placement.surfaces import MAX_ANCHORS, project
from placement.validation import Validation, ValidationOptions, validate_layout
from placement.workers import executor_workers
from simulation import checks, degeneracy, streams
from simulation.room import Room, room_or_default
from simulation.statistics import cost_unit
from simulation.system import as_system

logger = logging.getLogger(__name__)


def seed_then_pso(
    room: Room | None = None,
    M: int = 8,
    *,
    system=None,
    cost="auto",
    initial="auto",
    search: SearchOptions | None = None,
    swarm: PSOOptions | None = None,
    finalists: FinalistOptions | None = None,
    validation: ValidationOptions | None = None,
    effort: str = "default",
    nodes=None,
    rng=0,
    executor: Executor | None = None,
    checkpoint=None,
    callback=None,
    progress=True,
) -> PlacementResult:
    """Plan M anchors: range-table search → swarm → refinement → finalists → validation
    (module docstring); every argument is checked before any work.

    room : the room (None: the embedded default, :meth:`simulation.Room.techtile`).
    M : the number of anchors (4 … 100).
    system : the positioning system the installation will run (:class:`simulation.System`,
        a preset's name or None: the paper's, :meth:`simulation.System.paper`): its chirp
        and receiver are simulated and its positioning solves every fix; recorded in the
        result.
    cost : "auto" (the default: "variance" for the paper's system in the paper's room,
        "rms" otherwise, :func:`placement.costs.default_cost`), or "variance" (the
        paper's), "mean", "p95" or "rms" of the simulated Euclidean
        error over the scene draws (:class:`placement.costs.DrawsCost`); "peb" (mean PEB at
        the default range σ, :data:`analysis.fim.DEFAULT_SIGMA`; a
        :class:`placement.costs.PEBCost` sets another); or a callable ``f(anchors)`` /
        ``f(anchors, rng)``.
    initial : the swarm's starting layouts: "auto" (the search's optima for a simulated
        cost; relaxations and their refinements otherwise), None (random particles, the
        paper's unseeded swarm), or layouts (S, M, 3), projected onto the mounting surfaces.
    search : :class:`placement.simselect.SearchOptions` (None: the preset's): the range
        table, the search, the refinement's lattices, and the scene draws the swarm and
        the finalists share, with ``mount_tolerance``, the radius (m) of the in-plane
        mounting error of every moved draw and of the validation.
    swarm : :class:`placement.pso.PSOOptions` (None: :data:`LOCAL_SWARM` for a simulated
        cost with starting layouts, the paper's ``PSOOptions()`` otherwise).
    finalists : :class:`placement.finalists.FinalistOptions` (None: the preset's).
    validation : :class:`placement.validation.ValidationOptions` (None: the preset's;
        ``realizations=0``: no validation).
    effort : "quick", "default" or "thorough" (:mod:`placement.effort`): the options of
        ``search``, ``finalists`` and ``validation`` left as None.
    nodes : (P, 3) evaluation nodes (None: ``room.grid()``).
    rng : an int seed (default 0: the same result serially, in parallel and resumed from
        a checkpoint), a numpy Generator (drawn once) or None (fresh entropy); the int used
        is recorded in ``settings.seed``. The same rule holds for :func:`placement.sweep`
        and :func:`simulation.evaluate_layout`.
    executor : a ``concurrent.futures.Executor`` for the simulations (results do not
        depend on it).
    checkpoint : a file for the swarm's state after every iteration (the search's result
        beside it); rerunning with the same arguments resumes.
    callback : ``callback(PSOResult-like state)`` after every swarm iteration.
    progress : tqdm progress bars on stderr for every long phase (True), none (False), or
        a callable ``progress(phase, done, total)`` (:mod:`analysis.progress`).
    """
    planner = Planner(room, M, system=system, cost=cost, initial=initial, search=search,
                      swarm=swarm,
                      finalists=finalists, validation=validation, effort=effort, nodes=nodes,
                      rng=rng,
                      executor=executor, checkpoint=checkpoint, callback=callback,
                      progress=progress)  # fmt: skip
    return planner.solve()


#: what each phase's evaluations count (``PlacementResult.phases``)
COUNTS = {
    "search": "table layouts scored",
    "initial": "evaluations",
    "pso": "cost evaluations (simulations for a simulated cost)",
    "refinement": "table layouts scored",
    "finalists": "draw simulations",
    "validation": "noise realizations (grid, held-out grid and points, mounting and field draws)",
}

#: the swarm of ``seed_then_pso`` for a simulated cost: the starting layouts and a particle
#: started around them, scored on fresh draws; one iteration, what the swarm contributes
#: (docs/model.md, "Particle swarm optimization")
LOCAL_SWARM = PSOOptions(
    particles=5,
    iterations=1,
    init_spread=0.1,
    velocity_clamp=0.03,
    init_velocity=0.01,
    patience=6,
)


def default_swarm(cost, initial) -> PSOOptions:
    """The swarm ``seed_then_pso`` uses when given none: :data:`LOCAL_SWARM` for a
    simulated cost with starting layouts, the paper's ``PSOOptions()`` otherwise."""
    return LOCAL_SWARM if is_simulated(cost) and initial is not None else PSOOptions()


class Planner:
    """One run of :func:`seed_then_pso`: its checked settings, its state, its phases.

    Settings (read-only after construction): ``room``, ``M``, ``cost`` (the name or
    object given), ``cost_fn`` (the cost as ``f(anchors, rng)``), ``label``,
    ``simulated`` (a simulated cost), ``search``, ``swarm``, ``finalists``,
    ``validation`` (the options objects), ``effort`` (the :class:`placement.effort.Effort`
    preset the options left as None came from), ``initial`` (as given), ``nodes``, ``sigma`` (the
    range σ of the reported PEB), ``seed`` (the run's int entropy), ``executor``,
    ``workers``, ``checkpoint``, ``callback``, ``progress``.

    State, written by the phases in order: ``table`` (the range table, given or built on
    first use), ``reach`` (:func:`reach_check`), ``initial_layouts`` and ``search_summary``
    (:meth:`find_initial`), ``swarm_result`` (:meth:`run_swarm`), ``refined``
    (:meth:`refine`), ``finalist_rows``, ``anchors`` and ``chosen_cost`` (:meth:`choose`),
    ``validation_result`` (:meth:`validate`), and ``seconds`` and ``nfev`` per phase.
    """

    def __init__(self, room, M, *, system=None, cost="auto", initial="auto", search=None,
                 swarm=None,
                 finalists=None, validation=None, effort="default", nodes=None, rng=0,
                 executor=None,
                 checkpoint=None, callback=None, progress=True, table=None):  # fmt: skip
        self.room = room = room_or_default(room)
        self.system = as_system(system)
        self.system.check_room(room)
        if isinstance(cost, str) and cost == AUTO:
            cost = default_cost(room, self.system)
        self.M = checks.count("M", M, low=4, high=MAX_ANCHORS)
        self.cost, self.label, self.simulated = cost, cost_name(cost), is_simulated(cost)
        self.effort = preset = effort_options(effort)
        self.search = _options("search", search, preset.search)
        self.finalists = _options("finalists", finalists, preset.finalists)
        self.validation = _options("validation", validation, preset.validation)
        self.initial = _check_initial(initial)
        if swarm is None:
            swarm = default_swarm(cost, self.initial)
        self.swarm = _options("swarm", swarm, PSOOptions())
        if self.finalists.count > self.swarm.particles:
            raise ValueError(f"finalists.count: must be an integer in [1, {self.swarm.particles}] "
                             f"(the swarm's particles), got {self.finalists.count}")  # fmt: skip
        self.nodes = None if nodes is None else room.check_nodes(nodes)
        self.cost_fn = make_cost(cost, room, nodes=self.nodes, system=self.system)
        self.sigma = float(getattr(self.cost_fn, "sigma", DEFAULT_SIGMA))
        self.seed = streams.entropy("rng", rng)
        self.executor, self.workers = executor, executor_workers(executor)
        self.checkpoint = (
            None if checkpoint is None else checks.output_path("checkpoint", checkpoint)
        )
        self.store = None  # the finished phases beside the checkpoint (placement.resume)
        if callback is not None and not callable(callback):
            raise ValueError(
                f"callback: must be a callable or None, got {checks.describe(callback)}"
            )
        self.callback, self.progress = callback, check_progress(progress)
        self.table = _check_table(table, self.search.mount_tolerance)
        self.reach: dict[str, Any] = {}
        self.initial_layouts: list[InitialLayout] = []
        self.search_summary: dict[str, Any] = {}
        self.swarm_result: PSOResult | None = None
        self.refined: list[tuple[str, np.ndarray]] = []
        self.finalist_rows: list[dict[str, Any]] = []
        self.anchors: np.ndarray | None = None
        self.chosen_cost = math.nan
        self.validation_result: Validation | None = None
        self.seconds: dict[str, float] = {}
        self.nfev: dict[str, int] = {}
        self._t0 = self._last = time.perf_counter()

    # -- the phases --------------------------------------------------------------------------
    def solve(self) -> PlacementResult:
        """Run every phase and return the result."""
        self._t0 = self._last = time.perf_counter()
        if self.checkpoint is not None:
            self.store = resume.PhaseStore(self.checkpoint, self.identity())
        self.reach = reach_check(self.room, self.system, self.nodes)
        image_check(self.room)
        self.find_initial()
        self.run_swarm()
        self.refine()
        self.choose()
        self.validate()
        return self.result()

    def find_initial(self) -> None:
        """The swarm's starting layouts: the search's optima (simulated cost), the analytic
        ones (otherwise), or the user's, projected onto the surfaces."""
        room, M, initial = self.room, self.M, self.initial
        out: list[InitialLayout] = []
        if isinstance(initial, str) and self.simulated:
            out, self.search_summary = search_initial(
                room, M, statistic=self.cost, options=self.search, nodes=self.nodes,
                rng=phase_seed(self.seed, "search"), sigma=self.sigma, executor=self.executor,
                workers=self.workers, checkpoint=self.checkpoint, progress=self.progress,
                table=self.range_table, system=self.system,
            )  # fmt: skip
            self._lap("search", self.search_summary.get("nfev"))
        elif isinstance(initial, str):
            out = analytic_initial(room, M, sigma=self.sigma, nodes=self.nodes, rng=self.seed)
            self._lap("initial")
        elif initial is not None:
            arr = checks.reals("initial", initial)
            if arr.ndim not in (2, 3) or arr.shape[-2:] != (M, 3):
                raise ValueError(f"initial: expected layouts of shape (S, {M}, 3), got {arr.shape}")
            # on the mounting surfaces, as the swarm starts from them: the reported layout
            # and its PEB are the layout that is used
            grid = self.grid
            for i, a in enumerate(project(room, arr.reshape(-1, M, 3))):
                out.append(
                    InitialLayout(f"user-{i + 1}", a, float(np.mean(peb(a, grid, self.sigma))))
                )
        self.initial_layouts = out[: self.swarm.particles]

    def run_swarm(self) -> None:
        """The swarm on the run's cost, started from :attr:`initial_layouts`: for a simulated
        cost on the search's draws (common random numbers with the range table)."""
        s, cost = self.search, self.cost_fn
        if self.simulated:
            cost = self.draws_cost(s.draws, s.exact_draws, key="swarm", nodes_key="table")
            if self.table is not None:  # the table's own draws: common random numbers
                cost = dataclasses.replace(cost, nodes=self.table.nodes)
        layouts = self.initial_layouts
        res = pso(cost, self.room, self.M,
                  initial=np.stack([x.anchors for x in layouts]) if layouts else None,
                  options=self.swarm, executor=self.executor, rng=self.seed,
                  progress=self.progress, callback=self.callback, checkpoint=self.checkpoint,
                  cost_label=self.label)  # fmt: skip
        for i, x in enumerate(layouts):
            x.cost = float(res.costs[0][i])
        self.swarm_result = res
        self._lap("pso", res.nfev)

    def refine(self) -> None:
        """The swarm's best ``search.fine_optima_for(M)`` distinct layouts (None: all of
        them), each refined on finer lattices of the range table
        (:func:`placement.simselect.refine_on_table`). Simulated costs whose starting layouts
        came from the search only."""
        from placement.simselect import refine_on_table

        res, opt = self.swarm_result, self.search
        searched = self.simulated and isinstance(self.initial, str)
        if not (searched and res.success and opt.fine_spacings_for(self.room)):
            return
        saved = self.store.load("refinement") if self.store else None
        if saved is not None:  # a rerun of a killed plan: the refinement had finished
            self.refined = resume.refined_from_json(saved["refined"])
            self._lap("refinement", saved["nfev"])
            return
        starts = [res.pbest[i] for i in best_distinct(res, opt.fine_optima_for(self.M))]
        bar = ProgressBar(self.progress, "refinement")
        bar.update(0, len(starts))
        nfev = 0
        for k, start in enumerate(starts):
            # each on the table grown by its own lattices: another layout's columns would
            # change its descent (docs/model.md, "Refinement after the swarm")
            table = dataclasses.replace(self.range_table(), coverage_target=self.coverage_target)
            refined, _, n = refine_on_table(
                self.room, table, [start], statistic=self.cost, options=opt,
                rng=phase_seed(self.seed, "refinement"), executor=self.executor,
                workers=self.workers,
            )  # fmt: skip
            nfev += n
            self.refined += [(f"refined-{k + 1}", a) for a, f, _ in refined if math.isfinite(f)]
            bar.update(k + 1, len(starts))
        bar.close()
        if self.store:
            self.store.save("refinement", {"refined": resume.refined_to_json(self.refined),
                                           "nfev": nfev})  # fmt: skip
        self._lap("refinement", nfev)

    def choose(self) -> None:
        """The chosen layout: the finalist with the lowest cost on fresh draws (simulated
        costs), else the swarm's best; a degenerate layout is never chosen."""
        res, fin = self.swarm_result, self.finalists
        self.anchors, self.chosen_cost = np.asarray(res.anchors), float(res.cost)
        if not (
            self.simulated
            and res.success
            and (fin.count > 1 or self.initial_layouts or self.refined)
        ):
            return
        saved = self.store.load("finalists") if self.store else None
        if saved is not None:  # a rerun of a killed plan: the finalists had been scored
            self.finalist_rows = resume.finalists_from_json(saved)
        else:
            self.finalist_rows = self.score_finalists()
        usable = [f for f in self.finalist_rows
                  if math.isfinite(f["cost"]) and not _degenerate(f["anchors"])]  # fmt: skip
        if usable:  # a near-tie goes to the first in the finalists' order (placement.ties)
            best = usable[ties.argmin([f["cost"] for f in usable])]
            self.anchors, self.chosen_cost = np.asarray(best["anchors"]), float(best["cost"])
        self._lap("finalists", len(self.finalist_rows) * fin.draws)

    def score_finalists(self) -> list[dict[str, Any]]:
        """The finalists' rows (:func:`placement.finalists.score_finalists`) on fresh draws:
        new noise, by default at the exact nodes (the candidates already come from a search
        whose draws include moved ones, and the choice among near-equal optima needs draws
        that vary little; docs/model.md, "The whole chain: seed_then_pso")."""
        fin = self.finalists
        fresh = self.draws_cost(fin.draws, fin.exact, key="finalists", nodes_key="finalist_nodes")
        bar = ProgressBar(self.progress, "finalists")
        rows = score_finalists(self.swarm_result, self.initial_layouts, fresh, fin.count,
                               self.executor, bar.update, self.refined)  # fmt: skip
        bar.close()
        if self.store:
            self.store.save("finalists", rows)
        return rows

    def validate(self) -> None:
        """The chosen layout's validation (:func:`placement.validation.validate_layout`)."""
        if self.swarm_result.success and self.validation.realizations > 0:
            bar = ProgressBar(self.progress, "validation")
            self.validation_result = validate_layout(
                self.room, self.anchors, rng=phase_seed(self.seed, "validation"),
                options=self.validation, mount_tolerance=self.search.mount_tolerance,
                nodes=self.nodes, sigma=self.sigma, executor=self.executor, progress=bar.update,
                system=self.system,
            )  # fmt: skip
            bar.close()
        v = self.validation
        mounting = self.search.mount_tolerance > 0 and v.mount_draws
        n = (v.realizations + 2 * v.held_out_realizations + (v.mount_draws if mounting else 0)
             + v.field_draws)  # fmt: skip
        self._lap("validation", 0 if self.validation_result is None else n)

    def result(self) -> PlacementResult:
        """The run's :class:`PlacementResult`."""
        res, phases = self.swarm_result, self.phases()
        success = res.success and not _degenerate(self.anchors)
        return PlacementResult(
            room=self.room, system=self.system, anchors=self.anchors, cost=self.chosen_cost,
            cost_name=self.label,
            cost_unit=cost_unit(self.label), history=res.history,
            best_anchors_history=res.best_anchors_history, nit=res.nit,
            nfev=sum(p["nfev"] for p in phases.values()), phases=phases,
            success=success, status=0 if success else 1,
            message=res.message if success else "no usable layout: " + res.message,
            initial=self.initial_layouts, validation=self.validation_result,
            timings={**self.seconds, "total": time.perf_counter() - self._t0},
            settings=self.settings(), pso=res, finalists=self.finalist_rows,
        )  # fmt: skip

    # -- helpers -----------------------------------------------------------------------------
    @property
    def grid(self) -> np.ndarray:
        """(P, 3) the evaluation nodes."""
        return self.room.grid() if self.nodes is None else self.nodes

    def range_table(self):
        """The run's range table: the one given, else built once (its draws' node sets are
        those of the swarm's cost: the run's stream "table")."""
        if self.table is None:
            self.table = build_table(self.room, self.search, self.nodes, self.seed,
                                     self.executor, self.progress, system=self.system)  # fmt: skip
        return self.table

    def draws_cost(self, draws: int, exact: int, key: str, nodes_key: str) -> DrawsCost:
        """A :class:`DrawsCost` of the run's statistic over ``draws`` scene draws (``exact``
        of them at the exact nodes), its noise from the run's stream ``key`` and its node
        sets from ``nodes_key``."""
        sets = node_draws(self.room, self.grid, draws, exact, phase_seed(self.seed, nodes_key))
        return DrawsCost(self.room, sets, exact_draws=exact,
                         mount_tolerance=self.search.mount_tolerance,
                         seed=phase_seed(self.seed, key), statistic=self.cost,
                         precision=self.search.precision, system=self.system,
                         coverage_target=self.coverage_target)  # fmt: skip

    @property
    def coverage_target(self) -> CoverageTarget | None:
        """The coverage target the search kept to (``search.min_coverage`` where M anchors
        can reach it, and the shadow error of a robust system,
        :func:`placement.simselect.coverage_target`), which the swarm, the
        refinement and the finalists keep to as well; None: none."""
        t = self.search_summary.get("coverage_target")
        return None if t is None else CoverageTarget.from_dict(t)

    def identity(self) -> dict[str, Any]:
        """What identifies the run for its checkpoint: the room, every setting, the nodes."""
        s = self.settings().to_dict()
        for key in ("search_result", "reach"):  # outcomes, not settings
            s.pop(key)
        nodes = None if self.nodes is None else self.nodes.tolist()
        return {"room": self.room.to_dict(), "system": self.system.to_dict(), "settings": s,
                "nodes": nodes}  # fmt: skip

    def settings(self) -> PlanSettings:
        """Every setting of the run, for ``result.json``."""
        initial = self.initial
        return PlanSettings(
            M=self.M, cost=self.label, effort=self.effort.name,
            initial="auto" if isinstance(initial, str) else ("none" if initial is None else "user"),
            seed=self.seed, search=self.search,
            search_lattices={"spacing": self.search.spacing_for(self.room),
                             "fine_spacings": list(self.search.fine_spacings_for(self.room))},
            search_result=self.search_summary, swarm=self.swarm, finalists=self.finalists,
            validation=self.validation, sigma=self.sigma, reach=self.reach,
        )  # fmt: skip

    def phases(self) -> dict[str, dict[str, Any]]:
        """Per phase run: its seconds, its evaluations and what they count."""
        return {
            name: {"seconds": seconds, "nfev": self.nfev.get(name, 0), "counts": COUNTS[name]}
            for name, seconds in self.seconds.items()
        }

    def _lap(self, phase: str, nfev: int | None = None) -> None:
        now = time.perf_counter()
        self.seconds[phase] = self.seconds.get(phase, 0.0) + now - self._last
        self._last = now
        if nfev is not None:
            self.nfev[phase] = int(nfev)


def _options(name: str, value, default):
    """``value`` if it is of ``default``'s class (None: ``default``); else a ValueError
    naming ``name``."""
    if value is None:
        return default
    cls = type(default)
    if not isinstance(value, cls):
        raise ValueError(f"{name}: must be a {cls.__name__} or None, got {checks.describe(value)}")
    return value


def _check_initial(initial):
    if isinstance(initial, str) and initial != "auto":
        raise ValueError(f"initial: expected 'auto', None or an array of layouts, got {initial!r}")
    return initial


def _check_table(table, mount_tolerance: float):
    if table is None:
        return None
    if not hasattr(table, "ranges"):
        raise ValueError(f"table: must be a RangeTable or None, got {checks.describe(table)}")
    if table.mount_tolerance != mount_tolerance:
        raise ValueError(
            f"table: built with mount_tolerance {table.mount_tolerance:g} m, the search's is "
            f"{mount_tolerance:g} m; build it with the same search options"
        )
    return table


def _degenerate(anchors) -> bool:
    return degeneracy.geometry(anchors) in ("collinear", "coincident")


#: the image sources per anchor above which a plan warns that its simulations will be slow:
#: five times the committed warehouse's (4 097 at order 3), where a pair of an anchor and
#: a node already costs a quarter of a millisecond
MANY_IMAGES = 20_000


def image_check(room: Room) -> int:
    """The image sources of an anchor in ``room`` (:func:`simulation.polyhedral.image_count`;
    0 for a shoebox without obstacles, whose images are all valid and cheap). Logs a warning
    above :data:`MANY_IMAGES`: every simulation traces every node's paths against them, so
    the plan will be slow; the counts of each lower ``obstacle_order`` (the reflections a
    path may have on obstacle faces) are named (what a lower one changes: docs/model.md,
    "Obstacles")."""
    from simulation.polyhedral import image_count, reflectors

    if room.is_shoebox and not room.obstacles:
        return 0
    refl = reflectors(room)
    n = image_count(room, refl=refl)
    if n <= MANY_IMAGES:
        return n
    lower = " or ".join(
        f"{image_count(room, k, refl):,} ({k})" for k in range(room.obstacle_order - 1, 0, -1)
    )
    hint = (
        f"; a lower obstacle_order in the room file (the reflections a path may have on "
        f"obstacle faces) gives {lower}"
        if lower
        else ""
    )
    logger.warning(
        "the room has %d reflectors: an anchor has %s image sources up to order %d (%d on "
        "obstacle faces), more than %s: every simulation traces each node's paths against "
        "them, and the plan will be slow%s",
        len(refl.kind), f"{n:,}", room.max_order, room.obstacle_order,
        f"{MANY_IMAGES:,}", hint,
    )  # fmt: skip
    return n


def reach_check(room: Room, system=None, nodes=None) -> dict[str, Any]:
    """The signal's reach against the room: the reach and near limit (m) of ``system``'s
    chirp and receiver (:class:`simulation.System`), and the longest and shortest
    distances between the nodes
    (default ``room.grid()``) and the allowed mounting points. Logs a warning when the
    room is larger than the reach (or a node nearer a mounting point than the near limit):
    anchors that far give no range, and nodes may be left without a fix."""
    from placement.surfaces import rectangle_corners

    system = as_system(system)
    reach, near_limit = system.reach(room.speed_of_sound), system.near_limit(room.speed_of_sound)
    grid = room.grid() if nodes is None else np.asarray(nodes, dtype=float)
    # the farthest point of a rectangle from a node is one of its corners
    corners = rectangle_corners(room).reshape(-1, 3)
    far = np.max(np.linalg.norm(grid[:, None] - corners[None], axis=-1))
    near = np.linalg.norm(grid - project(room, grid), axis=-1).min()
    out = {
        "reach_m": reach,
        "near_limit_m": near_limit,
        "farthest_m": float(far),
        "nearest_m": float(near),
    }
    out["exceeded"] = bool(out["farthest_m"] > reach or out["nearest_m"] < near_limit)
    if out["exceeded"]:
        logger.warning(
            "the room is larger than the signal's reach: mounting points lie up to %.1f m "
            "from the nodes, the signal reaches %.2f m%s (chirp %.3g ms, window %.3g ms from "
            "%.3g ms); anchors beyond it give no range, the plan scores availability first "
            "and reports the share of node realizations without a fix",
            out["farthest_m"],
            reach,
            f" and sees nothing nearer than {near_limit:.2f} m" if near_limit else "",
            system.chirp.duration * 1e3,
            system.window_span * 1e3,
            system.receiver.t_wake * 1e3,
        )
    return out

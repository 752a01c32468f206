"""How many anchors: plan every anchor count of a range and compare their validated errors.

``sweep(room, anchors=range(4, 11), target_p95=1.0)`` runs :func:`placement.seed_then_pso`
once per M on one shared range table (the table depends on the candidate points and the
scene draws, not on M), and recommends the smallest M whose validated availability (the
share of node realizations with a fix) reaches ``target_availability``, whose share of
nodes seeing enough anchors in line of sight reaches ``target_coverage`` and whose P95 in
the field meets ``target_p95`` (docs/model.md, "Anchor-count sweep").
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from placement import ties
from placement.serialization import to_jsonable
from placement.surfaces import MAX_ANCHORS
from simulation import checks, streams
from simulation.room import Room, room_or_default


@dataclass(frozen=True)
class SweepRow:
    """One anchor count: M, the validated σ, mean and P95 (m, over the fixes) and the
    availability at the evaluation nodes, the held-out and mounting-error σ / P95 (m) and
    availabilities, the field σ / mean / P95 / median (m; random tags and mounting error
    together) and its share of verified fixes, the share of the nodes that see
    ``coverage_k`` anchors in line of sight and reach (``covered``) (NaN when not
    validated), the layout (M, 3) and the seconds its plan took."""

    M: int
    std: float
    mean: float
    p95: float
    held_out_std: float
    held_out_p95: float
    mounting_std: float
    mounting_p95: float
    anchors: np.ndarray
    seconds: float
    availability: float = math.nan
    held_out_availability: float = math.nan
    mounting_availability: float = math.nan
    field_std: float = math.nan
    field_mean: float = math.nan
    field_p95: float = math.nan
    field_median: float = math.nan
    field_verified: float = math.nan
    covered: float = math.nan
    coverage_k: int = 0

    def to_dict(self) -> dict[str, Any]:
        """The row as plain JSON types (anchors as nested lists)."""
        d = {k: getattr(self, k) for k in self.__dataclass_fields__}
        d["anchors"] = np.asarray(self.anchors).tolist()
        return d


@dataclass(frozen=True)
class SweepResult:
    """Result of :func:`sweep`: rows (one per M, increasing), recommended the smallest M
    whose validated availability ≥ ``target_availability``, line-of-sight coverage ≥
    ``target_coverage`` and field P95 ≤ ``target_p95`` (when given; :func:`recommend`; None
    when no M does), the
    room, the settings and the seconds of the shared table and of the whole sweep."""

    rows: tuple[SweepRow, ...]
    recommended: int | None
    target_p95: float | None
    room: Room
    settings: dict[str, Any] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    target_availability: float = 0.99
    target_coverage: float = 0.95

    def to_dict(self) -> dict[str, Any]:
        """The sweep as plain JSON types (``kind`` "sweep")."""
        return {
            "kind": "sweep",
            "rows": [r.to_dict() for r in self.rows],
            "recommended": self.recommended,
            "target_p95": self.target_p95,
            "target_availability": self.target_availability,
            "target_coverage": self.target_coverage,
            "room": self.room.to_dict(),
            "settings": self.settings,
            "timings": self.timings,
        }

    def to_json(self, **kw) -> str:
        """Strict JSON (non-finite numbers become null)."""
        return json.dumps(to_jsonable(self.to_dict()), **kw)


def _counts(anchors) -> list[int]:
    try:
        values = list(anchors)
    except TypeError:
        raise ValueError(
            f"anchors: expected anchor counts, e.g. range(4, 11), got {checks.describe(anchors)}"
        ) from None
    if not values:
        raise ValueError("anchors: expected at least one anchor count, got none")
    out = sorted({checks.count("anchors", m, low=4, high=MAX_ANCHORS) for m in values})
    return out


def _row(M: int, res, seconds: float) -> SweepRow:
    v = {} if res.validation is None else res.validation.to_dict()
    held = (v.get("held_out") or {}).get("grid", {})
    mount = v.get("mounting") or {}
    field = v.get("field") or {}
    nan = math.nan
    return SweepRow(
        M=M,
        std=v.get("std", nan),
        mean=v.get("mean", nan),
        p95=v.get("p95", nan),
        held_out_std=held.get("std", nan),
        held_out_p95=held.get("p95", nan),
        mounting_std=mount.get("std", nan),
        mounting_p95=mount.get("p95", nan),
        anchors=np.asarray(res.anchors),
        seconds=seconds,
        availability=v.get("availability", nan),
        held_out_availability=held.get("availability", nan),
        mounting_availability=mount.get("availability", nan),
        field_std=field.get("std", nan),
        field_mean=field.get("mean", nan),
        field_p95=field.get("p95", nan),
        field_median=field.get("median", nan),
        field_verified=field.get("verified", nan),
        covered=v.get("covered", nan),
        coverage_k=int(v.get("coverage_k", 0)),
    )


def recommend(
    rows, target_p95: float | None, target_availability: float, target_coverage: float = 0.0
) -> int | None:
    """The smallest M of ``rows`` whose availability ≥ ``target_availability``, whose
    line-of-sight coverage ≥ ``target_coverage`` and, with a ``target_p95``, whose P95 ≤ it:
    the field's P95 (random tags, anchors mounted with error: what an installation gets)
    where the row has one, else the P95 at the evaluation nodes; None when none does."""
    for r in rows:
        covered = getattr(r, "covered", math.nan)
        field_p95 = getattr(r, "field_p95", math.nan)
        p95 = field_p95 if math.isfinite(field_p95) else r.p95
        if (
            ties.reaches(r.availability, target_availability)
            and (target_coverage <= 0 or ties.reaches(covered, target_coverage))
            and (target_p95 is None or ties.meets(p95, target_p95))
        ):
            return r.M
    return None


def _targets(target_p95, target_availability, target_coverage) -> tuple:
    """The sweep's targets, checked (:func:`sweep`)."""
    if target_p95 is not None:
        target_p95 = checks.real("target_p95", target_p95, low=0.0, low_open=True, unit="m")
    target_availability = checks.real(
        "target_availability", target_availability, low=0.0, high=1.0, low_open=True
    )
    target_coverage = checks.real("target_coverage", target_coverage, low=0.0, high=1.0)
    return target_p95, target_availability, target_coverage


def _plan_each(planners, table, on_row) -> list[SweepRow]:
    """Each planner's plan on the shared ``table``, a row per M (``on_row`` after each)."""
    rows = []
    for planner in planners:
        t = time.perf_counter()
        planner.table = table
        res = planner.solve()
        rows.append(_row(planner.M, res, time.perf_counter() - t))
        if on_row is not None:
            on_row(planner.M, rows[-1])
    return rows


def _shared_table(first, most: int, seed: int):
    """The range table the sweep's plans share, built as the plan of ``first`` (a
    :class:`placement.Planner`) builds it; None for a cost without a table search."""
    from placement.initial import build_table
    from placement.surfaces import candidate_grid

    if not (first.simulated and isinstance(first.initial, str)):
        return None
    room, opt = first.room, first.search
    n = len(candidate_grid(room, opt.spacing_for(room)))
    if n < most:
        raise ValueError(f"anchors: {most} anchors exceed the {n} candidate points "
                         f"(spacing {opt.spacing_for(room):g} m) of this room")  # fmt: skip
    return build_table(room, opt, first.nodes, seed, first.executor, first.progress,
                       system=first.system)  # fmt: skip


def _kept_to(search, effort: str, target_coverage: float):
    """The search options of every M: ``search`` (None: the ``effort`` preset's) with
    ``min_coverage`` the coverage target where it is None, so that each M is planned for the
    coverage the sweep asks of it where M anchors can reach it."""
    from placement.effort import effort_options
    from placement.simselect import SearchOptions

    base = effort_options(effort).search if search is None else search
    if isinstance(base, SearchOptions) and base.min_coverage is None:
        return dataclasses.replace(base, min_coverage=target_coverage)
    return base


def sweep(
    room: Room | None = None,
    anchors=range(4, 11),
    *,
    system=None,
    target_p95: float | None = None,
    target_availability: float = 0.99,
    target_coverage: float = 0.95,
    on_row=None,
    cost="auto",
    initial="auto",
    search=None,
    swarm=None,
    finalists=None,
    validation=None,
    effort: str = "default",
    nodes=None,
    rng=0,
    executor=None,
    progress: bool = True,
) -> SweepResult:
    """Plan each anchor count in ``anchors`` with :func:`placement.seed_then_pso` (the
    keywords from ``cost`` on are its own; every M uses the same ``rng``) on one shared
    range table, built as a plan builds it, so that the row for M is the plan
    ``seed_then_pso(room, M, ...)``; and recommend the smallest M whose validated
    availability reaches ``target_availability`` (a share in (0, 1]), whose share of nodes
    that see k anchors in line of sight and reach reaches ``target_coverage`` (k = 5 for a
    system that rejects echoes, 4 otherwise; 0 turns it off) and whose P95 (m) in the field
    check (at the evaluation nodes where the validation has no field check) ≤ ``target_p95``
    (when given). Each M whose coverage selection reaches
    ``target_coverage`` is planned keeping every layout to it (``search.min_coverage``,
    :class:`placement.simselect.SearchOptions`, where ``search`` leaves it None).

    room : the room (None: the embedded default, :meth:`simulation.Room.techtile`).
    system : the positioning system (:class:`simulation.System`, a preset's name or None:
        the paper's).
    on_row : an optional callable ``on_row(M, row)`` called after each M.
    """
    from placement.plan import Planner

    room = room_or_default(room)
    counts = _counts(anchors)
    if on_row is not None and not callable(on_row):
        raise ValueError(f"on_row: must be a callable on_row(M, row) or None, got {on_row!r}")
    target_p95, target_availability, target_coverage = _targets(
        target_p95, target_availability, target_coverage
    )
    search = _kept_to(search, effort, target_coverage)
    kw = {"system": system, "cost": cost, "initial": initial, "search": search, "swarm": swarm,
          "finalists": finalists, "validation": validation, "effort": effort, "nodes": nodes,
          "executor": executor, "progress": progress}  # fmt: skip
    seed = streams.entropy("rng", rng)
    planners = [Planner(room, M, rng=seed, **kw) for M in counts]  # every argument checked
    first = planners[0]
    t0 = time.perf_counter()
    table = _shared_table(first, max(counts), seed)
    t_table = time.perf_counter() - t0
    rows = _plan_each(planners, table, on_row)
    return SweepResult(
        rows=tuple(rows),
        recommended=recommend(rows, target_p95, target_availability, target_coverage),
        target_p95=target_p95,
        room=room,
        settings={
            "anchors": counts,
            "rng": seed,
            "effort": first.effort.name,
            "search": first.search.__dict__,
            "system": first.system.to_dict(),
        },
        timings={"table": t_table, "total": time.perf_counter() - t0},
        target_availability=target_availability,
        target_coverage=target_coverage,
    )

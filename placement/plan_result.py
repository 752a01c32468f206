"""The planner's result (:func:`placement.seed_then_pso`): the ``result.json`` format."""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from analysis.report_data import system_of
from placement.finalists import FinalistOptions
from placement.initial import InitialLayout
from placement.pso import PSOOptions, PSOResult
from placement.result import LayoutResult
from placement.serialization import to_jsonable
from placement.simselect import SearchOptions
from placement.validation import Validation, ValidationOptions
from simulation.room import Room
from simulation.statistics import cost_unit
from simulation.system import System

#: status codes of :class:`PlacementResult`
PLACEMENT_STATUS = {
    0: "a layout was planned",
    1: "no usable layout: every candidate failed or is degenerate",
}


@dataclass(frozen=True)
class PlanSettings:
    """Every setting of a plan (the ``settings`` of ``result.json``).

    M the anchors; cost the cost's name; effort the preset (:mod:`placement.effort`) of
    the options not given; initial "auto", "none" or "user" (the starting
    layouts); seed the run's int entropy (:mod:`placement.streams`); search, swarm,
    finalists and validation the options objects used; search_lattices the candidate
    grid's ``spacing`` and the refinement's ``fine_spacings`` (m) in this room;
    search_result the search's summary (empty without a search); sigma the range σ (m) of
    the reported PEB; reach :func:`placement.plan.reach_check`'s figures.
    """

    M: int
    cost: str
    effort: str
    initial: str
    seed: int
    search: SearchOptions
    search_lattices: dict[str, Any]
    search_result: dict[str, Any]
    swarm: PSOOptions
    finalists: FinalistOptions
    validation: ValidationOptions
    sigma: float
    reach: dict[str, Any]

    @property
    def mount_tolerance(self) -> float:
        """The mounting tolerance (m) of the search's moved draws and of the validation."""
        return self.search.mount_tolerance

    def to_dict(self) -> dict[str, Any]:
        """The plain-JSON form (the options as dicts; ``mount_tolerance`` repeated at the
        top level for readers of the file)."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            out[f.name] = dataclasses.asdict(value) if dataclasses.is_dataclass(value) else value
            if f.name == "swarm":  # where the files have always had it
                out["mount_tolerance"] = self.mount_tolerance
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> PlanSettings:
        """Read back :meth:`to_dict` (options keys this version does not know are left out)."""
        options = {"search": SearchOptions, "swarm": PSOOptions, "finalists": FinalistOptions,
                   "validation": ValidationOptions}  # fmt: skip
        kw = {f.name: d.get(f.name) for f in dataclasses.fields(cls)}
        for key, kind in options.items():
            known = {f.name for f in dataclasses.fields(kind)}
            kw[key] = kind(**{k: v for k, v in (d.get(key) or {}).items() if k in known})
        kw["effort"] = d.get("effort") or "default"  # files before the presets
        kw["search_result"] = d.get("search_result") or {}
        kw["search_lattices"] = d.get("search_lattices") or {}
        kw["reach"] = d.get("reach") or {}
        kw["sigma"] = float(d["sigma"]) if d.get("sigma") is not None else math.nan
        return cls(**kw)


@dataclass(frozen=True)
class PlacementResult(LayoutResult):
    """Result of :func:`seed_then_pso` (the result convention of :mod:`placement.result`).

    anchors (M, 3) the chosen layout (m); cost (``fun``, in ``cost_unit``) its cost on the
    finalists' fresh draws (a simulated cost), or in the swarm (otherwise); history the
    swarm's best cost per iteration (non-increasing); finalists the layouts scored on
    fresh draws (``source``, ``anchors``, swarm cost ``pso_cost``, fresh-draw cost
    ``cost``; the chosen one has the lowest); initial the swarm's starting layouts with
    their costs;
    validation the checks of :func:`placement.validation.validate_layout` (a
    :class:`placement.validation.Validation`, None when it did not run); timings the
    seconds of every phase and ``total``; phases per phase its ``seconds``, its
    evaluations ``nfev`` and what it counts (``counts``: table layouts scored, swarm
    simulations, draw simulations, validation realizations); nfev their sum; nit the
    swarm's iterations; settings every setting of the run (:class:`PlanSettings`); system
    the positioning system planned for (:class:`simulation.System`).
    ``to_dict()`` is the
    ``result.json`` format, :meth:`from_dict` reads it back and :meth:`read` reads a
    result folder.
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
    initial: list[InitialLayout]
    validation: Validation | None
    timings: dict[str, float]
    settings: PlanSettings
    pso: PSOResult | None = field(default=None, repr=False)
    finalists: list[dict[str, Any]] = field(default_factory=list)
    phases: dict[str, dict[str, Any]] = field(default_factory=dict)
    system: System = field(default_factory=System)

    @property
    def availability(self) -> float:
        """The validated share of node realizations with a position fix at the evaluation
        nodes (NaN without a validation); 1 − it is the share of the zone without a fix."""
        return math.nan if self.validation is None else float(self.validation.availability)

    def to_dict(self) -> dict[str, Any]:
        """The plan as plain JSON types (``kind`` "plan"); :meth:`from_dict` reads it back."""
        return {
            "kind": "plan",
            "room": self.room.to_dict(),
            "system": self.system.to_dict(),
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
            "initial": [s.to_dict() for s in self.initial],
            "finalists": [
                {**f, "anchors": np.asarray(f["anchors"]).tolist()} for f in self.finalists
            ],
            "validation": {} if self.validation is None else self.validation.to_dict(),
            "timings": self.timings,
            "phases": self.phases,
            "settings": self.settings.to_dict(),
            "costs": None if self.pso is None else np.asarray(self.pso.costs).tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> PlacementResult:
        """The result read back from :meth:`to_dict` (e.g. a ``result.json``; JSON nulls
        become NaN); the swarm's full record (``pso``) is not kept."""

        def num(v):
            return math.nan if v is None else float(v)

        initial = [
            InitialLayout(
                s["name"],
                np.asarray(s["anchors"], dtype=float),
                num(s["mean_peb"]),
                num(s.get("cost")),
                num(s.get("table_cost")),
            )
            for s in d.get("initial", d.get("seeds", []))  # "seeds": earlier versions' files
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
            room=Room.from_dict({k: v for k, v in d["room"].items() if k != "signal"}),
            system=system_of({"result": d}),
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
            initial=initial,
            validation=Validation.from_dict(d.get("validation")),
            timings=d.get("timings", {}),
            phases=d.get("phases", {}),
            settings=PlanSettings.from_dict(d.get("settings", {})),
            finalists=finalists,
        )

    @classmethod
    def read(cls, result_dir) -> PlacementResult:
        """The plan in a result folder's ``result.json``, read by the one reader of result
        folders, :func:`analysis.report_data.load_results` (which the report, ``export``,
        ``sheet`` and ``stress`` use too); ValueError when the folder has no plan."""
        from analysis.report_data import RESULT_FILE, load_results

        try:
            data = load_results(result_dir)["result"]
        except FileNotFoundError as exc:
            raise ValueError(str(exc)) from None
        if data is None:
            raise ValueError(f"RESULT_DIR: {result_dir} has no {RESULT_FILE}")
        return cls.from_dict(data)

    def to_json(self, **kw) -> str:
        """Strict JSON (non-finite numbers become null)."""
        return json.dumps(to_jsonable(self.to_dict()), **kw)

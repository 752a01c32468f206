"""Layouts: mounting surfaces and projection, candidates, relaxation, refinement, PSO.

The top layer: imports :mod:`analysis` and :mod:`simulation`, never the reverse.
"""

from placement.anchor_sweep import SweepResult, sweep
from placement.costs import DrawsCost, PEBCost, SimulatedCost, make_cost
from placement.effort import EFFORT_NAMES, Effort, effort_options
from placement.exhaustive import ExhaustiveResult, exhaustive_search
from placement.finalists import FinalistOptions
from placement.initial import InitialLayout
from placement.plan import Planner, seed_then_pso
from placement.plan_result import PlacementResult
from placement.pso import PSOOptions, PSOResult, pso
from placement.refine import RefineResult, refine_peb
from placement.relaxation import Selection, relax_select
from placement.result import LayoutResult
from placement.simselect import SearchOptions
from placement.surfaces import (
    MountingSurface,
    aim,
    allowed,
    allowed_area,
    allowed_rectangles,
    area_counts,
    candidate_grid,
    from_uv,
    mounting_surfaces,
    naive_layout,
    on_surfaces,
    project,
    random_layout,
    surface_index,
    to_uv,
)
from placement.validation import ValidationOptions
from placement.workers import WorkerLost, WorkerPool

__all__ = [
    "EFFORT_NAMES",
    "Effort",
    "effort_options",
    "DrawsCost",
    "SearchOptions",
    "SweepResult",
    "ValidationOptions",
    "sweep",
    "PEBCost",
    "PSOOptions",
    "PSOResult",
    "PlacementResult",
    "InitialLayout",
    "FinalistOptions",
    "Planner",
    "SimulatedCost",
    "make_cost",
    "pso",
    "seed_then_pso",
    "ExhaustiveResult",
    "LayoutResult",
    "MountingSurface",
    "RefineResult",
    "Selection",
    "aim",
    "allowed",
    "allowed_area",
    "allowed_rectangles",
    "area_counts",
    "candidate_grid",
    "exhaustive_search",
    "from_uv",
    "mounting_surfaces",
    "naive_layout",
    "on_surfaces",
    "project",
    "random_layout",
    "refine_peb",
    "relax_select",
    "surface_index",
    "to_uv",
    "WorkerLost",
    "WorkerPool",
]

"""Effort presets: named sets of the planner's option values (docs/model.md, "Effort").

``seed_then_pso(room, M, effort="quick")`` takes the options objects of the preset for the
phases whose options it is not given; an options object given replaces the preset's for
its phase, whole. To change one value of a preset, start from its object::

    quick = placement.effort_options("quick")
    seed_then_pso(room, 8, search=dataclasses.replace(quick.search, chains=2), effort="quick")

The command line's flags change single values of the preset's objects (``--effort``).

- **quick**: one table draw (the exact nodes), four short search chains (1000 layouts),
  three starting layouts, the swarm's best refined (at every M) on one lattice at half the
  candidate spacing (0.2 m in techtile), three
  fresh draws for the finalists and a light validation (8 realizations at the evaluation
  nodes, no held-out nodes, 2 mounting and 3 field draws): a first answer.
- **default**: the planner's defaults (the options classes' own).
- **thorough**: six table draws (two of them at moved nodes with mounting error, the
  default's share), sixteen search chains of 9000 layouts, the three best swarm layouts
  refined, three finalists besides the starting and refined layouts scored on 24 fresh
  draws at the exact nodes, and a field check of 20 draws.

The swarm is :data:`placement.plan.LOCAL_SWARM` in every preset (for a simulated cost
with starting layouts; the paper's swarm otherwise): the refinement is the stage that
improves the starting layouts.
"""

from __future__ import annotations

from dataclasses import dataclass

from placement.finalists import FinalistOptions
from placement.simselect import SearchOptions
from placement.validation import ValidationOptions

#: the presets' names, in order of effort
EFFORT_NAMES = ("quick", "default", "thorough")


@dataclass(frozen=True)
class Effort:
    """One preset: its ``name`` and the options of the search, the finalists and the
    validation (the swarm's follow :func:`placement.plan.default_swarm`)."""

    name: str
    search: SearchOptions
    finalists: FinalistOptions
    validation: ValidationOptions


EFFORTS = {
    "quick": Effort(
        "quick",
        SearchOptions(draws=1, exact_draws=1, chains=4, evaluations=1000, random_starts=20,
                      fine_halvings=1, keep=3, fine_optima=1),
        FinalistOptions(draws=3),
        ValidationOptions(realizations=8, held_out_realizations=0, mount_draws=2,
                          field_draws=3),
    ),
    "default": Effort("default", SearchOptions(), FinalistOptions(), ValidationOptions()),
    "thorough": Effort(
        "thorough",
        SearchOptions(draws=6, exact_draws=4, chains=16, evaluations=9000, fine_optima=3),
        FinalistOptions(count=3, draws=24),
        ValidationOptions(field_draws=20),
    ),
}  # fmt: skip


def effort_options(effort: str) -> Effort:
    """The preset named ``effort`` (:data:`EFFORT_NAMES`); ValueError for another name."""
    if not isinstance(effort, str) or effort not in EFFORTS:
        raise ValueError(f"effort: expected one of {', '.join(EFFORT_NAMES)}, got {effort!r}")
    return EFFORTS[effort]


__all__ = ["EFFORTS", "EFFORT_NAMES", "Effort", "effort_options"]

"""Layouts: mounting surfaces and projection, candidates, relaxation, refinement, PSO.

The top layer: imports :mod:`analysis` and :mod:`simulation`, never the reverse.
"""

from placement.surfaces import (
    MountingSurface,
    aim,
    area_counts,
    candidate_grid,
    from_uv,
    mounting_surfaces,
    on_surfaces,
    project,
    random_layout,
    surface_index,
    to_uv,
)

__all__ = [
    "MountingSurface",
    "aim",
    "area_counts",
    "candidate_grid",
    "from_uv",
    "mounting_surfaces",
    "on_surfaces",
    "project",
    "random_layout",
    "surface_index",
    "to_uv",
]

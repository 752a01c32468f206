"""The random streams of a plan: one independent stream per phase, from the run's seed.

``seed_then_pso(rng=seed)`` draws everything from ``seed`` (its int entropy, recorded in
``settings.seed``): each phase takes the int seed :func:`phase_seed` of its own stream,
so that a phase's draws do not depend on how many numbers another phase drew, serially or
on any number of workers.
"""

from __future__ import annotations

from simulation import streams

#: the streams of a run: the range table (whose node sets the swarm's draws share), the
#: swarm's noise and mounting errors, the search's chains, the validation, the finalists'
#: noise and mounting errors, the finalists' node sets, and the refinement's descents
STREAMS = {
    "table": 1,
    "swarm": 2,
    "search": 3,
    "validation": 4,
    "finalists": 5,
    "finalist_nodes": 6,
    "refinement": 7,
}


def phase_seed(seed: int, name: str) -> int:
    """The int seed of the stream ``name`` (:data:`STREAMS`) of the run with int seed
    ``seed``."""
    return streams.substream(seed, STREAMS[name])

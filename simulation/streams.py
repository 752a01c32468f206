"""Random streams: numpy Generators from the ``rng`` arguments, and the independent
streams of reproducible work.

Every function that draws random numbers takes ``rng``: an int seed, a numpy ``Generator``
(drawn once), or None (fresh entropy). Work that must not depend on how it is split (a
table column, a search chain, a particle's evaluation) draws from its own stream
:func:`stream` of one integer seed and a key path.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from simulation.checks import describe

__all__ = ["entropy", "rng", "stream", "substream"]


def rng(name: str, value: Any) -> np.random.Generator:
    """A numpy ``Generator`` from a Generator, BitGenerator, SeedSequence, a seed (int >= 0)
    or None (fresh entropy), as :func:`numpy.random.default_rng` would; else ValueError."""
    if isinstance(value, np.random.Generator):
        return value
    if value is None or isinstance(value, np.random.BitGenerator | np.random.SeedSequence):
        return np.random.default_rng(value)
    if isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_):
        if value >= 0:
            return np.random.default_rng(int(value))
    raise ValueError(
        f"{name}: must be a numpy Generator, a seed (an integer >= 0) or None, "
        f"got {describe(value)}"
    )


def stream(seed: int, *key: int) -> np.random.Generator:
    """The random stream of an integer seed and a key path: ``Generator(PCG64(
    SeedSequence(seed, spawn_key=key)))``. Every reproducible piece of work (a table
    column, a chain, a particle's evaluation) draws from its own key, so results do not
    depend on how the work is split."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=key)))


def substream(seed: int, key: int) -> int:
    """An integer seed derived from ``seed`` for the part ``key`` of a run."""
    return int(np.random.SeedSequence(seed, spawn_key=(key,)).generate_state(1)[0])


def entropy(name: str, value: Any) -> int:
    """An integer seed (>= 0) standing for an ``rng`` argument: a seed is itself, so that
    ``rng=s`` reproduces what ``seed=s`` did; a Generator (BitGenerator, SeedSequence)
    gives one draw below 2**63; None gives fresh entropy (below 2**63). For functions that
    derive several child streams from one seed (``SeedSequence(entropy).spawn(n)``)."""
    if isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_):
        if value >= 0:
            return int(value)
    if value is None:
        return int(np.random.SeedSequence().entropy % 2**63)
    return int(rng(name, value).integers(2**63))

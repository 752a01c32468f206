"""The node's received windows of a room's paths (paper §II): the paths' delays and
amplitudes (:mod:`simulation.multipath`) synthesized from the analytic chirp
(:mod:`simulation.synthesis`)."""

from __future__ import annotations

import numpy as np

from simulation import checks
from simulation.chirp import Chirp
from simulation.multipath import Paths
from simulation.receiver import Receiver, signal_chain
from simulation.synthesis import synthesize


def received_windows(
    paths: Paths,
    speed_of_sound: float,
    chirp: Chirp | None = None,
    receiver: Receiver | None = None,
    air=None,
) -> np.ndarray:
    """(P, M, N) noise-free received windows of :class:`~simulation.multipath.Paths`;
    ``speed_of_sound`` in m/s; ``air`` the room's frequency-dependent excess attenuation
    (``Room.air_excess()``; None: the amplitudes hold all of it)."""
    if not isinstance(paths, Paths):
        raise ValueError(f"paths: must be simulation.multipath.Paths, got {checks.describe(paths)}")
    speed_of_sound = checks.real(
        "speed_of_sound", speed_of_sound, low=0.0, low_open=True, unit="m/s"
    )
    chirp, receiver = signal_chain(chirp, receiver)
    return synthesize(
        paths.delays(speed_of_sound),
        paths.amplitude,
        chirp,
        receiver,
        lengths=paths.length,
        air=air,
        grouped=paths.line_of_sight is not None,  # traced paths: uneven counts
    )

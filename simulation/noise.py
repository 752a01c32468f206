"""Receiver noise: AWGN with a per-anchor variance set by the SNR rule of paper §V-A.

For anchor j, the reference node is the node of the evaluation grid (``room.grid()``,
default shape) closest to the anchor. Its noise-free received window y_ref (N samples, all
paths) has mean power P_j = mean(y_ref²), and the noise variance is

    σ_j² = P_j / 10^(SNR/10),

the same at every node for that anchor, so the SNR falls with distance and off-axis angle
(paper §V-A: "the SNR is defined for the closest mobile node to a specific anchor"). Noise
is white Gaussian, independent across samples, nodes, anchors and realizations, and is
added to the received window before the receiver DSP. Where the window misses the
reference node's chirp (a signal design whose near limit exceeds that distance), P_j is
the direct path's mean power A²/2 instead.
"""

from __future__ import annotations

import numpy as np

from simulation import checks
from simulation.multipath import ImageSet, compute_paths
from simulation.received import received_windows
from simulation.room import Room, as_room
from simulation.system import as_system

#: default SNR at the grid node closest to each anchor, dB (paper §V-A)
DEFAULT_SNR_DB = 30.0
#: accepted SNR range in dB (from noise 100× the signal power to practically noise-free)
SNR_RANGE_DB = (-20.0, 120.0)


def check_snr(name: str, snr_db) -> float:
    """The SNR in dB as a float, in :data:`SNR_RANGE_DB`; ValueError otherwise."""
    lo, hi = SNR_RANGE_DB
    return checks.real(name, snr_db, low=lo, high=hi, unit="dB")


def reference_nodes(room: Room, anchors, grid_shape=(9, 6, 5)) -> np.ndarray:
    """(M, 3) the grid node closest to each anchor (ties: the first in grid order)."""
    room = as_room(room)
    a = checks.points("anchors", anchors)
    # the regular room grid even when the room has tag zones: the SNR reference is a
    # property of the room and its anchors, not of where tags are expected
    grid = room.grid(checks.grid_shape("grid_shape", grid_shape))
    d = np.linalg.norm(grid[:, None, :] - a[None, :, :], axis=-1)  # (G, M)
    return grid[np.argmin(d, axis=0)]


def noise_sigma(
    room: Room,
    anchors,
    snr_db: float = DEFAULT_SNR_DB,
    grid_shape=(9, 6, 5),
    images: ImageSet | None = None,
    system=None,
) -> np.ndarray:
    """(M,) noise standard deviation σ_j per anchor (units of the received signal).

    σ_j² = mean(y_ref,j²) / 10^(snr_db/10), y_ref,j the noise-free window (the chirp and
    receiver of ``system``, default the paper's) of anchor j at its :func:`reference_nodes`
    node.
    """
    snr_db = check_snr("snr_db", snr_db)
    room = as_room(room)
    a = checks.points("anchors", anchors)
    ref = reference_nodes(room, a, grid_shape)
    system = as_system(system)
    ch = system.chirp
    paths = compute_paths(room, a, ref, images=images, frequency=ch.centre)  # (M, M, I)
    w = received_windows(paths, room.speed_of_sound, ch, system.receiver,
                         room.air_excess(ch.centre))  # fmt: skip
    j = np.arange(len(a))
    own = w[j, j]  # (M, N): node j with anchor j
    power = np.mean(own * own, axis=-1)
    # a window that misses the chirp at the reference node (a design with a near limit):
    # the mean power A²/2 of its direct path instead
    direct = paths.amplitude[j, j, 0]
    power = np.where(power > 0, power, 0.5 * direct * direct)
    return np.sqrt(power / 10.0 ** (snr_db / 10.0))

"""Coverage: how many anchors a tag hears, and where fewer than 4 leave it without a fix.

A node hears anchor j when the receiver would report a range of its direct path
(:meth:`analysis.noise.PhysicalRangeNoise.heard`, docs/model.md, "Coverage"): nothing
blocks the line of sight (a wall of a non-convex room, an obstacle), the direct path lies
within the signal's reach (and beyond its near limit) and, for a receiver with a
detection threshold, its expected correlation peak clears it at the SNR rule's noise
level. A position fix needs 4 heard anchors (:mod:`simulation.positioning`); a blocked
anchor still gives the receiver an echo to pick, which the simulation counts and the
bound does not.
This is the geometry of the signal design, from the direct path alone; the simulated
availability (``Evaluation.availability``) also counts the noise. :func:`heard_sigma` gives
the bounds (PEB maps, the report) the same view: an anchor not heard carries no
information.
"""

from __future__ import annotations

import numpy as np

from analysis.fim import DEFAULT_SIGMA
from analysis.noise import PhysicalRangeNoise
from simulation import checks
from simulation.noise import DEFAULT_SNR_DB
from simulation.positioning import MIN_HEARD
from simulation.room import Room, as_room
from simulation.system import as_system


def heard(room: Room, anchors, nodes, snr_db: float = DEFAULT_SNR_DB, system=None) -> np.ndarray:
    """(..., P, M) bool: node p hears anchor j with ``system``'s signal and receiver
    (module docstring; default the paper's); anchors (..., M, 3), nodes (P, 3) in metres."""
    room = as_room(room)
    a = checks.reals("anchors", anchors)
    if a.ndim < 2 or a.shape[-1] != 3:
        raise ValueError(f"anchors: expected shape (..., M, 3), got {a.shape}")
    p = checks.points("nodes", nodes)
    return PhysicalRangeNoise(room, snr_db=snr_db, system=as_system(system)).heard(a, p)


def coverage(room: Room, anchors, nodes, snr_db: float = DEFAULT_SNR_DB, system=None):
    """(..., P) the number of anchors each node hears (:func:`heard`)."""
    return np.sum(heard(room, anchors, nodes, snr_db, system), axis=-1)


def covered_share(
    room: Room, anchors, nodes, snr_db: float = DEFAULT_SNR_DB, system=None, k: int = MIN_HEARD
) -> float:
    """The share of the nodes that hear at least ``k`` anchors (default 4,
    :data:`MIN_HEARD`; 5 lets a positioning that rejects echoes find one)."""
    return float(np.mean(coverage(room, anchors, nodes, snr_db, system) >= k))


def heard_sigma(
    room: Room, anchors, nodes, sigma=DEFAULT_SIGMA, snr_db: float = DEFAULT_SNR_DB, system=None
):
    """(..., P, M) the range σ (m; a scalar or anything broadcasting to (..., P, M)) where
    node p hears anchor j, +inf (no information, :func:`analysis.fim.fim`) where it does
    not: the bound then counts only the anchors the receiver reports."""
    h = heard(room, anchors, nodes, snr_db, system)
    s = np.broadcast_to(np.asarray(sigma, dtype=float), h.shape)
    return np.where(h, s, np.inf)


def bound(
    room: Room, anchors, nodes, sigma=DEFAULT_SIGMA, snr_db: float = DEFAULT_SNR_DB, system=None
):
    """(..., P) PEB = √tr J⁻¹ (m) from the anchors each node hears (:func:`heard_sigma`),
    +inf at a node that hears fewer than 4 (no fix) or whose heard anchors leave J
    singular: the bound the report and the PEB maps show."""
    from analysis.fim import peb

    s = heard_sigma(room, anchors, nodes, sigma, snr_db, system)
    out = peb(anchors, nodes, sigma=s)
    return np.where(np.sum(np.isfinite(s), axis=-1) >= MIN_HEARD, out, np.inf)


__all__ = ["bound", "coverage", "covered_share", "heard", "heard_sigma"]

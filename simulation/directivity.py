"""Anchor directivity: the cardioid speaker aimed at the room centroid (paper §V-A)."""

from __future__ import annotations

import numpy as np

from simulation import checks


def cardioid(cos_theta: np.ndarray) -> np.ndarray:
    """Cardioid amplitude gain g(θ) = ½(1 + cos θ), from cos θ (any shape)."""
    if cos_theta is None:  # np.asarray(None, dtype=float) is NaN, not an error
        raise ValueError("cos_theta: must be an array of cosines in [-1, 1], got None")
    return 0.5 * (1.0 + np.asarray(cos_theta, dtype=float))


def aim_vectors(anchors: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(..., M, 3) unit vectors from each anchor (..., M, 3) toward ``target`` (3,).

    An anchor exactly at the target gets the +z axis (any direction is as good).
    """
    a, t = checks.reals("anchors", anchors), checks.reals("target", target, shape=(3,))
    if a.ndim < 1 or a.shape[-1] != 3:
        raise ValueError(f"anchors: expected shape (..., M, 3), got {a.shape}")
    d = t - a
    n = np.linalg.norm(d, axis=-1, keepdims=True)
    safe = n > 0
    return np.where(safe, d / np.where(safe, n, 1.0), np.array([0.0, 0.0, 1.0]))

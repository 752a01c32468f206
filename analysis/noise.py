"""Range-noise models: the σ_j(p) that enters the Fisher information (SPEC §3).

- :class:`ConstantRangeNoise`: one σ for every anchor and node (default 0.04 m, the
  paper's 0.03–0.045 m).
- :class:`PhysicalRangeNoise`: σ_j(p) from the SNR that node p sees from anchor j, through
  the Cramér–Rao bound for time-delay estimation of the received 1 ms window.
- A model calibrated from simulated range errors lives with the simulator
  (``simulation`` issue): any (M,) or (P, M) array works as ``sigma``.

Every model has ``sigma(anchors, positions)`` returning σ in metres, broadcastable to
(..., P, M) for anchors (..., M, 3) and positions (P, 3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from simulation.chirp import Chirp
from simulation.directivity import aim_vectors, cardioid
from simulation.receiver import Receiver
from simulation.room import Room


@dataclass(frozen=True)
class ConstantRangeNoise:
    """σ_j(p) = ``value`` metres for every pair."""

    value: float = 0.04

    def __post_init__(self) -> None:
        if not (math.isfinite(self.value) and self.value > 0):
            raise ValueError(f"value: range σ must be > 0 m, got {self.value}")

    def sigma(self, anchors, positions) -> np.ndarray:
        """σ as a 0-d array (broadcasts to any (..., P, M))."""
        return np.asarray(self.value)


def direct_amplitude(room: Room, anchors, positions) -> np.ndarray:
    """Direct-path amplitude A_j(p), (..., P, M), for a unit-amplitude chirp at the speaker.

    A = g(θ)·exp(−a·d/2)/(4π d): cardioid gain toward p (anchor aimed at the centroid),
    air absorption and spherical spreading (SPEC §2). A node on an anchor gets +inf.
    """
    a = np.asarray(anchors, dtype=float)
    p = np.asarray(positions, dtype=float)
    diff = p[:, None, :] - a[..., None, :, :]  # (..., P, M, 3)
    d = np.linalg.norm(diff, axis=-1)
    aim = aim_vectors(a, room.centroid)[..., None, :, :]  # (..., 1, M, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.where(d > 0, np.sum(diff * aim, axis=-1) / np.where(d > 0, d, 1.0), 1.0)
        amp = cardioid(cos) * np.exp(-0.5 * room.air_absorption * d) / (4 * np.pi * d)
    return np.where(d > 0, amp, np.inf)


@dataclass(frozen=True)
class PhysicalRangeNoise:
    """Range σ from the SNR at each node and the CRLB of time-delay estimation.

    Per anchor j the white-noise variance is set as in SPEC §2: SNR = ``snr_db`` at the
    grid node closest to the anchor, σ_w,j² = (A_j(p_ref)²/2)/10^(SNR/10) (A²/2 is the mean
    power of the direct-path sinusoid; multipath is not modelled here). At node p the
    received window is A_j(p)·s(t_n − τ), t_n = t_wake + n/fs, n = 0…N−1, τ = d/c. The CRLB
    for the delay of a known waveform in white Gaussian noise is

        var(τ̂) ≥ σ_w² / Σ_n (A ṡ(t_n − τ))²  ≈  σ_w² / (A² · 2π² · Σ_n f(t_n − τ)²),

    using ṡ = 2π f(t) cos(·) with instantaneous frequency f(t) = f0 + k t and ⟨cos²⟩ = ½,
    the sum running over the samples where the chirp is on. Then σ_r = c·√var(τ̂):

        σ_j(p) = c / (2π) · (A_j(p_ref)/A_j(p)) / √(10^(SNR/10) · Σ_n f(t_n − τ)²).

    This is the coherent (carrier-phase) bound: it assumes the right carrier peak is
    found, so it is far below what the envelope-and-snap receiver achieves in a
    reverberant room (millimetres, against centimetres to metres); use it to see the
    geometry of the SNR, and a calibrated σ to compare with simulation. σ = inf where
    the window misses the chirp.
    """

    room: Room = field(default_factory=Room.techtile)
    snr_db: float = 30.0
    chirp: Chirp = field(default_factory=Chirp)
    receiver: Receiver = field(default_factory=Receiver)
    grid_shape: tuple[int, int, int] = (9, 6, 5)

    def __post_init__(self) -> None:
        if not math.isfinite(self.snr_db):
            raise ValueError(f"snr_db: must be finite, got {self.snr_db}")

    def reference_amplitude(self, anchors) -> np.ndarray:
        """A_j at the grid node closest to each anchor, (..., M)."""
        a = np.asarray(anchors, dtype=float)
        grid = self.room.grid(self.grid_shape)
        d = np.linalg.norm(grid[:, None, :] - a[..., None, :, :], axis=-1)  # (..., G, M)
        closest = np.argmin(d, axis=-2)  # (..., M)
        amp = direct_amplitude(self.room, a, grid)  # (..., G, M)
        return np.take_along_axis(amp, closest[..., None, :], axis=-2)[..., 0, :]

    def _sum_f2(self, tau: np.ndarray) -> np.ndarray:
        """Σ_n f(t_n − τ)² over window samples inside the chirp, closed form, shape of τ."""
        rx, ch = self.receiver, self.chirp
        fs, N = rx.fs, rx.window
        lo = np.clip(np.ceil((tau - rx.t_wake) * fs), 0, N)
        hi = np.clip(np.floor((tau + ch.duration - rx.t_wake) * fs), -1, N - 1)
        cnt = np.maximum(hi - lo + 1, 0)
        # f_n = α + β n with α = f0 + k(t_wake − τ), β = k/fs
        alpha = ch.f0 + ch.rate * (rx.t_wake - tau)
        beta = ch.rate / fs

        def s1(n):  # Σ_{i=0}^{n} i
            return n * (n + 1) / 2

        def s2(n):  # Σ_{i=0}^{n} i²
            return n * (n + 1) * (2 * n + 1) / 6

        S1 = np.where(cnt > 0, s1(hi) - s1(lo - 1), 0.0)
        S2 = np.where(cnt > 0, s2(hi) - s2(lo - 1), 0.0)
        return cnt * alpha**2 + 2 * alpha * beta * S1 + beta**2 * S2

    def sigma(self, anchors, positions) -> np.ndarray:
        """σ_j(p) in metres, (..., P, M)."""
        a = np.asarray(anchors, dtype=float)
        p = np.asarray(positions, dtype=float)
        c = self.room.speed_of_sound
        d = np.linalg.norm(p[:, None, :] - a[..., None, :, :], axis=-1)
        amp = direct_amplitude(self.room, a, p)
        ref = self.reference_amplitude(a)[..., None, :]
        f2 = self._sum_f2(d / c)
        snr = 10.0 ** (self.snr_db / 10.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = c / (2 * np.pi) * (ref / amp) / np.sqrt(snr * f2)
        return np.where(np.isfinite(s) & (f2 > 0), s, np.inf)

"""The transmitted linear up-chirp (paper §II).

s(t) = sin(2π(f0·t + ½·k·t²)) for 0 ≤ t ≤ T, zero elsewhere, k = (f1 − f0)/T. This is
``scipy.signal.chirp(t, f0, T, f1, method="linear", phi=270)``; the phase matters because
the receiver snaps to a peak of the carrier.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simulation import checks


@dataclass(frozen=True)
class Chirp:
    """Linear chirp from ``f0`` to ``f1`` Hz over ``duration`` seconds."""

    f0: float = 25e3
    f1: float = 45e3
    duration: float = 30e-3

    def __post_init__(self) -> None:
        for name in ("f0", "f1"):
            checks.real(name, getattr(self, name), low=0.0, high=1e6, low_open=True, unit="Hz")
        checks.real("duration", self.duration, low=0.0, high=1.0, low_open=True, unit="s")

    @property
    def centre(self) -> float:
        """The centre frequency (f0 + f1)/2 in Hz: where the air's attenuation is taken."""
        return 0.5 * (self.f0 + self.f1)

    @property
    def rate(self) -> float:
        """Sweep rate k = (f1 − f0)/T in Hz/s."""
        return (self.f1 - self.f0) / self.duration

    def __call__(self, t: np.ndarray) -> np.ndarray:
        """Waveform s(t) (any shape, seconds), zero outside [0, T]."""
        t = np.asarray(t, dtype=float)
        s = np.sin(2 * np.pi * (self.f0 * t + 0.5 * self.rate * t * t))
        return np.where((t >= 0) & (t <= self.duration), s, 0.0)

    def frequency(self, t: np.ndarray) -> np.ndarray:
        """Instantaneous frequency f0 + k·t in Hz inside [0, T], zero outside."""
        t = np.asarray(t, dtype=float)
        return np.where((t >= 0) & (t <= self.duration), self.f0 + self.rate * t, 0.0)

    def samples(self, fs: float) -> np.ndarray:
        """The reference chirp sampled at ``fs`` Hz: s(n/fs) for 0 ≤ n/fs < T."""
        n = int(round(self.duration * fs))
        return self(np.arange(n) / fs)

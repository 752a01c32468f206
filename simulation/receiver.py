"""Receiver configuration and DSP chain (SPEC §2).

The node samples at ``fs`` and is awake for ``window`` samples from ``t_wake`` seconds
after the chirp starts. The DSP (high-pass, pulse compression, low-pass envelope, peak
snapping, range formula) is implemented by the simulator issue.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Receiver:
    """Sampling and DSP settings of the mobile node (SPEC §2 defaults)."""

    fs: float = 192e3
    t_wake: float = 29e-3
    window: int = 192
    highpass_order: int = 10
    highpass_cutoff: float = 15e3
    lowpass_taps: int = 1000
    lowpass_cutoff: float = 5e3

    def __post_init__(self) -> None:
        if not (math.isfinite(self.fs) and self.fs > 0):
            raise ValueError(f"fs: must be > 0 Hz, got {self.fs}")
        if not (math.isfinite(self.t_wake) and self.t_wake >= 0):
            raise ValueError(f"t_wake: must be >= 0 s, got {self.t_wake}")
        if int(self.window) != self.window or self.window < 2:
            raise ValueError(f"window: must be an integer >= 2 samples, got {self.window}")
        if not (0 < self.highpass_cutoff < self.fs / 2):
            raise ValueError(f"highpass_cutoff: must be in (0, fs/2), got {self.highpass_cutoff}")
        if not (0 < self.lowpass_cutoff < self.fs / 2):
            raise ValueError(f"lowpass_cutoff: must be in (0, fs/2), got {self.lowpass_cutoff}")

    @property
    def window_times(self) -> np.ndarray:
        """(window,) sample times in seconds after the chirp start."""
        return self.t_wake + np.arange(self.window) / self.fs

"""The signal design: the transmitted chirp and the receiver that listens for it.

A :class:`Signal` pairs a :class:`~simulation.chirp.Chirp` with a
:class:`~simulation.receiver.Receiver`; a room carries one (``Room.signal``, the paper's
design by default) and the whole chain uses it: the simulation, the range tables, the
plan, the validation and the bounds' SNR model.

**Reach** (docs/model.md, "Reach of a signal design"). The receiver samples the window
t_n = t_wake + n/fs, n = 0 … N − 1, whose span is W = (N − 1)/fs. A path with delay τ puts
chirp time u = t_n − τ at sample n, and the chirp is on for 0 ≤ u ≤ T; the window holds the
part of the chirp with u ∈ [t_wake − τ, t_wake + W − τ] ∩ [0, T]. The receiver sees a path
when the window holds at least D = min(W, T, :data:`MIN_OVERLAP`) of its chirp: all of
what a window shorter than 1 ms can hold, else at least the 1 ms slice of the paper's
design. The overlap is at least D for

    τ ∈ [τ_min, τ_max],  τ_min = max(0, t_wake + min(0, D − T)),  τ_max = t_wake + max(0, W − D),

and at the speed of sound c the **reach** is c·τ_max and the **near limit** c·τ_min. A
path outside them overlaps the window less or not at all: its correlation peak is weak or
absent, and the receiver reports "no range" for a time of flight outside them
(:mod:`simulation.receiver`). The paper's design (T = 30 ms, t_wake = 29 ms, N = 192 at
192 kHz, so D = W) reaches c·29 ms = 9.95 m at 20 °C and has no near limit; a 20 ms
window from t_wake = 10 ms reaches c·(10 + 20 − 1) ms = 9.95 m too.

A window may be longer than the chirp (it then holds whole chirps); a room refuses one
that closes after the chirp's end plus its longest flight (nothing arrives so late).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from simulation import checks
from simulation.chirp import Chirp
from simulation.receiver import Receiver, dsp_form, signal_chain

#: the shortest overlap (s) of a path's chirp with a window longer than it that the
#: receiver is taken to see: the paper's 1 ms slice (module docstring)
MIN_OVERLAP = 1e-3

_CHIRP_KEYS = tuple(f.name for f in dataclasses.fields(Chirp))
_RECEIVER_KEYS = tuple(f.name for f in dataclasses.fields(Receiver))
#: the keys of a ``[signal]`` table: the chirp's fields, then the receiver's
KEYS = (*_CHIRP_KEYS, *_RECEIVER_KEYS)


@dataclass(frozen=True)
class Signal:
    """A chirp and the receiver that listens for it (defaults: the paper's design).

    chirp : the transmitted linear chirp (band f0 → f1 Hz, ``duration`` s).
    receiver : sampling rate, wake-up time and window, DSP and detection settings.

    The chirp's band must lie below the receiver's Nyquist frequency fs/2.
    """

    chirp: Chirp = field(default_factory=Chirp)
    receiver: Receiver = field(default_factory=Receiver)

    def __post_init__(self) -> None:
        chirp, rx = signal_chain(self.chirp, self.receiver)  # types and the Nyquist limit
        if chirp.f1 <= chirp.f0:
            raise ValueError(
                f"chirp: the band must rise, f0 < f1 (an up-chirp), got f0 = {chirp.f0:g} Hz, "
                f"f1 = {chirp.f1:g} Hz"
            )
        _check_highpass(rx)
        # a short window's DSP holds an (N, Nref + N − 1) matrix: refuse before any work
        if dsp_form(rx) == "matrix":
            n_ref = round(chirp.duration * rx.fs)
            checks.check_size(
                "chirp duration x fs x window",
                (n_ref + rx.window) * rx.window * 8 * 4,
                value=(chirp.duration, rx.fs, rx.window),
                hint="use a shorter chirp, a lower fs or a shorter window",
            )

    # -- reach ------------------------------------------------------------------------------
    @property
    def window_span(self) -> float:
        """W = (N − 1)/fs, seconds from the window's first sample to its last."""
        return (self.receiver.window - 1) / self.receiver.fs

    @property
    def min_overlap(self) -> float:
        """D = min(W, T, :data:`MIN_OVERLAP`) seconds: the least of a path's chirp the
        window must hold for the receiver to see it (module docstring)."""
        return min(self.window_span, self.chirp.duration, MIN_OVERLAP)

    @property
    def delays(self) -> tuple[float, float]:
        """(τ_min, τ_max) in seconds: the times of flight whose chirp the window holds at
        least :attr:`min_overlap` of (module docstring)."""
        t, D = self.receiver.t_wake, self.min_overlap
        return max(0.0, t + min(0.0, D - self.chirp.duration)), t + max(0.0, self.window_span - D)

    @property
    def window_end(self) -> float:
        """t_wake + W: when the window closes, seconds after the chirp starts."""
        return self.receiver.t_wake + self.window_span

    def describe(self) -> str:
        """One line naming the design: chirp band and length, window start, length, pick."""
        ch, rx = self.chirp, self.receiver
        return (
            f"chirp {ch.f0 / 1e3:g}–{ch.f1 / 1e3:g} kHz over {ch.duration * 1e3:g} ms; window "
            f"{self.window_span * 1e3:.3g} ms ({rx.window} samples at {rx.fs / 1e3:g} kHz) from "
            f"{rx.t_wake * 1e3:g} ms; {rx.pick} pick"
            + ("" if rx.false_alarm is None else f"; detection at P_fa {rx.false_alarm:g}")
        )

    def reach(self, speed_of_sound: float) -> float:
        """The longest range (m) the window sees at ``speed_of_sound`` (m/s): c·τ_max."""
        return float(speed_of_sound) * self.delays[1]

    def near_limit(self, speed_of_sound: float) -> float:
        """The shortest range (m) the window sees at ``speed_of_sound`` (m/s): c·τ_min
        (0 for the paper's design)."""
        return float(speed_of_sound) * self.delays[0]

    # -- serialization ------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The fields that differ from the paper's design, flat (the ``[signal]`` table of a
        room file: the chirp's ``f0``, ``f1``, ``duration`` and the receiver's fields)."""
        out: dict[str, Any] = {}
        for obj, default in ((self.chirp, Chirp()), (self.receiver, Receiver())):
            for f in dataclasses.fields(obj):
                value = getattr(obj, f.name)
                if value != getattr(default, f.name):
                    out[f.name] = value
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> Signal:
        """A signal from :meth:`to_dict` (any subset of :data:`KEYS`; the rest default)."""
        if d is None:
            return cls()
        if isinstance(d, Signal):
            return d
        checks.mapping("signal", d, f"a mapping (TOML table) with keys from {list(KEYS)}")
        unknown = [k for k in d if k not in KEYS]
        if unknown:
            raise ValueError(f"signal: unknown key(s) {unknown}; allowed: {list(KEYS)}")
        chirp = Chirp(**{k: d[k] for k in _CHIRP_KEYS if k in d})
        receiver = Receiver(**{k: d[k] for k in _RECEIVER_KEYS if k in d})
        return cls(chirp, receiver)


def closing_window(signal: Signal, window: float, pick: str | None = None) -> Signal:
    """``signal`` with a window of ``window`` seconds (N = round(window·fs) samples) that
    closes with the chirp (t_wake = T − N/fs, to the picosecond), and ``pick`` when given:
    the family of receiver designs the receiver study compares (the paper's is 1 ms)."""
    rx = signal.receiver
    w = checks.real("window", window, low=0.0, high=signal.chirp.duration, low_open=True, unit="s")
    n = int(round(w * rx.fs))
    t_wake = round(signal.chirp.duration - n / rx.fs, 12)
    changes = {"window": n, "t_wake": max(t_wake, 0.0)}
    if pick is not None:
        changes["pick"] = pick
    return dataclasses.replace(signal, receiver=dataclasses.replace(rx, **changes))


def _check_highpass(rx: Receiver) -> None:
    """The zero-phase high-pass needs initial conditions: refuse a cutoff so low that its
    poles sit at z = 1 to rounding (the DSP could not be built)."""
    import numpy as np
    import scipy.signal

    try:
        zi = scipy.signal.sosfilt_zi(rx.highpass_sos())
    except np.linalg.LinAlgError:
        zi = None
    if zi is None or not np.all(np.isfinite(zi)):
        raise ValueError(
            f"highpass_cutoff: {rx.highpass_cutoff:g} Hz is too close to 0 for a high-pass of "
            f"order {rx.highpass_order} at fs = {rx.fs:g} Hz"
        )


def as_signal(value: Any, name: str = "signal") -> Signal:
    """``value`` as a :class:`Signal`: a Signal, a mapping of :data:`KEYS`, or None (the
    paper's design); ValueError naming ``name`` otherwise."""
    if value is None or isinstance(value, Signal):
        return Signal() if value is None else value
    if isinstance(value, Mapping):
        try:
            return Signal.from_dict(value)
        except ValueError as exc:
            raise ValueError(f"{name}: {exc}") from None
    raise ValueError(
        f"{name}: must be a simulation.Signal, a mapping of its keys or None, "
        f"got {checks.describe(value)}"
    )

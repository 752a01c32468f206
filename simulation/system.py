"""The positioning system: the signal (chirp), the receiver and the positioning.

A plan is only as good as its model of the equipment the installation will run. A
:class:`System` holds all of it: the transmitted chirp, the receiver that listens for it
(sampling, window, pick, detection) and the positioning that turns ranges into positions.
The room (:class:`simulation.Room`) is the place; a scene is a room, a system and a layout.
Everything that simulates, plans, validates, stresses or reports takes a system (default
:data:`PRESETS` ``"paper"``) and records it.

Presets (:meth:`System.preset`):

- ``"paper"``: the paper's system exactly (§II): the 25–45 kHz chirp of 30 ms, a 1 ms
  window (192 samples at 192 kHz) 29 ms in, the strongest arrival (peak pick), least
  squares started inside the room's box and not kept in the room.
- ``"recommended"``: the 20 ms first-path receiver (a window of 20 ms that closes with the
  chirp) with a detection threshold (:data:`RECOMMENDED_FALSE_ALARM` per window), and
  positioning that rejects echoes (:mod:`simulation.robust`), kept in the floor plan. The
  threshold matters where an obstacle hides an anchor: its window then holds echoes and
  noise only, and a receiver that does not know its noise floor can pick a noise lobe
  before any path arrives, a range shorter than the direct path that no consistency test
  can explain (docs/model.md, "The system: signal, receiver, positioning").

A system is also a TOML table (:meth:`System.from_toml`, :meth:`System.to_dict`):

.. code-block:: toml

    [system]
    preset = "recommended"        # start from a preset (default "paper")
    [system.signal]                # the chirp: f0, f1 (Hz), duration (s)
    duration = 0.03
    [system.receiver]              # simulation.Receiver's fields
    pick = "first-path"
    [system.positioning]           # Positioning's fields
    method = "ls"
    keep_in_room = true

**Reach** (docs/model.md, "The system: signal, receiver, positioning"). The receiver
samples the window t_n = t_wake + n/fs, n = 0 … N − 1, whose span is W = (N − 1)/fs. A
path with delay τ puts chirp time u = t_n − τ at sample n, and the chirp is on for
0 ≤ u ≤ T. The receiver sees a path when the window holds at least
D = min(W, T, :data:`MIN_OVERLAP`) of its chirp, that is for τ ∈ [τ_min, τ_max]
(:func:`simulation.receiver.delay_span`); at the speed of sound c the **reach** is c·τ_max
and the **near limit** c·τ_min. The paper's design reaches c·29 ms = 9.95 m at 20 °C and
has no near limit. A window may be longer than the chirp; a room refuses one that closes
after the chirp's end plus its longest flight (:meth:`System.check_room`).
"""

from __future__ import annotations

import dataclasses
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from simulation import checks
from simulation.chirp import Chirp
from simulation.map_check import map_check, needs_check
from simulation.positioning import (
    ALERT_LIMIT,
    FALSE_ALARM,
    METHODS,
    RANGE_SIGMA,
    PositionFix,
    check_test,
    locate,
)
from simulation.receiver import MIN_OVERLAP, Receiver, delay_span, dsp_form, signal_chain

__all__ = ["MIN_OVERLAP", "PRESETS", "Positioning", "System", "as_system", "closing_window"]

#: the most iterations of the positioning solver a system may ask for
MAX_ITERATIONS = 100_000


@dataclass(frozen=True)
class Positioning:
    """How the installation turns ranges into positions (docs/model.md, "Positioning").

    method : ``"ls"``, least squares on every heard range (the paper's), or ``"robust"``,
        least squares on the anchors whose ranges agree to ``range_sigma``, the others
        rejected as echoes (:mod:`simulation.robust`).
    keep_in_room : keep every iterate inside the room: its box and its floor plan (a
        system that knows its room); False: unbounded iterates, started inside the box
        (the paper's).
    max_iter : the solver's iteration limit per fix.
    range_sigma : the receiver's range σ (m) the robust method tests the residuals at.
    false_alarm : the probability that the robust method's test rejects a consistent set.
    alert_limit : (m) a robust fix is verified only if one echo its test misses cannot move
        it farther (its protection level, :mod:`simulation.robust`).
    """

    method: str = "ls"
    keep_in_room: bool = False
    max_iter: int = 100
    range_sigma: float = RANGE_SIGMA
    false_alarm: float = FALSE_ALARM
    alert_limit: float = ALERT_LIMIT

    def __post_init__(self) -> None:
        checks.choice("method", self.method, METHODS)
        checks.flag("keep_in_room", self.keep_in_room)
        checks.count("max_iter", self.max_iter, low=1, high=MAX_ITERATIONS)
        check_test(self.range_sigma, self.false_alarm, self.alert_limit)

    def locate(self, room, anchors, ranges, *, full_output: bool = False):
        """Positions (..., P, 3) m (or a :class:`simulation.PositionFix`) from ranges
        (..., P, M) m of the anchors (M, 3) or layouts (L, M, 3), as this positioning
        solves them in ``room`` (started inside its box; kept in its box and floor plan
        with ``keep_in_room``). Robust fixes kept in a room whose map can block a path are
        verified only if they see the anchors they rest on (:mod:`simulation.map_check`)."""
        region = (np.zeros(3), np.asarray(room.size, dtype=float))
        poly = None if (room.is_shoebox or not self.keep_in_room) else room.floor_corners
        mapped = self.method == "robust" and self.keep_in_room and needs_check(room)
        fix = locate(anchors, ranges, method=self.method, region=region,
                     bounded=self.keep_in_room, floor_plan=poly, max_iter=self.max_iter,
                     range_sigma=self.range_sigma, false_alarm=self.false_alarm,
                     alert_limit=self.alert_limit,
                     room=room if mapped else None, full_output=full_output)  # fmt: skip
        if full_output and mapped:
            return _map_checked(room, anchors, fix)  # what it vouches for, on the room's map
        return fix

    def describe(self) -> str:
        """One line: the method and whether positions are kept in the room."""
        kept = "kept in the room" if self.keep_in_room else "not kept in the room"
        if self.method == "ls":
            return f"least squares, {kept}"
        return (f"robust least squares (echoes rejected at range sigma {self.range_sigma:g} m, "
                f"verified within {self.alert_limit:g} m), {kept}")  # fmt: skip


def _map_checked(room, anchors, fix: PositionFix) -> PositionFix:
    """``fix`` checked against the room's map (:func:`simulation.map_check.map_check`), on
    flat rows and shaped back: its quality, the positions as they were."""
    a = np.asarray(anchors, dtype=float)
    layouts = a.reshape(-1, a.shape[-2], 3)
    lead = fix.quality.shape
    flat = {"x": fix.x.reshape(-1, 3), "used": fix.used.reshape(-1, a.shape[-2]),
            "quality": fix.quality.reshape(-1)}  # fmt: skip
    owner = np.repeat(np.arange(len(layouts)), len(flat["x"]) // len(layouts))
    quality = map_check(room, layouts, owner, flat)["quality"]
    return dataclasses.replace(fix, quality=quality.reshape(lead))


@dataclass(frozen=True)
class System:
    """The positioning system (module docstring): ``chirp``, ``receiver``, ``positioning``
    and a ``name`` (the preset's, or "custom"). Default: the paper's system.

    The chirp's band must lie below the receiver's Nyquist frequency fs/2.
    """

    chirp: Chirp = field(default_factory=Chirp)
    receiver: Receiver = field(default_factory=Receiver)
    positioning: Positioning = field(default_factory=Positioning)
    name: str = "paper"

    def __post_init__(self) -> None:
        chirp, rx = signal_chain(self.chirp, self.receiver)  # types and the Nyquist limit
        if not isinstance(self.positioning, Positioning):
            raise ValueError(
                f"positioning: must be a simulation.Positioning, "
                f"got {checks.describe(self.positioning)}"
            )
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name: must be a non-empty string, got {self.name!r}")
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

    # -- presets -----------------------------------------------------------------------------
    @classmethod
    def preset(cls, name: str) -> System:
        """The preset ``name`` (:data:`PRESETS`); ValueError listing them otherwise."""
        if name not in PRESETS:
            raise ValueError(f"system: unknown preset {name!r}; the presets: {list(PRESETS)}")
        return PRESETS[name]()

    @classmethod
    def paper(cls) -> System:
        """The paper's system (module docstring)."""
        return cls()

    @classmethod
    def recommended(cls) -> System:
        """The 20 ms first-path receiver with a detection threshold, echoes rejected and
        positions kept in the floor plan (module docstring)."""
        base = closing_window(cls(), 20e-3, "first-path")
        base = base.with_signal(false_alarm=RECOMMENDED_FALSE_ALARM)
        positioning = Positioning(method="robust", keep_in_room=True)
        return dataclasses.replace(base, positioning=positioning, name="recommended")

    # -- reach -------------------------------------------------------------------------------
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
        return delay_span(self.chirp, self.receiver)

    @property
    def window_end(self) -> float:
        """t_wake + W: when the window closes, seconds after the chirp starts."""
        return self.receiver.t_wake + self.window_span

    def reach(self, speed_of_sound: float) -> float:
        """The longest range (m) the window sees at ``speed_of_sound`` (m/s): c·τ_max."""
        return float(speed_of_sound) * self.delays[1]

    def near_limit(self, speed_of_sound: float) -> float:
        """The shortest range (m) the window sees at ``speed_of_sound`` (m/s): c·τ_min
        (0 for the paper's design)."""
        return float(speed_of_sound) * self.delays[0]

    def within_reach(self, distances, speed_of_sound: float):
        """bool, shaped like ``distances`` (m): the range lies in what the window sees,
        between :meth:`near_limit` and :meth:`reach` at ``speed_of_sound`` (m/s)."""
        d = np.asarray(distances)
        c = float(speed_of_sound)
        return (d >= self.near_limit(c)) & (d <= self.reach(c))

    def check_room(self, room) -> None:
        """Refuse a window that closes after the chirp's end plus the longest flight in
        ``room`` (its diagonal over c): it would hold nothing but noise after that."""
        rx = self.receiver
        latest = self.chirp.duration + room.diagonal / room.speed_of_sound
        if self.window_end > latest + 1.0 / rx.fs:
            allowed = int((latest - rx.t_wake) * rx.fs) + 1
            raise ValueError(
                f"window: {rx.window} samples from t_wake = {rx.t_wake * 1e3:g} ms close "
                f"{self.window_end * 1e3:g} ms after the chirp starts, after its end plus the "
                f"room's longest flight ({latest * 1e3:.4g} ms); allowed: at most "
                f"{max(allowed, 0)} samples"
            )

    def describe(self) -> str:
        """One line naming the whole system: chirp, window, pick, detection, positioning."""
        ch, rx = self.chirp, self.receiver
        detect = "" if rx.false_alarm is None else f"; detection at P_fa {rx.false_alarm:g}"
        return (
            f"{self.name}: chirp {ch.f0 / 1e3:g}–{ch.f1 / 1e3:g} kHz over "
            f"{ch.duration * 1e3:g} ms; window {self.window_span * 1e3:.3g} ms ({rx.window} "
            f"samples at {rx.fs / 1e3:g} kHz) from {rx.t_wake * 1e3:g} ms; {rx.pick} pick"
            f"{detect}; {self.positioning.describe()}"
        )

    # -- serialization ---------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The whole system as plain JSON/TOML: ``name`` and the ``signal`` (the chirp's
        fields), ``receiver`` and ``positioning`` tables, every field written."""
        return {
            "name": self.name,
            "signal": dataclasses.asdict(self.chirp),
            "receiver": dataclasses.asdict(self.receiver),
            "positioning": dataclasses.asdict(self.positioning),
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> System:
        """A system from :meth:`to_dict`, or from a table that starts from a ``preset``
        (default "paper") and changes some fields of its parts; an unknown key or a bad
        value raises ``ValueError`` naming it."""
        if d is None:
            return cls()
        checks.mapping("system", d, "a mapping (TOML table) with keys " + str(list(_KEYS)))
        unknown = [k for k in d if k not in _KEYS]
        if unknown:
            raise ValueError(f"system: unknown key(s) {unknown}; allowed: {list(_KEYS)}")
        base = cls.preset(d.get("preset", "paper"))
        parts = {}
        for key, kind in _PARTS.items():
            given = d.get(key) or {}
            checks.mapping(f"system.{key}", given, f"a table of {kind.__name__}'s fields")
            known = [f.name for f in dataclasses.fields(kind)]
            bad = [k for k in given if k not in known]
            if bad:
                raise ValueError(f"system.{key}: unknown key(s) {bad}; allowed: {known}")
            try:
                parts[_FIELD[key]] = dataclasses.replace(getattr(base, _FIELD[key]), **given)
            except (ValueError, TypeError) as exc:
                raise ValueError(f"system.{key}: {exc}") from None
        changed = any(d.get(k) for k in _PARTS)
        name = d.get("name", "custom" if changed else base.name)
        return cls(**parts, name=name)

    @classmethod
    def from_toml(cls, path: str | Path) -> System:
        """The ``[system]`` table of a TOML file (a system file, or a room file that carries
        one; the paper's system when a room file has none); every problem raises
        ``ValueError`` naming the file."""
        p = checks.input_file("system file", path)
        try:
            with open(p, "rb") as fh:
                data = tomllib.load(fh)
        except OSError as exc:
            raise ValueError(f"system file {p}: cannot read it ({exc.strerror})") from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise ValueError(f"system file {p}: not valid TOML ({exc})") from None
        try:
            return cls.from_dict(data.get("system"))
        except ValueError as exc:
            raise ValueError(f"system file {p}: {exc}") from None

    def with_signal(self, **changes) -> System:
        """This system with single fields of its chirp (f0, f1, duration) or receiver
        changed (the command line's signal flags); ValueError naming the field."""
        chirp_keys = {f.name for f in dataclasses.fields(Chirp)}
        rx_keys = {f.name for f in dataclasses.fields(Receiver)}
        unknown = [k for k in changes if k not in chirp_keys | rx_keys]
        if unknown:
            raise ValueError(f"signal: unknown field(s) {unknown}")
        chirp = dataclasses.replace(self.chirp, **{k: v for k, v in changes.items()
                                                   if k in chirp_keys})  # fmt: skip
        rx = dataclasses.replace(self.receiver, **{k: v for k, v in changes.items()
                                                   if k in rx_keys})  # fmt: skip
        if chirp == self.chirp and rx == self.receiver:
            return self
        return dataclasses.replace(self, chirp=chirp, receiver=rx, name="custom")


#: the recommended receiver's detection threshold: its false-alarm bound per window
RECOMMENDED_FALSE_ALARM = 1e-3
#: the presets by name (module docstring)
PRESETS = {"paper": System.paper, "recommended": System.recommended}
#: a system table's parts and the classes of their fields
_PARTS = {"signal": Chirp, "receiver": Receiver, "positioning": Positioning}
_FIELD = {"signal": "chirp", "receiver": "receiver", "positioning": "positioning"}
_KEYS = ("name", "preset", *_PARTS)


def as_system(value: Any, name: str = "system") -> System:
    """``value`` as a :class:`System`: a System, a preset's name, a mapping of
    :meth:`System.from_dict`, or None (the paper's); ValueError naming ``name`` otherwise."""
    if value is None:
        return System()
    if isinstance(value, System):
        return value
    if isinstance(value, str):
        return System.preset(value)
    if isinstance(value, Mapping):
        try:
            return System.from_dict(value)
        except ValueError as exc:
            raise ValueError(f"{name}: {exc}") from None
    raise ValueError(
        f"{name}: must be a simulation.System, a preset's name {list(PRESETS)}, a mapping or "
        f"None, got {checks.describe(value)}"
    )


def closing_window(system: System, window: float, pick: str | None = None) -> System:
    """``system`` with a window of ``window`` seconds (N = round(window·fs) samples) that
    closes with the chirp (t_wake = T − N/fs, to the picosecond), and ``pick`` when given:
    the family of receiver designs the receiver study compares (the paper's is 1 ms)."""
    rx = system.receiver
    w = checks.real("window", window, low=0.0, high=system.chirp.duration, low_open=True,
                    unit="s")  # fmt: skip
    n = int(round(w * rx.fs))
    t_wake = round(system.chirp.duration - n / rx.fs, 12)
    changes = {"window": n, "t_wake": max(t_wake, 0.0)}
    if pick is not None:
        changes["pick"] = pick
    return dataclasses.replace(system, receiver=dataclasses.replace(rx, **changes),
                               name="custom")  # fmt: skip


def _check_highpass(rx: Receiver) -> None:
    """The zero-phase high-pass needs initial conditions: refuse a cutoff so low that its
    poles sit at z = 1 to rounding (the DSP could not be built)."""
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

"""The shoebox room: geometry, materials, sound speed, mounting surfaces and the node grid.

Defaults: the paper's Techtile room (docs/model.md). Surfaces are named after pyroomacoustics'
shoebox walls' compass convention: floor (z=0), ceiling (z=Lz), south (y=0),
north (y=Ly), west (x=0), east (x=Lx).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

#: The six planes of a shoebox: name -> (axis, side), side 0 is the plane at 0, 1 at L.
SURFACES: dict[str, tuple[int, int]] = {
    "floor": (2, 0),
    "ceiling": (2, 1),
    "south": (1, 0),
    "north": (1, 1),
    "west": (0, 0),
    "east": (0, 1),
}

TECHTILE_ABSORPTION: dict[str, float] = {
    "floor": 0.45,
    "ceiling": 0.45,
    "south": 0.45,
    "north": 0.45,
    "west": 1.0,
    "east": 1.0,
}


def _check_surface_names(names, what: str) -> None:
    unknown = [n for n in names if n not in SURFACES]
    if unknown:
        raise ValueError(f"{what}: unknown surface name(s) {unknown}; allowed: {list(SURFACES)}")


@dataclass(frozen=True)
class Room:
    """A shoebox room with per-surface energy absorption.

    Attributes
    ----------
    size : (Lx, Ly, Lz) in metres, each > 0.
    absorption : energy absorption coefficient α in [0, 1] per surface name; the
        reflection amplitude is β = √(1 − α). Missing surfaces default to the
        techtile values.
    temperature : air temperature in °C (> −273.15); sets :attr:`speed_of_sound`.
    max_order : image-source reflection order (integer ≥ 0).
    air_absorption : air attenuation coefficient a in 1/m; a path of length d is
        scaled in amplitude by exp(−a·d/2) (a ≥ 0).
    mounting : the surfaces anchors may be mounted on.
    anchor_offset : anchors sit this far (m) from their plane and at least this far
        from the neighbouring planes.
    node_margin : the evaluation grid keeps this distance (m) from every plane.
    sound_speed : optional explicit speed of sound in m/s, overriding temperature.
    name : a label used in reports.
    """

    size: tuple[float, float, float] = (8.0, 4.0, 2.4)
    absorption: Mapping[str, float] = field(default_factory=lambda: dict(TECHTILE_ABSORPTION))
    temperature: float = 20.0
    max_order: int = 3
    air_absorption: float = 0.0875
    mounting: tuple[str, ...] = ("south", "north", "ceiling")
    anchor_offset: float = 0.03
    node_margin: float = 0.05
    sound_speed: float | None = None
    name: str = "techtile"

    def __post_init__(self) -> None:
        size = tuple(float(s) for s in np.asarray(self.size, dtype=float).ravel())
        if len(size) != 3:
            raise ValueError(f"size: expected 3 lengths (Lx, Ly, Lz) in metres, got {len(size)}")
        if not all(math.isfinite(s) and s > 0 for s in size):
            raise ValueError(f"size: every length must be finite and > 0 m, got {size}")
        object.__setattr__(self, "size", size)

        absorption = dict(TECHTILE_ABSORPTION)
        _check_surface_names(self.absorption, "absorption")
        absorption.update({k: float(v) for k, v in self.absorption.items()})
        for k, v in absorption.items():
            if not (0.0 <= v <= 1.0):
                raise ValueError(f"absorption[{k!r}]: must be in [0, 1], got {v}")
        object.__setattr__(self, "absorption", absorption)

        mounting = (self.mounting,) if isinstance(self.mounting, str) else tuple(self.mounting)
        if not mounting:
            raise ValueError("mounting: at least one surface is required")
        _check_surface_names(mounting, "mounting")
        if len(set(mounting)) != len(mounting):
            raise ValueError(f"mounting: duplicate surface names in {mounting}")
        object.__setattr__(self, "mounting", mounting)

        if not (math.isfinite(self.temperature) and self.temperature > -273.15):
            raise ValueError(f"temperature: must be > -273.15 °C, got {self.temperature}")
        if self.sound_speed is not None and not (
            math.isfinite(self.sound_speed) and self.sound_speed > 0
        ):
            raise ValueError(f"sound_speed: must be > 0 m/s or None, got {self.sound_speed}")
        if int(self.max_order) != self.max_order or self.max_order < 0:
            raise ValueError(f"max_order: must be an integer >= 0, got {self.max_order}")
        object.__setattr__(self, "max_order", int(self.max_order))
        if not (math.isfinite(self.air_absorption) and self.air_absorption >= 0):
            raise ValueError(f"air_absorption: must be >= 0 1/m, got {self.air_absorption}")
        half = min(size) / 2
        for fname in ("anchor_offset", "node_margin"):
            v = float(getattr(self, fname))
            if not (0.0 <= v < half):
                raise ValueError(
                    f"{fname}: must be in [0, {half:g}) m (half the smallest room size), got {v}"
                )
            object.__setattr__(self, fname, v)

    # -- constructors -------------------------------------------------------------------
    @classmethod
    def techtile(cls) -> Room:
        """The paper's 8 × 4 × 2.4 m Techtile room (§II)."""
        return cls()

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Room:
        """Build a room from :meth:`to_dict` output (unknown keys raise ``ValueError``)."""
        known = {f for f in cls.__dataclass_fields__}
        unknown = set(d) - known
        if unknown:
            raise ValueError(f"room: unknown field(s) {sorted(unknown)}; allowed: {sorted(known)}")
        kw = dict(d)
        if "size" in kw:
            kw["size"] = tuple(kw["size"])
        if "mounting" in kw:
            kw["mounting"] = tuple(kw["mounting"])
        return cls(**kw)

    @classmethod
    def from_toml(cls, path: str | Path) -> Room:
        """Read a room from a TOML file with the keys of :meth:`to_dict`."""
        with open(path, "rb") as fh:
            return cls.from_dict(tomllib.load(fh))

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON/TOML-serializable dictionary of every field."""
        d = {
            "name": self.name,
            "size": list(self.size),
            "temperature": self.temperature,
            "max_order": self.max_order,
            "air_absorption": self.air_absorption,
            "mounting": list(self.mounting),
            "anchor_offset": self.anchor_offset,
            "node_margin": self.node_margin,
            "absorption": dict(self.absorption),
        }
        if self.sound_speed is not None:
            d["sound_speed"] = self.sound_speed
        return d

    def to_toml(self, path: str | Path) -> None:
        """Write the room as TOML (readable by :meth:`from_toml`)."""
        lines = []
        d = self.to_dict()
        absorption = d.pop("absorption")
        for k, v in d.items():
            lines.append(f"{k} = {_toml_value(v)}")
        lines.append("")
        lines.append("[absorption]")
        for k, v in absorption.items():
            lines.append(f"{k} = {_toml_value(v)}")
        Path(path).write_text("\n".join(lines) + "\n")

    # -- derived quantities --------------------------------------------------------------
    @property
    def speed_of_sound(self) -> float:
        """Speed of sound in m/s: c = 331.3·√(1 + T/273.15) (343.2 m/s at 20 °C).

        The authors' simulation framework uses c = 20·√(273 + T), 342.3 m/s at 20 °C
        (docs/model.md, "Deliberate differences"). ``sound_speed`` overrides both.
        """
        if self.sound_speed is not None:
            return float(self.sound_speed)
        return 331.3 * math.sqrt(1.0 + self.temperature / 273.15)

    @property
    def dimensions(self) -> np.ndarray:
        """(3,) room size in metres."""
        return np.array(self.size)

    @property
    def centroid(self) -> np.ndarray:
        """(3,) room centre in metres (the anchors' aim point)."""
        return np.array(self.size) / 2

    def reflection(self, surface: str) -> float:
        """Amplitude reflection coefficient β = √(1 − α) of a surface."""
        return math.sqrt(1.0 - self.absorption[surface])

    @property
    def reflections(self) -> np.ndarray:
        """(3, 2) reflection amplitudes β indexed by [axis, side] (side 0: plane at 0)."""
        b = np.empty((3, 2))
        for name, (axis, side) in SURFACES.items():
            b[axis, side] = self.reflection(name)
        return b

    def grid(self, shape: Sequence[int] = (9, 6, 5)) -> np.ndarray:
        """(nx·ny·nz, 3) evaluation nodes, evenly spaced, ``node_margin`` from every plane.

        Ordered with x slowest and z fastest. The default gives the paper's 270 nodes with
        spacing 98.75 / 78.0 / 57.5 cm.
        """
        shape = tuple(int(n) for n in shape)
        if len(shape) != 3 or any(n < 1 for n in shape):
            raise ValueError(f"shape: expected 3 integers >= 1, got {shape}")
        m = self.node_margin
        axes = [
            np.linspace(m, L - m, n) if n > 1 else np.array([L / 2])
            for L, n in zip(self.size, shape, strict=True)
        ]
        g = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
        return g.reshape(-1, 3)

    def contains(self, points: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """(P,) bool: points (P, 3) lie inside the room, at least ``margin`` from each plane."""
        p = np.asarray(points, dtype=float)
        return np.all((p >= margin) & (p <= np.array(self.size) - margin), axis=-1)

    def check_anchors(self, anchors, min_anchors: int = 4) -> np.ndarray:
        """Validate an anchor layout: (M, 3) finite, M ≥ ``min_anchors``, inside the room.

        Returns the layout as a float array; raises ``ValueError`` naming the problem.
        """
        a = np.asarray(anchors, dtype=float)
        if a.ndim != 2 or a.shape[1] != 3:
            raise ValueError(f"anchors: expected shape (M, 3), got {a.shape}")
        if a.shape[0] < min_anchors:
            raise ValueError(
                f"anchors: need at least {min_anchors} anchors for 3D positioning, got {a.shape[0]}"
            )
        if not np.all(np.isfinite(a)):
            raise ValueError("anchors: coordinates must be finite (no NaN or inf)")
        outside = ~self.contains(a)
        if np.any(outside):
            raise ValueError(
                f"anchors: anchor(s) {np.flatnonzero(outside).tolist()} lie outside the room "
                f"[0, {self.size[0]}] x [0, {self.size[1]}] x [0, {self.size[2]}] m"
            )
        return a

    def corners_layout(self) -> np.ndarray:
        """(4, 3) the paper's non-optimized "corners" layout (§V-A), offset from the planes.

        For techtile: (0.03, 0.03, 0.03) south, (7.97, 3.97, 0.03) north, (7.97, 0.03, 2.37)
        and (0.03, 3.97, 2.37) ceiling.
        """
        o = self.anchor_offset
        Lx, Ly, Lz = self.size
        return np.array(
            [[o, o, o], [Lx - o, Ly - o, o], [Lx - o, o, Lz - o], [o, Ly - o, Lz - o]], dtype=float
        )


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(float(v)) if isinstance(v, float) else str(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")

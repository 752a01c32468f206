"""The room: geometry, materials, sound speed, mounting surfaces and the node grid.

A room is a shoebox (``Room(size=...)``; defaults: the paper's Techtile room, docs/model.md)
or an extruded simple polygon (``Room.from_corners(corners, height)``, :mod:`simulation.
floorplan`), either with obstacles standing in it. A shoebox's surfaces are named after
pyroomacoustics' compass convention: floor (z=0), ceiling (z=Lz), south (y=0), north
(y=Ly), west (x=0), east (x=Lx); a polygonal room's walls are ``wall-0`` … (or named), with
its floor and ceiling.
"""

from __future__ import annotations

import json
import math
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from simulation import air, checks, floorplan
from simulation.output import write_file
from simulation.regions import in_boxes

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


#: physically meaningful ranges of the room's numbers (checked by :class:`Room`)
SIZE_RANGE = (0.5, 100.0)  # m, each side of an indoor room
TEMPERATURE_RANGE = (-40.0, 60.0)  # °C: c from 306 to 366 m/s
SOUND_SPEED_RANGE = (250.0, 450.0)  # m/s, air
AIR_ABSORPTION_RANGE = (0.0, 5.0)  # 1/m
#: highest image-source order: (2N+1)(2N²+2N+3)/3 images, 2625 at N = 12
MAX_ORDER = 12


def _check_surface_names(names, what: str, allowed=tuple(SURFACES)) -> None:
    unknown = [n for n in names if not isinstance(n, str) or n not in allowed]
    if unknown:
        raise ValueError(f"{what}: unknown surface name(s) {unknown}; allowed: {list(allowed)}")


@dataclass(frozen=True)
class Room:
    """A room, shoebox or polygonal, with per-surface energy absorption and obstacles.

    Attributes
    ----------
    size : (Lx, Ly, Lz) in metres, each in [0.5, 100] m; for a polygonal room the
        corners' largest x and y and the height (:meth:`from_corners` sets it).
    corners : None (a shoebox), or the floor plan's corners ((x, y), ...) in metres, a
        simple polygon with x, y ≥ 0, stored counter-clockwise (:mod:`simulation.floorplan`).
    wall_names : the polygon's wall names, one per edge (corner i to i + 1; default
        ``wall-i``); a shoebox's walls are south, east, north, west.
    obstacles : boxes standing in the room, :class:`simulation.floorplan.Obstacle` or
        ``{"min": [x, y, z], "max": [x, y, z], "name", "absorption", "mountable"}``; they
        block and reflect sound, hold no node or anchor, and a ``mountable`` one's faces
        carry anchors.
    obstacle_order : the most reflections on obstacle faces a path may have (None: the
        room's ``max_order``).
    absorption : energy absorption coefficient α in [0, 1] per surface name; the
        reflection amplitude is β = √(1 − α). Missing surfaces default to the
        techtile values (a shoebox) or 0.45 (a polygonal room).
    temperature : air temperature in °C, in [−40, 60]; sets :attr:`speed_of_sound`.
    max_order : image-source reflection order, an integer in [0, 12].
    air_absorption : the air's attenuation: a number a in 1/m (in [0, 5]; a path of
        length d is scaled in amplitude by exp(−a·d/2) at every frequency, the paper's
        model), or ``"iso9613"``: ISO 9613-1 per frequency from ``temperature``,
        ``humidity`` and ``pressure`` (:mod:`simulation.air`).
    humidity : relative humidity of the air in %, in [0, 100] (ISO 9613-1 only).
    pressure : air pressure in kPa, in [50, 110] (ISO 9613-1 only).
    mounting : the surfaces anchors may be mounted on (default: south, north and ceiling
        in a shoebox, every wall and the ceiling in a polygonal room); the faces of
        mountable obstacles come on top.
    anchor_offset : anchors sit this far (m) from their plane and at least this far
        from the neighbouring planes.
    node_margin : the evaluation grid keeps this distance (m) from every plane.
    sound_speed : optional explicit speed of sound in m/s (in [250, 450]), overriding
        temperature.
    name : a label used in reports.
    keepouts : boxes ``(min_xyz, max_xyz)`` (m) where no anchor may go (windows, doors,
        lamps, vents): an anchor at p is forbidden iff min ≤ p ≤ max on every axis (faces
        included). Stored as a tuple of ((x0, y0, z0), (x1, y1, z1)) float tuples; items
        may also be mappings ``{"min": [...], "max": [...], "name": ...}``. Every box lies
        in the room, and no surface of ``mounting`` may be covered entirely.
    zones : boxes ``(min_xyz, max_xyz)`` (m) where tags are expected; when given,
        :meth:`grid` (the evaluation nodes) is a grid of ``zone_spacing`` over them.
    zone_spacing : node spacing (m, > 0) of the zone grid.
    keepout_names, zone_names : optional labels, one per box ("" when unnamed).
    """

    size: tuple[float, float, float] = (8.0, 4.0, 2.4)
    absorption: Mapping[str, float] | None = None
    temperature: float = 20.0
    max_order: int = 3
    air_absorption: float = 0.0875
    mounting: tuple[str, ...] | None = None
    anchor_offset: float = 0.03
    node_margin: float = 0.05
    sound_speed: float | None = None
    name: str = "techtile"
    keepouts: tuple = ()
    zones: tuple = ()
    zone_spacing: float = 0.5
    keepout_names: tuple[str, ...] = ()
    zone_names: tuple[str, ...] = ()
    humidity: float = 50.0
    pressure: float = air.REFERENCE_PRESSURE
    corners: tuple | None = None
    wall_names: tuple[str, ...] = ()
    obstacles: tuple = ()
    obstacle_order: int | None = None

    def __post_init__(self) -> None:
        size = self._init_geometry()
        self._init_surfaces()
        lo, hi = TEMPERATURE_RANGE
        t = checks.real("temperature", self.temperature, low=lo, high=hi, unit="°C")
        object.__setattr__(self, "temperature", t)
        if self.sound_speed is not None:
            lo, hi = SOUND_SPEED_RANGE
            c = checks.real("sound_speed", self.sound_speed, low=lo, high=hi, unit="m/s")
            object.__setattr__(self, "sound_speed", c)
        object.__setattr__(
            self, "max_order", checks.count("max_order", self.max_order, low=0, high=MAX_ORDER)
        )
        order = self.max_order if self.obstacle_order is None else self.obstacle_order
        order = checks.count("obstacle_order", order, low=0, high=self.max_order)
        object.__setattr__(self, "obstacle_order", order)
        self._init_air()
        if not isinstance(self.name, str):
            raise ValueError(f"name: must be a string, got {checks.describe(self.name)}")
        half = min(size) / 2
        for fname in ("anchor_offset", "node_margin"):
            v = checks.real(fname, getattr(self, fname), low=0.0, high=half, high_open=True)
            object.__setattr__(self, fname, v)
        object.__setattr__(
            self, "obstacles", floorplan.obstacles_from(self.obstacles, size, self.corners)
        )
        self._init_boxes(size)

    def _init_geometry(self) -> tuple[float, float, float]:
        """Check the size, or normalize the floor plan and derive the size from it."""
        lo, hi = SIZE_RANGE
        if self.corners is not None:
            c, names = floorplan.normalize_corners(self.corners, self.wall_names)
            object.__setattr__(self, "corners", tuple((float(x), float(y)) for x, y in c))
            object.__setattr__(self, "wall_names", names)
            h = (
                self.size[2]
                if isinstance(self.size, list | tuple) and len(self.size) == 3
                else None
            )
            want = (float(c[:, 0].max()), float(c[:, 1].max()), h)
            given = checks.reals("size", self.size, shape=(3,))
            if not np.allclose(given[:2], want[:2], atol=1e-9):
                raise ValueError(
                    f"size: with corners, size is (max x, max y, height) = ({want[0]:g}, "
                    f"{want[1]:g}, height), got {given.tolist()} (use Room.from_corners)"
                )
        elif self.wall_names:
            raise ValueError("wall_names: only a polygonal room (corners) takes wall names")
        try:
            size = checks.reals("size", self.size, shape=(3,), low=lo, high=hi, unit="m")
        except ValueError as exc:
            what = "the corners' largest x and y and the height" if self.corners else "Lx, Ly, Lz"
            raise ValueError(
                f"size: expected 3 lengths ({what}), each in [{lo:g}, {hi:g}] m, "
                f"got {checks.describe(self.size)}"
            ) from exc
        size = tuple(float(v) for v in size)
        object.__setattr__(self, "size", size)
        return size

    def _init_surfaces(self) -> None:
        """Absorption per surface and the mounting surfaces, by the room's surface names."""
        names = self.surface_names
        if self.is_shoebox:
            absorption = dict(TECHTILE_ABSORPTION)
            default_mounting: tuple[str, ...] = ("south", "north", "ceiling")
        else:
            absorption = dict.fromkeys(names, floorplan.DEFAULT_ABSORPTION)
            default_mounting = (*self.wall_names, "ceiling")
        given = {} if self.absorption is None else self.absorption
        checks.mapping("absorption", given, "a mapping (TOML table) of surface name -> [0, 1]")
        _check_surface_names(given, "absorption", names)
        for k, v in given.items():
            absorption[k] = checks.real(f"absorption[{k!r}]", v, low=0.0, high=1.0)
        object.__setattr__(self, "absorption", absorption)
        mounting = default_mounting if self.mounting is None else self.mounting
        if isinstance(mounting, str):
            mounting = (mounting,)
        elif isinstance(mounting, list | tuple):
            mounting = tuple(mounting)
        else:
            raise ValueError(
                f"mounting: must be a surface name or a list of them from {list(names)}, "
                f"got {checks.describe(mounting)}"
            )
        if not mounting:
            raise ValueError("mounting: at least one surface is required")
        _check_surface_names(mounting, "mounting", names)
        if len(set(mounting)) != len(mounting):
            raise ValueError(f"mounting: duplicate surface names in {mounting}")
        object.__setattr__(self, "mounting", mounting)

    def _init_air(self) -> None:
        """Check the air model: a coefficient, or ISO 9613-1 with humidity and pressure."""
        if isinstance(self.air_absorption, str):
            if self.air_absorption != air.ISO9613:
                raise ValueError(
                    f"air_absorption: expected a coefficient in 1/m or {air.ISO9613!r}, "
                    f"got {self.air_absorption!r}"
                )
        else:
            lo, hi = AIR_ABSORPTION_RANGE
            a = checks.real("air_absorption", self.air_absorption, low=lo, high=hi, unit="1/m")
            object.__setattr__(self, "air_absorption", a)
        lo, hi = air.HUMIDITY_RANGE
        object.__setattr__(
            self, "humidity", checks.real("humidity", self.humidity, low=lo, high=hi, unit="%")
        )
        lo, hi = air.PRESSURE_RANGE
        object.__setattr__(
            self, "pressure", checks.real("pressure", self.pressure, low=lo, high=hi, unit="kPa")
        )

    def _init_boxes(self, size) -> None:
        """Normalize and check keep-outs and zones (after the other fields)."""
        for field_, names_field in (("keepouts", "keepout_names"), ("zones", "zone_names")):
            boxes, names = _boxes(getattr(self, field_), field_, size)
            given = getattr(self, names_field)
            given = (given,) if isinstance(given, str) else tuple(given)
            if given:
                if len(given) != len(boxes):
                    raise ValueError(
                        f"{names_field}: expected one name per box of {field_} "
                        f"({len(boxes)}), got {len(given)}"
                    )
                names = tuple(str(n) for n in given)
            object.__setattr__(self, field_, boxes)
            object.__setattr__(self, names_field, names)
        zs = self.zone_spacing
        try:
            ok = not isinstance(zs, bool) and math.isfinite(float(zs)) and float(zs) > 0
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise ValueError(f"zone_spacing: must be a finite number > 0 m, got {zs!r}")
        object.__setattr__(self, "zone_spacing", float(zs))
        from simulation.mounting import check_mounting_area

        check_mounting_area(self)  # every mounting surface keeps some allowed area
        for k, (lo, hi) in enumerate(self.zones):
            if len(self._zone_nodes(lo, hi)) == 0:
                where = (
                    ""
                    if self.is_shoebox and not self.obstacles
                    else (", inside the floor plan and outside the obstacles")
                )
                raise ValueError(
                    f"zones[{k}]: no node of its {self.zone_spacing:g} m grid lies at least "
                    f"node_margin = {self.node_margin:g} m from every plane{where}, got min="
                    f"{list(lo)} max={list(hi)}; allowed: a box that reaches into the room's "
                    f"free space, [{self.node_margin:g}, L - {self.node_margin:g}] on every axis"
                )
        if len(self.grid()) == 0:
            raise ValueError(
                "obstacles: no node of the room's grid is left outside them; allowed: "
                "obstacles that leave room for tags"
            )

    # -- constructors -------------------------------------------------------------------
    @classmethod
    def techtile(cls) -> Room:
        """The paper's 8 × 4 × 2.4 m Techtile room (§II)."""
        return cls()

    @classmethod
    def from_corners(cls, corners, height: float, **kw) -> Room:
        """A polygonal room: the floor plan ``corners`` [[x, y], ...] (m; a simple polygon,
        convex or not, either orientation, x, y ≥ 0) extruded to ``height`` m. Every other
        keyword is a :class:`Room` field (absorption by wall name, ``wall_names``,
        ``obstacles``, keep-outs, zones, mounting, sound speed, ...)."""
        if "size" in kw:
            raise ValueError("size: a polygonal room takes corners and height, not size")
        c = checks.reals("corners", corners, finite=False)
        if c.ndim != 2 or c.shape[-1] != 2 or len(c) == 0:
            raise ValueError(
                f"corners: expected corners [[x, y], ...] in metres, got {checks.describe(corners)}"
            )
        lo, hi = SIZE_RANGE
        h = checks.real("height", height, low=lo, high=hi, unit="m")
        size = (float(np.nanmax(c[:, 0])), float(np.nanmax(c[:, 1])), h)
        kw.setdefault("name", "room")
        return cls(size=size, corners=c.tolist(), **kw)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Room:
        """Build a room from :meth:`to_dict` output (unknown keys raise ``ValueError``)."""
        checks.mapping("room", d, "a mapping of Room fields")
        kw = dict(d)
        aliases = (("keepout", "keepouts"), ("zone", "zones"), ("obstacle", "obstacles"))
        for alias, fname in aliases:  # TOML [[keepout]], [[zone]], [[obstacle]]
            if alias in kw:
                if fname in kw:
                    raise ValueError(f"room: give either {alias!r} or {fname!r}, not both")
                kw[fname] = kw.pop(alias)
        if "signal" in kw:
            raise ValueError(
                "room: a [signal] table belongs to the system now: move its chirp keys (f0, f1, "
                "duration) to [system.signal] and the receiver's to [system.receiver] "
                "(simulation.System; CHANGELOG)"
            )
        known = {f for f in cls.__dataclass_fields__} | {"height"}
        unknown = [k for k in kw if k not in known]
        if unknown:
            raise ValueError(f"room: unknown field(s) {unknown}; allowed: {sorted(known)}")
        if isinstance(kw.get("mounting"), list):
            kw["mounting"] = tuple(kw["mounting"])
        if "corners" in kw or "height" in kw:
            if "corners" not in kw or "height" not in kw:
                raise ValueError("room: a polygonal room needs both 'corners' and 'height'")
            if "size" in kw:
                raise ValueError("room: give either size (a shoebox) or corners and height")
            return cls.from_corners(kw.pop("corners"), kw.pop("height"), **kw)
        return cls(**kw)

    @classmethod
    def from_toml(cls, path: str | Path) -> Room:
        """Read a room from a TOML file with the keys of :meth:`to_dict`.

        Keep-outs and zones are arrays of tables, ``[[keepout]]`` and ``[[zone]]``, each
        with ``min = [x, y, z]``, ``max = [x, y, z]`` and an optional ``name``. A
        ``[system]`` table is the positioning system's (:meth:`simulation.System.from_toml`
        reads it) and not part of the room. Every
        problem (missing, unreadable, empty or invalid file, a bad key or value) raises
        ``ValueError`` naming the file.
        """
        p = checks.input_file("room file", path)
        try:
            with open(p, "rb") as fh:
                data = tomllib.load(fh)
        except OSError as exc:
            raise ValueError(f"room file {p}: cannot read it ({exc.strerror})") from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise ValueError(f"room file {p}: not valid TOML ({exc})") from None
        data.pop("system", None)  # the system's table, read by simulation.System.from_toml
        if not data:
            raise ValueError(
                f"room file {p}: empty; give at least size = [Lx, Ly, Lz] in metres "
                "(keys of Room.to_dict())"
            )
        try:
            return cls.from_dict(data)
        except ValueError as exc:
            raise ValueError(f"room file {p}: {exc}") from None

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON/TOML-serializable dictionary of every field."""
        d = {"name": self.name}
        if self.is_shoebox:
            d["size"] = list(self.size)
        else:
            d["corners"] = [list(c) for c in self.corners]
            d["height"] = self.size[2]
            if self.wall_names != tuple(f"wall-{i}" for i in range(len(self.corners))):
                d["wall_names"] = list(self.wall_names)
        d |= {
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
        # only when set, so that the dictionary of a plain room is unchanged
        for fname, names in (("keepouts", self.keepout_names), ("zones", self.zone_names)):
            boxes = getattr(self, fname)
            if boxes:
                d[fname] = [
                    {"min": list(lo), "max": list(hi), **({"name": n} if n else {})}
                    for (lo, hi), n in zip(boxes, names, strict=True)
                ]
        if self.zones or self.zone_spacing != 0.5:
            d["zone_spacing"] = self.zone_spacing
        if self.air_absorption == air.ISO9613 or self.humidity != 50.0:
            d["humidity"] = self.humidity
        if self.air_absorption == air.ISO9613 or self.pressure != air.REFERENCE_PRESSURE:
            d["pressure"] = self.pressure
        if self.obstacles:
            d["obstacles"] = [ob.to_dict() for ob in self.obstacles]
        if self.obstacle_order != self.max_order:
            d["obstacle_order"] = self.obstacle_order
        return d

    def to_toml(self, path: str | Path) -> None:
        """Write the room as TOML (readable by :meth:`from_toml`)."""
        path = checks.output_path("path", path, suffixes=(".toml",))
        lines = []
        d = self.to_dict()
        absorption = d.pop("absorption")
        tables = {
            "keepout": d.pop("keepouts", []),
            "zone": d.pop("zones", []),
            "obstacle": d.pop("obstacles", []),
        }
        for k, v in d.items():
            lines.append(f"{k} = {_toml_value(v)}")
        lines += ["", "[absorption]"] + [f"{k} = {_toml_value(v)}" for k, v in absorption.items()]
        for key, items in tables.items():
            for item in items:
                lines += ["", f"[[{key}]]"] + [f"{k} = {_toml_value(v)}" for k, v in item.items()]
        write_file(path, "\n".join(lines) + "\n")

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
    def diagonal(self) -> float:
        """The longest distance between two points of the room (m)."""
        if self.is_shoebox:
            return float(np.linalg.norm(self.size))
        c = np.asarray(self.corners)
        span = np.max(np.linalg.norm(c[:, None] - c[None], axis=-1))
        return float(math.hypot(span, self.size[2]))

    # -- geometry --------------------------------------------------------------------------
    @property
    def is_shoebox(self) -> bool:
        """Whether the room is a shoebox (no floor plan); it may still hold obstacles."""
        return self.corners is None

    @property
    def surface_names(self) -> tuple[str, ...]:
        """The names of the room's surfaces: a shoebox's six compass planes, or a polygonal
        room's walls, floor and ceiling."""
        if self.is_shoebox:
            return tuple(SURFACES)
        return (*self.wall_names, "floor", "ceiling")

    @property
    def floor_corners(self) -> np.ndarray:
        """(n, 2) the floor plan's corners, counter-clockwise (a shoebox's rectangle)."""
        if self.is_shoebox:
            Lx, Ly, _ = self.size
            return np.array([[0.0, 0.0], [Lx, 0.0], [Lx, Ly], [0.0, Ly]])
        return np.asarray(self.corners, dtype=float)

    @property
    def walls(self) -> list[floorplan.Wall]:
        """The vertical walls, in corner order (a shoebox: south, east, north, west)."""
        names = floorplan.SHOEBOX_WALLS if self.is_shoebox else self.wall_names
        return floorplan.walls(self.floor_corners, names, self.size[2])

    @property
    def is_convex(self) -> bool:
        """Whether the floor plan is convex (no wall can block a path between two points)."""
        if self.is_shoebox:
            return True
        from shapely import Polygon

        poly = Polygon(self.corners)
        return bool(abs(poly.convex_hull.area - poly.area) <= 1e-9 * poly.area)

    def air_coefficient(self, frequency) -> np.ndarray:
        """The air's energy attenuation coefficient m(f) in 1/m at ``frequency`` (Hz, any
        shape): the constant ``air_absorption``, or ISO 9613-1 (:mod:`simulation.air`)."""
        f = np.asarray(frequency, dtype=float)
        if self.air_absorption != air.ISO9613:
            return np.full(f.shape, float(self.air_absorption))
        db = air.iso9613_db_per_m(f, self.temperature, self.humidity, self.pressure)
        return air.energy_coefficient(db)

    def air_excess(self, frequency: float):
        """None for a constant coefficient, else the function f ↦ m(f) − m(``frequency``)
        (1/m) that the received windows apply across the chirp's band around its centre
        ``frequency`` (Hz; :mod:`simulation.synthesis`)."""
        if self.air_absorption != air.ISO9613:
            return None
        ref = float(self.air_coefficient(frequency))
        return lambda f: self.air_coefficient(f) - ref

    @property
    def dimensions(self) -> np.ndarray:
        """(3,) room size in metres."""
        return np.array(self.size)

    @property
    def centroid(self) -> np.ndarray:
        """(3,) room centre in metres (the anchors' aim point): the box's centre, or the
        floor plan's area centroid at half the height."""
        if self.is_shoebox:
            return np.array(self.size) / 2
        cx, cy = floorplan.centroid(self.floor_corners)
        return np.array([cx, cy, self.size[2] / 2])

    def reflection(self, surface: str) -> float:
        """Amplitude reflection coefficient β = √(1 − α) of a surface."""
        return math.sqrt(1.0 - self.absorption[surface])

    @property
    def reflections(self) -> np.ndarray:
        """(3, 2) reflection amplitudes β of a shoebox indexed by [axis, side] (side 0: plane
        at 0)."""
        if not self.is_shoebox:
            raise ValueError("reflections: a polygonal room has no shoebox planes (see walls)")
        b = np.empty((3, 2))
        for name, (axis, side) in SURFACES.items():
            b[axis, side] = self.reflection(name)
        return b

    def grid(self, shape: Sequence[int] | None = None) -> np.ndarray:
        """(P, 3) evaluation nodes: the tag zones' grid, or a regular grid of the room.

        Without ``shape`` and with :attr:`zones`, the nodes are the zone grid (see
        :meth:`zone_grid`). Otherwise (no zones, or an explicit ``shape``, e.g. for held-out
        nodes) a regular (nx, ny, nz) grid of the whole room, evenly spaced,
        ``node_margin`` from every plane, ordered with x slowest and z fastest; the
        default (9, 6, 5) gives the paper's 270 nodes with spacing 98.75 / 78.0 / 57.5 cm.
        In a polygonal room or one with obstacles the grid spans the bounding box and
        keeps the nodes inside the room (:meth:`contains`, ``node_margin`` from its walls
        and obstacles).
        """
        if shape is None:
            if self.zones:
                return self.zone_grid()
            shape = (9, 6, 5)
        shape = checks.grid_shape("shape", shape)
        checks.check_size("shape", math.prod(shape) * 3 * 8 * 4, value=shape)
        m = self.node_margin
        axes = [
            np.linspace(m, L - m, n) if n > 1 else np.array([L / 2])
            for L, n in zip(self.size, shape, strict=True)
        ]
        g = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        if self.is_shoebox and not self.obstacles:
            return g
        return g[self.contains(g, margin=max(self.node_margin - 1e-9, 0.0))]

    def _zone_nodes(self, lo, hi) -> np.ndarray:
        """(n, 3) grid nodes of one zone inside the node margin (see :meth:`zone_grid`)."""
        axes = []
        for a, b in zip(lo, hi, strict=True):
            n = int(round((b - a) / self.zone_spacing)) + 1
            axes.append(np.linspace(a, b, n) if n > 1 else np.array([(a + b) / 2]))
        g = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        return g[self.contains(g, margin=self.node_margin - 1e-9)]

    def zone_grid(self) -> np.ndarray:
        """(P, 3) the evaluation nodes of the tag zones (empty (0, 3) without zones).

        Each zone side of length ℓ gets n = round(ℓ / zone_spacing) + 1 evenly spaced
        levels from face to face (both faces included; the spacing is ℓ/(n − 1), exactly
        ``zone_spacing`` when it divides ℓ; a side shorter than half the spacing gets one
        level at its middle). Nodes closer than ``node_margin`` to a plane are dropped,
        nodes shared by overlapping zones kept once (compared to 1e-9 m). Ordered zone by
        zone, x slowest and z fastest within a zone.
        """
        if not self.zones:
            return np.empty((0, 3))
        g = np.concatenate([self._zone_nodes(lo, hi) for lo, hi in self.zones])
        _, first = np.unique(np.round(g, 9), axis=0, return_index=True)
        return g[np.sort(first)]

    def in_keepout(self, points) -> np.ndarray:
        """(...,) bool: points (..., 3) lie in a keep-out box (closed: faces included)."""
        return in_boxes(self.keepouts, points).any(axis=-1)

    def contains(self, points: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """(P,) bool: points (P, 3) lie inside the room, at least ``margin`` from each plane
        (the walls, floor and ceiling) and outside every obstacle grown by ``margin``."""
        p = checks.reals("points", points, finite=False)
        if p.ndim < 1 or p.shape[-1] != 3:
            raise ValueError(f"points: expected shape (..., 3), got {p.shape}")
        margin = checks.real("margin", margin, low=0.0, unit="m")
        inside = np.all((p >= margin) & (p <= np.array(self.size) - margin), axis=-1)
        if not self.is_shoebox:
            inside &= floorplan.contains_xy(self.floor_corners, p[..., :2], margin)
        for ob in self.obstacles:
            # a point on a face is outside (anchors sit 3 cm off a mountable face)
            inside &= ~ob.contains(p, margin - 1e-12 if margin > 0 else -1e-12)
        return inside

    def in_obstacle(self, points) -> np.ndarray:
        """(...,) bool: points (..., 3) inside an obstacle (faces excluded)."""
        p = np.asarray(points, dtype=float)
        out = np.zeros(p.shape[:-1], dtype=bool)
        for ob in self.obstacles:
            out |= ob.contains(p, -1e-12)
        return out

    def check_nodes(self, nodes) -> np.ndarray:
        """Validate evaluation nodes: (P, 3) finite, P ≥ 1, inside the room (and, in a
        polygonal room or one with obstacles, inside the floor plan and outside every
        obstacle); returns them as a float array, or raises ``ValueError`` naming ``nodes``."""
        p = checks.points("nodes", nodes)
        checks.inside("nodes", p, self.size)
        if not self.is_shoebox or self.obstacles:
            out = ~self.contains(p)
            if np.any(out):
                bad = np.flatnonzero(out)
                raise ValueError(
                    f"nodes: node(s) {bad[:10].tolist()} lie outside the floor plan or inside "
                    f"an obstacle, e.g. {p[bad[0]].tolist()}"
                )
        return p

    def check_anchors(self, anchors, min_anchors: int = 4) -> np.ndarray:
        """Validate an anchor layout: (M, 3) finite, M ≥ ``min_anchors``, inside the room.

        Returns the layout as a float array; raises ``ValueError`` naming the problem.
        """
        min_anchors = checks.count("min_anchors", min_anchors, low=1, high=1_000_000)
        a = checks.reals("anchors", anchors)
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
            bad = np.flatnonzero(outside).tolist()
            if self.obstacles and np.any(self.in_obstacle(a)):
                k = int(np.argmax(self.in_obstacle(a)))
                raise ValueError(
                    f"anchors: anchor(s) {bad} lie outside the room or in an obstacle; anchor "
                    f"{k} at {a[k].tolist()} is inside an obstacle (use placement.project)"
                )
            where = (
                f"[0, {self.size[0]}] x [0, {self.size[1]}] x [0, {self.size[2]}] m"
                if self.is_shoebox
                else f"the floor plan {np.round(self.floor_corners, 3).tolist()} (m) from "
                f"z = 0 to {self.size[2]:g} m"
            )
            raise ValueError(f"anchors: anchor(s) {bad} lie outside the room: {where}")
        hits = in_boxes(self.keepouts, a)  # (M, B)
        if np.any(hits):
            bad = np.flatnonzero(hits.any(axis=1))
            j, b = int(bad[0]), int(np.argmax(hits[bad[0]]))
            label = f" ({self.keepout_names[b]!r})" if self.keepout_names[b] else ""
            raise ValueError(
                f"anchors: anchor(s) {bad.tolist()} lie in a keep-out box; anchor {j} at "
                f"{a[j].tolist()} is in keepouts[{b}]{label} min={list(self.keepouts[b][0])} "
                f"max={list(self.keepouts[b][1])} (use placement.project)"
            )
        return a

    def corners_layout(self) -> np.ndarray:
        """(4, 3) the paper's non-optimized "corners" layout (§V-A), offset from the planes.

        For techtile: (0.03, 0.03, 0.03) south, (7.97, 3.97, 0.03) north, (7.97, 0.03, 2.37)
        and (0.03, 3.97, 2.37) ceiling. A polygonal room: one anchor in every corner of the
        floor plan (inset by ``anchor_offset``), alternately near the floor and near the
        ceiling (n anchors for n corners).
        """
        o = self.anchor_offset
        if not self.is_shoebox:
            xy = floorplan.inset(self.floor_corners, o)
            z = np.where(np.arange(len(xy)) % 2 == 0, o, self.size[2] - o)
            return np.column_stack([xy, z])
        Lx, Ly, Lz = self.size
        return np.array(
            [[o, o, o], [Lx - o, Ly - o, o], [Lx - o, o, Lz - o], [o, Ly - o, Lz - o]], dtype=float
        )


def as_room(value: Any, name: str = "room") -> Room:
    """``value`` if it is a :class:`Room`; ValueError naming ``name`` otherwise."""
    if not isinstance(value, Room):
        raise ValueError(
            f"{name}: must be a simulation.Room (e.g. Room.techtile(), Room.from_toml(path)), "
            f"got {checks.describe(value)}"
        )
    return value


def room_or_default(value: Any, name: str = "room") -> Room:
    """:func:`as_room`, with None standing for the embedded default room,
    :meth:`Room.techtile`."""
    return Room.techtile() if value is None else as_room(value, name)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(float(v)) if isinstance(v, float) else str(v)
    if isinstance(v, str):  # a JSON string is a valid TOML basic string (DEL escaped too)
        return json.dumps(v, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _vec3(v, what: str) -> tuple[float, float, float]:
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: expected 3 numbers [x, y, z] in metres, got {v!r}") from None
    if a.shape != (3,):
        raise ValueError(f"{what}: expected 3 numbers [x, y, z] in metres, got {v!r}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what}: coordinates must be finite (no NaN or inf), got {a.tolist()}")
    return tuple(float(x) for x in a)


def _boxes(items, what: str, size) -> tuple[tuple, tuple[str, ...]]:
    """Normalize keep-out or zone boxes to ((min, max), ...) and their names; check them."""
    if items is None:
        items = ()
    if isinstance(items, Mapping | str | bytes) or not isinstance(items, Iterable):
        raise ValueError(f"{what}: expected a list of boxes (min_xyz, max_xyz), got {items!r}")
    boxes, names = [], []
    for k, item in enumerate(items):
        w = f"{what}[{k}]"
        if isinstance(item, Mapping):
            extra = set(item) - {"min", "max", "name"}
            if what == "zones" and "weight" in extra:
                raise ValueError(
                    f"{w}: zone weights are not supported (got weight = {item['weight']!r}); "
                    "every node counts equally: remove 'weight' (allowed keys: min, max, name)"
                )
            if extra or not {"min", "max"} <= set(item):
                raise ValueError(
                    f"{w}: expected keys 'min', 'max' and optionally 'name', got {sorted(item)}"
                )
            lo, hi, name = item["min"], item["max"], item.get("name", "")
            if not isinstance(name, str):
                raise ValueError(f"{w}: name must be a string, got {name!r}")
        else:
            try:
                lo, hi = item
            except (TypeError, ValueError):
                raise ValueError(
                    f"{w}: expected a box (min_xyz, max_xyz) or "
                    f"{{'min': [x, y, z], 'max': [x, y, z]}}, got {item!r}"
                ) from None
            name = ""
        lo, hi = _vec3(lo, f"{w} min"), _vec3(hi, f"{w} max")
        if any(a > b for a, b in zip(lo, hi, strict=True)):
            raise ValueError(
                f"{w}: inverted box, min {list(lo)} exceeds max {list(hi)} on some axis; "
                "allowed: min <= max on every axis"
            )
        tol = 1e-9
        if any(a < -tol for a in lo) or any(b > L + tol for b, L in zip(hi, size, strict=True)):
            raise ValueError(
                f"{w}: box min={list(lo)} max={list(hi)} is not inside the room; allowed: "
                f"[0, {size[0]:g}] x [0, {size[1]:g}] x [0, {size[2]:g}] m"
            )
        boxes.append((lo, hi))
        names.append(name)
    return tuple(boxes), tuple(names)

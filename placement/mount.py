"""One anchor as mounted and a wall as the installer sees it: the rows of the mounting sheet
(:mod:`placement.sheet` computes them, :mod:`placement.sheet_html` draws them).
"""

from __future__ import annotations

from dataclasses import dataclass

#: the CSV's columns, in order
COLUMNS = (
    "id", "surface", "reference", "reference_x_m", "reference_y_m", "along_m", "height_m",
    "plan_x_m", "plan_y_m", "off_surface_m", "aim_azimuth_deg", "aim_elevation_deg",
    "aim_pan_deg", "tolerance_m", "room_x_m", "room_y_m", "room_z_m",
)  # fmt: skip


@dataclass(frozen=True)
class Mount:
    """One anchor as mounted (:mod:`placement.sheet` gives the conventions); lengths in m,
    angles in degrees.

    ``kind`` is ``"wall"`` (a vertical surface: ``along`` is set, ``plan_x``/``plan_y``
    are None), ``"plane"`` (a horizontal one: ``plan_x``, ``plan_y`` set, ``along`` and
    ``pan`` None) or ``"free"`` (on no mounting surface: only the room coordinates).
    """

    id: int
    surface: str
    kind: str
    reference: str
    reference_xy: tuple[float, float]
    along: float | None
    height: float
    plan_x: float | None
    plan_y: float | None
    off_surface: float
    azimuth: float
    elevation: float
    pan: float | None
    tolerance: float | None
    position: tuple[float, float, float]

    def row(self) -> dict[str, str]:
        """The CSV row: metres to the millimetre, degrees to a tenth; blank where unset."""

        def m(x):
            return "" if x is None else f"{x:.3f}"

        def deg(x):
            return "" if x is None else f"{x:.1f}"

        values = (self.id, self.surface, self.reference, m(self.reference_xy[0]),
                  m(self.reference_xy[1]), m(self.along), m(self.height), m(self.plan_x),
                  m(self.plan_y), m(self.off_surface), deg(self.azimuth), deg(self.elevation),
                  deg(self.pan), m(self.tolerance), *(m(v) for v in self.position))  # fmt: skip
        return dict(zip(COLUMNS, (str(v) for v in values), strict=True))


@dataclass(frozen=True)
class VerticalFrame:
    """A vertical mounting surface as the installer sees it: its ``reference`` corner
    ``start`` (2,) (the left end seen from the room), the unit ``right`` (2,) along it
    away from that corner, the unit ``normal`` (2,) into the room, its ``length`` and the
    height span ``bottom``–``top`` (m)."""

    name: str
    reference: str
    start: tuple[float, float]
    right: tuple[float, float]
    normal: tuple[float, float]
    length: float
    bottom: float
    top: float

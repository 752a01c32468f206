"""Figures of layouts, bounds and simulated errors (paper Figs. 1–8), headless.

Every function takes plain arrays (and a :class:`~simulation.room.Room` for the geometry)
and returns a :class:`matplotlib.figure.Figure` drawn on an Agg canvas. Nothing here
touches pyplot or its global state and nothing calls ``show``; save with :func:`save` or
:func:`png_bytes`. The figure size in pixels is ``figsize × dpi`` exactly (no tight
bounding box), so callers get the size they ask for.

This module imports matplotlib; ``import analysis`` does not import it (use
``from analysis import figures``).

Conventions: lengths in metres; PEB = √tr J⁻¹ in metres (docs/model.md); colour bars are
labelled with their unit; non-finite values (a singular FIM gives PEB = +inf) are drawn
in grey and never stretch a colour scale. Several layouts in one figure take a mapping
name → array, drawn in the colours of :func:`layout_colors` so a layout keeps its colour
from figure to figure.

Artists carry a ``gid`` so tests and users can find them: ``"anchors"`` (one anchor
marker collection per axes, M points), ``"aim"`` (aim vectors), ``"nodes"``,
``"cdf:NAME"`` / ``"peb:NAME"`` / ``"rmse:NAME"`` (one CDF line per layout),
``"keepouts"`` (the room's keep-out boxes: grey boxes in 3D, hatched rectangles projected
onto plan and elevation views) and ``"zones"`` (its tag zones: dashed outlines).
"""

from __future__ import annotations

import io
import math
import textwrap
import zlib
from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import LogNorm, Normalize, TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from analysis.coverage import bound as _bound
from analysis.coverage import coverage as _coverage
from analysis.fim import DEFAULT_SIGMA
from analysis.fim import peb as _peb
from analysis.stacking import groups, stacks
from analysis.statistics import ecdf, error_stats
from simulation import checks
from simulation.directivity import aim_vectors
from simulation.mounting import mounting_surfaces as _mounting_surfaces
from simulation.output import write_with
from simulation.room import SURFACES, Room, as_room
from simulation.system import as_system

#: colour-blind-friendly qualitative palette (Okabe–Ito without black, plus extras)
PALETTE: tuple[str, ...] = (
    "#0072B2",  # blue
    "#D55E00",  # vermillion
    "#009E73",  # green
    "#CC79A7",  # purple-pink
    "#E69F00",  # orange
    "#56B4E9",  # sky blue
    "#8C564B",  # brown
    "#882255",  # wine
    "#7F7F7F",  # grey
    "#17BECF",  # cyan
)

#: colour map of PEB and error magnitudes (metres)
CMAP = "viridis"
#: colour of non-finite cells/nodes (PEB = inf where the FIM is singular)
BAD_COLOR = "0.78"
#: default anchor marker colour when no layout name is given (the paper's orange squares)
ANCHOR_COLOR = "#E69F00"
#: keep-out boxes (grey, hatched in 2D) and tag-zone outlines (dashed)
KEEPOUT_COLOR = "0.3"
ZONE_COLOR = "0.1"
#: an obstacle narrower and shallower than this share of the room's larger plan side (a
#: column in a hall: smaller than its height tag at a figure's scale) has the tag above it
SMALL_OBSTACLE = 0.07
#: CDF lines are reduced to at most this many points (quantiles) to keep figures fast
_MAX_CDF_POINTS = 2000


# -- colours ------------------------------------------------------------------------------
#: fixed palette slots of the names the CLI and reports use (high contrast between them)
FIXED_SLOTS: dict[str, int] = {"optimized": 0, "corners": 1, "evaluated": 2, "naive": 3}


def layout_colors(names: Sequence[str], palette: Sequence[str] = PALETTE) -> dict[str, str]:
    """Colour per layout name, stable across figures: name → hex colour.

    The names of :data:`FIXED_SLOTS` ("optimized", "corners", "evaluated", "naive") always
    get their slot (blue, vermillion, green, purple-pink with the default palette); any
    other name prefers the slot given by a hash of the name (CRC-32, independent of
    Python's hash seed), so a layout gets the same colour whenever it is drawn with
    different companions; collisions within ``names`` move to the next free slot (in the
    order of ``names``). Pass the same mapping to every figure to be fully consistent.
    """
    names = list(dict.fromkeys(names))
    out: dict[str, str] = {}
    n = len(palette)
    fixed = {k: v % n for k, v in FIXED_SLOTS.items() if k in names}
    used: set[int] = set(fixed.values())
    for name in names:
        if name in fixed:
            out[name] = palette[fixed[name]]
            continue
        slot = zlib.crc32(str(name).encode()) % n
        for k in range(n):
            if (slot + k) % n not in used:
                slot = (slot + k) % n
                break
        used.add(slot)
        if len(used) == n:  # more layouts than colours: start a new cycle
            used.clear()
        out[name] = palette[slot]
    return out


def _colors_for(names, colors):
    base = layout_colors(list(names))
    if colors:
        base.update({k: v for k, v in colors.items() if k in base})
    return base


# -- figure plumbing ------------------------------------------------------------------------
def new_figure(figsize=(7.0, 4.5), dpi: float = 100, layout: str | None = "constrained") -> Figure:
    """An empty figure on its own Agg canvas (no pyplot); ``figsize`` in inches."""
    w, h = (float(v) for v in figsize)
    if not (w > 0 and h > 0 and math.isfinite(w) and math.isfinite(h)):
        raise ValueError(f"figsize: expected two positive inch sizes, got {figsize}")
    dpi = checks.real("dpi", dpi, low=0.0, high=10_000.0, low_open=True)
    fig = Figure(figsize=(w, h), dpi=dpi, layout=layout)
    FigureCanvasAgg(fig)
    return fig


def save(fig: Figure, path: str | Path, dpi: float | None = None) -> Path:
    """Write the figure (format from the suffix, e.g. ``.png``; never half-written,
    :mod:`simulation.output`); size = figsize × dpi pixels."""
    return write_with(path, lambda tmp: fig.savefig(tmp, dpi=dpi or fig.dpi))


def png_bytes(fig: Figure, dpi: float | None = None, palette: bool = False) -> bytes:
    """The figure as PNG bytes (size = figsize × dpi pixels).

    ``palette=True`` quantizes to a 256-colour palette PNG (about 3× smaller), fine for
    line plots; continuous colour scales then show visible steps, so keep full colour
    for figures with a colour bar.
    """
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi or fig.dpi, pil_kwargs={"optimize": True})
    if not palette:
        return buf.getvalue()
    from PIL import Image  # a matplotlib dependency

    buf.seek(0)
    img = Image.open(buf).convert("RGB")
    q = img.quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    out = io.BytesIO()
    q.save(out, format="PNG", optimize=True)
    return out.getvalue()


def _cmap(name=CMAP):
    return matplotlib.colormaps[name].with_extremes(bad=BAD_COLOR)


def _norm(values, scale: str = "auto", vmin=None, vmax=None):
    """Colour normalization spanning the finite data range (or the given limits).

    ``scale``: "linear", "log", or "auto" (log when the finite data span more than a
    factor 10, e.g. near-singular layouts whose PEB reaches metres next to centimetres).
    Returns (norm, extend) with ``extend`` the colour-bar arrow for clipped data.
    """
    if scale not in ("auto", "linear", "log"):
        raise ValueError(f"scale: must be 'auto', 'linear' or 'log', got {scale!r}")
    v = np.asarray(values, dtype=float)
    f = v[np.isfinite(v)]
    lo = float(f.min()) if f.size else 0.0
    hi = float(f.max()) if f.size else 1.0
    vmin = lo if vmin is None else float(vmin)
    vmax = hi if vmax is None else float(vmax)
    if not vmax > vmin:
        vmax = vmin + max(abs(vmin) * 1e-6, 1e-12)
    if scale == "auto":
        scale = "log" if vmin > 0 and vmax / vmin > 10 else "linear"
    if scale == "log" and vmin <= 0:
        raise ValueError(f"scale: 'log' needs positive values, got minimum {vmin}")
    under, over = f.size and lo < vmin, f.size and hi > vmax
    extend = {(0, 0): "neither", (1, 0): "min", (0, 1): "max", (1, 1): "both"}[
        (int(bool(under)), int(bool(over)))
    ]
    norm = LogNorm(vmin, vmax) if scale == "log" else Normalize(vmin, vmax)
    return norm, extend


def _colorbar(fig, mappable, ax, label: str, extend: str = "neither", **kw):
    """Colour bar with ``label`` (and unit); log scales get plain-number ticks 1-2-5."""
    cb = fig.colorbar(mappable, ax=ax, label=label, extend=extend, **kw)
    if isinstance(mappable.norm, LogNorm):
        from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

        cb.ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        cb.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        cb.ax.yaxis.set_minor_formatter(NullFormatter())
    cb.ax.set_gid("colorbar")
    return cb


def _as_points(a, name: str, n: int | None = None) -> np.ndarray:
    a = checks.reals(name, a, finite=False)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name}: expected shape (N, 3), got {a.shape}")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name}: expected {n} rows, got {a.shape[0]}")
    return a


def _values(v, name: str, n: int) -> np.ndarray:
    v = np.asarray(v, dtype=float).ravel()
    if v.size != n:
        raise ValueError(f"{name}: expected {n} values (one per node), got {v.size}")
    return v


# -- PEB maps on planes ---------------------------------------------------------------------
_AXES = "xyz"


def _draw_room2d(ax, room: Room, iu: int, iv: int, cut=None) -> None:
    """A polygonal room's floor plan (outline, the outside of it blanked) in a plan view,
    and the obstacles (cross-hatched; in a plan view their heights written on them, once
    per solid: :func:`_labelled`) projected onto the (iu, iv) plane. On a slice, ``cut``
    (axis, value) its plane, an obstacle the plane does not cut (a duct above a slice at
    tag height) is its dashed outline only: the map under it is the slice's."""
    from matplotlib.patches import PathPatch, Rectangle
    from matplotlib.path import Path as MPath

    L = room.size
    if not room.is_shoebox and (iu, iv) == (0, 1):
        c = room.floor_corners
        box = [(0, 0), (L[0], 0), (L[0], L[1]), (0, L[1]), (0, 0)]
        ring = [*map(tuple, c[::-1]), tuple(c[-1])]  # clockwise: a hole in the box
        codes = [MPath.MOVETO] + [MPath.LINETO] * 3 + [MPath.CLOSEPOLY]
        codes += [MPath.MOVETO] + [MPath.LINETO] * (len(c) - 1) + [MPath.CLOSEPOLY]
        path = MPath(box + ring, codes)
        ax.add_patch(PathPatch(path, facecolor="white", edgecolor="none", zorder=2.2,
                               gid="outside"))  # fmt: skip
        closed = np.vstack([c, c[:1]])
        ax.plot(closed[:, 0], closed[:, 1], color="black", lw=1.2, zorder=2.3, gid="floorplan")
    for ob in room.obstacles:
        lo, hi = ob.lo, ob.hi
        solid = cut is None or lo[cut[0]] <= cut[1] <= hi[cut[0]]
        style = (dict(facecolor=(0.3, 0.3, 0.3, 0.55), hatch="xx", gid="obstacles") if solid
                 else dict(facecolor="none", linestyle="--", gid="off-slice"))  # fmt: skip
        ax.add_patch(Rectangle((lo[iu], lo[iv]), hi[iu] - lo[iu], hi[iv] - lo[iv],
                               edgecolor="black", linewidth=0.8, zorder=2.6, **style))  # fmt: skip
    if (iu, iv) != (0, 1):
        return
    small = SMALL_OBSTACLE * max(L[0], L[1])
    for ob in _labelled(room.obstacles):
        lo, hi = ob.lo, ob.hi
        centre = ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2)
        # a box smaller than its tag (a column in a hall) gets the tag above it, not on it
        beside = hi[0] - lo[0] < small and hi[1] - lo[1] < small
        # dark on a white tag: legible on the hatch, and beside a box thinner than it
        ax.annotate(_obstacle_heights(lo, hi), (centre[0], hi[1]) if beside else centre,
                    xytext=(0, 1.5 if beside else 0), textcoords="offset points",
                    fontsize=6, ha="center", va="bottom" if beside else "center",
                    color="black", zorder=2.7, gid="obstacle-height",
                    bbox=dict(boxstyle="round,pad=0.15", facecolor="white", alpha=0.8,
                              edgecolor="none"))  # fmt: skip


def _labelled(obstacles) -> list:
    """The obstacles a plan view writes heights on: of the boxes that meet side by side
    with the same bottom and top (a pillar, a counter described as several boxes), only
    the largest footprint (the first of equals), so that one solid gets one label."""
    obstacles = list(obstacles)
    n = len(obstacles)
    same = np.array([[_same_solid(a, b) for b in obstacles] for a in obstacles], bool).reshape(n, n)
    area = [(ob.hi[0] - ob.lo[0]) * (ob.hi[1] - ob.lo[1]) for ob in obstacles]
    keep = [max(g, key=lambda i: (area[i], -i)) for g in groups(same)]
    return [obstacles[i] for i in sorted(keep)]


def _same_solid(a, b, tol: float = 1e-9) -> bool:
    """Boxes a and b have the same bottom and top and their footprints touch."""
    same_z = abs(a.lo[2] - b.lo[2]) <= tol and abs(a.hi[2] - b.hi[2]) <= tol
    return same_z and all(a.lo[k] <= b.hi[k] + tol and b.lo[k] <= a.hi[k] + tol for k in (0, 1))


def _obstacle_heights(lo, hi) -> str:
    """An obstacle's heights as a plan view writes them: its top ("2 m") for one that
    stands on the floor, its bottom and top ("3–3.5 m") for one that does not (a duct, a
    hanging cabinet)."""
    return f"{hi[2]:g} m" if lo[2] <= 0 else f"{lo[2]:g}–{hi[2]:g} m"


def _blank_outside(ax, room: Room, pts: np.ndarray, shape, extent) -> None:
    """Cover the cells (``pts`` (n, 3), reshaped to ``shape``) outside the room (beyond
    the floor plan or in an obstacle) in white, over a heat map."""
    if room.is_shoebox and not room.obstacles:
        return
    outside = ~room.contains(pts).reshape(shape)
    if not outside.any():
        return
    rgba = np.zeros((*outside.T.shape, 4))
    rgba[outside.T] = (1.0, 1.0, 1.0, 1.0)
    ax.imshow(rgba, origin="lower", extent=extent, interpolation="nearest", aspect="equal",
              zorder=1.5)  # fmt: skip


def _draw_regions2d(ax, room: Room, iu: int, iv: int, cut=None) -> None:
    """Keep-outs (hatched grey) and tag zones (dashed) projected onto the (iu, iv) plane,
    with a polygonal room's outline and its obstacles (:func:`_draw_room2d`; ``cut`` a
    slice's plane)."""
    from matplotlib.patches import Polygon as MPolygon
    from matplotlib.patches import Rectangle

    _draw_room2d(ax, room, iu, iv, cut)

    for boxes, keepout in ((room.keepouts, True), (room.zones, False)):
        for lo, hi in boxes:
            xy, w, h = (lo[iu], lo[iv]), hi[iu] - lo[iu], hi[iv] - lo[iv]
            if keepout:
                patch = Rectangle(
                    xy,
                    w,
                    h,
                    facecolor=(0.5, 0.5, 0.5, 0.45),
                    edgecolor=KEEPOUT_COLOR,
                    hatch="////",
                    linewidth=0.8,
                    zorder=2.5,
                    gid="keepouts",
                )
            else:
                patch = Rectangle(
                    xy,
                    w,
                    h,
                    fill=False,
                    edgecolor=ZONE_COLOR,
                    linestyle="--",
                    linewidth=0.9,
                    zorder=2.4,
                    gid="zones",
                )
            ax.add_patch(patch)
            if not keepout and not room.is_shoebox and (iu, iv) == (0, 1):
                # a zone box over a floor plan that is not a rectangle holds nodes only
                # inside the plan: its outline is drawn there
                patch.set_clip_path(MPolygon(room.floor_corners, transform=ax.transData))


def peb_plane(
    room: Room,
    anchors,
    axis: int | str,
    value: float,
    sigma=DEFAULT_SIGMA,
    resolution: float = 0.05,
    system=None,
):
    """PEB (m) on the plane ``axis = value`` across the whole room, for the anchors each
    point hears with ``system`` (default the paper's).

    Returns ``(u, v, values)``: cell-centre coordinates u (nu,), v (nv,) along the two
    other axes in increasing order and PEB values (nu, nv) in metres, +inf where the FIM
    is singular or a point hears fewer than 4 anchors, NaN outside the room (beyond a
    polygonal floor plan, in an obstacle); ``resolution`` is the cell size in metres and
    ``sigma`` the range σ (m), for the anchors each point hears
    (:func:`analysis.coverage.bound`).
    """
    if not isinstance(axis, int | str) or isinstance(axis, bool) or axis not in (0, 1, 2, *_AXES):
        raise ValueError(f"axis: must be 0, 1, 2 or 'x', 'y', 'z', got {axis!r}")
    k = _AXES.index(axis) if isinstance(axis, str) else int(axis)
    L = as_room(room).size
    value = checks.real("value", value, low=0.0, high=L[k], unit="m")
    resolution = checks.real("resolution", resolution, low=0.0, low_open=True, unit="m")
    iu, iv = (i for i in range(3) if i != k)
    nu = max(2, math.ceil(L[iu] / resolution))
    nv = max(2, math.ceil(L[iv] / resolution))
    if nu * nv > 4_000_000:
        raise ValueError(
            f"resolution: {resolution:g} m gives {nu * nv:.3g} cells, more than 4e6; use a "
            "coarser resolution"
        )
    u = (np.arange(nu) + 0.5) * (L[iu] / nu)
    v = (np.arange(nv) + 0.5) * (L[iv] / nv)
    pts = np.empty((nu, nv, 3))
    pts[..., k] = value
    pts[..., iu] = u[:, None]
    pts[..., iv] = v[None, :]
    flat = pts.reshape(-1, 3)
    vals = _bound(room, anchors, flat, sigma, system=system)
    if not room.is_shoebox or room.obstacles:
        vals = np.where(room.contains(flat), vals, np.nan)
    return u, v, vals.reshape(nu, nv)


def peb_map(
    room: Room,
    anchors,
    *,
    sigma=DEFAULT_SIGMA,
    heights: Sequence[float] | None = None,
    x_cuts: Sequence[float] = (),
    y_cuts: Sequence[float] = (),
    resolution: float = 0.05,
    scale: str = "auto",
    vmax: float | None = None,
    anchor_color: str = ANCHOR_COLOR,
    title: str | None = None,
    ncols: int | None = None,
    figsize=None,
    dpi: float = 100,
    system=None,
) -> Figure:
    """PEB heat maps (m) on horizontal slices and vertical cuts, anchors marked (Figs. 1, 2, 6);
    the anchors each point hears with ``system`` (default the paper's) count.

    One panel per height z (x–y plane), per ``x_cuts`` value (y–z plane) and per ``y_cuts``
    value (x–z plane); default heights: the room's mid height. All panels share one colour
    scale spanning the finite PEB over every panel (``vmax`` clips it) and one colour bar
    "PEB (m)". Anchors are projected onto each panel as numbered squares (numbers = row
    in ``anchors``, from 1), and so are the room's keep-outs (hatched) and tag zones
    (dashed); grey cells are singular (PEB = ∞).
    """
    room = as_room(room)
    anchors = _as_points(anchors, "anchors")
    if heights is None:
        heights = () if (x_cuts or y_cuts) else (room.size[2] / 2,)
    planes = [(2, float(z)) for z in heights]
    planes += [(0, float(x)) for x in x_cuts] + [(1, float(y)) for y in y_cuts]
    if not planes:
        raise ValueError("heights/x_cuts/y_cuts: at least one plane is required")
    maps = [peb_plane(room, anchors, k, c, sigma, resolution, system) for k, c in planes]
    allvals = np.concatenate([m[2].ravel() for m in maps])
    allvals = allvals[~np.isnan(allvals)]  # outside the room
    norm, extend = _norm(allvals, scale, vmax=vmax)
    n = len(planes)
    ncols = ncols or (1 if n == 1 else 2 if n <= 4 else 3)
    nrows = math.ceil(n / ncols)
    if figsize is None:
        figsize = (5.2 * ncols + 1.2, 3.0 * nrows + 0.8) if n > 1 else (7.0, 4.2)
    fig = new_figure(figsize, dpi)
    axs = fig.subplots(nrows, ncols, squeeze=False).ravel()
    im = None
    for ax, (k, c), (_, _, vals) in zip(axs, planes, maps, strict=False):
        im = _peb_panel(ax, room, anchors, k, c, vals, norm, anchor_color)
    for ax in axs[n:]:
        ax.set_visible(False)
    _colorbar(fig, im, list(axs[:n]), "PEB (m)", extend, shrink=0.9)
    finite = allvals[np.isfinite(allvals)]
    if title is None:
        title = (
            f"PEB = √tr J⁻¹, σ = {_fmt_sigma(sigma)}, M = {len(anchors)} "
            "(anchors projected onto each plane)"
        )
        if finite.size < allvals.size:
            title += "   (grey: singular, PEB = ∞)"
    fig.suptitle(_fit(title, fig, 11), fontsize=11)
    return fig


def _fit(title: str, fig, fontsize: float) -> str:
    """``title`` broken into lines that fit the figure's width (a glyph about half the
    font size wide): a one-panel map is narrower than its title."""
    return textwrap.fill(title, max(20, int(fig.get_figwidth() * 72 / (0.55 * fontsize))))


def _peb_panel(ax, room: Room, anchors, k: int, c: float, vals, norm, anchor_color: str):
    """One panel of :func:`peb_map`: the PEB ``vals`` on the plane where axis ``k`` = ``c``,
    the room's regions and the numbered anchors; the image (for the colour bar)."""
    iu, iv = (i for i in range(3) if i != k)
    extent = (0.0, room.size[iu], 0.0, room.size[iv])
    im = ax.imshow(np.ma.masked_invalid(vals.T), origin="lower", extent=extent, cmap=_cmap(),
                   norm=norm, interpolation="nearest", aspect="equal")  # fmt: skip
    if np.isnan(vals).any():  # outside the room: white, not the singular grey
        rgba = np.zeros((*vals.T.shape, 4))
        rgba[np.isnan(vals.T)] = (1.0, 1.0, 1.0, 1.0)
        ax.imshow(rgba, origin="lower", extent=extent, interpolation="nearest",
                  aspect="equal", zorder=1.5)  # fmt: skip
    _draw_regions2d(ax, room, iu, iv, (k, c))
    # white edges: visible on the dark and the bright end of viridis
    _numbered_anchors2d(ax, anchors, iu, iv, anchor_color, edge="white")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel(f"{_AXES[iu]} (m)")
    ax.set_ylabel(f"{_AXES[iv]} (m)")
    ax.set_title(f"{_AXES[k]} = {c:.2f} m", fontsize=10, pad=14)
    return im


def coverage_map(
    room: Room,
    anchors,
    *,
    heights: Sequence[float] | None = None,
    resolution: float = 0.1,
    anchor_color: str = ANCHOR_COLOR,
    dpi: float = 100,
    system=None,
    k: int = 4,
) -> Figure:
    """Coverage: the number of anchors heard with ``system`` (default the paper's;
    :func:`analysis.coverage.coverage`; red hatching and the red line where fewer than
    ``k`` are heard: 4, no fix; 5, an echo cannot be found) on
    horizontal slices at ``heights`` (default: the room's mid height), one discrete colour
    per count; red hatching where fewer than 4 are heard (no position fix); anchors
    numbered as the rows of ``anchors`` (M, 3), keep-outs and tag zones as in
    :func:`peb_map`."""
    import matplotlib.colors as mcolors

    room = as_room(room)
    anchors = _as_points(anchors, "anchors")
    resolution = checks.real("resolution", resolution, low=0.0, low_open=True, unit="m")
    heights = (room.size[2] / 2,) if heights is None else tuple(float(z) for z in heights)
    if not heights:
        raise ValueError("heights: at least one height is required")
    L, M = room.size, len(anchors)
    nu, nv = (max(2, math.ceil(L[i] / resolution)) for i in (0, 1))
    if nu * nv * len(heights) * M > 50_000_000:
        raise ValueError(f"resolution: {resolution:g} m gives too many cells; use a coarser one")
    u = (np.arange(nu) + 0.5) * (L[0] / nu)
    v = (np.arange(nv) + 0.5) * (L[1] / nv)
    n = len(heights)
    ncols = 1 if n == 1 else 2 if n <= 4 else 3
    nrows = math.ceil(n / ncols)
    aspect = L[1] / L[0]  # panels as tall as the room is deep
    panel = (5.2, 5.2 * aspect + 1.2)
    fig = new_figure((panel[0] * ncols + 1.2, panel[1] * nrows + 0.8), dpi)
    axs = fig.subplots(nrows, ncols, squeeze=False).ravel()
    cmap = matplotlib.colormaps["viridis"].resampled(M + 1)
    norm = mcolors.BoundaryNorm(np.arange(-0.5, M + 1.5), M + 1)
    im = None
    short = 0.0
    for ax, z in zip(axs, heights, strict=False):
        pts = np.stack(np.meshgrid(u, v, [z], indexing="ij"), axis=-1).reshape(-1, 3)
        count = _coverage(room, anchors, pts, system=system).reshape(nu, nv)
        inside = room.contains(pts).reshape(nu, nv)
        short = max(short, float(np.mean(count[inside] < k)) if inside.any() else 0.0)
        extent = (0.0, L[0], 0.0, L[1])
        im = ax.imshow(count.T, origin="lower", extent=extent, cmap=cmap, norm=norm,
                       interpolation="nearest", aspect="equal")  # fmt: skip
        _blank_outside(ax, room, pts, (nu, nv), extent)
        low = (count < k) & inside
        if np.any(low):
            ax.contourf(u, v, low.T.astype(float), levels=[0.5, 1.5], colors="none",
                        hatches=["////"], zorder=1.8)  # fmt: skip
            ax.contour(u, v, low.T.astype(float), levels=[0.5], colors="red",
                       linewidths=1.0, zorder=1.8)  # fmt: skip
        _draw_regions2d(ax, room, 0, 1, (2, z))
        _numbered_anchors2d(ax, anchors, 0, 1, anchor_color, edge="white")
        ax.set_xlim(0, L[0])
        ax.set_ylim(0, L[1])
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(f"z = {z:.2f} m", fontsize=10, pad=14)
    for ax in axs[n:]:
        ax.set_visible(False)
    cb = fig.colorbar(im, ax=list(axs[:n]), shrink=0.9, ticks=range(M + 1))
    cb.set_label("anchors heard")
    note = f"; hatched: < {k} heard (≤ {100 * short:.1f} % of a slice)" if short else ""
    reach = as_system(system).reach(room.speed_of_sound)
    fig.suptitle(_fit(f"Anchors heard, M = {M}, reach {reach:.2f} m{note}", fig, 10), fontsize=10)
    return fig


def _numbered_anchors2d(ax, anchors, iu: int, iv: int, color, edge: str = "black") -> None:
    """Anchors projected onto the (iu, iv) plane as squares numbered 1…M (row order);
    anchors that the projection puts on one spot (three on one vertical line of a wall,
    seen from above) share one label, "2,3,4" (:func:`analysis.stacking.stacks`)."""
    ax.scatter(
        anchors[:, iu],
        anchors[:, iv],
        marker="s",
        s=46,
        c=color,
        edgecolors=edge,
        linewidths=1.0,
        zorder=3,
        gid="anchors",
        clip_on=False,
    )
    for stack in stacks(anchors[:, [iu, iv]]):
        ax.annotate(
            ",".join(str(j + 1) for j in stack),
            tuple(anchors[stack[0], [iu, iv]]),
            xytext=(5, 4),
            textcoords="offset points",
            fontsize=8,
            color="black",
            fontweight="bold",
            path_effects=_outline(),
            annotation_clip=False,
        )


#: a surface whose normal's component along the view is at most this is seen edge-on
EDGE_ON = 1e-6


def _draw_mounting2d(ax, room: Room, k: int) -> None:
    """The mounting surfaces seen along axis ``k``: a surface seen edge-on (the view
    along it) as a thick line along its trace (for a shoebox's walls, its plane), any other
    (parallel to the view, or oblique: a slanted wall of a floor plan seen from the south)
    as its shaded allowed region projected onto the view."""
    from matplotlib.patches import Polygon as MPolygon
    from matplotlib.patches import Rectangle

    from simulation.mounting import mounting_surfaces, regions

    iu, iv = (i for i in range(3) if i != k)
    L, o = room.size, room.anchor_offset
    if room.is_shoebox and not room.obstacles:  # the planes themselves, as always
        for name in room.mounting:
            axis, side = SURFACES[name]
            if axis == k:
                ax.add_patch(Rectangle((o, o), L[iu] - 2 * o, L[iv] - 2 * o,
                                       facecolor=(0.85, 0.88, 0.93), edgecolor="none",
                                       zorder=0.5, gid="mounting"))  # fmt: skip
                continue
            at = side * L[axis]
            if axis == iu:
                ax.plot([at, at], [0, L[iv]], color="0.35", lw=4, zorder=1, gid="mounting")
            else:
                ax.plot([0, L[iu]], [at, at], color="0.35", lw=4, zorder=1, gid="mounting")
        return
    lo, hi, idx = regions(room)[1]
    for i, s in enumerate(mounting_surfaces(room)):
        if abs(s.normal[k]) > EDGE_ON:  # not seen edge-on: its allowed rectangles
            for a, b in zip(lo[idx == i], hi[idx == i], strict=True):
                quad = s.point(np.array([a, [b[0], a[1]], b, [a[0], b[1]]]))[:, [iu, iv]]
                ax.add_patch(MPolygon(quad, closed=True, facecolor=(0.85, 0.88, 0.93),
                                      edgecolor="none", zorder=0.5, gid="mounting"))  # fmt: skip
            continue
        quad = s.point(np.array([s.lower, [s.upper[0], s.lower[1]], s.upper,
                                 [s.lower[0], s.upper[1]]]))[:, [iu, iv]]  # fmt: skip
        gap = np.linalg.norm(quad[:, None] - quad[None], axis=-1)
        ends = quad[list(np.unravel_index(np.argmax(gap), gap.shape))]  # seen edge-on
        ax.plot(ends[:, 0], ends[:, 1], color="0.35", lw=4, zorder=1, gid="mounting")


def plan_view(
    room: Room,
    anchors,
    *,
    color: str = ANCHOR_COLOR,
    title: str | None = None,
    figsize=None,
    dpi: float = 100,
) -> Figure:
    """The layout in two views: the plan (from above, x–y) and the elevation (from the
    south, x–z), anchors as squares numbered as the rows of ``anchors`` (M, 3) in metres.

    Mounting surfaces are drawn shaded (parallel to the view) or as thick grey lines (seen
    edge-on); keep-outs hatched, tag zones dashed, as in :func:`peb_map`.
    """
    from matplotlib.patches import Rectangle

    room = as_room(room)
    anchors = _as_points(anchors, "anchors")
    L = room.size
    fig = new_figure(figsize or (10.0, 3.6), dpi)
    # room between the titles: at some proportions of a room (its depth about 0.6 of its
    # width) the constrained layout of the equal-aspect plan left the plan's title on the
    # figure's
    fig.get_layout_engine().set(h_pad=0.1)
    views = ((2, "plan (from above)"), (1, "elevation (from the south)"))
    for ax, (k, label) in zip(fig.subplots(1, 2).ravel(), views, strict=True):
        iu, iv = (i for i in range(3) if i != k)
        ax.add_patch(Rectangle((0, 0), L[iu], L[iv], fill=False, edgecolor="black", lw=1.0))
        _draw_mounting2d(ax, room, k)
        _draw_regions2d(ax, room, iu, iv)
        _numbered_anchors2d(ax, anchors, iu, iv, color)
        ax.set_xlim(-0.02 * L[iu], 1.02 * L[iu])
        ax.set_ylim(-0.04 * L[iv], 1.04 * L[iv])
        ax.set_aspect("equal")
        ax.set_xlabel(f"{_AXES[iu]} (m)")
        ax.set_ylabel(f"{_AXES[iv]} (m)")
        ax.set_title(label, fontsize=10, pad=10)
    if title is None:
        title = f"Layout, M = {len(anchors)} (shaded, thick grey: the mounting surfaces)"
    fig.suptitle(title, fontsize=11)
    return fig


def _fmt_sigma(sigma) -> str:
    s = np.asarray(sigma, dtype=float)
    if s.size == 1:
        return f"{float(s):g} m"
    return f"{float(np.min(s)):.3g}–{float(np.max(s)):.3g} m"


def _outline():
    from matplotlib import patheffects

    return [patheffects.withStroke(linewidth=2.2, foreground="white")]


# -- 3D views -----------------------------------------------------------------------------------
def _box_corners(lo, hi) -> np.ndarray:
    """(8, 3) corners of a box, index bits (x, y, z) as in :func:`_room_box`."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i, j, k in _BITS])


_BITS = [(i, j, k) for i in (0, 1) for j in (0, 1) for k in (0, 1)]
#: the 12 edges (corner pairs differing in one bit) and 6 faces (cyclic corners) of a box
_EDGES = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
_FACES = [[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4], [2, 3, 7, 6], [0, 2, 6, 4], [1, 3, 7, 5]]


def _draw_regions3d(ax, room: Room) -> None:
    """Keep-outs as grey boxes and tag zones as dashed wire boxes."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    if room.keepouts:
        faces = [c[f] for lo, hi in room.keepouts for c in [_box_corners(lo, hi)] for f in _FACES]
        ax.add_collection3d(
            Poly3DCollection(
                faces,
                facecolors="0.45",
                alpha=0.35,
                edgecolors=KEEPOUT_COLOR,
                linewidths=0.4,
                gid="keepouts",
            )
        )
    if room.zones:
        edges = [
            (c[a], c[b]) for lo, hi in room.zones for c in [_box_corners(lo, hi)] for a, b in _EDGES
        ]
        ax.add_collection3d(
            Line3DCollection(edges, colors=ZONE_COLOR, linewidths=0.7, linestyles="--", gid="zones")
        )


def _room_box(ax, room: Room, zoom: float = 1.0) -> None:
    """Room edges, the allowed mounting surfaces lightly shaded, keep-outs and tag zones,
    equal-metre axes."""
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    L = np.asarray(room.size, dtype=float)
    c = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float) * L
    faces = []
    if room.is_shoebox:
        edges = [
            (c[a], c[b])
            for a in range(8)
            for b in range(a + 1, 8)
            if np.count_nonzero(c[a] != c[b]) == 1
        ]
        for name in room.mounting:
            axis, side = SURFACES[name]
            face = c[c[:, axis] == side * L[axis]]
            faces.append(face[[0, 1, 3, 2]])  # corners in cyclic order
    else:  # the floor plan's outline at the floor and the ceiling, and its vertical edges
        fc = room.floor_corners
        low = np.column_stack([fc, np.zeros(len(fc))])
        high = np.column_stack([fc, np.full(len(fc), L[2])])
        ring = list(range(len(fc))) + [0]
        edges = [(low[a], low[b]) for a, b in zip(ring[:-1], ring[1:], strict=True)]
        edges += [(high[a], high[b]) for a, b in zip(ring[:-1], ring[1:], strict=True)]
        edges += [(low[a], high[a]) for a in range(len(fc))]
        for s in _mounting_surfaces(room):
            faces.append(s.point(np.array([s.lower, [s.upper[0], s.lower[1]], s.upper,
                                           [s.lower[0], s.upper[1]]])))  # fmt: skip
    for ob in room.obstacles:
        b = _box_corners(ob.lo, ob.hi)
        edges += [(b[a], b[k]) for a, k in _EDGES]
    ax.add_collection3d(Line3DCollection(edges, colors="0.45", linewidths=0.7, gid="room"))
    ax.add_collection3d(
        Poly3DCollection(faces, facecolors="0.5", alpha=0.07, edgecolors="none", gid="mounting")
    )
    _draw_regions3d(ax, room)
    ax.set_xlim(0, L[0])
    ax.set_ylim(0, L[1])
    ax.set_zlim(0, L[2])
    ax.set_box_aspect(L, zoom=zoom)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(nbins=4, steps=[1, 2, 5, 10]))
    ax.set_xlabel("x (m)", labelpad=0, fontsize=9)
    ax.set_ylabel("y (m)", labelpad=0, fontsize=9)
    ax.set_zlabel("z (m)", labelpad=-2, fontsize=9)
    ax.tick_params(labelsize=7, pad=-1)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):  # blank panes: only mounting surfaces shaded
        axis.set_pane_color((1.0, 1.0, 1.0, 0.0))
        axis._axinfo["grid"]["color"] = (0.8, 0.8, 0.8, 0.6)
    ax.view_init(elev=24, azim=-58)


def _draw_anchors3d(
    ax, room: Room, anchors, color, aim: bool, label=None, numbers: bool = True
) -> None:
    ax.scatter(
        anchors[:, 0],
        anchors[:, 1],
        anchors[:, 2],
        marker="s",
        s=42,
        c=color,
        edgecolors="black",
        linewidths=0.7,
        depthshade=False,
        gid="anchors",
        label=label,
    )
    if aim:
        u = aim_vectors(anchors, room.centroid)
        length = 0.12 * max(room.size)
        ax.quiver(
            anchors[:, 0],
            anchors[:, 1],
            anchors[:, 2],
            u[:, 0],
            u[:, 1],
            u[:, 2],
            length=length,
            color=color,
            linewidths=1.3,
            arrow_length_ratio=0.3,
            gid="aim",
        )
    if numbers:  # rows of the layout table, from 1
        for j, a in enumerate(anchors):
            ax.text(a[0], a[1], a[2] + 0.04 * room.size[2], f" {j + 1}", fontsize=7, zorder=5)


def _draw_nodes3d(ax, nodes, values, norm, cmap):
    ok = np.isfinite(values)
    sc = ax.scatter(
        nodes[ok, 0],
        nodes[ok, 1],
        nodes[ok, 2],
        c=values[ok],
        cmap=cmap,
        norm=norm,
        s=14,
        depthshade=False,
        gid="nodes",
    )
    if not np.all(ok):
        ax.scatter(
            nodes[~ok, 0],
            nodes[~ok, 1],
            nodes[~ok, 2],
            marker="x",
            c=BAD_COLOR,
            s=14,
            depthshade=False,
            gid="nodes-invalid",
        )
    return sc


def scatter3d(
    room: Room,
    nodes,
    values,
    anchors=None,
    *,
    label: str = "PEB (m)",
    title: str | None = None,
    scale: str = "auto",
    vmin: float | None = None,
    vmax: float | None = None,
    aim: bool = True,
    anchor_color: str = ANCHOR_COLOR,
    cmap: str = CMAP,
    figsize=(7.0, 4.2),
    dpi: float = 100,
) -> Figure:
    """3D scatter of the nodes (P, 3) coloured by ``values`` (P,), anchors and aim vectors.

    ``values`` is PEB (m) or a simulated error (e.g. the per-node RMSE, m): pass the
    colour-bar ``label`` with its unit. Non-finite values are grey crosses. Anchors
    (M, 3) are squares with an arrow along their aim (toward the room centroid) — paper
    Figs. 1, 2 and 6.
    """
    nodes = _as_points(nodes, "nodes")
    values = _values(values, "values", len(nodes))
    norm, extend = _norm(values, scale, vmin, vmax)
    fig = new_figure(figsize, dpi)
    ax = fig.add_subplot(projection="3d")
    _room_box(ax, room)
    sc = _draw_nodes3d(ax, nodes, values, norm, _cmap(cmap))
    if anchors is not None:
        _draw_anchors3d(ax, room, _as_points(anchors, "anchors"), anchor_color, aim)
    _colorbar(fig, sc, ax, label, extend, shrink=0.7, pad=0.12)
    if title:
        ax.set_title(title, fontsize=11)
    return fig


def scatter3d_panels(
    room: Room,
    nodes,
    values: Mapping[str, np.ndarray],
    anchors: Mapping[str, np.ndarray] | None = None,
    *,
    label: str = "PEB (m)",
    colors: Mapping[str, str] | None = None,
    scale: str = "auto",
    vmin: float | None = None,
    vmax: float | None = None,
    aim: bool = True,
    ncols: int | None = None,
    figsize=None,
    dpi: float = 100,
) -> Figure:
    """Side-by-side 3D scatters of the nodes, one per layout, on one shared colour scale.

    ``values`` maps a layout name to (P,) values (PEB or a simulated error, m) and
    ``anchors`` a name to its anchors (M, 3), drawn in the layout's colour (paper Figs. 1
    and 2: the errors of the corners and the optimized layout). The colour bar spans the
    finite values of every panel (or ``vmin``/``vmax``); titles give each panel's mean.
    """
    if not values:
        raise ValueError("values: at least one layout is required")
    nodes = _as_points(nodes, "nodes")
    names = list(values)
    vals = {k: _values(v, f"values[{k!r}]", len(nodes)) for k, v in values.items()}
    col = _colors_for(names, colors)
    norm, extend = _norm(np.concatenate(list(vals.values())), scale, vmin, vmax)
    n = len(names)
    ncols = ncols or min(n, 2)
    nrows = math.ceil(n / ncols)
    figsize = figsize or (5.0 * ncols + 1.0, 3.4 * nrows + 0.3)
    fig = new_figure(figsize, dpi)
    axs = []
    sc = None
    unit = label[label.rfind("(") :] if "(" in label else ""
    for i, name in enumerate(names):
        ax = fig.add_subplot(nrows, ncols, i + 1, projection="3d")
        _room_box(ax, room)
        sc = _draw_nodes3d(ax, nodes, vals[name], norm, _cmap())
        if anchors is not None and name in anchors:
            _draw_anchors3d(ax, room, _as_points(anchors[name], "anchors"), col[name], aim)
        fin = vals[name][np.isfinite(vals[name])]
        mean = f"mean {fin.mean():.3g} {unit.strip('()')}" if fin.size else "no finite value"
        ax.set_title(f"{name}: {mean}", fontsize=10, y=0.95)
        axs.append(ax)
    _colorbar(fig, sc, axs, label, extend, shrink=0.7)
    return fig


def layout_views(
    room: Room,
    layouts: Mapping[str, np.ndarray],
    *,
    colors: Mapping[str, str] | None = None,
    aim: bool = True,
    ncols: int | None = None,
    figsize=None,
    dpi: float = 100,
) -> Figure:
    """Side-by-side 3D views of several layouts (e.g. M = 4, 6, 8, 10 — paper Fig. 7).

    ``layouts`` maps a name to anchors (M, 3); each panel shows the room box, the anchors
    in the layout's colour with their aim vectors, titled "name (M = …)".
    """
    if not layouts:
        raise ValueError("layouts: at least one layout is required")
    names = list(layouts)
    col = _colors_for(names, colors)
    n = len(names)
    ncols = ncols or min(n, 3 if n != 4 else 2)
    nrows = math.ceil(n / ncols)
    figsize = figsize or (4.2 * ncols, 2.9 * nrows + 0.2)
    fig = new_figure(figsize, dpi)
    for i, name in enumerate(names):
        a = _as_points(layouts[name], f"layouts[{name!r}]")
        ax = fig.add_subplot(nrows, ncols, i + 1, projection="3d")
        _room_box(ax, room, zoom=0.92)
        _draw_anchors3d(ax, room, a, col[name], aim)
        m = len(a)
        has_m = f"M={m}" in name.replace(" ", "")
        ax.set_title(name if has_m else f"{name} (M = {m})", fontsize=10, y=0.95)
    return fig


# -- CDFs ---------------------------------------------------------------------------------------
def _cdf_xy(values) -> tuple[np.ndarray, np.ndarray]:
    """:func:`analysis.statistics.ecdf` (failures keep F < 1), reduced to at most
    ``_MAX_CDF_POINTS`` points (evenly spaced ranks, last one kept)."""
    x, f = ecdf(values)
    if x.size > _MAX_CDF_POINTS:
        idx = np.unique(np.linspace(0, x.size - 1, _MAX_CDF_POINTS).round().astype(int))
        x, f = x[idx], f[idx]
    return x, f


def _cdf_axes_style(ax, xscale: str, xlabel: str) -> None:
    ax.axhline(0.95, color="0.6", lw=0.8, ls=":", gid="p95")
    ax.set_xscale(xscale)
    if xscale == "log":  # minor ticks over many decades cost seconds of layout, add nothing
        from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator

        ax.xaxis.set_major_locator(LogLocator(numticks=8))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_locator(NullLocator())
    ax.set_ylim(0, 1.01)
    ax.set_xlabel(xlabel)
    ax.grid(True, which="major", alpha=0.3)


def error_cdfs(
    errors: Mapping[str, np.ndarray],
    axis_errors: Mapping[str, np.ndarray] | None = None,
    *,
    colors: Mapping[str, str] | None = None,
    xscale: str = "log",
    title: str | None = None,
    figsize=None,
    dpi: float = 100,
) -> Figure:
    """CDFs of the Euclidean error and, if given, of |x|, |y|, |z| errors (paper Fig. 3).

    ``errors`` maps a layout name to Euclidean errors (any shape, m, e.g. (R, P));
    ``axis_errors`` maps names to per-axis errors (..., 3) (signed or absolute, m). One
    line per layout in each panel, with the layout's P95 in the legend; non-finite errors
    (failed fixes) count in the denominator, so such a curve stays below 1.
    """
    if not errors:
        raise ValueError("errors: at least one layout is required")
    names = list(errors)
    col = _colors_for(names, colors)
    panels = [("Euclidean", {k: np.asarray(v, float) for k, v in errors.items()})]
    if axis_errors:
        for i, ax_name in enumerate(_AXES):
            d = {}
            for k, v in axis_errors.items():
                v = np.asarray(v, dtype=float)
                if v.shape[-1] != 3:
                    raise ValueError(f"axis_errors[{k!r}]: last axis must be 3, got {v.shape}")
                d[k] = np.abs(v[..., i])
            panels.append((f"|{ax_name} error|", d))
    n = len(panels)
    ncols = 1 if n == 1 else 2
    nrows = math.ceil(n / ncols)
    figsize = figsize or ((6.4, 4.2) if n == 1 else (10.0, 3.3 * nrows + 0.5))
    fig = new_figure(figsize, dpi)
    axs = fig.subplots(nrows, ncols, squeeze=False, sharey=True).ravel()
    for ax, (pname, data) in zip(axs, panels, strict=False):
        for name, v in data.items():
            x, f = _cdf_xy(v)
            ax.plot(
                x,
                f,
                color=col.get(name, "black"),
                lw=1.6,
                drawstyle="steps-post",
                gid=f"cdf:{name}",
                label=f"{name}  (P95 {error_stats(v)['p95']:.3g} m)",
            )
        _cdf_axes_style(ax, xscale, f"{pname} (m)")
        if xscale == "log":  # start at the 0.5 % quantile: tiny errors carry no information
            pooled = np.concatenate([np.ravel(v) for v in data.values()])
            pooled = pooled[np.isfinite(pooled) & (pooled > 0)]
            if pooled.size:
                ax.set_xlim(left=float(np.percentile(pooled, 0.5)))
        ax.set_title(pname, fontsize=10)
        ax.legend(fontsize=7.5, loc="upper left", frameon=True)
    for ax in axs[::ncols]:
        ax.set_ylabel("CDF")
    for ax in axs[n:]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title, fontsize=11)
    return fig


def bound_gap_cdfs(
    peb: Mapping[str, np.ndarray],
    rmse: Mapping[str, np.ndarray],
    *,
    colors: Mapping[str, str] | None = None,
    xscale: str = "log",
    title: str | None = "Bound vs simulation: CDF over nodes of PEB and simulated RMSE",
    figsize=(7.0, 4.4),
    dpi: float = 100,
) -> Figure:
    """CDFs over nodes of the PEB (dashed) and the simulated per-node RMSE (solid) (Figs. 5, 8).

    ``peb`` and ``rmse`` map layout names to (P,) arrays in metres (the same nodes). The
    horizontal distance between a layout's two curves is the bound-versus-reality gap;
    the legend gives the median ratio RMSE/PEB. A layout present in only one mapping gets
    only that curve.
    """
    names = list(dict.fromkeys([*peb, *rmse]))
    if not names:
        raise ValueError("peb/rmse: at least one layout is required")
    col = _colors_for(names, colors)
    fig = new_figure(figsize, dpi)
    ax = fig.add_subplot()
    for name in names:
        c = col[name]
        label = name
        if name in peb and name in rmse:
            p = np.asarray(peb[name], float).ravel()
            r = np.asarray(rmse[name], float).ravel()
            if p.size == r.size:
                ok = np.isfinite(p) & np.isfinite(r) & (p > 0)
                if np.any(ok):
                    label += f"  (median RMSE/PEB {np.median(r[ok] / p[ok]):.3g})"
        if name in rmse:
            x, f = _cdf_xy(rmse[name])
            ax.plot(x, f, color=c, lw=1.7, drawstyle="steps-post", gid=f"rmse:{name}")
        if name in peb:
            x, f = _cdf_xy(peb[name])
            ax.plot(x, f, color=c, lw=1.5, ls="--", drawstyle="steps-post", gid=f"peb:{name}")
        ax.plot([], [], color=c, lw=4, label=label)  # legend swatch (no data)
    _cdf_axes_style(ax, xscale, "per-node error (m)")
    ax.set_ylabel("CDF over nodes")
    style = [
        Line2D([], [], color="black", lw=1.7, label="simulated RMSE"),
        Line2D([], [], color="black", lw=1.5, ls="--", label="PEB (√tr J⁻¹)"),
    ]
    leg1 = ax.legend(handles=style, loc="lower right", fontsize=8)
    ax.add_artist(leg1)
    ax.legend(loc="upper left", fontsize=8)
    if title:
        ax.set_title(title, fontsize=10)
    return fig


# -- DOP difference ---------------------------------------------------------------------------
def _grid_layers(nodes: np.ndarray):
    """(xs, ys, zs, index) if the nodes form a full regular grid, else None.

    ``index`` (nx, ny, nz) gives the node row at each grid position.
    """
    axes = [np.unique(np.round(nodes[:, k], 9)) for k in range(3)]
    if int(np.prod([a.size for a in axes])) != len(nodes):
        return None
    ijk = [np.searchsorted(axes[k], np.round(nodes[:, k], 9)) for k in range(3)]
    index = np.full([a.size for a in axes], -1)
    index[ijk[0], ijk[1], ijk[2]] = np.arange(len(nodes))
    if np.any(index < 0):
        return None
    return (*axes, index)


def _cell_edges(c: np.ndarray, lo: float, hi: float) -> np.ndarray:
    if c.size == 1:
        return np.array([lo, hi])
    mid = (c[1:] + c[:-1]) / 2
    return np.concatenate([[max(lo, 2 * c[0] - mid[0])], mid, [min(hi, 2 * c[-1] - mid[-1])]])


#: the DOP definitions :func:`dop_difference` can label: symbol and formula
DOP_DEFINITIONS: dict[str, tuple[str, str]] = {
    "paper": ("DOP", "the paper's DOP = σ/σ_r"),
    "rms": ("DOP_RMS", "RMS-based DOP = RMSE/σ_r"),
    "precision": ("DOP_prec", "precision DOP = spread of p̂/σ_r"),
}


def _dop_scale(diff: np.ndarray, vlim: float | None):
    """(norm, limit, colour-bar extend) of the symmetric diverging DOP-difference scale."""
    finite = diff[np.isfinite(diff)]
    lim = float(np.max(np.abs(finite))) if finite.size else 1.0
    extend = "neither"
    if vlim is not None:
        if not (math.isfinite(vlim) and vlim > 0):
            raise ValueError(f"vlim: must be > 0, got {vlim}")
        extend = "both" if lim > vlim else "neither"
        lim = float(vlim)
    elif finite.size:
        p95 = float(np.percentile(np.abs(finite), 95))
        if p95 > 0 and lim > 3 * p95:
            lim, extend = p95, "both"
    lim = lim if lim > 0 else 1.0
    return TwoSlopeNorm(0.0, -lim, lim), lim, extend


def _anchor_marks2d(ax, marks, col) -> None:
    for name, anc in marks:
        if anc is None:
            continue
        anc = _as_points(anc, "anchors")
        ax.scatter(
            anc[:, 0],
            anc[:, 1],
            marker="s",
            s=30,
            c=col[name],
            edgecolors="black",
            linewidths=0.6,
            zorder=3,
            clip_on=False,
            gid="anchors",
        )


def _dop_layers(room, diff, grid, norm, cmap, marks, col, figsize, dpi, cb_label, extend):
    """One x–y panel of the difference per node height (nodes on a full regular grid)."""
    xs, ys, zs, index = grid
    nz = zs.size
    ncols = 1 if nz == 1 else 2 if nz <= 4 else 3
    nrows = math.ceil(nz / ncols)
    fig = new_figure(figsize or (4.6 * ncols + 1.0, 2.6 * nrows + 0.9), dpi)
    fig.get_layout_engine().set(wspace=0.06)
    axs = fig.subplots(nrows, ncols, squeeze=False, sharex=True, sharey=True).ravel()
    xe = _cell_edges(xs, 0.0, room.size[0])
    ye = _cell_edges(ys, 0.0, room.size[1])
    mesh = None
    for iz, ax in enumerate(axs[:nz]):
        layer = diff[index[:, :, iz]]
        mesh = ax.pcolormesh(xe, ye, np.ma.masked_invalid(layer.T), cmap=cmap, norm=norm, gid="dop")
        _draw_regions2d(ax, room, 0, 1, (2, zs[iz]))
        _anchor_marks2d(ax, marks, col)
        ax.set_xlim(0, room.size[0])
        ax.set_ylim(0, room.size[1])
        ax.set_aspect("equal")
        ax.set_title(f"nodes at z = {zs[iz]:.2f} m", fontsize=9)
        # outer labels only (fewer texts: faster layout, less clutter)
        last_in_column = iz + ncols >= nz
        ax.set_xlabel("x (m)" if last_in_column else "")
        ax.tick_params(labelbottom=last_in_column)
        ax.set_ylabel("y (m)" if iz % ncols == 0 else "")
        ax.tick_params(labelleft=iz % ncols == 0)
    for ax in axs[nz:]:
        ax.set_visible(False)
    _colorbar(fig, mesh, list(axs[:nz]), cb_label, extend, shrink=0.9)
    handles = [
        Line2D([], [], marker="s", ls="", color=col[n_], mec="black", label=f"anchors {n_}")
        for n_, anc in marks
        if anc is not None
    ]
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=8)
    return fig


def _dop_scatter3d(room, nodes, diff, norm, cmap, marks, col, figsize, dpi, cb_label, extend):
    """The difference on a 3D scatter of the nodes (any node set)."""
    fig = new_figure(figsize or (7.0, 4.6), dpi)
    ax = fig.add_subplot(projection="3d")
    _room_box(ax, room)
    sc = _draw_nodes3d(ax, nodes, diff, norm, cmap)
    for name, anc in marks:
        if anc is not None:
            _draw_anchors3d(ax, room, _as_points(anc, "anchors"), col[name], aim=False)
    _colorbar(fig, sc, ax, cb_label, extend, shrink=0.7, pad=0.12)
    return fig


def dop_difference(
    room: Room,
    nodes,
    dop_a,
    dop_b,
    *,
    labels: tuple[str, str] = ("initial", "optimized"),
    anchors_a=None,
    anchors_b=None,
    colors: Mapping[str, str] | None = None,
    kind: str = "auto",
    vlim: float | None = None,
    definition: str = "paper",
    figsize=None,
    dpi: float = 100,
) -> Figure:
    """Per-node DOP difference DOP_a − DOP_b (dimensionless, paper Fig. 4).

    ``definition`` names the DOP given, for the labels (:data:`DOP_DEFINITIONS`):
    "paper" (default, σ^p/σ_r^p with σ^p the standard deviation of the error,
    :func:`simulation.statistics.dop`), "rms" (RMSE^p/σ_r^p,
    :func:`simulation.statistics.dop_rms`) or "precision".
    Positive (blue) = layout b has the lower DOP there (improvement from a to b); the
    diverging colour scale is symmetric, ±max |difference|, or ±``vlim``; by default a
    heavy tail (max |difference| > 3 × its P95) is clipped at ±P95 with arrows on the
    colour bar, so that a few extreme nodes do not wash out the map. ``kind`` "layers" draws one
    x–y panel per node height (needs a full regular grid such as ``room.grid()``),
    "scatter3d" a 3D scatter, "auto" picks layers when possible. Anchors of either layout,
    if given, are marked in their layout colours (projected in the layers view).
    """
    nodes = _as_points(nodes, "nodes")
    a = _values(dop_a, "dop_a", len(nodes))
    b = _values(dop_b, "dop_b", len(nodes))
    sym, formula = DOP_DEFINITIONS[checks.choice("definition", definition, DOP_DEFINITIONS)]
    if kind not in ("auto", "layers", "scatter3d"):
        raise ValueError(f"kind: must be 'auto', 'layers' or 'scatter3d', got {kind!r}")
    with np.errstate(invalid="ignore"):  # inf − inf (σ_r = 0 in both) → NaN, drawn grey
        diff = a - b
    norm, lim, extend = _dop_scale(diff, vlim)
    grid = _grid_layers(nodes) if kind in ("auto", "layers") else None
    if kind == "layers" and grid is None:
        raise ValueError("kind: 'layers' needs nodes on a full regular grid; use 'scatter3d'")
    la, lb = labels
    col = _colors_for(list(labels), colors)
    marks = [(la, anchors_a), (lb, anchors_b)]
    ma, mb = np.mean(a[np.isfinite(a)]), np.mean(b[np.isfinite(b)])
    title = f"{sym}({la}) − {sym}({lb}), {formula};  mean {sym} {la} {ma:.3g} → {lb} {mb:.3g}"
    if extend == "both" and vlim is None:
        title += f"\n(colour scale clipped at ±{lim:.3g}, the P95 of |difference|)"
    cb_label = f"{sym} {la} − {sym} {lb}  (> 0: {lb} better)"
    common = (norm, _cmap("RdBu"), marks, col, figsize, dpi, cb_label, extend)
    if grid is not None:
        fig = _dop_layers(room, diff, grid, *common)
    else:
        fig = _dop_scatter3d(room, nodes, diff, *common)
    fig.suptitle(title, fontsize=10)
    return fig


# -- PSO evolution ------------------------------------------------------------------------------
def pso_history(
    history,
    *,
    cost_name: str = "cost",
    unit: str = "",
    marks: Sequence[int] = (),
    ax=None,
    figsize=(6.4, 3.6),
    dpi: float = 100,
) -> Figure:
    """Best cost per PSO iteration (iterations numbered from 1); ``marks`` are highlighted.

    ``unit`` is appended to the axis label (e.g. "m²" for the error variance).
    """
    h = np.asarray(history, dtype=float).ravel()
    if h.size == 0:
        raise ValueError("history: at least one iteration is required")
    if ax is None:
        fig = new_figure(figsize, dpi)
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    it = np.arange(1, h.size + 1)
    ax.plot(it, h, color="#0072B2", lw=1.6, marker="o", ms=3, gid="history")
    marks = [int(m) for m in marks if 1 <= int(m) <= h.size]
    if marks:
        m = np.asarray(marks)
        ax.plot(m, h[m - 1], ls="", marker="o", ms=8, mfc="none", mec="#D55E00", mew=1.6)
        for t in marks:
            right = t > 0.85 * h.size  # keep the label inside the axes near the right edge
            ax.annotate(
                f"t={t}",
                (t, h[t - 1]),
                xytext=(-5 if right else 5, 6),
                textcoords="offset points",
                ha="right" if right else "left",
                size=8,
            )
    pos = h[np.isfinite(h)]
    if pos.size and pos.min() > 0 and pos.max() / pos.min() > 20:
        ax.set_yscale("log")
    ax.margins(x=0.03, y=0.15)
    ax.set_xlabel("iteration")
    ax.set_ylabel(f"best {cost_name}" + (f" ({unit})" if unit else ""))
    ax.grid(True, alpha=0.3)
    return fig


def pso_evolution(
    room: Room,
    history,
    best_anchors_history,
    *,
    iterations: Sequence[int] | None = None,
    sigma=DEFAULT_SIGMA,
    nodes=None,
    cost_name: str = "cost",
    unit: str = "",
    scale: str = "auto",
    anchor_color: str = ANCHOR_COLOR,
    figsize=None,
    dpi: float = 100,
) -> Figure:
    """PSO evolution: best cost per iteration and the PEB of the best layout at chosen
    iterations (paper Fig. 6).

    ``history`` (T,) best cost per iteration; ``best_anchors_history`` (T, M, 3) the best
    layout after each iteration; ``iterations`` are 1-based (default: first, middle,
    last). The PEB panels (nodes default to ``room.grid()``) share one colour scale
    "PEB (m)" spanning their finite values.
    """
    h = np.asarray(history, dtype=float).ravel()
    A = np.asarray(best_anchors_history, dtype=float)
    if A.ndim != 3 or A.shape[-1] != 3 or len(A) == 0:
        raise ValueError(f"best_anchors_history: expected shape (T, M, 3), got {A.shape}")
    T = len(A)
    if iterations is None:
        iterations = sorted({1, (T + 1) // 2, T})
    iterations = [int(t) for t in iterations]
    bad = [t for t in iterations if not 1 <= t <= T]
    if bad:
        raise ValueError(f"iterations: must be in [1, {T}] (1-based), got {bad}")
    nodes = room.grid() if nodes is None else _as_points(nodes, "nodes")
    vals = [_peb(A[t - 1], nodes, sigma=sigma) for t in iterations]
    norm, extend = _norm(np.concatenate(vals), scale)
    k = len(iterations)
    figsize = figsize or (max(9.0, 4.2 * k), 5.4)
    fig = new_figure(figsize, dpi)
    top, bottom = fig.subfigures(2, 1, height_ratios=[1.0, 1.6])
    pso_history(h, cost_name=cost_name, unit=unit, marks=iterations, ax=top.add_subplot())
    axs = [bottom.add_subplot(1, k, i + 1, projection="3d") for i in range(k)]
    sc = None
    for ax, t, v in zip(axs, iterations, vals, strict=True):
        _room_box(ax, room, zoom=0.95)
        sc = _draw_nodes3d(ax, nodes, v, norm, _cmap())
        _draw_anchors3d(ax, room, A[t - 1], anchor_color, aim=True)
        fin = v[np.isfinite(v)]
        sub = f"mean PEB {fin.mean():.3g} m" if fin.size else "singular"
        ax.set_title(f"t = {t}: {sub}", fontsize=9, y=0.95)
    _colorbar(bottom, sc, axs, "PEB (m)", extend, shrink=0.75)
    return fig


def sweep_curves(
    rows: Sequence[Mapping],
    target_p95: float | None = None,
    paper: Mapping[int, Mapping[str, float]] | None = None,
    dpi: float = 100,
    target_coverage: float | None = None,
) -> Figure:
    """σ, mean and P95 (m) of the validated error against the anchor count M, from rows
    with keys ``M``, ``std``, ``mean``, ``p95`` (at the evaluation nodes, solid) and, when
    the rows have them, ``field_std``, ``field_mean``, ``field_p95``, ``field_median`` (the
    field check, dashed); the target P95 as a horizontal line and reference points (e.g. the
    paper's Table I: {M: {"std", "mean", "p95"}}) as hollow markers. Rows with ``covered``
    (the share of the nodes seeing ``coverage_k`` anchors in line of sight and reach) add
    it in % on a right-hand axis, with ``target_coverage`` (a share) as a dotted line."""
    fig = new_figure((6.4, 4.8), dpi=dpi)
    ax = fig.add_subplot()
    M = np.array([r["M"] for r in rows], dtype=int)
    styles = (("std", "σ", "o", PALETTE[0]), ("mean", "mean", "s", PALETTE[1]),
              ("p95", "P95", "^", PALETTE[2]), ("median", "median", "D", PALETTE[3]))  # fmt: skip
    for key, label, marker, color in styles:
        y = np.array([r.get(key) for r in rows], dtype=float)  # None: NaN
        field = np.array([r.get(f"field_{key}") for r in rows], dtype=float)
        if np.isfinite(field).any():  # first: what an installation delivers
            ax.plot(M, field, marker=marker, color=color, linestyle="--",
                    label=f"field {label}")  # fmt: skip
            label = f"{label}, evaluation nodes"
        if np.isfinite(y).any():
            ax.plot(M, y, marker=marker, color=color, label=label)
        if paper:
            pm = sorted(m for m in paper if key in paper[m])
            ax.plot(pm, [paper[m][key] for m in pm], linestyle="none", marker=marker,
                    markerfacecolor="none", color=color, markersize=9)  # fmt: skip
    if target_p95 is not None:
        ax.axhline(target_p95, color="black", linestyle="--", linewidth=1)
        ax.annotate(f"target P95 {target_p95:g} m", (M.min(), target_p95),
                    textcoords="offset points", xytext=(2, 4), fontsize=8)  # fmt: skip
    handles, labels = ax.get_legend_handles_labels()
    if paper:
        handles.append(Line2D([], [], linestyle="none", marker="o", markerfacecolor="none",
                              color="grey"))  # fmt: skip
        labels.append("paper, Table I")
    more = _coverage_axis(ax, rows, M, target_coverage)
    # below the axes: up to ten entries would hide the curves and the coverage's points
    ax.legend(handles + more[0], labels + more[1], fontsize=8, loc="upper center",
              bbox_to_anchor=(0.5, -0.13), ncol=3)  # fmt: skip
    ax.set_xlabel("anchors M")
    ax.set_ylabel("Euclidean error (m)")
    ax.set_xticks(M)
    ax.grid(alpha=0.3)
    return fig


def _coverage_axis(ax, rows, M, target_coverage):
    """The rows' line-of-sight coverage (%) on a right-hand axis of ``ax`` with the target
    as a dotted line; returns the legend's (handles, labels) for it (none without it)."""
    cov = np.array([r.get("covered") for r in rows], dtype=float)
    if not np.isfinite(cov).any():
        return [], []
    k = next((int(r["coverage_k"]) for r in rows if r.get("coverage_k")), None)
    right = ax.twinx()
    label = "line of sight" + ("" if k is None else f", nodes seeing {k}")
    (line,) = right.plot(M, 100 * cov, color="grey", marker="x", linestyle=":", label=label)
    handles, labels = [line], [label + " (right)"]
    if target_coverage:
        right.axhline(100 * target_coverage, color="grey", linestyle=":", linewidth=1)
        right.annotate(f"target {100 * target_coverage:g} %", (M.max(), 100 * target_coverage),
                       textcoords="offset points", xytext=(-60, -12), fontsize=8,
                       color="grey")  # fmt: skip
    right.set_ylim(0, 105)
    right.set_ylabel("nodes covered (%)")
    return handles, labels

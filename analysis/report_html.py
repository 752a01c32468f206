"""HTML of the report (:mod:`analysis.report`): one self-contained page, inline CSS only.

:func:`render` puts the sections in the order a user reads them: headline numbers, the
layout (coordinates, plan view), the comparison with the naive and corners layouts, the
plan's validation, the figures, the other layouts' coordinates, the settings and the
software. No script, no external resource, no network.
"""

from __future__ import annotations

import datetime as _dt
import html
import json
import math
import platform
from importlib import metadata
from typing import Any

import numpy as np

from analysis.coverage import covered_share
from analysis.fim import peb
from analysis.percent import percent_cell
from analysis.report_data import EVALUATION_FILE, RESULT_FILE, Context, LayoutEntry
from simulation.room import SURFACES, Room
from simulation.statistics import error_stats, penalty_text

#: packages whose versions the report lists
PACKAGES = (
    "anchorplan",
    "numpy",
    "scipy",
    "matplotlib",
    "cvxpy",
    "clarabel",
    "casadi",
    "pyroomacoustics",
)

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0;color:#1d232a;
background:#f6f7f9;line-height:1.45}
main{max-width:1180px;margin:0 auto;padding:24px 28px 48px;background:#fff}
h1{font-size:1.6em;margin:0 0 4px}h2{font-size:1.25em;margin:32px 0 8px;
border-bottom:1px solid #dde1e6;padding-bottom:4px}h3{font-size:1.05em;margin:18px 0 6px}
.sub{color:#5b6570;margin:0 0 16px}
table{border-collapse:collapse;margin:6px 0 12px;font-size:.9em}
th,td{border:1px solid #dde1e6;padding:3px 9px;text-align:right}
th{background:#eef1f4;font-weight:600}td.l,th.l{text-align:left;white-space:nowrap}
tr:nth-child(even) td{background:#fafbfc}
.sw{display:inline-block;width:.9em;height:.9em;border-radius:2px;margin-right:6px;
vertical-align:-1px;border:1px solid #0003}
figure{margin:18px 0 26px}figure img{max-width:100%;height:auto;border:1px solid #e3e6ea}
figcaption{color:#4a535c;font-size:.9em;margin-top:4px}
.note{background:#fff8e1;border-left:4px solid #f0b400;padding:6px 10px;margin:6px 0;
font-size:.92em}
.kv td:first-child{text-align:left;color:#4a535c}.kv td{text-align:left;white-space:normal}
.kv{display:inline-table;vertical-align:top;margin-right:18px}
code{font-size:.92em}details{margin:6px 0}
.cards{display:flex;flex-wrap:wrap;gap:12px;margin:10px 0}
.card{border:1px solid #dde1e6;border-radius:6px;padding:8px 14px;min-width:150px}
.card b{display:block;font-size:1.35em}.card span{color:#5b6570;font-size:.85em}
"""


def _e(x: Any) -> str:
    return html.escape(str(x), quote=True)


def _num(x: Any, digits: int = 3) -> str:
    if x is None:
        return "–"
    try:
        v = float(x)
    except (TypeError, ValueError):
        return _e(x)
    if math.isnan(v):
        return "–"
    if math.isinf(v):
        return "∞"
    return f"{v:.{digits}f}" if abs(v) < 1e4 else f"{v:.{digits}g}"


def _percent(x: Any) -> str:
    """A share as a percentage ("–" when unknown, "100 %" for all)."""
    return percent_cell(x, whole="100 %")


def _table(header: list[str], rows: list[list[str]], left: int = 1, cls: str = "") -> str:
    """HTML table; cells are already-escaped HTML; the first ``left`` columns align left."""
    th = "".join(
        f'<th class="l">{h}</th>' if i < left else f"<th>{h}</th>" for i, h in enumerate(header)
    )
    body = "".join(
        "<tr>"
        + "".join(
            f'<td class="l">{c}</td>' if i < left else f"<td>{c}</td>" for i, c in enumerate(r)
        )
        + "</tr>"
        for r in rows
    )
    c = f' class="{cls}"' if cls else ""
    return f"<table{c}><thead><tr>{th}</tr></thead><tbody>{body}</tbody></table>"


def _num_list(v) -> str:
    return "[" + ", ".join(f"{float(x):g}" for x in v) + "]"


def _swatch(color: str, name: str) -> str:
    return f'<span class="sw" style="background:{_e(color)}"></span>{_e(name)}'


def _kv(d: dict, header: str = "setting") -> str:
    rows = []
    for k, v in d.items():
        if isinstance(v, dict | list):
            v = json.dumps(v, separators=(", ", ": "))
        elif isinstance(v, float):
            v = f"{v:g}"
        rows.append([_e(k), f"<code>{_e(v)}</code>"])
    return _table([_e(header), "value"], rows, left=2, cls="kv")


def _versions() -> list[list[str]]:
    rows = [["python", _e(platform.python_version())]]
    for p in PACKAGES:
        try:
            v = metadata.version(p)
        except metadata.PackageNotFoundError:
            v = "not installed"
        rows.append([_e(p), _e(v)])
    return rows


def _summary(values) -> dict[str, float]:
    """mean, median, p95 … of the finite values (:func:`simulation.statistics.error_stats`)."""
    return error_stats(values)


def _nearest_surface(room: Room, anchors: np.ndarray) -> list[str]:
    """Name of the nearest room plane per anchor; ties (corners, edges) joined by '/',
    allowed mounting surfaces first."""
    names = sorted(SURFACES, key=lambda n: (n not in room.mounting, list(SURFACES).index(n)))
    L = np.asarray(room.size)
    d = np.stack(
        [np.abs(anchors[:, SURFACES[n][0]] - SURFACES[n][1] * L[SURFACES[n][0]]) for n in names],
        axis=-1,
    )
    near = d <= d.min(axis=-1, keepdims=True) + 1e-6
    return ["/".join(n for n, k in zip(names, row, strict=True) if k) for row in near]


def _figure_numbers(ctx: Context) -> dict[int, int]:
    """Figure number (document order: layout section first) by index in ctx.figures."""
    order = [i for i, f in enumerate(ctx.figures) if f.section == "layout"]
    order += [i for i, f in enumerate(ctx.figures) if f.section != "layout"]
    return {i: n for n, i in enumerate(order, 1)}


def _figures_html(ctx: Context, section: str) -> list[str]:
    numbers = _figure_numbers(ctx)
    return [
        f'<figure><img src="{f.uri}" alt="{_e(f.title)}">'
        f"<figcaption><b>Figure {numbers[i]}. {_e(f.title)}.</b> {_e(f.caption)}</figcaption>"
        "</figure>"
        for i, f in enumerate(ctx.figures)
        if (f.section == "layout") == (section == "layout")
    ]


# -- sections ------------------------------------------------------------------------------
def _head(ctx: Context) -> list[str]:
    room, best = ctx.room, ctx.best
    sources = ", ".join(
        n for n, d in ((RESULT_FILE, ctx.result), (EVALUATION_FILE, ctx.evaluation)) if d
    )
    now = _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z")
    name = ctx.result_dir.name or str(ctx.result_dir)
    return [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>anchorplan report – {_e(room.name)}</title>",
        f"<style>{_CSS}</style></head><body><main>",
        f"<h1>anchorplan report — {_e(room.name)}, M = {len(best.anchors)}</h1>",
        f'<p class="sub">{_e(name)}: {_e(sources)} · generated {_e(now)} · PEB = √tr J⁻¹ in '
        f"metres at constant σ<sub>r</sub> = {ctx.sigma:g} m</p>",
        f'<p class="sub">System: {_e(ctx.system.describe())}; reach '
        f"{ctx.system.reach(room.speed_of_sound):.2f} m. The errors are this system's: its "
        "receiver and positioning change them more than the layout does (BENCHMARKS.md, "
        "“The receiver”).</p>",
    ]


def _headline(ctx: Context) -> list[str]:
    """Cards: the field's median / mean / P95 and share of verified fixes, then σ, the
    layout's figures at the nodes, the line-of-sight coverage and mean PEB, σ of each
    comparison layout."""
    best = ctx.best
    cards = []
    field = ((ctx.result or {}).get("validation") or {}).get("field")
    robust = ctx.system.positioning.method == "robust"
    if field:  # first: what the installation delivers where the tags go
        what = f"tags anywhere, anchors within {100 * field['tolerance_m']:g} cm"
        cards += [
            (f"{_num(field.get('median'))} m", f"field median error ({what})"),
            (f"{_num(field['mean'])} m", "field mean error"),
            (f"{_num(field['p95'])} m", "field P95 error"),
        ]
        if robust:
            cards.append((_percent(field.get("verified")), "field fixes verified (≥ 5 agree)"))
        cards.append((f"{_num(field['std'])} m", "field σ (the paper's figure)"))
    if best.sim is not None:
        st = best.sim.stats
        cards += [
            (f"{_num(st.get('median'))} m", f"median error ({best.name}, at the nodes)"),
            (f"{_num(st['mean'])} m", "mean error"),
            (f"{_num(st['p95'])} m", "P95 error"),
            (f"{_num(st['std'])} m", "σ of the error"),
            (_percent(st.get("availability")), "availability (share with a fix)"),
        ]
    k = 5 if robust else 4
    share = covered_share(ctx.room, best.anchors, ctx.nodes, system=ctx.system, k=k)
    cards.append((_percent(share), f"nodes seeing ≥ {k} anchors (line of sight, reach)"))
    cards.append((f"{_num(_summary(best.peb)['mean'])} m", "mean PEB"))
    for e in ctx.layouts[1:]:
        if e.role in ("comparison", "reference") and e.sim is not None:
            cards.append((f"{_num(e.sim.stats['std'])} m", f"σ of the {e.name} layout"))
    out = [
        '<div class="cards">'
        + "".join(f'<div class="card"><b>{v}</b><span>{_e(k)}</span></div>' for v, k in cards)
        + "</div>"
    ]
    return out + [f'<div class="note">{_e(n)}</div>' for n in ctx.notes]


def _coordinates(ctx: Context, e: LayoutEntry) -> str:
    surf = _nearest_surface(ctx.room, e.anchors)
    rows = [
        [str(j + 1), _num(a[0]), _num(a[1]), _num(a[2]), _e(s)]
        for j, (a, s) in enumerate(zip(e.anchors, surf, strict=True))
    ]
    return _table(["#", "x (m)", "y (m)", "z (m)", "surface"], rows, left=0)


def _head_of(ctx: Context, e: LayoutEntry) -> str:
    return f"{_swatch(ctx.colors[e.name], e.name)} (M = {len(e.anchors)}, {_e(e.role)})"


def _layout_section(ctx: Context) -> list[str]:
    best = ctx.best
    return [
        "<h2>Layout</h2>",
        f"<h3>{_head_of(ctx, best)}</h3>",
        '<p class="sub">Anchor coordinates in room coordinates; surface: the nearest room '
        "plane.</p>",
        _coordinates(ctx, best),
        *_figures_html(ctx, "layout"),
    ]


def _mean_finite(v) -> str:
    return "–" if v is None else _num(_summary(v)["mean"], 2)


def _comparison_rows(ctx: Context) -> list[list[str]]:
    rows = []
    for e in ctx.layouts:
        s, pb = e.sim, _summary(e.peb)
        rows.append(
            [
                _swatch(ctx.colors[e.name], e.name),
                str(len(e.anchors)),
                _e(s.source if s else "not simulated"),
                str(s.realizations) if s else "–",
                # what a user's tags see first, then the paper's σ and the RMS
                *(
                    _num(s.stats.get(k)) if s else "–"
                    for k in ("median", "mean", "p95", "std", "rms")
                ),
                _percent(s.stats.get("availability")) if s else "–",
                _mean_finite(s.dop if s else None),
                _mean_finite(s.dop_rms if s else None),
                _num(pb["mean"]),
                _num(pb["p95"]),
                _e(p) if (p := penalty_text(e.cost)) else _num(e.cost, 4),
            ]
        )
    return rows


def _comparison_section(ctx: Context) -> list[str]:
    header = [
        "layout", "M", "simulated errors from", "R", "median (m)", "mean (m)", "P95 (m)",
        "σ (m)", "RMS (m)", "availability", "mean DOP (paper: σ/σ<sub>r</sub>)",
        "mean DOP<sub>RMS</sub> (RMSE/σ<sub>r</sub>)", "mean PEB (m)", "P95 PEB (m)", "cost",
    ]  # fmt: skip
    naive = any(e.role == "comparison" for e in ctx.layouts)
    parts = [
        "<h2>Comparison: position error, DOP and bound</h2>",
        _table(header, _comparison_rows(ctx), left=1),
        '<p class="sub">Euclidean position errors over the fixes of all nodes and '
        "realizations; σ is the population standard deviation (the paper's figure of "
        "merit); availability: the share of node realizations with a fix (4 or more "
        "anchors heard). "
        + ("" if naive else "No naive comparison layout was given (anchorplan report adds "
           "one: anchors spread evenly along the top edges of the mounting walls). ")
        + "DOP per node, averaged over the nodes with finite DOP: the paper's DOP is the "
        "standard deviation over the realizations of the node's error over σ<sub>r</sub>, "
        "the mean over anchors of the range-error standard deviation (§V-A); DOP<sub>RMS"
        "</sub> uses the node's RMS error instead, so it also counts a steady multipath "
        "bias (DOP<sub>RMS</sub> ≥ DOP). PEB over the "
        f"{len(ctx.nodes)} evaluation nodes. cost: the plan's cost of that layout "
        f"({_e((ctx.result or {}).get('cost_name', '–'))}; starting layouts: "
        "first-iteration cost).</p>",
    ]  # fmt: skip
    return parts + _gap_section(ctx)


def _calibrated(ctx: Context, e: LayoutEntry) -> str:
    """Calibrated σ_r range and the mean PEB with it, from range errors simulated here."""
    if e.fresh is None or e.fresh.range_errors is None:
        return "–"
    from analysis.noise import calibrated_sigma

    try:
        s = calibrated_sigma(e.fresh.range_errors)
    except ValueError:
        return "–"
    mean = _summary(peb(e.anchors, ctx.nodes, sigma=s))["mean"]
    return f"{_num(np.min(s))}–{_num(np.max(s))} m → {_num(mean)}"


def _gap_row(ctx: Context, e: LayoutEntry) -> list[str]:
    p, r = e.peb, e.sim.rmse
    ok = np.isfinite(p) & np.isfinite(r) & (p > 0)
    ratio = float(np.median(r[ok] / p[ok])) if np.any(ok) else math.nan
    within = float(np.mean(r[ok] <= 2 * p[ok])) if np.any(ok) else math.nan
    sp, sr = _summary(p), _summary(r)
    return [
        _swatch(ctx.colors.get(e.name, "#000"), e.name),
        _num(sp["mean"]),
        _num(sr["mean"]),
        _num(sp["median"]),
        _num(sr["median"]),
        _num(ratio, 2),
        _num(sp["p95"]),
        _num(sr["p95"]),
        "–" if math.isnan(within) else f"{100 * within:.0f} %",
        _calibrated(ctx, e),
    ]


def _gap_section(ctx: Context) -> list[str]:
    rows = [_gap_row(ctx, e) for e in ctx.layouts if e.sim is not None]
    if not rows:
        return []
    calibrated = any(r[-1] != "–" for r in rows)
    header = [
        "layout", "mean PEB", "mean RMSE", "median PEB", "median RMSE", "median RMSE/PEB",
        "P95 PEB", "P95 RMSE", "nodes with RMSE ≤ 2·PEB", "calibrated σ<sub>r</sub> → mean PEB",
    ]  # fmt: skip
    note = (
        "Calibrated σ<sub>r</sub>: per-anchor inlier standard deviation of the simulated "
        "range errors (outliers beyond 3 MAD-σ removed, as the paper's 0.03–0.045 m), and "
        "the mean PEB with it."
        if calibrated
        else "Calibrated σ<sub>r</sub> needs range errors simulated here."
    )
    return [
        "<h3>Bound versus simulation (per node)</h3>",
        _table(header, rows, left=1),
        '<p class="sub">All lengths in metres. RMSE: per-node RMS Euclidean error over the '
        f"realizations; PEB at σ<sub>r</sub> = {ctx.sigma:g} m. {note}</p>",
    ]


#: the columns of :func:`_stat_cells`
STAT_HEADER = ["median (m)", "mean (m)", "P95 (m)", "σ (m)", "availability"]


def _stat_cells(block: dict) -> list[str]:
    """median, mean, P95, then σ (a file of an earlier version has no median: "–")."""
    return [_num(block.get(k)) for k in ("median", "mean", "p95", "std")] + [
        _percent(block.get("availability"))
    ]


def _held_out(v: dict, nominal: list[str], P: int) -> list[str]:
    held = v.get("held_out")
    if not isinstance(held, dict) or not held:
        return []
    rows = [["evaluation grid (validation)", str(P), *nominal]]
    for name, block in held.items():
        block = block if isinstance(block, dict) else {}
        rows.append([_e(name), _e(block.get("nodes", "–")), *_stat_cells(block)])
    return [
        "<h3>Held-out nodes</h3>",
        _table(["nodes", "count", *STAT_HEADER], rows, left=1),
        '<p class="sub">The chosen layout simulated at nodes the optimizer did not use '
        "(grid: another grid of nodes; random: random points in the room), against the "
        "validation on the evaluation grid.</p>",
    ]


def _mounting(v: dict, nominal: list[str]) -> list[str]:
    m = v.get("mounting")
    if not isinstance(m, dict) or not m:
        return []
    rows = [
        ["as planned", "0", "–", *nominal],
        ["moved", _num(m.get("tolerance_m")), _e(m.get("draws", "–")), *_stat_cells(m)],
    ]
    return [
        "<h3>Mounting tolerance</h3>",
        _table(
            ["anchors", "tolerance (m)", "draws", *STAT_HEADER],
            rows,
        ),
        '<p class="sub">The layout with every anchor moved at random by up to the tolerance '
        "on its surface, as an installer might mount it, over the given number of draws.</p>",
    ]


def _validation_section(ctx: Context) -> list[str]:
    """The plan's held-out and mounting-tolerance validations, when result.json has them."""
    v = (ctx.result or {}).get("validation") or {}
    if not isinstance(v, dict):
        return []
    nominal = _stat_cells(v)
    parts = _held_out(v, nominal, len(ctx.nodes)) + _mounting(v, nominal)
    return ["<h2>Validation</h2>", *parts] if parts else []


def _what_if_section(ctx: Context) -> list[str]:
    """The what-if tables of ``anchorplan stress`` (RESULT_DIR/stress.json), when present."""
    path = ctx.result_dir / "stress.json"
    if not path.is_file():
        return []
    try:
        w = json.loads(path.read_text())
        down, temp, mount = w["anchor_down"], w["temperature"], w["mounting"]
        worst = int(w["worst_anchor"])
    except (ValueError, KeyError, TypeError):
        return ['<h2>What if</h2><p class="sub">stress.json is unreadable.</p>']

    # what a user's tags see first, then σ (a file of an earlier version has no median)
    method = w.get("settings", {}).get("system", {}).get("positioning", {}).get("method")
    verified = method == "robust"

    def cells(r):
        share = [_percent(r.get("verified"))] if verified else []
        return [_num(r.get("median")), _num(r["mean"]), _num(r["p95"]), *share,
                _num(r["std"]), _percent(r["availability"])]  # fmt: skip

    stats = ["median (m)", "mean (m)", "P95 (m)", *(["verified"] if verified else []), "σ (m)",
             "availability"]  # fmt: skip
    rows = [[f"{r['anchor'] + 1}" + (" (worst)" if r["anchor"] == worst else ""), *cells(r),
             _percent(r["covered_share"])] for r in down]  # fmt: skip
    return [
        "<h2>What if</h2>",
        '<p class="sub">From <code>anchorplan stress</code>: the full simulation with one '
        "anchor down, with the air warmer or colder than the receiver's configured speed of "
        "sound assumes, and with the anchors mounted within a tolerance of the plan "
        f"(seed {w.get('seed')}).</p>",
        "<h3>One anchor down</h3>",
        _table(["anchor down", *stats, "hearing ≥ 4"], rows, left=0),
        "<h3>Air temperature</h3>",
        _table(
            ["offset (°C)", *stats], [[f"{r['offset']:+g}", *cells(r)] for r in temp], left=0
        ),  # fmt: skip
        "<h3>Mounting tolerance</h3>",
        _table(
            ["tolerance (cm)", *stats],
            [[f"{100 * r['tolerance']:g}", *cells(r)] for r in mount],
            left=0,
        ),  # fmt: skip
    ]


def _figures_section(ctx: Context) -> list[str]:
    return ["<h2>Figures</h2>", *_figures_html(ctx, "figures")]


def _other_coordinates(ctx: Context) -> list[str]:
    others = ctx.layouts[1:]
    if not others:
        return []
    parts = ["<h2>Coordinates of the other layouts</h2>"]
    for e in others:
        head, table = _head_of(ctx, e), _coordinates(ctx, e)
        if e.role == "initial":
            parts.append(f"<details><summary>{head}</summary>{table}</details>")
        else:
            parts.append(f"<h3>{head}</h3>{table}")
    return parts


def _walls(ctx: Context, room_dict: dict) -> list[str]:
    """A polygonal room's walls (name, from, to, length, absorption) and its obstacles."""
    room = ctx.room
    parts = []
    if not room.is_shoebox:
        room_dict.pop("corners", None)
        room_dict.pop("wall_names", None)
        rows = [
            [_e(w.name), _e(_num_list(w.start)), _e(_num_list(w.end)), _num(w.length, 2),
             _num(room.absorption[w.name], 2)]
            for w in room.walls
        ]  # fmt: skip
        parts += [
            "<h3>Walls</h3>",
            '<p class="sub">The floor plan’s walls in corner order (m), height '
            f"{room.size[2]:g} m; floor α = {room.absorption['floor']:g}, ceiling α = "
            f"{room.absorption['ceiling']:g}.</p>",
            _table(["wall", "from (x, y)", "to (x, y)", "length (m)", "α"], rows, left=1),
        ]
    obstacles = room_dict.pop("obstacles", [])
    if obstacles:
        rows = [
            [_e(o.get("name", "")), _e(_num_list(o["min"])), _e(_num_list(o["max"])),
             _num(o.get("absorption"), 2), "yes" if o.get("mountable") else "no"]
            for o in obstacles
        ]  # fmt: skip
        parts += [
            "<h3>Obstacles</h3>",
            '<p class="sub">Boxes standing in the room (m): they block and reflect sound and '
            "hold no node; anchors may go on the faces of a mountable one.</p>",
            _table(["name", "min (m)", "max (m)", "α", "mountable"], rows, left=1),
        ]
    return parts


def _regions(ctx: Context, room_dict: dict) -> list[str]:
    room = ctx.room
    regions = [("keep-out", b) for b in room_dict.pop("keepouts", [])]
    regions += [("tag zone", b) for b in room_dict.pop("zones", [])]
    if not regions:
        return []
    rows = [
        [_e(kind), _e(b.get("name", "")), _e(_num_list(b["min"])), _e(_num_list(b["max"]))]
        for kind, b in regions
    ]
    what = "No anchor may lie in a keep-out (hatched or grey in the figures)"
    if room.zones:
        what += (
            f"; the room's evaluation nodes are a {room.zone_spacing:g} m grid over the tag "
            "zones (dashed)"
        )
    return [
        "<h3>Keep-outs and tag zones</h3>",
        f'<p class="sub">Boxes in room coordinates (m). {what}.</p>',
        _table(["kind", "name", "min (m)", "max (m)"], rows, left=2),
    ]


def _system(room: Room, system) -> list[str]:
    """The system: the chirp, the receiver, the reach they imply, the positioning."""
    d = {"system": system.name}
    d.update({f"chirp {k}": v for k, v in system.chirp.__dict__.items()})
    d.update({f"receiver {k}": v for k, v in system.receiver.__dict__.items()})
    d["reach (m)"] = round(system.reach(room.speed_of_sound), 3)
    d["near limit (m)"] = round(system.near_limit(room.speed_of_sound), 3)
    d.update({f"positioning {k}": v for k, v in system.positioning.__dict__.items()})
    return [
        "<h3>System</h3>",
        '<p class="sub">The transmitted chirp, the receiver (durations in s, frequencies '
        "in Hz, window in samples) and the positioning. The reach is the longest range whose "
        "chirp the window holds enough of (1 ms, or all of a shorter window); a receiver "
        "without a false-alarm setting has no detection threshold (the paper's); the pick is "
        "the paper's (the strongest arrival) or the first path's (the earliest that stands "
        "out); positions kept in the room stay inside its box.</p>",
        _kv(d),
    ]


def _timings(timings) -> list[str]:
    """The plan's time per phase (a dict phase → seconds)."""
    if not isinstance(timings, dict) or not timings:
        return []
    rows = [
        [_e(k), _num(v, 1) if isinstance(v, int | float) else f"<code>{_e(json.dumps(v))}</code>"]
        for k, v in timings.items()
    ]
    return ["<h3>Time per phase</h3>", _table(["phase", "seconds"], rows, left=1)]


def _settings_section(ctx: Context) -> list[str]:
    room, result, evaluation = ctx.room, ctx.result, ctx.evaluation
    room_dict = room.to_dict()
    walls = _walls(ctx, room_dict)  # takes the floor plan and obstacles out of room_dict
    regions = _regions(ctx, room_dict)  # takes the boxes out of room_dict
    parts = ["<h2>Settings</h2>", "<h3>Room</h3>"]
    parts.append(_kv({**room_dict, "speed_of_sound (m/s)": round(room.speed_of_sound, 3)}))
    parts += walls + regions
    parts += _system(room, ctx.system)
    if result is not None:
        keys = ("cost_name", "cost", "nfev", "nit", "success", "message")
        run = {k: result[k] for k in keys if k in result}
        parts += ["<h3>Optimization</h3>", _kv(run, header="result")]
        if result.get("settings"):
            parts.append(_kv(result["settings"]))
        parts += _timings(result.get("timings"))
    if evaluation is not None:
        keys = ("realizations", "seed", "snr_db", "seconds")
        parts += ["<h3>Evaluation</h3>", _kv({k: evaluation[k] for k in keys if k in evaluation})]
    return parts


def _software(ctx: Context) -> list[str]:
    return [
        "<h2>Software</h2>",
        _table(["package", "version"], _versions(), left=2),
        f'<p class="sub">Report built in {ctx.elapsed:.1f} s.</p>',
    ]


def render(ctx: Context) -> str:
    """The report's HTML, the sections in reading order (see the module docstring)."""
    parts = [
        *_head(ctx),
        *_headline(ctx),
        *_layout_section(ctx),
        *_comparison_section(ctx),
        *_validation_section(ctx),
        *_what_if_section(ctx),
        *_figures_section(ctx),
        *_other_coordinates(ctx),
        *_settings_section(ctx),
        *_software(ctx),
        "</main></body></html>",
    ]
    return "\n".join(parts) + "\n"

"""One self-contained HTML report of a planning / evaluation result folder.

Reads ``RESULT_DIR/result.json`` (written by ``anchorplan plan``) and/or
``RESULT_DIR/evaluation.json`` (``anchorplan evaluate``) and renders settings, layout
coordinates, the simulated error statistics (σ, mean, P95, RMS), the PEB, a bound-versus-
simulation gap table, the figures of :mod:`analysis.figures` (embedded as base64 PNG
``data:`` URIs) and the package versions. The HTML has inline CSS only: no script, no
external resource, no network.

PEB = √tr J⁻¹ in metres at a constant range σ (the plan's ``settings.sigma``, default
0.04 m) is computed here with :func:`analysis.fim.peb`. Simulated errors come from the
JSON files; the reference "corners" layout (and per-axis errors, which the files do not
store) are simulated here with :func:`simulation.evaluate_layout` for a small number of
realizations, when the simulator is available and ``realizations`` > 0.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import json
import logging
import math
import platform
import re
import time
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from analysis.fim import peb
from analysis.statistics import error_stats, node_rmse
from simulation.room import SURFACES, Room

logger = logging.getLogger(__name__)

RESULT_FILE = "result.json"
EVALUATION_FILE = "evaluation.json"
DEFAULT_SIGMA = 0.04
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


# -- data model ----------------------------------------------------------------------------
@dataclass
class Simulated:
    """Simulated Euclidean errors of one layout (metres).

    errors (R, P); rmse (P,) per-node RMS over realizations; dop (P,) or None; stats
    {std, mean, p95, rms}; estimates (R, P, 3) and range_errors (R, P, M) when simulated
    here (the JSON files do not store them); source says where the numbers come from.
    """

    errors: np.ndarray
    rmse: np.ndarray
    dop: np.ndarray | None
    stats: dict[str, float]
    realizations: int
    source: str
    estimates: np.ndarray | None = None
    range_errors: np.ndarray | None = None


@dataclass
class LayoutEntry:
    """A layout shown in the report: name, anchors (M, 3), role, optional cost and data."""

    name: str
    anchors: np.ndarray
    role: str  # "optimized", "evaluated", "reference" or "seed"
    cost: float | None = None
    sim: Simulated | None = None  # the layout's main simulated data (files first)
    fresh: Simulated | None = None  # simulated for this report (with per-axis errors)
    peb: np.ndarray | None = field(default=None, repr=False)


@dataclass
class Report:
    """The rendered report: ``html`` text, figure titles, and notes on what was skipped."""

    html: str
    figures: list[str]
    notes: list[str]
    layouts: list[LayoutEntry]


# -- reading -------------------------------------------------------------------------------
def load_results(result_dir: str | Path) -> dict[str, dict | None]:
    """{"result": ..., "evaluation": ...} from the folder (None where a file is absent).

    Raises ``FileNotFoundError`` if the folder has neither file, ``ValueError`` on bad JSON.
    """
    d = Path(result_dir)
    if not d.is_dir():
        raise FileNotFoundError(f"RESULT_DIR: {d} is not a folder")
    out: dict[str, dict | None] = {}
    for key, name in (("result", RESULT_FILE), ("evaluation", EVALUATION_FILE)):
        p = d / name
        if not p.exists():
            out[key] = None
            continue
        try:
            data = json.loads(p.read_text())
        except json.JSONDecodeError as exc:
            raise ValueError(f"{p}: not valid JSON ({exc})") from None
        if not isinstance(data, dict) or "anchors" not in data:
            raise ValueError(f"{p}: expected an object with 'anchors'")
        out[key] = data
    if out["result"] is None and out["evaluation"] is None:
        raise FileNotFoundError(f"RESULT_DIR: {d} has neither {RESULT_FILE} nor {EVALUATION_FILE}")
    return out


def _array(x, name: str, ndim: int | None = None) -> np.ndarray:
    """Float array from JSON lists (null → NaN)."""
    try:
        a = np.array(x, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected numbers") from None
    if ndim is not None and a.ndim != ndim:
        raise ValueError(f"{name}: expected {ndim} dimensions, got shape {a.shape}")
    return a


def _stats_from(src: dict | None, errors: np.ndarray | None) -> dict[str, float]:
    keys = ("std", "mean", "p95", "rms")
    if src and all(isinstance(src.get(k), int | float) for k in keys):
        return {k: float(src[k]) for k in keys}
    if errors is not None:
        s = error_stats(errors)
        return {k: s[k] for k in keys}
    return {k: math.nan for k in keys}


def _sim_from_json(block: dict, per_node: dict | None, P: int, R: int | None, source: str):
    """Simulated from a validation/evaluation block; None without errors or per-node RMSE."""
    errors = block.get("errors")
    per_node = per_node or {}
    e = _array(errors, f"{source} errors", 2) if errors is not None else None
    if e is not None and e.shape[1] != P:
        raise ValueError(f"{source} errors: expected (R, {P}) for {P} nodes, got {e.shape}")
    rmse = per_node.get("rmse")
    rmse = _array(rmse, f"{source} per_node.rmse", 1) if rmse is not None else None
    if rmse is None and e is not None:
        rmse = node_rmse(e)
    if rmse is None:
        return None
    dop = per_node.get("dop")
    dop = _array(dop, f"{source} per_node.dop", 1) if dop is not None else None
    if e is None:
        e = rmse[None, :]  # only the per-node RMSE is known; CDFs use it as one "realization"
    stats_src = block.get("stats", block)
    R = int(R or block.get("realizations") or e.shape[0])
    return Simulated(e, rmse, dop, _stats_from(stats_src, e), R, source)


def _sim_from_evaluation(ev, source: str) -> Simulated:
    errors = np.asarray(ev.errors, dtype=float)
    return Simulated(
        errors=errors,
        rmse=np.asarray(ev.rmse, dtype=float),
        dop=np.asarray(ev.dop, dtype=float),
        stats=_stats_from(None, errors),
        realizations=errors.shape[0],
        source=source,
        estimates=np.asarray(ev.estimates, dtype=float),
        range_errors=np.asarray(ev.range_errors, dtype=float),
    )


def _evaluator():
    """``simulation.evaluate_layout`` if the simulator is installed, else None."""
    try:
        import simulation
    except ImportError:  # pragma: no cover - simulation is part of the distribution
        return None
    return getattr(simulation, "evaluate_layout", None)


def collect_layouts(data: dict[str, dict | None], room: Room, nodes: np.ndarray):
    """Layouts of the report in display order: optimized, evaluated, seeds, corners."""
    P = len(nodes)
    result, evaluation = data.get("result"), data.get("evaluation")
    out: list[LayoutEntry] = []
    if result is not None:
        v = result.get("validation") or {}
        sim = None
        if v:
            R = v.get("realizations")
            sim = _sim_from_json(v, v.get("per_node"), P, R, f"{RESULT_FILE} validation")
        cost = result.get("cost")
        out.append(
            LayoutEntry(
                "optimized",
                _array(result["anchors"], "result anchors", 2),
                "optimized",
                None if cost is None else float(cost),
                sim,
            )
        )
        for i, s in enumerate(result.get("seeds") or []):
            name = f"seed {s.get('name', i + 1)}"
            c = s.get("cost")
            anchors = _array(s["anchors"], f"seeds[{i}] anchors", 2)
            out.append(LayoutEntry(name, anchors, "seed", None if c is None else float(c)))
    if evaluation is not None:
        anchors = _array(evaluation["anchors"], "evaluation anchors", 2)
        sim = _sim_from_json(
            evaluation,
            evaluation.get("per_node"),
            P,
            evaluation.get("realizations"),
            EVALUATION_FILE,
        )
        same = (
            out and out[0].anchors.shape == anchors.shape and np.allclose(out[0].anchors, anchors)
        )
        if same:
            # same layout: keep the larger sample as its main data
            if sim is not None and (
                out[0].sim is None or sim.realizations > out[0].sim.realizations
            ):
                out[0].sim = sim
        else:
            out.insert(1 if out else 0, LayoutEntry("evaluated", anchors, "evaluated", None, sim))
    corners = room.corners_layout()
    if not any(e.anchors.shape == corners.shape and np.allclose(e.anchors, corners) for e in out):
        out.append(LayoutEntry("corners", corners, "reference"))
    return out


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


# -- building ------------------------------------------------------------------------------
def build_report(
    result_dir: str | Path,
    *,
    realizations: int = 10,
    seed: int = 0,
    sigma: float | None = None,
    dpi: float = 100,
    figures_dir: str | Path | None = None,
) -> Report:
    """Render the report of ``result_dir`` (see the module docstring).

    realizations: R for the layouts simulated here (corners reference, per-axis errors);
        0 disables all simulation here.
    seed: seed of those simulations. sigma: range σ (m) of the PEB (default: the plan's
        ``settings.sigma`` or 0.04 m). dpi: resolution of the embedded figures.
    figures_dir: if given, every figure is also written there as ``NN-title.png``.
    """
    if int(realizations) != realizations or realizations < 0:
        raise ValueError(f"realizations: must be an integer >= 0, got {realizations}")
    from analysis import figures as F  # matplotlib only when a report is built

    t0 = time.perf_counter()
    data = load_results(result_dir)
    result, evaluation = data["result"], data["evaluation"]
    main = result if result is not None else evaluation
    room = Room.from_dict(main["room"]) if main.get("room") else Room.techtile()
    nodes = (
        _array(evaluation["nodes"], "evaluation nodes", 2)
        if evaluation is not None and evaluation.get("nodes") is not None
        else room.grid()
    )
    settings = (result or {}).get("settings") or {}
    if sigma is None:
        sigma = float(settings.get("sigma") or DEFAULT_SIGMA)
    if not (math.isfinite(sigma) and sigma > 0):
        raise ValueError(f"sigma: must be > 0 m, got {sigma}")
    layouts = collect_layouts(data, room, nodes)
    for e in layouts:
        e.peb = peb(e.anchors, nodes, sigma=sigma)
    notes: list[str] = []

    # simulate here what the files lack (small R)
    evaluate = _evaluator() if realizations > 0 else None
    if realizations == 0:
        notes.append("Simulation in the report is disabled (realizations = 0).")
    elif evaluate is None:
        notes.append(
            "The simulator (simulation.evaluate_layout) is not available: figures of "
            "simulated errors for layouts without stored errors are skipped."
        )
    if evaluate is not None:
        for e in layouts:
            if e.role == "seed":
                continue
            try:
                room.check_anchors(e.anchors)
            except ValueError as exc:
                notes.append(f"{e.name}: not simulated ({exc}).")
                continue
            t = time.perf_counter()
            ev = evaluate(room, e.anchors, realizations=int(realizations), rng=seed, nodes=nodes)
            e.fresh = _sim_from_evaluation(ev, f"simulated for this report (R = {realizations})")
            if e.sim is None:
                e.sim = e.fresh
            logger.info(
                "simulated %s, R = %d, in %.1f s", e.name, realizations, time.perf_counter() - t
            )

    names = [e.name for e in layouts]
    colors = F.layout_colors(names)
    figs: list[tuple[str, str, Any]] = []  # (title, caption, figure)
    best = layouts[0]
    zs = np.unique(np.round(nodes[:, 2], 9))
    heights = sorted({float(zs[0]), float(zs[len(zs) // 2]), float(zs[-1])})

    regions_note = (
        " Keep-outs (hatched) and tag zones (dashed) are projected too."
        if room.keepouts or room.zones
        else ""
    )

    def add(title, caption, make):
        t = time.perf_counter()
        try:
            fig = make()
        except ValueError as exc:  # bad or degenerate data: say so, keep the report
            notes.append(f"Figure '{title}' skipped: {exc}")
            return
        figs.append((title, caption, fig))
        logger.debug("figure %s in %.2f s", title, time.perf_counter() - t)

    add(
        f"PEB map of the {best.name} layout",
        f"PEB = √tr J⁻¹ (m) at σ = {sigma:g} m on horizontal slices at the node heights and "
        f"a vertical cut at y = {room.size[1] / 2:g} m; anchors (numbered as in the "
        "coordinate table) are projected onto each plane (paper Figs. 1, 2, 6)." + regions_note,
        lambda: F.peb_map(
            room,
            best.anchors,
            sigma=sigma,
            heights=heights,
            y_cuts=[room.size[1] / 2],
            anchor_color=colors[best.name],
            dpi=dpi,
        ),
    )
    main_layouts = [e for e in layouts if e.role != "seed"]
    add(
        "PEB at the evaluation nodes",
        f"The {len(nodes)} evaluation nodes coloured by PEB (m, σ = {sigma:g} m) on one "
        "colour scale; anchors with arrows along their aim (room centroid); shaded: the "
        "allowed mounting surfaces"
        + ("; grey boxes: keep-outs" if room.keepouts else "")
        + ("; dashed: tag zones" if room.zones else "")
        + ".",
        lambda: F.scatter3d_panels(
            room,
            nodes,
            {e.name: e.peb for e in main_layouts},
            {e.name: e.anchors for e in main_layouts},
            colors=colors,
            dpi=dpi,
        ),
    )
    simulated = [e for e in layouts if e.sim is not None]
    if simulated:
        add(
            "Simulated per-node RMSE",
            "Per-node RMS Euclidean position error (m) over the realizations ("
            + "; ".join(f"{e.name}: R = {e.sim.realizations}, {e.sim.source}" for e in simulated)
            + ") on one colour scale (paper Figs. 1, 2).",
            lambda: F.scatter3d_panels(
                room,
                nodes,
                {e.name: e.sim.rmse for e in simulated},
                {e.name: e.anchors for e in simulated},
                label="RMSE (m)",
                colors=colors,
                dpi=dpi,
            ),
        )
        fresh = [e for e in layouts if e.fresh is not None and e.fresh.estimates is not None]
        if fresh:
            add(
                "Error CDFs: Euclidean and per axis",
                "CDFs of the Euclidean and |x|, |y|, |z| position errors over all nodes and "
                f"realizations, R = {realizations} simulated for this report (paper Fig. 3); "
                "the legend gives each layout's P95.",
                lambda: F.error_cdfs(
                    {e.name: e.fresh.errors for e in fresh},
                    {e.name: e.fresh.estimates - nodes for e in fresh},
                    colors=colors,
                    dpi=dpi,
                ),
            )
        else:
            add(
                "Error CDFs: Euclidean",
                "CDF of the Euclidean position error over all nodes and realizations (per-axis "
                "errors are not stored in the JSON files).",
                lambda: F.error_cdfs(
                    {e.name: e.sim.errors for e in simulated}, colors=colors, dpi=dpi
                ),
            )
        add(
            "Bound vs simulation",
            f"CDFs over nodes of the PEB (dashed, σ = {sigma:g} m) and the simulated per-node "
            "RMSE (solid): the horizontal distance is the gap between the bound and the "
            "realistic error, caused mostly by multipath outliers the range model of the bound "
            "does not contain (paper Figs. 5, 8).",
            lambda: F.bound_gap_cdfs(
                {e.name: e.peb for e in simulated},
                {e.name: e.sim.rmse for e in simulated},
                colors=colors,
                dpi=dpi,
            ),
        )
        ref = next((e for e in layouts if e.role == "reference"), None)
        if (
            ref is not None
            and ref is not best
            and best.sim is not None
            and ref.sim is not None
            and best.sim.dop is not None
            and ref.sim.dop is not None
            and np.any(np.isfinite(best.sim.dop) & np.isfinite(ref.sim.dop))
        ):
            add(
                f"DOP difference {ref.name} → {best.name}",
                f"Per-node DOP = σ_pos/σ_r of the {ref.name} layout minus that of the "
                f"{best.name} layout (R = {ref.sim.realizations} and {best.sim.realizations}); "
                f"blue: {best.name} better (paper Fig. 4). σ_pos is the per-node RMSE and σ_r "
                "the mean over anchors of the range-error standard deviation, so a node with "
                "a steady multipath bias but little noise has a large DOP.",
                lambda: F.dop_difference(
                    room,
                    nodes,
                    ref.sim.dop,
                    best.sim.dop,
                    labels=(ref.name, best.name),
                    anchors_a=ref.anchors,
                    anchors_b=best.anchors,
                    colors=colors,
                    dpi=dpi,
                ),
            )
        else:
            notes.append(
                "DOP difference map skipped: it needs per-node DOP (R ≥ 2) of both the "
                "corners reference and the best layout."
            )
    else:
        notes.append("No simulated errors are available: simulated-error figures are skipped.")
    add(
        "Layouts",
        "Every layout of the report; squares are anchors, arrows their aim (paper Fig. 7)."
        + (" Grey boxes: keep-outs; dashed: tag zones." if room.keepouts or room.zones else ""),
        lambda: F.layout_views(room, {e.name: e.anchors for e in layouts}, colors=colors, dpi=dpi),
    )
    if result is not None and result.get("history") and result.get("best_anchors_history"):
        history = _array(result["history"], "history", 1)
        bah = _array(result["best_anchors_history"], "best_anchors_history", 3)
        T = min(len(history), len(bah))
        add(
            "PSO evolution",
            f"Best {result.get('cost_name', 'cost')} per iteration and the PEB (m, σ = "
            f"{sigma:g} m) of the best layout at the marked iterations (paper Fig. 6).",
            lambda: F.pso_evolution(
                room,
                history[:T],
                bah[:T],
                sigma=sigma,
                nodes=nodes,
                cost_name=str(result.get("cost_name", "cost")),
                unit=_cost_unit(result.get("cost_name")),
                anchor_color=colors[best.name],
                dpi=dpi,
            ),
        )
    elif result is not None:
        notes.append("PSO evolution skipped: result.json has no history.")

    # palette PNGs are ~3× smaller but band colour scales: only for figures without one
    pngs = [
        F.png_bytes(f, palette=not any(a.get_gid() == "colorbar" for a in f.axes))
        for _, _, f in figs
    ]
    if figures_dir is not None:
        fdir = Path(figures_dir)
        fdir.mkdir(parents=True, exist_ok=True)
        for i, ((title, _, _), png) in enumerate(zip(figs, pngs, strict=True), 1):
            (fdir / f"{i:02d}-{_slug(title)}.png").write_bytes(png)
    body = _render(
        result_dir=Path(result_dir),
        data=data,
        room=room,
        nodes=nodes,
        sigma=sigma,
        layouts=layouts,
        colors=colors,
        figures=[(t, c, _data_uri(png)) for (t, c, _), png in zip(figs, pngs, strict=True)],
        notes=notes,
        elapsed=time.perf_counter() - t0,
    )
    return Report(body, [t for t, _, _ in figs], notes, layouts)


def write_report(
    result_dir: str | Path, out: str | Path | None = None, **kwargs
) -> tuple[Path, Report]:
    """Build the report and write it (default ``result_dir/report.html``); returns the path."""
    rep = build_report(result_dir, **kwargs)
    path = Path(out) if out is not None else Path(result_dir) / "report.html"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(rep.html, encoding="utf-8")
    return path, rep


def _cost_unit(name) -> str:
    return {"variance": "m²", "mean": "m", "p95": "m", "rms": "m", "peb": "m"}.get(
        str(name).lower(), ""
    )


def _slug(title: str) -> str:
    """File-name part from a figure title: ASCII letters and digits joined by '-'."""
    words = re.findall(r"[a-z0-9]+", title.lower().encode("ascii", "ignore").decode())
    return "-".join(words) or "figure"


def _data_uri(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


# -- HTML ----------------------------------------------------------------------------------
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


def _finite(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=float).ravel()
    return v[np.isfinite(v)]


def _pct(v, q) -> float:
    f = _finite(v)
    return float(np.percentile(f, q)) if f.size else math.nan


def _mean(v) -> float:
    f = _finite(v)
    return float(f.mean()) if f.size else math.nan


def _gap_rows(layouts, nodes, sigma, colors) -> tuple[list[list[str]], bool]:
    rows = []
    calibrated_any = False
    for e in layouts:
        if e.sim is None:
            continue
        p, r = e.peb, e.sim.rmse
        ok = np.isfinite(p) & np.isfinite(r) & (p > 0)
        ratio = float(np.median(r[ok] / p[ok])) if np.any(ok) else math.nan
        within = float(np.mean(r[ok] <= 2 * p[ok])) if np.any(ok) else math.nan
        cal = "–"
        if e.fresh is not None and e.fresh.range_errors is not None:
            try:
                from analysis.noise import calibrated_sigma

                s = calibrated_sigma(e.fresh.range_errors)
                cal = (
                    f"{_num(np.min(s))}–{_num(np.max(s))} m → "
                    f"{_num(_mean(peb(e.anchors, nodes, sigma=s)))}"
                )
                calibrated_any = True
            except (ImportError, ValueError):
                cal = "–"
        rows.append(
            [
                _swatch(colors.get(e.name, "#000"), e.name),
                _num(_mean(p)),
                _num(_mean(r)),
                _num(_pct(p, 50)),
                _num(_pct(r, 50)),
                _num(ratio, 2),
                _num(_pct(p, 95)),
                _num(_pct(r, 95)),
                "–" if math.isnan(within) else f"{100 * within:.0f} %",
                cal,
            ]
        )
    return rows, calibrated_any


def _render(
    *, result_dir, data, room, nodes, sigma, layouts, colors, figures, notes, elapsed
) -> str:
    result, evaluation = data["result"], data["evaluation"]
    best = layouts[0]
    ref = next((e for e in layouts if e.role == "reference"), None)
    sources = ", ".join(
        n for n, d in ((RESULT_FILE, result), (EVALUATION_FILE, evaluation)) if d is not None
    )
    now = _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z")
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>anchorplan report – {_e(room.name)}</title>",
        f"<style>{_CSS}</style></head><body><main>",
        f"<h1>anchorplan report — {_e(room.name)}, M = {len(best.anchors)}</h1>",
        f'<p class="sub">{_e(result_dir.name or str(result_dir))}: {_e(sources)} · '
        f"generated {_e(now)} · PEB = √tr J⁻¹ in metres at constant σ<sub>r</sub> = "
        f"{sigma:g} m</p>",
    ]
    # summary cards
    cards = []
    if best.sim is not None:
        st = best.sim.stats
        cards += [
            (f"{_num(st['std'])} m", f"σ of the error ({best.name})"),
            (f"{_num(st['mean'])} m", "mean error"),
            (f"{_num(st['p95'])} m", "P95 error"),
        ]
    cards.append((f"{_num(_mean(best.peb))} m", "mean PEB"))
    if ref is not None and ref.sim is not None and best.sim is not None:
        cards.append((f"{_num(ref.sim.stats['std'])} m", f"σ of the {ref.name} reference"))
    parts.append(
        '<div class="cards">'
        + "".join(f'<div class="card"><b>{v}</b><span>{_e(k)}</span></div>' for v, k in cards)
        + "</div>"
    )
    for n in notes:
        parts.append(f'<div class="note">{_e(n)}</div>')

    # settings
    parts.append("<h2>Settings</h2>")
    parts.append("<h3>Room</h3>")
    room_dict = room.to_dict()
    regions = [("keep-out", b) for b in room_dict.pop("keepouts", [])]
    regions += [("tag zone", b) for b in room_dict.pop("zones", [])]
    parts.append(_kv({**room_dict, "speed_of_sound (m/s)": round(room.speed_of_sound, 3)}))
    if regions:
        parts.append("<h3>Keep-outs and tag zones</h3>")
        parts.append(
            '<p class="sub">Boxes in room coordinates (m). No anchor may lie in a keep-out '
            "(hatched or grey in the figures); the room's evaluation nodes are a "
            f"{room.zone_spacing:g} m grid over the tag zones (dashed).</p>"
            if room.zones
            else '<p class="sub">Boxes in room coordinates (m). No anchor may lie in a '
            "keep-out (hatched or grey in the figures).</p>"
        )
        rows = [
            [_e(kind), _e(b.get("name", "")), _e(_num_list(b["min"])), _e(_num_list(b["max"]))]
            for kind, b in regions
        ]
        parts.append(_table(["kind", "name", "min (m)", "max (m)"], rows, left=2))
    if result is not None:
        run = {
            k: result[k]
            for k in ("cost_name", "cost", "nfev", "nit", "success", "message")
            if k in result
        }
        parts.append("<h3>Optimization</h3>")
        parts.append(_kv(run, header="result"))
        if result.get("settings"):
            parts.append(_kv(result["settings"]))
        if result.get("timings"):
            parts.append(_kv({k: v for k, v in result["timings"].items()}, header="time (s)"))
    if evaluation is not None:
        ev = {
            k: evaluation[k]
            for k in ("realizations", "seed", "snr_db", "seconds")
            if k in evaluation
        }
        parts.append("<h3>Evaluation</h3>")
        parts.append(_kv(ev))

    # statistics
    parts.append("<h2>Position error and bound</h2>")
    rows = []
    for e in layouts:
        s = e.sim
        rows.append(
            [
                _swatch(colors[e.name], e.name),
                str(len(e.anchors)),
                _e(s.source if s else "not simulated"),
                str(s.realizations) if s else "–",
                _num(s.stats["std"]) if s else "–",
                _num(s.stats["mean"]) if s else "–",
                _num(s.stats["p95"]) if s else "–",
                _num(s.stats["rms"]) if s else "–",
                _num(_mean(e.peb)),
                _num(_pct(e.peb, 95)),
                _num(e.cost, 4) if e.cost is not None else "–",
            ]
        )
    parts.append(
        _table(
            [
                "layout",
                "M",
                "simulated errors from",
                "R",
                "σ (m)",
                "mean (m)",
                "P95 (m)",
                "RMS (m)",
                "mean PEB (m)",
                "P95 PEB (m)",
                "cost",
            ],
            rows,
            left=1,
        )
    )
    parts.append(
        '<p class="sub">Euclidean position errors over all nodes and realizations; σ is the '
        "population standard deviation (the paper's figure of merit). PEB over the "
        f"{len(nodes)} evaluation nodes. cost: the plan's cost of that layout "
        f"({_e((result or {}).get('cost_name', '–'))}; seeds: first-iteration cost).</p>"
    )
    gap, cal = _gap_rows(layouts, nodes, sigma, colors)
    if gap:
        parts.append("<h3>Bound versus simulation (per node)</h3>")
        header = [
            "layout",
            "mean PEB",
            "mean RMSE",
            "median PEB",
            "median RMSE",
            "median RMSE/PEB",
            "P95 PEB",
            "P95 RMSE",
            "nodes with RMSE ≤ 2·PEB",
            "calibrated σ<sub>r</sub> → mean PEB",
        ]
        parts.append(_table(header, gap, left=1))
        parts.append(
            '<p class="sub">All lengths in metres. RMSE: per-node RMS Euclidean error over '
            f"the realizations; PEB at σ<sub>r</sub> = {sigma:g} m. "
            + (
                "Calibrated σ<sub>r</sub>: per-anchor inlier standard deviation of the "
                "simulated range errors (outliers beyond 3 MAD-σ removed, as the paper's "
                "0.03–0.045 m), and the mean PEB with it."
                if cal
                else "Calibrated σ<sub>r</sub> needs range errors simulated here."
            )
            + "</p>"
        )

    # coordinates
    parts.append("<h2>Layout coordinates</h2>")
    for e in layouts:
        surf = _nearest_surface(room, e.anchors)
        rows = [
            [str(j + 1), _num(a[0]), _num(a[1]), _num(a[2]), _e(s)]
            for j, (a, s) in enumerate(zip(e.anchors, surf, strict=True))
        ]
        table = _table(["#", "x (m)", "y (m)", "z (m)", "surface"], rows, left=0)
        head = f"{_swatch(colors[e.name], e.name)} (M = {len(e.anchors)}, {_e(e.role)})"
        if e.role == "seed":
            parts.append(f"<details><summary>{head}</summary>{table}</details>")
        else:
            parts.append(f"<h3>{head}</h3>{table}")

    # figures
    parts.append("<h2>Figures</h2>")
    for i, (title, caption, uri) in enumerate(figures, 1):
        parts.append(
            f'<figure><img src="{uri}" alt="{_e(title)}">'
            f"<figcaption><b>Figure {i}. {_e(title)}.</b> {_e(caption)}</figcaption></figure>"
        )

    parts.append("<h2>Software</h2>")
    parts.append(_table(["package", "version"], _versions(), left=2))
    parts.append(f'<p class="sub">Report built in {elapsed:.1f} s.</p>')
    parts.append("</main></body></html>")
    return "\n".join(parts) + "\n"

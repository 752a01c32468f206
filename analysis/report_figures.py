"""The figures of the HTML report (:mod:`analysis.report`), in display order.

Each step adds its figures to a list through :class:`_Figures`, which turns a figure that
cannot be drawn (bad or degenerate data) into a note instead of a failed report.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from analysis import figures as F
from analysis.report_data import Context, Figure, json_array
from simulation.statistics import cost_unit

logger = logging.getLogger(__name__)


class _Figures:
    """The figures made so far and the notes of those skipped."""

    def __init__(self, ctx: Context, dpi: float):
        self.ctx, self.dpi, self.out = ctx, dpi, []

    def add(self, title: str, caption: str, make, section: str = "figures") -> None:
        t = time.perf_counter()
        try:
            fig = make()
        except ValueError as exc:  # bad or degenerate data: say so, keep the report
            self.ctx.notes.append(f"Figure '{title}' skipped: {exc}")
            return
        self.out.append(Figure(title, caption, fig, section))
        logger.debug("figure %s in %.2f s", title, time.perf_counter() - t)


def make_figures(ctx: Context, dpi: float) -> list[Figure]:
    """Every figure of the report: the plan view (layout section), then PEB maps,
    simulated errors, the DOP map, the layouts and the PSO evolution."""
    figs = _Figures(ctx, dpi)
    _plan(figs)
    _coverage(figs)
    _peb(figs)
    if any(e.sim is not None for e in ctx.layouts):
        _simulated(figs)
        _dop(figs)
    else:
        ctx.notes.append("No simulated errors are available: simulated-error figures are skipped.")
    _layouts(figs)
    _history(figs)
    return figs.out


def _regions_note(ctx: Context) -> str:
    room = ctx.room
    if not (room.keepouts or room.zones):
        return ""
    return " Keep-outs (hatched) and tag zones (dashed) are projected too."


def _plan(figs: _Figures) -> None:
    ctx, best = figs.ctx, figs.ctx.best
    figs.add(
        f"Plan view of the {best.name} layout",
        "The anchors (numbered as in the coordinate table) seen from above and from the "
        "south; shaded or thick grey: the allowed mounting surfaces." + _regions_note(ctx),
        lambda: F.plan_view(ctx.room, best.anchors, color=ctx.colors[best.name], dpi=figs.dpi),
        section="layout",
    )


def _coverage(figs: _Figures) -> None:
    ctx, best, nodes = figs.ctx, figs.ctx.best, figs.ctx.nodes
    zs = np.unique(np.round(nodes[:, 2], 9))
    heights = sorted({float(zs[0]), float(zs[len(zs) // 2]), float(zs[-1])})
    figs.add(
        f"Coverage of the {best.name} layout",
        "The number of anchors each point hears (within the signal's reach"
        + (" and above the receiver's detection threshold" if ctx.system.receiver.false_alarm
           is not None else "")
        + f", reach {ctx.system.reach(ctx.room.speed_of_sound):.2f} m) on horizontal slices "
        f"at the node heights; a position needs 4{_k_note(ctx)}. Red hatching and line: fewer "
        f"than {_k(ctx)} heard." + _regions_note(ctx),
        lambda: F.coverage_map(
            ctx.room, best.anchors, heights=heights, anchor_color=ctx.colors[best.name],
            dpi=figs.dpi, system=ctx.system, k=_k(ctx),
        ),
        section="layout",
    )  # fmt: skip


def _k(ctx: Context) -> int:
    """The anchors a node needs with the plan's system: 5 where it rejects echoes, else 4."""
    return 5 if ctx.system.positioning.method == "robust" else 4


def _k_note(ctx: Context) -> str:
    return ", and 5 for this system to find an echo among them" if _k(ctx) == 5 else ""


def _peb(figs: _Figures) -> None:
    ctx, best, sigma, nodes = figs.ctx, figs.ctx.best, figs.ctx.sigma, figs.ctx.nodes
    room = ctx.room
    zs = np.unique(np.round(nodes[:, 2], 9))
    heights = sorted({float(zs[0]), float(zs[len(zs) // 2]), float(zs[-1])})
    figs.add(
        f"PEB map of the {best.name} layout",
        f"PEB = √tr J⁻¹ (m) at σ = {sigma:g} m on horizontal slices at the node heights and "
        f"a vertical cut at y = {room.size[1] / 2:g} m; anchors (numbered as in the "
        "coordinate table) are projected onto each plane (paper Figs. 1, 2, 6)."
        + _regions_note(ctx),
        lambda: F.peb_map(
            room,
            best.anchors,
            sigma=sigma,
            heights=heights,
            y_cuts=[room.size[1] / 2],
            anchor_color=ctx.colors[best.name],
            dpi=figs.dpi,
            system=ctx.system,
        ),
    )
    shown = [e for e in ctx.layouts if e.role != "initial"]
    figs.add(
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
            {e.name: e.peb for e in shown},
            {e.name: e.anchors for e in shown},
            colors=ctx.colors,
            dpi=figs.dpi,
        ),
    )


def _simulated(figs: _Figures) -> None:
    ctx, nodes = figs.ctx, figs.ctx.nodes
    simulated = [e for e in ctx.layouts if e.sim is not None]
    figs.add(
        "Simulated per-node RMSE",
        "Per-node RMS Euclidean position error (m) over the realizations ("
        + "; ".join(f"{e.name}: R = {e.sim.realizations}, {e.sim.source}" for e in simulated)
        + ") on one colour scale (paper Figs. 1, 2).",
        lambda: F.scatter3d_panels(
            ctx.room,
            nodes,
            {e.name: e.sim.rmse for e in simulated},
            {e.name: e.anchors for e in simulated},
            label="RMSE (m)",
            colors=ctx.colors,
            dpi=figs.dpi,
        ),
    )
    fresh = [e for e in ctx.layouts if e.fresh is not None and e.fresh.estimates is not None]
    if fresh:
        figs.add(
            "Error CDFs: Euclidean and per axis",
            "CDFs of the Euclidean and |x|, |y|, |z| position errors over all nodes and "
            f"realizations, R = {ctx.realizations} simulated for this report (paper Fig. 3); "
            "the legend gives each layout's P95.",
            lambda: F.error_cdfs(
                {e.name: e.fresh.errors for e in fresh},
                {e.name: e.fresh.estimates - nodes for e in fresh},
                colors=ctx.colors,
                dpi=figs.dpi,
            ),
        )
    else:
        figs.add(
            "Error CDFs: Euclidean",
            "CDF of the Euclidean position error over all nodes and realizations (per-axis "
            "errors are not stored in the JSON files).",
            lambda: F.error_cdfs(
                {e.name: e.sim.errors for e in simulated}, colors=ctx.colors, dpi=figs.dpi
            ),
        )
    figs.add(
        "Bound vs simulation",
        f"CDFs over nodes of the PEB (dashed, σ = {ctx.sigma:g} m) and the simulated per-node "
        "RMSE (solid): the horizontal distance is the gap between the bound and the "
        "realistic error, caused mostly by multipath outliers the range model of the bound "
        "does not contain (paper Figs. 5, 8).",
        lambda: F.bound_gap_cdfs(
            {e.name: e.peb for e in simulated},
            {e.name: e.sim.rmse for e in simulated},
            colors=ctx.colors,
            dpi=figs.dpi,
        ),
    )


def _paper_dop(e) -> np.ndarray | None:
    """The layout's per-node paper DOP: from its main data, else from this report's run."""
    for sim in (e.sim, e.fresh):
        if sim is not None and sim.dop is not None:
            return sim.dop
    return None


def _dop(figs: _Figures) -> None:
    ctx, best, ref = figs.ctx, figs.ctx.best, figs.ctx.reference
    a = None if ref is None or ref is best else _paper_dop(ref)
    b = _paper_dop(best)
    if a is None or b is None or not np.any(np.isfinite(a) & np.isfinite(b)):
        ctx.notes.append(
            "DOP difference map skipped: it needs per-node DOP (R ≥ 2) of both the "
            "corners reference and the best layout."
        )
        return
    figs.add(
        f"DOP difference {ref.name} → {best.name}",
        f"Per-node DOP of the {ref.name} layout minus that of the {best.name} layout, with the "
        "paper's DOP = σ/σ_r (§V-A): σ the standard deviation over the realizations of the "
        "node's Euclidean error and σ_r the mean over anchors of the range-error standard "
        f"deviation; blue: {best.name} better (paper Fig. 4). The RMS-based DOP (RMSE/σ_r, "
        "which also counts a steady multipath bias) is in the comparison table.",
        lambda: F.dop_difference(
            ctx.room,
            ctx.nodes,
            a,
            b,
            labels=(ref.name, best.name),
            anchors_a=ref.anchors,
            anchors_b=best.anchors,
            colors=ctx.colors,
            definition="paper",
            dpi=figs.dpi,
        ),
    )


def _layouts(figs: _Figures) -> None:
    ctx = figs.ctx
    room = ctx.room
    figs.add(
        "Layouts",
        "Every layout of the report; squares are anchors, arrows their aim (paper Fig. 7)."
        + (" Grey boxes: keep-outs; dashed: tag zones." if room.keepouts or room.zones else ""),
        lambda: F.layout_views(
            room, {e.name: e.anchors for e in ctx.layouts}, colors=ctx.colors, dpi=figs.dpi
        ),
    )


def _history(figs: _Figures) -> None:
    ctx, result = figs.ctx, figs.ctx.result
    if result is None:
        return
    if not (result.get("history") and result.get("best_anchors_history")):
        ctx.notes.append("PSO evolution skipped: result.json has no history.")
        return
    history = json_array(result["history"], "history", 1)
    bah = json_array(result["best_anchors_history"], "best_anchors_history", 3)
    T = min(len(history), len(bah))
    figs.add(
        "PSO evolution",
        f"Best {result.get('cost_name', 'cost')} per iteration and the PEB (m, σ = "
        f"{ctx.sigma:g} m) of the best layout at the marked iterations (paper Fig. 6).",
        lambda: F.pso_evolution(
            ctx.room,
            history[:T],
            bah[:T],
            sigma=ctx.sigma,
            nodes=ctx.nodes,
            cost_name=str(result.get("cost_name", "cost")),
            unit=cost_unit(result.get("cost_name")),
            anchor_color=ctx.colors[ctx.best.name],
            dpi=figs.dpi,
        ),
    )

"""One self-contained HTML report of a planning / evaluation result folder.

Reads ``RESULT_DIR/result.json`` (written by ``anchorplan plan``) and/or
``RESULT_DIR/evaluation.json`` (``anchorplan evaluate``). The report leads with what a user
opens it for and ends with how it was made:

1. the headline numbers of the layout (σ, mean and P95 of the simulated Euclidean error,
   mean PEB) beside those of the comparison layouts;
2. the layout: its coordinates and a plan view;
3. the comparison with a naive layout of the same M (given by the caller in
   ``comparisons``: ``anchorplan report`` adds :func:`placement.naive_layout`, anchors
   spread evenly along the top edges of the mounting walls) and with the paper's corners
   layout: error statistics, both per-node DOPs (the paper's and the RMS-based, labelled),
   the PEB, and the bound-versus-simulation gap;
4. the plan's validation sections when ``result.json`` has them (held-out nodes,
   mounting tolerance);
5. the figures of :mod:`analysis.figures` (embedded as base64 PNG ``data:`` URIs);
6. the other layouts' coordinates, then the settings (room, keep-outs and tag zones,
   optimization, timings per phase, evaluation) and the package versions.

The HTML has inline CSS only: no script, no external resource, no network
(:mod:`analysis.report_html`).

PEB = √tr J⁻¹ in metres at a constant range σ (the plan's ``settings.sigma``, default
0.04 m) is computed here with :func:`analysis.fim.peb`. Simulated errors come from the
JSON files; the layouts they lack (the corners and naive comparisons, per-axis errors,
range errors) are simulated here with :func:`simulation.evaluate_layout` for a small
number of realizations, when the simulator is available and ``realizations`` > 0. Every
statistic is one of :mod:`simulation.statistics`.
"""

from __future__ import annotations

import base64
import logging
import math
import re
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from analysis.coverage import bound
from analysis.fim import DEFAULT_SIGMA
from analysis.progress import ProgressBar, check_progress
from analysis.report_data import (
    Context,
    Figure,
    Report,
    collect_layouts,
    json_array,
    load_results,
    room_of,
    sim_from_evaluation,
    system_of,
)
from simulation import streams
from simulation.output import write_file

logger = logging.getLogger(__name__)


def _evaluator():
    """``simulation.evaluate_layout`` if the simulator is installed, else None."""
    try:
        import simulation
    except ImportError:  # pragma: no cover - simulation is part of the distribution
        return None
    return getattr(simulation, "evaluate_layout", None)


# -- simulation here -------------------------------------------------------------------------
def _simulate_missing(ctx: Context, seed: int, bar: ProgressBar) -> None:
    """Simulate (R = ``ctx.realizations``, common noise ``seed``) every layout but the
    starting layouts that has no fresh simulation: the corners and naive comparisons, and
    the per-axis and range errors the files do not store (one step of ``bar`` each)."""
    R = ctx.realizations
    evaluate = _evaluator() if R > 0 else None
    if R == 0:
        ctx.notes.append("Simulation in the report is disabled (realizations = 0).")
    elif evaluate is None:
        ctx.notes.append(
            "The simulator (simulation.evaluate_layout) is not available: figures of "
            "simulated errors for layouts without stored errors are skipped."
        )
    if evaluate is None:
        return
    todo = [e for e in ctx.layouts if e.role != "initial" and e.fresh is None]
    for i, e in enumerate(todo):
        bar.update(i, len(todo))
        try:
            ctx.room.check_anchors(e.anchors)
        except ValueError as exc:
            ctx.notes.append(f"{e.name}: not simulated ({exc}).")
            continue
        t = time.perf_counter()
        ev = evaluate(ctx.room, e.anchors, realizations=R, rng=seed, nodes=ctx.nodes,
                      system=ctx.system)  # the plan's system, as the plan's figures  # fmt: skip
        e.fresh = sim_from_evaluation(ev, f"simulated for this report (R = {R})")
        if e.sim is None:
            e.sim = e.fresh
        logger.info("simulated %s, R = %d, in %.1f s", e.name, R, time.perf_counter() - t)
    bar.close()


def _check_failures(ctx: Context) -> None:
    reach = ((ctx.result or {}).get("settings") or {}).get("reach") or {}
    if reach.get("exceeded"):
        ctx.notes.append(
            f"The room is larger than the signal's reach ({reach['reach_m']:.2f} m; mounting "
            f"points lie up to {reach['farthest_m']:.1f} m from the nodes): anchors farther "
            "than the reach give no range (see the coverage figure)."
        )
    for e in ctx.layouts:
        bad = e.sim.stats.get("n_invalid", 0) if e.sim is not None else 0
        if bad:
            share = e.sim.stats.get("availability", math.nan)
            ctx.notes.append(
                f"{e.name}: {bad} node realization(s) without a position fix "
                f"(availability {100 * share:.2f} %); σ, mean, P95 and RMS are over the fixes."
            )


# -- building ------------------------------------------------------------------------------
def build_report(
    result_dir: str | Path,
    *,
    realizations: int = 10,
    rng: int | np.random.Generator | None = 0,
    sigma: float | None = None,
    dpi: float = 100,
    figures_dir: str | Path | None = None,
    comparisons: Mapping[str, Any] | None = None,
    progress=False,
) -> Report:
    """Render the report of ``result_dir`` (see the module docstring).

    realizations: R for the layouts simulated here (comparisons, corners reference,
        per-axis errors); 0 disables all simulation here.
    rng: an int seed, a numpy Generator or None for those simulations; all of them share
        one seed (common random numbers). sigma: range σ (m) of the PEB (default: the
        plan's ``settings.sigma`` or 0.04 m). dpi: resolution of the embedded figures.
    figures_dir: if given, every figure is also written there as ``NN-title.png``.
    comparisons: layouts to compare with, name → anchors (M, 3) or a precomputed
        :class:`simulation.Evaluation`; e.g. ``{"naive": placement.naive_layout(room, M)}``
        (``anchorplan report`` adds that one). The corners layout is always added.
    progress: a bar per simulated layout (True), none (False) or a callable
        ``progress("report simulations", done, total)`` (:mod:`analysis.progress`).
    """
    if int(realizations) != realizations or realizations < 0:
        raise ValueError(f"realizations: must be an integer >= 0, got {realizations}")
    seed = streams.entropy("rng", rng)
    progress = check_progress(progress)
    t0 = time.perf_counter()
    ctx = _context(result_dir, sigma, int(realizations), comparisons)
    _simulate_missing(ctx, seed, ProgressBar(progress, "report simulations"))
    _check_failures(ctx)
    from analysis import report_figures  # matplotlib only when a report is built

    ctx.figures = report_figures.make_figures(ctx, dpi)
    _encode_figures(ctx.figures, figures_dir)
    ctx.elapsed = time.perf_counter() - t0
    from analysis.report_html import render

    return Report(render(ctx), [f.title for f in ctx.figures], ctx.notes, ctx.layouts)


def _context(result_dir, sigma, realizations: int, comparisons) -> Context:
    """Read the folder and collect the layouts with their PEB."""
    from analysis.figures import layout_colors

    data = load_results(result_dir)
    evaluation = data["evaluation"]
    room, system = room_of(data), system_of(data)
    nodes = (
        json_array(evaluation["nodes"], "evaluation nodes", 2)
        if evaluation is not None and evaluation.get("nodes") is not None
        else room.grid()
    )
    settings = (data["result"] or {}).get("settings") or {}
    if sigma is None:
        sigma = float(settings.get("sigma") or DEFAULT_SIGMA)
    if not (math.isfinite(sigma) and sigma > 0):
        raise ValueError(f"sigma: must be > 0 m, got {sigma}")
    layouts = collect_layouts(data, room, nodes, comparisons)
    for e in layouts:
        e.peb = bound(room, e.anchors, nodes, sigma, system=system)
    colors = layout_colors([e.name for e in layouts])
    return Context(Path(result_dir), data, room, nodes, sigma, layouts, colors, [], [],
                   realizations, system=system)  # fmt: skip


def _encode_figures(figures: list[Figure], figures_dir) -> None:
    """PNG data URIs of the figures (and files ``NN-title.png`` in ``figures_dir``)."""
    from analysis.figures import png_bytes

    fdir = None if figures_dir is None else Path(figures_dir)
    if fdir is not None:
        fdir.mkdir(parents=True, exist_ok=True)
    for i, f in enumerate(figures, 1):
        # palette PNGs are ~3× smaller but band colour scales: only for figures without one
        palette = not any(a.get_gid() == "colorbar" for a in f.figure.axes)
        png = png_bytes(f.figure, palette=palette)
        f.uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
        if fdir is not None:
            write_file(fdir / f"{i:02d}-{_slug(f.title)}.png", png)


def write_report(
    result_dir: str | Path, out: str | Path | None = None, **kwargs
) -> tuple[Path, Report]:
    """Build the report and write it (default ``result_dir/report.html``); returns the path."""
    rep = build_report(result_dir, **kwargs)
    path = Path(out) if out is not None else Path(result_dir) / "report.html"
    return write_file(path, rep.html), rep


def _slug(title: str) -> str:
    """File-name part from a figure title: ASCII letters and digits joined by '-'."""
    words = re.findall(r"[a-z0-9]+", title.lower().encode("ascii", "ignore").decode())
    return "-".join(words) or "figure"

"""Reproduce the paper's experiments (§V-A, §V-B, Table I) and compare bound-driven with
simulation-driven layouts (issue 7).

Sections (``--sections``, default all):

a. Four anchors, corners versus optimized (paper §V-A): σ / mean / P95 of the Euclidean
   error and mean DOP over ``--corner-realizations`` (paper: R = 500) for the corners layout,
   the paper-settings PSO layout and the ``seed_then_pso`` layout at M = 4; DOP-difference
   maps, error CDFs (Euclidean, |x|, |y|, |z|) and the PSO evolution (PEB at t = 1, mid, end).
b. Table I (paper §V-B): for each M, paper-settings PSO (``initial=None``: 15 particles,
   area-proportional random start, ≤ ``--iterations``, stop on small improvement, on the
   default cost) and ``seed_then_pso`` with its defaults (or its runs saved by
   bench_pso.py, ``--stp-from``), validated with ``--realizations`` (≥ 100): σ, mean,
   P95 beside the paper's values; error CDFs and layout views.
c. Bound-driven versus simulation-driven: for each M, the PEB-optimal layout
   (``relax_select`` A-optimal + ``refine_peb``), the PSO layout and the ``seed_then_pso``
   layout: mean PEB (√tr J⁻¹ in m, constant σ_r = 0.04 m), simulated σ / mean / P95,
   quantiles over nodes of RMSE / PEB, the fraction of nodes with RMSE > 2 × PEB, the robust
   range σ and outlier-range rate of the simulation, and the wall-clock seconds to obtain
   the layout; PEB-versus-RMSE CDFs per M.
d. Speed: seconds per PSO iteration and per evaluation of every PSO run, and one swarm
   batch (``--particles`` layouts) evaluated serially and on the process pool in the same run.

Every PSO runs once per (M, method, seed); all sections reuse the layouts. The layouts go
to ``OUT/layouts.json`` (updated after each PSO, so ``--resume`` skips finished runs),
every JSON line to ``OUT/results.jsonl`` (and stdout), figures to ``OUT/*.png``.

Run: python benchmarks/bench_paper.py [--anchors 4 6 8 10] [--seeds 0] [--workers 2]
     [--particles 15] [--iterations 40 | --iterations 4:40 10:25] [--realizations 100]
     [--corner-realizations 500] [--out docs/benchmarks] [--sections a b c d] [--resume]
Tiny smoke run: --anchors 4 --particles 4 --iterations 2 --realizations 5
     --corner-realizations 5 --out /tmp/bench_paper
"""

from __future__ import annotations

import os

# One BLAS/FFT thread per process: the process pool is the parallelism (and the serial
# versus pool comparison is then one core against two).
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import contextlib  # noqa: E402
import io  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _common import PAPER_TABLE1, emit  # noqa: E402

from analysis.fim import peb  # noqa: E402
from placement.costs import make_cost  # noqa: E402
from placement.plan import seed_then_pso  # noqa: E402
from placement.pso import PSOOptions, evaluate_swarm  # noqa: E402
from placement.serialization import to_jsonable  # noqa: E402
from placement.surfaces import random_layout  # noqa: E402
from placement.validation import ValidationOptions  # noqa: E402
from simulation import Room, evaluate_layout  # noqa: E402

SIGMA_R = 0.04  # m, range σ of the PEB (the library default, paper §V-A: 0.03-0.045 m)
OUTLIER_M = 0.2  # m: a range error beyond this (5 σ_r) counts as an outlier range
RATIO_QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95, 1.0)

#: paper values, §V-A (Table I is PAPER_TABLE1 in _common)
PAPER_CORNERS = {
    "corners": {"std": 1.362, "mean_dop": 2.52},
    "optimized": {"std": 0.811, "mean_dop": 1.74},
}

METHODS = {"pso": "paper-PSO", "stp": "seed_then_pso", "peb": "PEB-optimal"}
#: one colour per layout family in every figure (Okabe–Ito)
COLORS = {"corners": "#E69F00", "pso": "#0072B2", "stp": "#009E73", "peb": "#D55E00"}


# -- output --------------------------------------------------------------------------------
class Recorder:
    """``emit`` to stdout and append the same line to OUT/results.jsonl."""

    def __init__(self, path: Path, append: bool):
        self.path = path
        if not append and path.exists():
            path.unlink()

    def __call__(self, name: str, **fields) -> None:
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            emit(name, **to_jsonable(fields))
        line = buf.getvalue()
        print(line, end="", flush=True)
        with open(self.path, "a") as fh:
            fh.write(line)


def key(method: str, M: int, seed: int) -> str:
    return f"{method}/M{M}/s{seed}"


def label(method: str, M: int) -> str:
    return f"{METHODS.get(method, method)} M={M}"


# -- validation (runs in the worker processes) ------------------------------------------------
def validate(room: Room, anchors, realizations: int, seed: int, axis: bool) -> dict:
    """Simulated statistics of one layout: σ / mean / P95 over all R·P errors, per-node RMSE
    and DOP, range-error statistics, errors (R, P) and optionally signed axis errors."""
    t0 = time.perf_counter()
    ev = evaluate_layout(room, anchors, realizations=realizations, rng=seed)
    re = np.asarray(ev.range_errors)  # (R, P, M)
    med = np.median(re)
    robust = 1.4826 * float(np.median(np.abs(re - med)))
    outlier = np.abs(re) > OUTLIER_M
    # precision DOP: spread of the estimates about their own mean (no bias) over σ_r; the
    # paper's DOP (ev.dop) uses the standard deviation of the Euclidean error, the
    # RMS-based one (ev.dop_rms, docs/model.md) the RMS error, which includes the bias
    spread = np.sqrt(np.sum(np.var(np.asarray(ev.estimates), axis=0), axis=-1))
    sr = np.asarray(ev.range_std)
    dop_precision = np.full(sr.shape, np.inf)
    np.divide(spread, sr, out=dop_precision, where=sr > 0)
    out = {
        "stats": ev.stats,
        "n_unconverged": ev.n_unconverged,
        "rmse": np.asarray(ev.rmse),
        "dop": np.asarray(ev.dop),
        "dop_rms": np.asarray(ev.dop_rms),
        "dop_precision": dop_precision,
        "range_std": np.asarray(ev.range_std),
        "robust_range_sigma": robust,
        "outlier_range_fraction": float(outlier.mean()),
        "node_outlier_rate": outlier.mean(axis=(0, 2)),
        "noise_sigma": np.asarray(ev.noise_sigma),
        "errors": np.asarray(ev.errors, dtype=np.float32),
        "seconds": time.perf_counter() - t0,
    }
    if axis:
        out["axis_errors"] = np.asarray(ev.estimates - ev.nodes, dtype=np.float32)
    return out


def _mean_dop(dop) -> float:
    d = np.asarray(dop, float)
    d = d[np.isfinite(d)]
    return float(d.mean()) if d.size else math.inf


def _median_dop(dop) -> float:
    d = np.asarray(dop, float)
    d = d[np.isfinite(d)]
    return float(np.median(d)) if d.size else math.inf


# -- layouts -----------------------------------------------------------------------------------
def peb_optimal(room: Room, M: int, seed: int) -> dict:
    """A-optimal relaxation + CasADi refinement of mean PEB, timed."""
    from placement.refine import refine_peb
    from placement.relaxation import relax_select

    t0 = time.perf_counter()
    sel = relax_select(room, M, criterion="A", sigma=SIGMA_R, rng=seed)
    t1 = time.perf_counter()
    ref = refine_peb(room, sel.anchors, sigma=SIGMA_R, return_info=True)
    t2 = time.perf_counter()
    return {
        "method": "peb",
        "M": M,
        "seed": seed,
        "anchors": np.asarray(ref.anchors).tolist(),
        "seconds": t2 - t0,
        "relax_seconds": t1 - t0,
        "refine_seconds": t2 - t1,
        "relax_status": sel.message,
        "relax_value_m2": sel.cost_m2,
        "relax_lower_bound_m2": sel.lower_bound_m2,
        "relax_gap": sel.gap,
        "refine_status": ref.message,
        "mean_peb_relaxed_m": ref.initial_mean_peb_m,
        "mean_peb_refined_m": ref.mean_peb_m,
    }


def run_pso(room, M, seed, method, args, executor, ckpt_dir) -> dict:
    iters = args.iterations_for(M)
    options = args.pso_options()
    ckpt = None
    if ckpt_dir is not None:
        tag = f"p{args.particles}_i{iters}_tol{options.tol:g}_pat{options.patience}"
        ckpt = ckpt_dir / f"{method}_M{M}_s{seed}_{tag}.json"
    t0 = time.perf_counter()
    # "pso": the paper's unseeded swarm (on the default cost's common draws); "stp":
    # seed_then_pso with its defaults
    swarm = {"initial": None, "swarm": options} if method == "pso" else {}
    res = seed_then_pso(
        room,
        M,
        cost="variance",
        executor=executor,
        rng=seed,
        progress=False,
        validation=ValidationOptions(realizations=0),
        checkpoint=ckpt,
        **swarm,
    )
    seconds = time.perf_counter() - t0
    p = res.pso
    return {
        "method": method,
        "M": M,
        "seed": seed,
        "anchors": np.asarray(res.anchors).tolist(),
        # wall-clock to obtain the layout: seeding + PSO (a resumed PSO counts the elapsed
        # time stored in its checkpoint)
        "seconds": res.timings["total"] - res.timings.get("validation", 0.0),
        "invocation_seconds": seconds,
        "cost_variance_m2": res.cost,
        "nit": res.nit,
        "nfev": res.nfev,
        "max_iterations": iters,
        "particles": args.particles,
        "tol": options.tol,
        "patience": options.patience,
        "message": res.message,
        "history": list(res.history),
        "best_anchors_history": [np.asarray(a).tolist() for a in res.best_anchors_history],
        "timings": res.timings,
        "pso_elapsed": p.elapsed,
        "seconds_per_iteration": p.elapsed / max(res.nit, 1),
        "seconds_per_evaluation": p.elapsed / max(res.nfev, 1),
        "initial": [
            {"name": s.name, "mean_peb_m": s.mean_peb, "cost": s.cost} for s in res.initial
        ],
        "resumed_from_checkpoint": bool(ckpt is not None and p.elapsed > seconds + 1.0),
    }


def stp_from_bench_pso(path: Path, args) -> dict:
    """A seed_then_pso layout entry from a run that bench_pso.py saved (same seed, the
    library's current defaults); seconds = every phase but the validation."""
    r = json.loads(path.read_text())
    t = r["timings"]
    return {
        "method": "stp",
        "M": r["M"],
        "seed": r["seed"],
        "anchors": r["anchors"],
        "seconds": t["total"] - t.get("validation", 0.0),
        "cost_variance_m2": r["cost"],
        "nit": r["nit"],
        "nfev": r["nfev"],
        "max_iterations": args.iterations_for(r["M"]),
        "particles": args.particles,
        "message": r.get("message", ""),
        "history": r["history"],
        "timings": t,
        "seeds": r["seeds"],
        "from": str(path),
    }


# -- figures -----------------------------------------------------------------------------------
def figures_module():
    try:
        from analysis import figures

        return figures
    except ImportError:  # pragma: no cover - the figures module is optional here
        return None


def save_fig(fig, path: Path, rec) -> None:
    fig.savefig(path, dpi=fig.dpi)
    rec("figure", path=str(path), bytes=path.stat().st_size)


# -- sections ----------------------------------------------------------------------------------
def section_speed(room, args, executor, rec) -> None:
    """One swarm batch evaluated serially and on the pool, same layouts and noise streams."""
    if executor is None:
        rec("swarm_batch", skipped="--workers 1: no process pool")
        return
    for M in sorted({min(args.anchors), max(args.anchors)}):
        rng = np.random.default_rng(M)
        layouts = np.stack([random_layout(room, M, rng) for _ in range(args.particles)])
        cost = make_cost("variance", room, realizations=args.pso_realizations)
        # warm up the pool and this process: worker start-up and the first call (filter
        # design, FFT plans) are not the batch's; both are timed best of 2
        evaluate_swarm(cost, layouts, 99, 0, executor)
        evaluate_swarm(cost, layouts[:1], 99, 0, None)
        t_serial = t_pool = math.inf
        for _ in range(2):
            t0 = time.perf_counter()
            serial, _ = evaluate_swarm(cost, layouts, 7, 0, None)
            t1 = time.perf_counter()
            pooled, _ = evaluate_swarm(cost, layouts, 7, 0, executor)
            t2 = time.perf_counter()
            t_serial, t_pool = min(t_serial, t1 - t0), min(t_pool, t2 - t1)
        rec(
            "swarm_batch",
            M=M,
            particles=args.particles,
            workers=args.workers,
            serial_seconds=t_serial,
            pool_seconds=t_pool,
            speedup=t_serial / t_pool,
            seconds_per_evaluation_serial=t_serial / args.particles,
            seconds_per_evaluation_pool=t_pool / args.particles,
            same_costs=bool(np.array_equal(serial, pooled)),
            load_average=os.getloadavg(),
        )


def section_a(room, L, V, args, rec, out, figs) -> None:
    M, s = 4, args.seeds[0]
    rows = {"corners": V["corners"], "pso": V[key("pso", M, s)], "stp": V[key("stp", M, s)]}
    for name, v in rows.items():
        st = v["stats"]
        paper = PAPER_CORNERS["corners" if name == "corners" else "optimized"]
        rec(
            "corners_vs_optimized",
            layout=name,
            M=4,
            seed=None if name == "corners" else s,
            realizations=args.corner_realizations,
            std=st["std"],
            mean=st["mean"],
            p95=st["p95"],
            median=st["median"],
            max=st["max"],
            mean_dop=_mean_dop(v["dop"]),
            median_dop=_median_dop(v["dop"]),
            mean_dop_rms=_mean_dop(v["dop_rms"]),
            median_dop_rms=_median_dop(v["dop_rms"]),
            mean_dop_precision=_mean_dop(v["dop_precision"]),
            median_dop_precision=_median_dop(v["dop_precision"]),
            dop_finite_nodes=int(np.isfinite(v["dop"]).sum()),
            mean_range_sigma=float(np.mean(v["range_std"])),
            robust_range_sigma=v["robust_range_sigma"],
            n_unconverged=v["n_unconverged"],
            paper_std=paper["std"],
            paper_mean_dop=paper["mean_dop"],
            anchors=L["corners" if name == "corners" else key(name, M, s)]["anchors"],
        )
    if figs is None:
        return
    nodes = room.grid()
    corners = np.asarray(L["corners"]["anchors"])
    for name in ("pso", "stp"):
        fig = figs.dop_difference(
            room,
            nodes,
            rows["corners"]["dop"],
            rows[name]["dop"],
            labels=("corners", METHODS[name]),
            anchors_a=corners,
            anchors_b=np.asarray(L[key(name, M, s)]["anchors"]),
            colors={"corners": COLORS["corners"], METHODS[name]: COLORS[name]},
            dpi=80,
        )
        save_fig(fig, out / f"a_dop_difference_{name}_M4.png", rec)
    names = {"corners": "corners", "pso": METHODS["pso"], "stp": METHODS["stp"]}
    fig = figs.error_cdfs(
        {names[k]: v["errors"] for k, v in rows.items()},
        {names[k]: v["axis_errors"] for k, v in rows.items()},
        colors={names[k]: COLORS[k] for k in rows},
        title=f"M = 4, R = {args.corner_realizations}: corners vs optimized",
        dpi=80,
    )
    save_fig(fig, out / "a_error_cdfs_M4.png", rec)
    rec_pso = L[key("pso", M, s)]
    fig = figs.pso_evolution(
        room,
        rec_pso["history"],
        rec_pso["best_anchors_history"],
        cost_name="variance",
        unit="m²",
        dpi=80,
    )
    save_fig(fig, out / "a_pso_evolution_M4.png", rec)


def section_b(room, L, V, args, rec, out, figs) -> None:
    for M in args.anchors:
        for s in args.seeds:
            for method in ("pso", "stp"):
                k = key(method, M, s)
                st, lay = V[k]["stats"], L[k]
                paper = PAPER_TABLE1.get(M)
                rec(
                    "table1",
                    M=M,
                    method=METHODS[method],
                    seed=s,
                    realizations=V[k]["realizations"],
                    std=st["std"],
                    mean=st["mean"],
                    p95=st["p95"],
                    paper_std=paper and paper["std"],
                    paper_mean=paper and paper["mean"],
                    paper_p95=paper and paper["p95"],
                    beats_paper_std=paper and bool(st["std"] < paper["std"]),
                    beats_paper_p95=paper and bool(st["p95"] < paper["p95"]),
                    n_unconverged=V[k]["n_unconverged"],
                    pso_iterations=lay["nit"],
                    max_iterations=lay["max_iterations"],
                    particles=lay["particles"],
                    nfev=lay["nfev"],
                    pso_message=lay["message"],
                    anchors=lay["anchors"],
                )
    if figs is None:
        return
    s = args.seeds[0]
    for method in ("pso", "stp"):
        errs = {label(method, M): V[key(method, M, s)]["errors"] for M in args.anchors}
        fig = figs.error_cdfs(errs, title=f"{METHODS[method]}: Euclidean error CDF", dpi=80)
        save_fig(fig, out / f"b_error_cdfs_{method}.png", rec)
        fig = figs.layout_views(
            room,
            {label(method, M): np.asarray(L[key(method, M, s)]["anchors"]) for M in args.anchors},
            colors={label(method, M): COLORS[method] for M in args.anchors},
            dpi=70,
        )
        save_fig(fig, out / f"b_layouts_{method}.png", rec)


def section_c(room, L, V, args, rec, out, figs) -> None:
    nodes = room.grid()
    for M in args.anchors:
        for s in args.seeds:
            pebs, rmses = {}, {}
            for method in ("peb", "pso", "stp"):
                k = key(method, M, s)
                lay, v = L[k], V[k]
                a = np.asarray(lay["anchors"])
                pb = peb(a, nodes, SIGMA_R)
                rmse = np.asarray(v["rmse"])
                ok = np.isfinite(pb) & (pb > 0)
                ratio = rmse[ok] / pb[ok]
                gap_nodes = rmse > 2 * pb
                rate = np.asarray(v["node_outlier_rate"])
                rec(
                    "bound_vs_sim",
                    M=M,
                    seed=s,
                    layout=METHODS[method],
                    peb_definition=f"sqrt(tr J^-1) in m, constant sigma_r = {SIGMA_R} m",
                    mean_peb=float(np.mean(pb)),
                    max_peb=float(np.max(pb)),
                    realizations=v["realizations"],
                    std=v["stats"]["std"],
                    mean=v["stats"]["mean"],
                    p95=v["stats"]["p95"],
                    mean_rmse=float(np.mean(rmse)),
                    rmse_over_peb_quantiles={
                        f"q{int(q * 100)}": float(np.quantile(ratio, q)) for q in RATIO_QUANTILES
                    },
                    fraction_rmse_gt_2peb=float(np.mean(gap_nodes)),
                    robust_range_sigma=v["robust_range_sigma"],
                    outlier_range_fraction=v["outlier_range_fraction"],
                    outlier_rate_gap_nodes=float(rate[gap_nodes].mean())
                    if gap_nodes.any()
                    else None,
                    outlier_rate_other_nodes=float(rate[~gap_nodes].mean())
                    if (~gap_nodes).any()
                    else None,
                    seconds_to_obtain=lay["seconds"],
                    workers=1 if method == "peb" else args.workers,
                    anchors=lay["anchors"],
                )
                pebs[label(method, M)] = pb
                rmses[label(method, M)] = rmse
            if figs is not None and s == args.seeds[0]:
                fig = figs.bound_gap_cdfs(
                    pebs,
                    rmses,
                    colors={label(m, M): COLORS[m] for m in ("peb", "pso", "stp")},
                    title=f"M = {M}: PEB (σ_r = {SIGMA_R} m) vs simulated RMSE per node",
                    dpi=80,
                )
                save_fig(fig, out / f"c_bound_vs_sim_M{M}.png", rec)


def section_d_runs(L, args, rec) -> None:
    for M in args.anchors:
        for s in args.seeds:
            for method in ("pso", "stp"):
                lay = L[key(method, M, s)]
                rec(
                    "pso_speed",
                    M=M,
                    seed=s,
                    method=METHODS[method],
                    workers=args.workers,
                    particles=lay["particles"],
                    nit=lay["nit"],
                    nfev=lay["nfev"],
                    pso_seconds=lay["pso_elapsed"],
                    seeding_seconds=lay["timings"].get("seeding"),
                    seconds_per_iteration=lay["seconds_per_iteration"],
                    seconds_per_evaluation=lay["seconds_per_evaluation"],
                    resumed_from_checkpoint=lay["resumed_from_checkpoint"],
                )


# -- main --------------------------------------------------------------------------------------
def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--anchors", type=int, nargs="+", default=[4, 6, 8, 10], help="M list")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0], help="PSO seeds")
    ap.add_argument("--workers", type=int, default=2, help="process pool size (1: serial)")
    ap.add_argument("--particles", type=int, default=15)
    ap.add_argument(
        "--iterations",
        nargs="+",
        default=["40"],
        help="max PSO iterations: one number, or M:N pairs (e.g. 4:40 10:25; others: 40)",
    )
    ap.add_argument(
        "--tol",
        type=float,
        default=None,
        help="PSO stop: relative improvement below this over --patience iterations (0: never); "
        "default: PSOOptions()",
    )
    ap.add_argument("--patience", type=int, default=None, help="default: PSOOptions()")
    ap.add_argument("--pso-realizations", type=int, default=1, help="per cost evaluation")
    ap.add_argument(
        "--stp-from",
        metavar="DIR",
        help="take the seed_then_pso layouts from bench_pso.py's saved seeded runs in DIR",
    )
    ap.add_argument("--realizations", type=int, default=100, help="validation R (b, c)")
    ap.add_argument("--corner-realizations", type=int, default=500, help="R of section a")
    ap.add_argument("--validation-seed", type=int, default=2023, help="same for every layout")
    ap.add_argument("--out", default="docs/benchmarks", help="folder for JSON and figures")
    ap.add_argument("--checkpoint-dir", default=None, help="PSO checkpoints (resumable)")
    ap.add_argument("--sections", nargs="+", default=list("abcd"), choices=list("abcd"))
    ap.add_argument("--resume", action="store_true", help="reuse layouts in OUT/layouts.json")
    ap.add_argument("--no-figures", action="store_true")
    args = ap.parse_args()
    per_m, default = {}, 40
    for item in args.iterations:
        if ":" in item:
            m, n = item.split(":")
            per_m[int(m)] = int(n)
        else:
            default = int(item)
    args.iterations_for = lambda M: per_m.get(M, default)
    stop = {k: v for k, v in (("tol", args.tol), ("patience", args.patience)) if v is not None}
    args.pso_options = lambda: PSOOptions(**stop)
    if "a" in args.sections and 4 not in args.anchors:
        args.anchors = [4, *args.anchors]
    return args


def _record_run(args, rec) -> None:
    rec(
        "bench_paper_run",
        argv={k: v for k, v in vars(args).items() if not callable(v)}
        | {
            "iterations_for": {M: args.iterations_for(M) for M in args.anchors},
            "pso_options": args.pso_options().__dict__,
        },
        cpus=os.cpu_count(),
        load_average=os.getloadavg(),
        numpy=np.__version__,
        started_utc=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    )


def _stp_runs(args, store) -> None:
    """seed_then_pso layouts from bench_pso.py's saved runs (``--stp-from``)."""
    for M in args.anchors:
        for s in args.seeds:
            for name in (f"M{M}_s{s}.json", f"M{M}_s{s}_seeded.json"):
                path = Path(args.stp_from) / name
                if path.exists():
                    store(key("stp", M, s), stp_from_bench_pso(path, args))
                    break


def _layouts(room, args, sections, L, store, rec, executor, ckpt_dir) -> None:
    """Every layout the sections need: corners, PEB-optimal, paper-PSO, seed_then_pso."""
    store(
        "corners", {"method": "corners", "M": 4, "anchors": room.corners_layout(), "seconds": 0.0}
    )
    for M in args.anchors:
        for s in args.seeds:
            if "c" in sections and key("peb", M, s) not in L:
                store(key("peb", M, s), peb_optimal(room, M, s))
            if not sections & set("abcd"):
                continue
            for method in ("pso", "stp"):
                k = key(method, M, s)
                if k in L:
                    continue
                entry = run_pso(room, M, s, method, args, executor, ckpt_dir)
                store(k, entry)
                rec("layout", key=k, **{kk: vv for kk, vv in entry.items()
                                        if kk != "best_anchors_history"})  # fmt: skip


def _validation_jobs(args, sections) -> dict[str, tuple[int, bool]]:
    """Which layouts to validate: key -> (realizations, keep axis errors)."""
    jobs: dict[str, tuple[int, bool]] = {}
    if "a" in sections:
        s = args.seeds[0]
        for k in ("corners", key("pso", 4, s), key("stp", 4, s)):
            jobs[k] = (args.corner_realizations, True)
    methods = (("pso", "stp") if sections & set("bc") else ()) + (
        ("peb",) if "c" in sections else ()
    )
    for M in args.anchors:
        for s in args.seeds:
            for method in methods:
                jobs.setdefault(key(method, M, s), (args.realizations, False))
    return jobs


def _validations(room, args, sections, L, rec, executor) -> dict[str, dict]:
    jobs = _validation_jobs(args, sections)
    # biggest first for load balance: cost ~ R · M
    order = sorted(jobs, key=lambda k: -jobs[k][0] * len(L[k]["anchors"]))
    t0 = time.perf_counter()
    run = [(room, L[k]["anchors"], jobs[k][0], args.validation_seed, jobs[k][1]) for k in order]
    from placement.workers import run_jobs

    results = dict(zip(order, run_jobs(executor, validate, run), strict=True))
    V = {}
    for k, v in results.items():
        v["realizations"] = jobs[k][0]
        V[k] = v
        rec(
            "validation",
            key=k,
            realizations=jobs[k][0],
            seed=args.validation_seed,
            **v["stats"],
            mean_dop=_mean_dop(v["dop"]),
            mean_dop_rms=_mean_dop(v["dop_rms"]),
            robust_range_sigma=v["robust_range_sigma"],
            outlier_range_fraction=v["outlier_range_fraction"],
            n_unconverged=v["n_unconverged"],
            seconds=v["seconds"],
        )
    rec("validations_done", layouts=len(jobs), wall_seconds=time.perf_counter() - t0)
    return V


def main() -> None:
    args = parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    ckpt_dir = Path(args.checkpoint_dir) if args.checkpoint_dir else None
    if ckpt_dir is not None:
        ckpt_dir.mkdir(parents=True, exist_ok=True)
    rec = Recorder(out / "results.jsonl", append=args.resume)
    figs = None if args.no_figures else figures_module()
    room = Room.techtile()
    sections = set(args.sections)
    t_start = time.perf_counter()
    _record_run(args, rec)
    layouts_path = out / "layouts.json"
    L: dict[str, dict] = {}
    if args.resume and layouts_path.exists():
        L = json.loads(layouts_path.read_text())

    def store(k, entry):
        L[k] = to_jsonable(entry)
        layouts_path.write_text(json.dumps(L, indent=1))

    if args.stp_from:
        _stp_runs(args, store)
    executor = ProcessPoolExecutor(args.workers) if args.workers > 1 else None
    try:
        if "d" in sections:
            section_speed(room, args, executor, rec)
        _layouts(room, args, sections, L, store, rec, executor, ckpt_dir)
        V = _validations(room, args, sections, L, rec, executor)
        for name, section in (("a", section_a), ("b", section_b), ("c", section_c)):
            if name in sections:
                section(room, L, V, args, rec, out, figs)
        if "d" in sections:
            section_d_runs(L, args, rec)
    finally:
        if executor is not None:
            executor.shutdown()
    rec("bench_paper_done", wall_seconds=time.perf_counter() - t_start)


if __name__ == "__main__":
    main()

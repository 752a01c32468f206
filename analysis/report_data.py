"""The data of a report: the result files read, the layouts they describe and the
context that the report's figures (:mod:`analysis.report_figures`) and HTML
(:mod:`analysis.report_html`) are made from. :mod:`analysis.report` assembles them.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from simulation import checks
from simulation.room import Room
from simulation.statistics import dop, dop_rms, error_stats, node_rmse
from simulation.system import System

RESULT_FILE = "result.json"
EVALUATION_FILE = "evaluation.json"
#: the statistics of the simulated errors the report shows, as in ``error_stats``
SHOWN_STATS = ("std", "mean", "p95", "rms")


# -- data model ----------------------------------------------------------------------------
@dataclass
class Simulated:
    """Simulated Euclidean errors of one layout (metres).

    errors (R, P); rmse (P,) per-node RMS over realizations; dop (P,) the paper's DOP
    (standard deviation of the error / σ_r) and dop_rms (P,) the RMS-based one (RMSE / σ_r),
    None when unknown; stats {std, mean, p95, rms, median, n_invalid, availability};
    estimates (R, P, 3) and range_errors (R, P, M) when simulated here (the JSON files do
    not store them); source says where the numbers come from.
    """

    errors: np.ndarray
    rmse: np.ndarray
    dop: np.ndarray | None
    dop_rms: np.ndarray | None
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
    role: str  # "optimized", "evaluated", "comparison", "reference" or "initial"
    cost: float | None = None
    sim: Simulated | None = None  # the layout's main simulated data (files first)
    fresh: Simulated | None = None  # simulated for this report (with per-axis errors)
    peb: np.ndarray | None = field(default=None, repr=False)


@dataclass
class Figure:
    """A figure of the report: title, caption, the matplotlib figure, and its section
    ("layout": beside the coordinates; "figures": the figures section)."""

    title: str
    caption: str
    figure: Any
    section: str = "figures"
    uri: str = ""


@dataclass
class Report:
    """The rendered report: ``html`` text, figure titles, and notes on what was skipped."""

    html: str
    figures: list[str]
    notes: list[str]
    layouts: list[LayoutEntry]


@dataclass
class Context:
    """Everything the HTML needs: the inputs, the layouts (the first is the main one) and
    the figures, in display order."""

    result_dir: Path
    data: dict[str, dict | None]
    room: Room
    nodes: np.ndarray
    sigma: float
    layouts: list[LayoutEntry]
    colors: dict[str, str]
    notes: list[str]
    figures: list[Figure] = field(default_factory=list)
    realizations: int = 0
    elapsed: float = 0.0
    system: System = field(default_factory=System)

    @property
    def result(self) -> dict | None:
        """The run's result.json, if the folder has one."""
        return self.data.get("result")

    @property
    def evaluation(self) -> dict | None:
        """The run's evaluation.json, if the folder has one."""
        return self.data.get("evaluation")

    @property
    def best(self) -> LayoutEntry:
        """The main layout (the first)."""
        return self.layouts[0]

    @property
    def reference(self) -> LayoutEntry | None:
        """The reference layout the report compares with, if any."""
        return next((e for e in self.layouts if e.role == "reference"), None)


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


def room_of(data: dict[str, dict | None]) -> Room:
    """The room of a result folder's data (techtile when the files do not name one; the
    ``signal`` table of files written before the system was its own setting left out)."""
    main = data["result"] if data.get("result") is not None else data["evaluation"]
    if not main.get("room"):
        return Room.techtile()
    return Room.from_dict({k: v for k, v in main["room"].items() if k != "signal"})


def system_of(data: dict[str, dict | None]) -> System:
    """The system of a result folder's data: its ``system``; in files written before the
    system was its own setting, the room's ``signal`` table with the paper's positioning;
    else the paper's system."""
    main = data["result"] if data.get("result") is not None else data["evaluation"]
    if main.get("system"):
        return System.from_dict(main["system"])
    legacy = (main.get("room") or {}).get("signal") or {}
    chirp = {k: v for k, v in legacy.items() if k in {"f0", "f1", "duration"}}
    receiver = {k: v for k, v in legacy.items() if k not in chirp}
    if not legacy:
        return System()
    return System.from_dict({"signal": chirp, "receiver": receiver})


def main_anchors(data: dict[str, dict | None]) -> np.ndarray:
    """(M, 3) the layout the report is about: the plan's, else the evaluated one."""
    main = data["result"] if data.get("result") is not None else data["evaluation"]
    return json_array(main["anchors"], "anchors", 2)


def json_array(x, name: str, ndim: int | None = None) -> np.ndarray:
    """Float array from JSON lists (null → NaN)."""
    try:
        a = np.array(x, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected numbers") from None
    if ndim is not None and a.ndim != ndim:
        raise ValueError(f"{name}: expected {ndim} dimensions, got shape {a.shape}")
    return a


def _stats_from(src: dict | None, errors: np.ndarray | None) -> dict[str, float]:
    """The stored statistics when the block has them all, else those of the errors; with
    the ``median``, ``n_invalid`` and the ``availability`` (the share of realizations with
    a fix), stored or computed (NaN when neither)."""
    computed = error_stats(errors) if errors is not None else None
    if src and all(isinstance(src.get(k), int | float) for k in SHOWN_STATS):
        out = {k: float(src[k]) for k in SHOWN_STATS}
        out["n_invalid"] = int(src.get("n_invalid") or 0)
        for k in ("median", "availability"):
            stored = src.get(k)
            out[k] = (float(stored) if isinstance(stored, int | float)
                      else computed[k] if computed is not None else math.nan)  # fmt: skip
        return out
    if computed is not None:
        return {k: computed[k] for k in (*SHOWN_STATS, "median", "n_invalid", "availability")}
    return {**dict.fromkeys((*SHOWN_STATS, "median"), math.nan), "n_invalid": 0,
            "availability": math.nan}  # fmt: skip


def _per_node(per_node: dict, key: str, source: str, P: int) -> np.ndarray | None:
    v = per_node.get(key)
    if v is None:
        return None
    a = json_array(v, f"{source} per_node.{key}", 1)
    if a.size != P:
        raise ValueError(f"{source} per_node.{key}: expected {P} values, got {a.size}")
    return a


def _sim_from_json(block: dict, P: int, R: int | None, source: str) -> Simulated | None:
    """Simulated from a validation/evaluation block; None without errors or per-node RMSE.

    ``per_node.dop`` is the paper's DOP and ``per_node.dop_rms`` the RMS-based one."""
    errors = block.get("errors")
    per_node = block.get("per_node") or {}
    e = json_array(errors, f"{source} errors", 2) if errors is not None else None
    if e is not None and e.shape[1] != P:
        raise ValueError(f"{source} errors: expected (R, {P}) for {P} nodes, got {e.shape}")
    rmse = _per_node(per_node, "rmse", source, P)
    if rmse is None and e is not None:
        rmse = node_rmse(e)
    if rmse is None:
        return None
    if e is None:
        e = rmse[None, :]  # only the per-node RMSE is known; CDFs use it as one "realization"
    stats = _stats_from(block.get("stats", block), e)
    R = int(R or block.get("realizations") or e.shape[0])
    d, d_rms = _per_node(per_node, "dop", source, P), _per_node(per_node, "dop_rms", source, P)
    return Simulated(e, rmse, d, d_rms, stats, R, source)


def sim_from_evaluation(ev, source: str) -> Simulated:
    """Simulated from an :class:`simulation.Evaluation` (or anything with its arrays)."""
    errors = np.asarray(ev.errors, dtype=float)
    range_errors = np.asarray(ev.range_errors, dtype=float)
    return Simulated(
        errors=errors,
        rmse=node_rmse(errors),
        dop=dop(errors, range_errors),
        dop_rms=dop_rms(errors, range_errors),
        stats=_stats_from(None, errors),
        realizations=errors.shape[0],
        source=source,
        estimates=np.asarray(ev.estimates, dtype=float),
        range_errors=range_errors,
    )


# -- the layouts ---------------------------------------------------------------------------
def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and bool(np.allclose(a, b))


def _plan_layouts(result: dict, P: int) -> tuple[LayoutEntry, list[LayoutEntry]]:
    """The optimized layout (with its validation) and the swarm's starting layouts."""
    v = result.get("validation") or {}
    sim = _sim_from_json(v, P, v.get("realizations"), f"{RESULT_FILE} validation") if v else None
    cost = result.get("cost")
    best = LayoutEntry(
        "optimized",
        json_array(result["anchors"], "result anchors", 2),
        "optimized",
        None if cost is None else float(cost),
        sim,
    )
    initial = []
    # "seeds": the name in result files of earlier versions
    for i, s in enumerate(result.get("initial", result.get("seeds")) or []):
        c = s.get("cost")
        anchors = json_array(s["anchors"], f"initial[{i}] anchors", 2)
        name = f"initial {s.get('name', i + 1)}"
        initial.append(LayoutEntry(name, anchors, "initial", None if c is None else float(c)))
    return best, initial


def _add_evaluation(out: list[LayoutEntry], evaluation: dict, P: int) -> None:
    """The evaluated layout: merged into the optimized one when it is the same layout
    (the larger sample becomes its main data), else a layout of its own."""
    anchors = json_array(evaluation["anchors"], "evaluation anchors", 2)
    sim = _sim_from_json(evaluation, P, evaluation.get("realizations"), EVALUATION_FILE)
    if out and _same(out[0].anchors, anchors):
        if sim is not None and (out[0].sim is None or sim.realizations > out[0].sim.realizations):
            out[0].sim = sim
        return
    out.insert(1 if out else 0, LayoutEntry("evaluated", anchors, "evaluated", None, sim))


def _comparison(name: str, value) -> LayoutEntry:
    """A caller's comparison layout: anchors (M, 3), or an Evaluation of them."""
    if hasattr(value, "errors") and hasattr(value, "anchors"):
        anchors = json_array(value.anchors, f"comparisons[{name!r}]", 2)
        entry = LayoutEntry(name, anchors, "comparison")
        entry.sim = entry.fresh = sim_from_evaluation(value, f"given (R = {len(value.errors)})")
        return entry
    anchors = checks.reals(f"comparisons[{name!r}]", value)
    if anchors.ndim != 2 or anchors.shape[1] != 3:
        raise ValueError(f"comparisons[{name!r}]: expected anchors (M, 3), got {anchors.shape}")
    return LayoutEntry(str(name), anchors, "comparison")


def _check_layout(room: Room, entry: LayoutEntry) -> None:
    """A layout the report is about: ≥ 4 distinct anchors inside the room."""
    try:
        checks.distinct("anchors", room.check_anchors(entry.anchors))
    except ValueError as exc:
        raise ValueError(f"{entry.name} layout: {exc}") from None


def collect_layouts(
    data: dict[str, dict | None],
    room: Room,
    nodes: np.ndarray,
    comparisons: Mapping[str, Any] | None = None,
) -> list[LayoutEntry]:
    """Layouts of the report in display order: optimized, evaluated, the ``comparisons``
    (name → anchors (M, 3) or an Evaluation), the corners reference, the swarm's starting
    layouts."""
    P = len(nodes)
    result, evaluation = data.get("result"), data.get("evaluation")
    out: list[LayoutEntry] = []
    initial: list[LayoutEntry] = []
    if result is not None:
        best, initial = _plan_layouts(result, P)
        out.append(best)
    if evaluation is not None:
        _add_evaluation(out, evaluation, P)
    for name, value in (comparisons or {}).items():
        entry = _comparison(name, value)
        if not any(_same(e.anchors, entry.anchors) for e in out):
            out.append(entry)
    for e in out:
        _check_layout(room, e)
    corners = room.corners_layout()
    if not any(_same(e.anchors, corners) for e in out):
        out.append(LayoutEntry("corners", corners, "reference"))
    return out + initial

"""Validation of a planned layout: the paper's statistics and whether they hold where the
tags will be and as the anchors will be mounted (docs/model.md, "The whole chain:
seed_then_pso", step 5).

Three checks, each with its own independent noise:

- **grid**: the Euclidean error at the evaluation nodes (``room.grid()``, the paper's 270
  nodes in techtile) over many noise realizations: σ, mean, P95 as in the paper's Table I;
- **held-out nodes**: nodes the optimizer never scored: a regular grid with one more node
  per axis than the evaluation grid (techtile: 10 × 7 × 6 = 420 nodes; with tag zones,
  the zones gridded at 0.8 × their spacing) and uniform random points in the node region
  (in the zones when the room has zones);
- **mounting error**: the anchors mounted at a random in-plane offset within
  ``mount_tolerance`` of their planned points (several draws), positions solved with the
  planned points as an installed system would;
- **field**: what an installation delivers: in each draw, tags at uniform random points of
  the tag zones (the room's node region without zones) and the anchors mounted within
  ``mount_tolerance``, together, one noise realization; positions solved with the planned
  points, as for the mounting error.

Every check simulates the plan's system (:class:`simulation.System`: its chirp, receiver
and positioning; docs/model.md, "Positioning").
"""

from __future__ import annotations

import math
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.coverage import covered_share
from analysis.fim import DEFAULT_SIGMA, peb
from placement.coverage import K_LINE_OF_SIGHT, coverage_k
from placement.rangetable import check_mount_tolerance, mounted_points
from placement.tags import random_nodes
from placement.workers import run_calls
from simulation import checks, streams
from simulation.robust import VERIFIED
from simulation.room import Room
from simulation.statistics import dop, dop_rms, error_stats, node_rmse, node_std
from simulation.system import as_system


@dataclass(frozen=True)
class ValidationOptions:
    """How a planned layout is validated (:func:`validate_layout`).

    realizations : noise realizations at the evaluation nodes (the paper: 100; 0 skips
        the whole validation).
    held_out_realizations : noise realizations at the held-out nodes (0: skip them).
    random_nodes : uniform random held-out points.
    mount_draws : mounting-error draws at the evaluation nodes (0: skip).
    field_draws : draws of the field check (random tags and mounting error together;
        0: skip), each of ``random_nodes`` tags.
    precision : the receiver DSP's precision.
    """

    realizations: int = 100
    held_out_realizations: int = 10
    random_nodes: int = 300
    mount_draws: int = 10
    field_draws: int = 10
    precision: str = "float32"

    def __post_init__(self) -> None:
        checks.count("realizations", self.realizations, low=0, high=100_000)
        checks.count("held_out_realizations", self.held_out_realizations, low=0, high=10_000)
        checks.count("random_nodes", self.random_nodes, low=1, high=100_000)
        checks.count("mount_draws", self.mount_draws, low=0, high=10_000)
        checks.count("field_draws", self.field_draws, low=0, high=10_000)
        checks.choice("precision", self.precision, ("float64", "float32"))


@dataclass(frozen=True)
class ErrorSummary:
    """Euclidean position errors summarized over the fixes: σ (population), mean, P95,
    RMS and median (m), ``n`` fixes, ``n_invalid`` realizations without one, the
    availability, n / (n + n_invalid) (:func:`simulation.statistics.error_stats`), and
    ``verified``, the share of the realizations whose fix is verified (5 or more anchors
    consistent, :mod:`simulation.robust`; 0 for a least-squares system)."""

    std: float
    mean: float
    p95: float
    rms: float
    n: int
    n_invalid: int
    availability: float
    median: float = math.nan
    verified: float = math.nan

    def summary_dict(self) -> dict[str, Any]:
        """The eight figures as a plain dict, in the order above."""
        return {k: getattr(self, k) for k in _SUMMARY_KEYS}

    @staticmethod
    def summary_from(d: dict[str, Any]) -> dict[str, Any]:
        """The eight figures' keyword arguments from a JSON block (nulls as NaN)."""
        return {k: _num(d.get(k), int if k.startswith("n") else float) for k in _SUMMARY_KEYS}

    @staticmethod
    def read(d: dict[str, Any] | None) -> ErrorSummary | None:
        """An :class:`ErrorSummary` from a JSON block, None for an absent one."""
        return None if not d else ErrorSummary(**ErrorSummary.summary_from(d))


@dataclass(frozen=True)
class NodesSummary(ErrorSummary):
    """One held-out node set's errors and its ``nodes`` count."""

    nodes: int = 0

    def to_dict(self) -> dict[str, Any]:
        return {**self.summary_dict(), "nodes": self.nodes}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> NodesSummary:
        return cls(**cls.summary_from(d), nodes=int(d["nodes"]))


@dataclass(frozen=True)
class HeldOut:
    """The held-out check: ``realizations`` per node at the held-out ``grid`` and at the
    ``random`` points (:class:`NodesSummary` each)."""

    realizations: int
    grid: NodesSummary
    random: NodesSummary

    def to_dict(self) -> dict[str, Any]:
        return {"realizations": self.realizations, "grid": self.grid.to_dict(),
                "random": self.random.to_dict()}  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> HeldOut:
        return cls(int(d["realizations"]), NodesSummary.from_dict(d["grid"]),
                   NodesSummary.from_dict(d["random"]))  # fmt: skip


@dataclass(frozen=True)
class MountingCheck(ErrorSummary):
    """The mounting-error check: the errors at the evaluation nodes over ``draws``
    mountings within ``tolerance_m`` of the plan."""

    tolerance_m: float = 0.0
    draws: int = 0

    def to_dict(self) -> dict[str, Any]:
        return {"tolerance_m": self.tolerance_m, "draws": self.draws, **self.summary_dict()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> MountingCheck:
        return cls(**cls.summary_from(d), tolerance_m=float(d["tolerance_m"]),
                   draws=int(d["draws"]))  # fmt: skip


@dataclass(frozen=True)
class FieldCheck(ErrorSummary):
    """The field check: ``draws`` of ``tags_per_draw`` random tags with the anchors mounted
    within ``tolerance_m`` of the plan."""

    draws: int = 0
    tags_per_draw: int = 0
    tolerance_m: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        return {"draws": self.draws, "tags_per_draw": self.tags_per_draw,
                "tolerance_m": self.tolerance_m, **self.summary_dict()}  # fmt: skip

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> FieldCheck:
        return cls(**cls.summary_from(d), draws=int(d["draws"]),
                   tags_per_draw=int(d["tags_per_draw"]),
                   tolerance_m=float(d["tolerance_m"]))  # fmt: skip


#: the per-node figures of the grid check
PER_NODE_KEYS = ("availability", "rmse", "std", "dop", "dop_rms", "verified")


@dataclass(frozen=True, eq=False)  # arrays: compare ``to_dict()``
class Validation:
    """What :func:`validate_layout` found (the ``validation`` of ``result.json``).

    The grid check: ``realizations`` noise realizations at the evaluation nodes from the
    int ``seed``; ``std``, ``mean``, ``p95``, ``rms`` (m) over the fixes among the R · P
    errors, ``n_invalid`` without a fix and the ``availability``; ``mean_peb`` (m, √tr J⁻¹
    at the constant σ of ``peb_definition``); ``per_node`` (P,) arrays by
    :data:`PER_NODE_KEYS` (availability, RMSE, σ, the paper's DOP, the RMS-based DOP);
    ``errors`` (R, P) m, NaN without a fix; ``median`` (m); ``verified`` the share of
    verified fixes; ``covered`` the share of the nodes that see at least ``coverage_k``
    anchors in line of sight and reach (:func:`analysis.coverage.covered_share`). Then the
    other checks that
    ran (None otherwise): ``held_out``, ``mounting``, ``field``; and a ``message`` when
    some realizations have no fix or some errors are not finite.
    """

    realizations: int
    seed: int
    std: float
    mean: float
    p95: float
    rms: float
    n_invalid: int
    availability: float
    mean_peb: float
    peb_definition: str
    per_node: dict[str, np.ndarray]
    errors: np.ndarray
    median: float = math.nan
    verified: float = math.nan
    coverage_k: int = K_LINE_OF_SIGHT
    covered: float = math.nan
    held_out: HeldOut | None = None
    mounting: MountingCheck | None = None
    field: FieldCheck | None = None
    message: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """The plain-JSON form (errors rounded to the µm)."""
        out: dict[str, Any] = {
            k: getattr(self, k)
            for k in ("realizations", "seed", "std", "mean", "p95", "rms", "median",
                      "verified", "n_invalid", "availability", "mean_peb", "peb_definition",
                      "coverage_k", "covered")
        }  # fmt: skip
        out["per_node"] = {k: np.asarray(v).tolist() for k, v in self.per_node.items()}
        out["errors"] = np.round(np.asarray(self.errors, dtype=float), 6).tolist()
        for key in ("held_out", "mounting", "field"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key).to_dict()
        if self.message is not None:
            out["message"] = self.message
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any] | None) -> Validation | None:
        """Read back :meth:`to_dict` (None for an empty or absent block)."""
        if not d:
            return None
        blocks = {"held_out": HeldOut, "mounting": MountingCheck, "field": FieldCheck}
        return cls(
            realizations=int(d["realizations"]),
            seed=int(d["seed"]),
            **{k: _num(d.get(k)) for k in ("std", "mean", "p95", "rms", "median",
                                           "verified", "availability", "mean_peb")},
            n_invalid=int(d.get("n_invalid", 0)),
            coverage_k=int(d.get("coverage_k", K_LINE_OF_SIGHT)),
            covered=_num(d.get("covered")),
            peb_definition=str(d.get("peb_definition", "")),
            per_node={k: _array(v) for k, v in d.get("per_node", {}).items()},
            errors=_array(d.get("errors", [])),
            **{k: c.from_dict(d[k]) for k, c in blocks.items() if d.get(k)},
            message=d.get("message"),
        )  # fmt: skip


_SUMMARY_KEYS = ("std", "mean", "p95", "rms", "n", "n_invalid", "availability", "median",
                 "verified")  # fmt: skip


def _num(v, kind=float):
    """A JSON number (null: NaN for a float)."""
    return math.nan if v is None and kind is float else kind(v)


def _array(v) -> np.ndarray:
    """A JSON array of numbers (nulls as NaN)."""
    return np.array(v, dtype=float)


def summary(errors, verified=None) -> dict[str, float]:
    """σ (population), mean, P95, RMS and median (m) of the fixes among Euclidean errors,
    how many, the availability, the share of node realizations with a fix
    (:func:`simulation.statistics.error_stats`), and the share of verified fixes among
    them (``verified``: booleans of the errors' shape; None: NaN)."""
    s = error_stats(np.asarray(errors, dtype=float).ravel())
    s["verified"] = math.nan if verified is None else float(np.mean(verified))
    return {k: s[k] for k in _SUMMARY_KEYS}


def held_out_grid(room: Room) -> np.ndarray:
    """(P', 3) held-out regular nodes: one more node per axis than the default grid, or
    the tag zones gridded at 0.8 × ``zone_spacing``."""
    if not room.zones:
        return room.grid((10, 7, 6))
    import dataclasses

    finer = dataclasses.replace(room, zone_spacing=0.8 * room.zone_spacing)
    return finer.grid()


def _evaluate(room, system, anchors, nodes, realizations, seed, precision):
    from simulation.evaluation import evaluate_layout

    return evaluate_layout(room, anchors, realizations=realizations, rng=seed, nodes=nodes,
                           precision=precision, system=system)  # fmt: skip


def mounted_errors(
    room, anchors, nodes, tolerance, draw, seed, precision=None, stream: int = 7, system=None
) -> np.ndarray:
    """(2, P): row 0 the position errors (m) at ``nodes`` when the anchors (M, 3) are
    mounted within ``tolerance`` m of the plan as in draw ``draw`` of ``seed``, one noise
    draw from the stream ``(stream, draw)`` of ``seed``, positions solved with the planned
    anchors by the ``system``'s positioning (``precision``: the receiver DSP's, None for the
    default); row 1 whether each fix is verified (1.0) or not (0.0)."""
    system = as_system(system)
    ranges = _mounted_ranges(room, system, anchors, nodes, tolerance, draw, seed, precision,
                             stream)  # fmt: skip
    return _errors(room, system, anchors, nodes, ranges)


def field_tags(room, tags: int, draw, seed) -> np.ndarray:
    """(tags, 3) the tag points of draw ``draw`` of the field check (:func:`field_errors`):
    uniform random points of the room's tag zones (:func:`random_nodes`), the stream
    (0, draw) of ``seed``."""
    return random_nodes(room, tags, streams.stream(seed, 0, draw))


def field_errors(
    room, anchors, tags: int, tolerance, draw, seed, precision=None, system=None
) -> np.ndarray:
    """(2, tags): the position errors (m) and whether each fix is verified, of draw
    ``draw`` of the field check: ``tags`` uniform random tag points (:func:`random_nodes`,
    the stream (0, draw) of ``seed``) with the anchors (M, 3) mounted within ``tolerance``
    m (:func:`mounted_errors`' mounting of the same draw), one noise realization,
    positions solved by the ``system``'s positioning."""
    nodes = field_tags(room, tags, draw, seed)
    return mounted_errors(room, anchors, nodes, tolerance, draw, seed, precision, 1, system)


def _mounted_ranges(room, system, anchors, nodes, tolerance, draw, seed, precision, stream):
    """(P, M) ranges of one noise draw with the anchors mounted as in draw ``draw``."""
    from simulation.evaluation import DEFAULT_PRECISION, RangingScene

    ids = np.arange(len(anchors))
    mounted = mounted_points(room, anchors, ids, draw, tolerance, False, seed)
    scene = RangingScene(room, mounted, nodes, system=system,
                         precision=precision or DEFAULT_PRECISION)  # fmt: skip
    return scene.ranges(
        np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(stream, draw)))
    )


def _errors(room, system, anchors, nodes, ranges) -> np.ndarray:
    """(2, P) errors (m) of the positions solved from ``ranges`` with the planned anchors by
    the ``system``'s positioning, and whether each fix is verified (1.0, else 0.0)."""
    fix = system.positioning.locate(room, anchors, ranges, full_output=True)
    return np.stack([np.linalg.norm(fix.x - nodes, axis=-1), fix.verified.astype(float)])


def validate_layout(
    room: Room,
    anchors,
    *,
    rng,
    options: ValidationOptions | None = None,
    mount_tolerance: float = 0.03,
    nodes=None,
    sigma: float = DEFAULT_SIGMA,
    executor: Executor | None = None,
    progress=None,
    system=None,
) -> Validation | None:
    """The four checks of the module docstring for anchors (M, 3) with ``system`` (default
    the paper's): a :class:`Validation` (None with ``options.realizations == 0``). Each
    check draws its noise from its
    own stream of ``rng`` (an int seed, a numpy Generator drawn once, or None). Checks run
    on ``executor`` when given; the result does not depend on it. ``progress(done,
    total)`` is called as the checks' parts finish.
    """
    opt = options or ValidationOptions()
    seed = streams.entropy("rng", rng)
    mount_tolerance = check_mount_tolerance(mount_tolerance)
    a = np.asarray(anchors, dtype=float)
    nodes = room.grid() if nodes is None else np.asarray(nodes, dtype=float)
    if opt.realizations == 0:
        return None
    calls = _calls(room, as_system(system), a, nodes, opt, mount_tolerance, seed)
    flat = [c for group in calls.values() for c in group]
    results = iter(run_calls(executor, flat, progress=progress))
    jobs = {name: [next(results) for _ in group] for name, group in calls.items()}
    grid = _grid_block(jobs["grid"], a, nodes, opt, seed, sigma)
    system = as_system(system)
    grid["coverage_k"] = coverage_k(system)
    grid["covered"] = covered_share(room, a, nodes, system=system, k=grid["coverage_k"])
    message = None
    if grid["availability"] < 1:
        message = (
            f"{100 * (1 - grid['availability']):.2f} % of the node realizations have no fix "
            "(fewer than 4 anchors heard); the statistics are over the fixes"
        )
    elif not math.isfinite(grid["std"]):
        message = "some position errors are not finite"
    return Validation(**grid, **_other_blocks(jobs, opt, mount_tolerance), message=message)


def _calls(room, system, a, nodes, opt: ValidationOptions, tolerance: float, seed: int) -> dict:
    """The validation's work by check, as (function, args) calls, each on its own stream of
    ``seed``."""
    child = [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(seed).spawn(5)]
    # the grid check in two halves, each with its own stream, to keep two workers busy
    halves = [opt.realizations - opt.realizations // 2, opt.realizations // 2]
    halves_seeds = [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(child[0]).spawn(2)]
    P = opt.precision
    calls: dict[str, list] = {
        "grid": [(_evaluate, (room, system, a, nodes, R, s, P))
                 for R, s in zip(halves, halves_seeds, strict=True) if R > 0]
    }  # fmt: skip
    if opt.held_out_realizations:
        R = opt.held_out_realizations
        rnd = random_nodes(room, opt.random_nodes, np.random.default_rng(child[1]))
        held = held_out_grid(room)
        calls["held_grid"] = [(_evaluate, (room, system, a, held, R, child[2], P))]
        calls["held_random"] = [(_evaluate, (room, system, a, rnd, R, child[3], P))]
    if opt.mount_draws and tolerance > 0:
        calls["mounting"] = [
            (mounted_errors, (room, a, nodes, tolerance, d, child[0], P, 7, system))
            for d in range(opt.mount_draws)
        ]
    if opt.field_draws:
        tags = opt.random_nodes
        calls["field"] = [
            (field_errors, (room, a, tags, tolerance, d, child[4], P, system))
            for d in range(opt.field_draws)
        ]
    return calls


def _grid_block(parts, a, nodes, opt: ValidationOptions, seed, sigma) -> dict[str, Any]:
    """The grid check's fields of :class:`Validation` from its evaluations ``parts``."""
    e = np.concatenate([p.errors for p in parts])
    range_errors = np.concatenate([p.range_errors for p in parts])
    verified = np.concatenate([p.fix_quality == VERIFIED for p in parts])
    return {
        "realizations": int(opt.realizations),
        "seed": int(seed),
        **{k: v for k, v in summary(e, verified).items() if k != "n"},
        "mean_peb": float(np.mean(peb(a, nodes, sigma))),
        "peb_definition": f"sqrt(tr J^-1), metres, sigma_r = {sigma:g} m",
        "per_node": {
            "availability": np.mean(np.isfinite(e), axis=0),
            "rmse": node_rmse(e),
            "std": node_std(e),
            "dop": dop(e, range_errors),
            "dop_rms": dop_rms(e, range_errors),
            "verified": np.mean(verified, axis=0),
        },
        "errors": e,
    }


def _other_blocks(jobs: dict, opt: ValidationOptions, tolerance: float) -> dict[str, Any]:
    """The ``held_out``, ``mounting`` and ``field`` checks that ran."""
    out: dict[str, Any] = {}
    if "held_grid" in jobs:
        (g,), (r,) = jobs["held_grid"], jobs["held_random"]
        out["held_out"] = HeldOut(
            int(opt.held_out_realizations),
            NodesSummary(**summary(g.errors, g.fix_quality == VERIFIED), nodes=int(len(g.nodes))),
            NodesSummary(**summary(r.errors, r.fix_quality == VERIFIED), nodes=int(len(r.nodes))),
        )
    if "mounting" in jobs:
        both = np.concatenate(jobs["mounting"], axis=1)  # (2, draws · P)
        mounting = summary(both[0], both[1] > 0)
        out["mounting"] = MountingCheck(**mounting, tolerance_m=float(tolerance),
                                        draws=int(opt.mount_draws))  # fmt: skip
    if "field" in jobs:
        both = np.concatenate(jobs["field"], axis=1)  # (2, draws · tags)
        out["field"] = FieldCheck(**summary(both[0], both[1] > 0), draws=int(opt.field_draws),
                                  tags_per_draw=int(opt.random_nodes),
                                  tolerance_m=float(tolerance))  # fmt: skip
    return out


__all__ = [
    "ErrorSummary",
    "FieldCheck",
    "HeldOut",
    "MountingCheck",
    "NodesSummary",
    "Validation",
    "ValidationOptions",
    "field_errors",
    "held_out_grid",
    "mounted_errors",
    "random_nodes",
    "validate_layout",
]

"""A catalogue of bad inputs to the library and the CLI, and what each one gets.

Run: python benchmarks/bad_inputs.py [--only CATEGORY] [--timeout 5]
Prints one JSON line per case and a summary line with the counts (overall, and without
the ``plan`` group: seed_then_pso and its options, whose checks belong to the optimizer).

Each API case runs in a forked child (killed after ``--timeout`` seconds: "hang"); each CLI
case runs ``anchorplan`` as a subprocess. Outcomes:

- ``clear``: ValueError (API) or exit code 2 with one line on stderr (CLI) that names the
  argument or file, within the time limit;
- ``handled``: a case where the right answer is not an error (a seed accepted as ``rng``,
  collinear anchors flagged, options honoured) and the check passed;
- ``unclear``: the right kind of error, but the message does not name the argument;
- ``wrong_type``: another exception (TypeError, MemoryError, ...), or a CLI exit code 1;
- ``traceback``: the CLI printed a traceback;
- ``accepted``: no error (or the check of a ``handled`` case failed);
- ``hang``: no answer within the time limit; ``slow``: an answer after it.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing as mp
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

import analysis
import placement
from analysis import figures
from placement.plan import seed_then_pso
from placement.pso import PSOOptions, pso
from placement.rangetable import range_table
from simulation import Room, evaluate_layout, locate, simulate_ranges
from simulation.multipath import image_indices
from simulation.noise import noise_sigma

ROOM = Room.techtile()
A = ROOM.corners_layout()
NODES = ROOM.grid()[::27]  # 10 nodes: an accepted case stays fast
CASES: list[dict] = []


def api(category, label, name, fn, group="core", check=None):
    CASES.append(
        dict(kind="api", category=category, input=label, name=name, fn=fn, group=group, check=check)
    )


def cli(category, argv, name, group="core"):
    CASES.append(
        dict(
            kind="cli",
            category=category,
            input="anchorplan " + " ".join(argv),
            name=name,
            argv=argv,
            group=group,
        )
    )


def peb_cost(anchors, rng=None):
    return float(np.mean(analysis.peb(anchors, NODES)))


def one_arg_cost(anchors):
    return float(np.mean(analysis.peb(anchors, NODES)))


FAST = PSOOptions(particles=3, iterations=1)
BAD_COUNTS = [True, False, 2.5, "3", -1, None, [3], float("nan")]
PLAN_KW = dict(cost="peb", initial=None, swarm=FAST, progress=False, rng=0)
PLAN_KW["validation"] = placement.ValidationOptions(realizations=0)
BAD_REALS = [True, "1", None, float("nan"), float("inf"), [1.0], 1j]


# -- counts: bools, floats, strings -------------------------------------------------------
def _simulation_count_cases() -> None:
    """Counts of the simulation: bools, floats, strings."""
    for v in [*BAD_COUNTS, 13, 200, 1000]:
        api("counts", f"Room(max_order={v!r})", "max_order", lambda v=v: Room(max_order=v))
    for v in [*BAD_COUNTS, 0, 10**9, 10**7]:
        api(
            "counts",
            f"evaluate_layout(realizations={v!r})",
            "realizations",
            lambda v=v: evaluate_layout(ROOM, A, realizations=v, nodes=NODES),
        )
    for v in [1.7, -1, "0", True, [1, 2]]:
        api(
            "counts",
            f"evaluate_layout(rng={v!r})",
            "rng",
            lambda v=v: evaluate_layout(ROOM, A, rng=v, nodes=NODES),
        )
    from simulation import Positioning

    for v in [0, 1.5, True]:  # the solver's settings are the system's positioning
        api("counts", f"Positioning(max_iter={v!r})", "max_iter",
            lambda v=v: Positioning(max_iter=v))  # fmt: skip
    for arg, vals in (
        ("chunk", [0, 2.5, True, "1"]),
        ("workers", [0, 1.5, "2", True, -5]),
    ):
        for v in vals:
            api(
                "counts",
                f"evaluate_layout({arg}={v!r})",
                arg,
                lambda a=arg, v=v: evaluate_layout(ROOM, A, nodes=NODES, **{a: v}),
            )
    for v in [True, 0, 2.5, "4", -3, 10**9]:
        api(
            "counts",
            f"random_layout(room, {v!r}, rng)",
            "M",
            lambda v=v: placement.random_layout(ROOM, v, 0),
        )
    for v in [1.5, "x", -1, True]:
        api(
            "counts",
            f"random_layout(room, 4, rng={v!r})",
            "rng",
            lambda v=v: placement.random_layout(ROOM, 4, v),
        )


def _optimizer_count_cases() -> None:
    """Counts of the optimizers and positioning: bools, floats, strings."""
    for arg, vals in (
        ("particles", [True, 1, 3.7, "4", 10**9]),
        ("iterations", [True, 0, 1.9]),
        ("patience", [0, 1.5, True]),
        ("inertia", ["0.7", float("nan"), -1]),
        ("velocity_clamp", [0, -1, float("inf")]),
    ):
        for v in vals:
            api("counts", f"PSOOptions({arg}={v!r})", arg, lambda a=arg, v=v: PSOOptions(**{a: v}))
    for arg, vals in (
        ("M", [True, 0, 4.5, "4", 10**6]),
        ("chunksize", [0, 1.5, True]),
        ("rng", [1.7, -1, "1"]),
    ):
        for v in vals:
            kw = {"M": 4, arg: v} if arg == "M" else {"M": 4, "rng": 0, arg: v}
            api(
                "counts",
                f"pso(cost, room, {arg}={v!r})",
                arg,
                lambda kw=kw: pso(peb_cost, ROOM, options=FAST, **kw),
            )
    for arg, vals in (
        ("M", [3, 4.5, True, 10**6]),
        ("samples", [0, True]),
        ("starts", [0, 2.5]),
        ("rng", [1.5, "a"]),
    ):
        for v in vals:
            kw = {"M": 4, arg: v}
            api(
                "counts",
                f"relax_select(room, {arg}={v!r})",
                arg,
                lambda kw=kw: placement.relax_select(ROOM, spacing=1.6, **kw),
            )
    for arg, vals in (("top_k", [0, True]), ("max_subsets", [0, 1.5])):
        for v in vals:
            api(
                "counts",
                f"exhaustive_search({arg}={v!r})",
                arg,
                lambda a=arg, v=v: placement.exhaustive_search(ROOM, 4, spacing=3.0, **{a: v}),
            )
    for arg, vals in (("multistart", [-1, 1.5, True]), ("max_iter", [0, True])):
        for v in vals:
            api(
                "counts",
                f"refine_peb({arg}={v!r})",
                arg,
                lambda a=arg, v=v: placement.refine_peb(ROOM, A, **{a: v}),
            )
    for v in [0, 2.5, True]:
        api(
            "counts",
            f"locate(max_iter={v!r})",
            "max_iter",
            lambda v=v: locate(A, np.ones((2, 4)), max_iter=v),
        )
    for v in [(9, 6), (0, 1, 1), (1.5, 2, 2), (True, 2, 2), (10**4, 10**4, 10**4)]:
        api("counts", f"room.grid({v!r})", "shape", lambda v=v: ROOM.grid(v))
    for v in [1000, True, -1, 2.5]:
        api("counts", f"image_indices({v!r})", "max_order", lambda v=v: image_indices(v))


def _plan_cases() -> None:
    """Seed_then_pso and its options objects: the optimizer's (plan group)."""
    from placement.finalists import FinalistOptions
    from placement.validation import ValidationOptions

    for label, name, call in (
        ("PSOOptions(particles=3.7)", "particles", lambda: PSOOptions(particles=3.7)),
        ("PSOOptions(iterations=1.9)", "iterations", lambda: PSOOptions(iterations=1.9)),
        ("PSOOptions(particles=True)", "particles", lambda: PSOOptions(particles=True)),
        ("PSOOptions(iterations='2')", "iterations", lambda: PSOOptions(iterations="2")),
        ("PSOOptions(eval_timeout=0)", "eval_timeout", lambda: PSOOptions(eval_timeout=0)),
        ("FinalistOptions(count=1.5)", "count", lambda: FinalistOptions(count=1.5)),
        ("FinalistOptions(draws=0)", "draws", lambda: FinalistOptions(draws=0)),
        ("FinalistOptions(exact_draws=13)", "exact_draws", lambda: FinalistOptions(exact_draws=13)),
        ("FinalistOptions(exact_draws=1.5)", "exact_draws",
         lambda: FinalistOptions(exact_draws=1.5)),
        ("ValidationOptions(realizations=-1)", "realizations",
         lambda: ValidationOptions(realizations=-1)),
        ("seed_then_pso(rng=1.7)", "rng",
         lambda: seed_then_pso(ROOM, 4, **{**PLAN_KW, "rng": 1.7})),
        ("seed_then_pso(M=True)", "M", lambda: seed_then_pso(ROOM, True, **PLAN_KW)),
        ("seed_then_pso(M=300)", "M", lambda: seed_then_pso(ROOM, 300, **PLAN_KW)),
        ("seed_then_pso(finalists=FinalistOptions(count=9))", "finalists",
         lambda: seed_then_pso(ROOM, 4, **PLAN_KW, finalists=FinalistOptions(count=9))),
    ):  # fmt: skip
        api("counts", label, name, call, group="plan")
    # a table built with another mounting tolerance than the search's
    api(
        "options",
        "Planner(search=SearchOptions(mount_tolerance=0.05), table=<built with 0>)",
        "table",
        lambda: placement.Planner(
            ROOM,
            4,
            search=placement.SearchOptions(mount_tolerance=0.05),
            table=range_table(ROOM, A, NODES, rng=0),
        ),  # fmt: skip
        group="plan",
    )


def _ignored_option_cases() -> None:
    """Options silently ignored or swallowed."""
    for v in [{"particles": 4}, "fast", 3]:
        api(
            "options",
            f"pso(options={v!r})",
            "options",
            lambda v=v: pso(peb_cost, ROOM, 4, options=v),
        )
    api(
        "options",
        "relax_select(solver_opts='x')",
        "solver_opts",
        lambda: placement.relax_select(ROOM, 4, spacing=1.6, solver_opts="x"),
    )
    api(
        "options",
        "seed_then_pso(swarm={'particles': 4})",
        "swarm",
        lambda: seed_then_pso(ROOM, 4, **{**PLAN_KW, "swarm": {"particles": 4}}),
        group="plan",
    )

    def honoured():
        kw = {**PLAN_KW, "swarm": PSOOptions(particles=4, iterations=2)}
        return seed_then_pso(ROOM, 4, **kw).nfev == 8

    api(
        "options",
        "seed_then_pso(swarm=PSOOptions(particles=4, iterations=2)) runs 4 x 2",
        "swarm",
        honoured,
        group="plan",
        check=True,
    )
    for v in [{"start": 1}, {"starts": -1}, {"spacing": 0}, "starts"]:
        api(
            "options",
            f"seed_then_pso(search={v!r})",
            "search",
            lambda v=v: seed_then_pso(ROOM, 4, **{**PLAN_KW, "cost": "variance", "search": v}),
            group="plan",
        )
    for v in [{"start": 1}, {"spacing": 0}]:
        api(
            "options",
            f"SearchOptions(**{v!r})",
            next(iter(v)) if "start" not in v else "start",
            lambda v=v: placement.SearchOptions(**v),
            group="plan",
        )


def _failed_result_cases() -> None:
    """Bad input turned into a failed result."""
    for label, v in (
        ("5", 5),
        ("'variance'", "variance"),
        ("None", None),
        ("lambda: 1.0", lambda: 1.0),
        ("lambda a, b, c: 1.0", lambda a, b, c: 1.0),
    ):
        api(
            "failed-result",
            f"pso(cost={label})",
            "cost",
            lambda v=v: pso(v, ROOM, 4, options=FAST, rng=0),
        )
    api(
        "failed-result",
        "pso(one-argument cost) runs",
        "cost",
        lambda: pso(one_arg_cost, ROOM, 4, options=FAST, rng=0).success,
        check=True,
    )

    def unpicklable():
        with placement.WorkerPool(2) as ex:
            return pso(lambda a, r: 1.0, ROOM, 4, options=FAST, rng=0, executor=ex)

    api("failed-result", "pso(lambda cost, executor=WorkerPool)", "cost", unpicklable)
    for v in ["x", 5]:
        api(
            "failed-result",
            f"pso(callback={v!r})",
            "callback",
            lambda v=v: pso(peb_cost, ROOM, 4, options=FAST, callback=v),
        )
    api(
        "failed-result",
        "pso(executor='pool')",
        "executor",
        lambda: pso(peb_cost, ROOM, 4, options=FAST, executor="pool"),
    )
    api("failed-result", "pso(room='techtile')", "room", lambda: pso(peb_cost, "techtile", 4))
    api(
        "failed-result",
        "pso(initial=wrong shape)",
        "initial",
        lambda: pso(peb_cost, ROOM, 4, options=FAST, initial=np.zeros((2, 5, 3))),
    )
    for v in (0, -1, "x"):
        api(
            "failed-result",
            f"seed_then_pso(cost=PEBCost(room, sigma={v!r}))",
            "sigma",
            lambda v=v: seed_then_pso(
                ROOM, 4, **{**PLAN_KW, "cost": placement.PEBCost(ROOM, sigma=v)}
            ),
            group="plan",
        )
    for v in [0, -0.04]:
        api(
            "failed-result",
            f"PEBCost(room, sigma={v!r})",
            "sigma",
            lambda v=v: placement.PEBCost(ROOM, sigma=v),
            group="plan",
        )
    for v in [True, 0, 1.5]:
        api(
            "failed-result",
            f"SimulatedCost(realizations={v!r})",
            "realizations",
            lambda v=v: placement.SimulatedCost(ROOM, realizations=v),
            group="plan",
        )


def _outside_and_duplicate_cases() -> None:
    """Geometry: points outside the room, duplicated anchors."""
    outside = {"x > Lx": [[9.0, 1, 1]], "negative": [[-0.5, 1, 1]], "z > Lz": [[1, 1, 3.0]]}
    for label, pts in outside.items():
        api(
            "geometry",
            f"evaluate_layout(nodes {label})",
            "nodes",
            lambda p=pts: evaluate_layout(ROOM, A, nodes=p),
        )
        api(
            "geometry",
            f"simulate_ranges(nodes {label})",
            "nodes",
            lambda p=pts: simulate_ranges(ROOM, A, p),
        )
        api(
            "geometry",
            f"relax_select(nodes {label})",
            "nodes",
            lambda p=pts: placement.relax_select(ROOM, 4, spacing=1.6, nodes=p),
        )
        api(
            "geometry",
            f"refine_peb(nodes {label})",
            "nodes",
            lambda p=pts: placement.refine_peb(ROOM, A, nodes=p),
        )
        api(
            "geometry",
            f"exhaustive_search(nodes {label})",
            "nodes",
            lambda p=pts: placement.exhaustive_search(ROOM, 4, spacing=3.0, nodes=p),
        )
    dup = np.vstack([A, A[:1]])
    near = np.vstack([A, A[:1] + [0, 0, 0.0005]])
    for label, lay in (("duplicated", dup), ("0.5 mm apart", near)):
        _bad_anchor_cases(label, lay, refine=True)


def _bad_anchor_cases(label: str, lay, *, ranges: bool = True, refine: bool = False) -> None:
    """Anchors ``lay`` given to the simulation (and the refinement)."""
    api(
        "geometry",
        f"evaluate_layout(anchors {label})",
        "anchors",
        lambda a=lay: evaluate_layout(ROOM, a, nodes=NODES),
    )
    if ranges:
        api(
            "geometry",
            f"simulate_ranges(anchors {label})",
            "anchors",
            lambda a=lay: simulate_ranges(ROOM, a, NODES),
        )
    if refine:
        api(
            "geometry",
            f"refine_peb(anchors {label})",
            "anchors",
            lambda a=lay: placement.refine_peb(ROOM, a),
        )


def _degenerate_geometry_cases() -> None:
    """Geometry: degenerate layouts and node sets."""
    for label, lay in (
        ("outside", A + [0, 0, 5]),
        ("NaN", np.where(A == A[0, 0], np.nan, A)),
        ("(M, 2)", A[:, :2]),
        ("3 anchors", A[:3]),
        ("strings", "abc"),
        ("ragged", [[1, 1, 1], [2, 2]]),
    ):
        _bad_anchor_cases(label, lay, ranges=label != "3 anchors")  # 3 are fine for ranges
    api(
        "geometry",
        "refine_peb(anchors off the surfaces)",
        "anchors",
        lambda: placement.refine_peb(ROOM, A + [0.5, 0.5, 0.5]),
    )
    api(
        "geometry",
        "relax_select(candidates off the surfaces)",
        "candidates",
        lambda: placement.relax_select(ROOM, 4, candidates=[[4, 2, 1.2]] * 5),
    )
    api(
        "geometry",
        "relax_select(candidates NaN)",
        "candidates",
        lambda: placement.relax_select(ROOM, 4, candidates=np.full((5, 3), np.nan)),
    )
    for label, r in (
        ("negative", -np.ones((2, 4)) * 2),
        ("NaN", np.full((2, 4), np.nan)),
        ("wrong shape", np.ones((2, 5))),
        ("strings", "1 2 3 4"),
    ):
        api("geometry", f"locate(ranges {label})", "ranges", lambda r=r: locate(A, r))
    api("geometry", "locate(anchors 2 rows)", "anchors", lambda: locate(A[:2], np.ones((2, 2))))
    line = np.array([[1, 2, 2.37], [3, 2, 2.37], [5, 2, 2.37], [7, 2, 2.37]])
    api(
        "geometry",
        "locate(collinear anchors) flags every fix",
        "anchors",
        lambda: bool(np.all(locate(line, np.full((3, 4), 2.0), full_output=True).status == -1)),
        check=True,
    )
    api(
        "geometry",
        "evaluate_layout(collinear anchors) reports it",
        "anchors",
        lambda: (lambda ev: ev.geometry == "collinear" and ev.n_unconverged == ev.errors.size)(
            evaluate_layout(ROOM, line, nodes=NODES)
        ),
        check=True,
    )


def _bound_and_projection_cases() -> None:
    """Geometry: bad points for the bound and the projection; a degenerate plan."""
    for label, kw in (
        ("sigma=-1", {"sigma": -1}),
        ("sigma='a'", {"sigma": "a"}),
        ("sigma=NaN", {"sigma": np.nan}),
        ("positions (P, 2)", {"positions": np.ones((3, 2))}),
        ("anchors NaN", {"anchors": A * np.nan}),
    ):
        args = {"anchors": A, "positions": NODES, "sigma": 0.04, **kw}
        api("geometry", f"peb({label})", next(iter(kw)), lambda a=args: analysis.peb(**a))
    for label, v in (
        ("NaN", np.full((2, 3), np.nan)),
        ("'abc'", "abc"),
        ("(2, 2)", np.ones((2, 2))),
    ):
        api(
            "geometry",
            f"project(room, points {label})",
            "points",
            lambda v=v: placement.project(ROOM, v),
        )

    def degenerate_answer():
        narrow = Room(size=(8.0, 4.0, 2.4), mounting=("south",), anchor_offset=1.1996)
        res = seed_then_pso(
            narrow,
            4,
            **{**PLAN_KW, "swarm": PSOOptions(particles=4, iterations=2)},
        )
        from simulation.degeneracy import geometry

        return (not res.success) or geometry(res.anchors) not in ("collinear", "coincident")

    api(
        "geometry",
        "seed_then_pso never returns a collinear layout",
        "anchors",
        degenerate_answer,
        group="plan",
        check=True,
    )


def _room_physics_cases() -> None:
    """Absurd physics: the room, the SNR."""
    for v in [1e9, -273.1, -41, 61, *BAD_REALS]:
        api("physics", f"Room(temperature={v!r})", "temperature", lambda v=v: Room(temperature=v))
    for v in [
        (8, 4),
        5,
        (8, -1, 2),
        (1e9, 1, 1),
        (0.1, 1, 1),
        "8x4x2",
        (8, 4, np.nan),
        None,
        (8, 4, 2, 1),
        (True, 4, 2),
    ]:
        api("physics", f"Room(size={v!r})", "size", lambda v=v: Room(size=v))
    for v in [
        0.5,
        {"floor": 1.5},
        {"roof": 0.1},
        {"floor": "x"},
        "high",
        [0.5] * 6,
        {"floor": np.nan},
        {"floor": True},
        {"floor": -0.1},
    ]:
        api("physics", f"Room(absorption={v!r})", "absorption", lambda v=v: Room(absorption=v))
    for arg, vals in (
        ("air_absorption", [-1, 100, "x", np.nan]),
        ("sound_speed", [0, -340, 1e6, "343", np.nan, 4.5]),
        ("anchor_offset", [-0.01, 5, "x"]),
        ("node_margin", [2, -1, np.nan]),
        ("mounting", ["attic", [], ["ceiling", "ceiling"], 5, ["ceiling", 3]]),
        ("name", [3, None]),
    ):
        for v in vals:
            api("physics", f"Room({arg}={v!r})", arg, lambda a=arg, v=v: Room(**{a: v}))
    for v in [1e6, -1e6, np.nan, "30", -100, 500, True]:
        api(
            "physics",
            f"simulate_ranges(snr_db={v!r})",
            "snr_db",
            lambda v=v: simulate_ranges(ROOM, A, NODES, snr_db=v),
        )
    for v in [1e6, -1e6, np.inf]:
        api(
            "physics",
            f"evaluate_layout(snr_db={v!r})",
            "snr_db",
            lambda v=v: evaluate_layout(ROOM, A, nodes=NODES, snr_db=v),
        )
        api(
            "physics",
            f"noise_sigma(snr_db={v!r})",
            "snr_db",
            lambda v=v: noise_sigma(ROOM, A, snr_db=v),
        )
        api(
            "physics",
            f"PhysicalRangeNoise(snr_db={v!r})",
            "snr_db",
            lambda v=v: analysis.PhysicalRangeNoise(ROOM, snr_db=v),
        )


def _signal_physics_cases() -> None:
    """Absurd physics: range σ, chirp and receiver."""
    for v in [0, -1, "0.04", np.nan, np.inf, 1e6, True]:
        api(
            "physics",
            f"ConstantRangeNoise({v!r})",
            "value",
            lambda v=v: analysis.ConstantRangeNoise(v),
        )
    for v in [0, "x"]:
        api(
            "physics",
            f"MultipathRangeNoise(floor={v!r})",
            "floor",
            lambda v=v: analysis.MultipathRangeNoise(ROOM, floor=v),
        )
    from simulation import Chirp, Receiver, System

    for arg, v in (("f0", "25e3"), ("f0", -1), ("duration", 100.0), ("duration", 0)):
        api("physics", f"Chirp({arg}={v!r})", arg, lambda a=arg, v=v: Chirp(**{a: v}))
    # the signal design of rooms bigger than the paper's (issue 26)
    signal_cases = [
        ("inverted band", "chirp", dict(chirp=Chirp(f0=45e3, f1=25e3))),
        ("band above fs/2", "chirp", dict(chirp=Chirp(f1=120e3))),
        ("a 1 s chirp at 10 MHz (tens of GB of DSP)", "chirp duration x fs x window",
         dict(chirp=Chirp(duration=1.0, f1=450e3), receiver=Receiver(fs=10e6))),
    ]  # fmt: skip
    for label, name, kw in signal_cases:
        api("physics", f"System({label})", name, lambda kw=kw: System(**kw))
    # a window closing after the chirp's end plus the room's longest flight (issue 28)
    late = System(receiver=Receiver(t_wake=0.0, window=20000))
    api("physics", "System.check_room(window after the last arrival)", "window",
        lambda: late.check_room(Room()))  # fmt: skip
    for arg, v in (("pick", "last"), ("first_path_ratio", 0.0), ("first_path_ratio", 1.5),
                   ("first_path_noise", -1.0)):  # fmt: skip
        api("physics", f"Receiver({arg}={v!r})", arg, lambda a=arg, v=v: Receiver(**{a: v}))
    for arg, v in (("false_alarm", 0.0), ("false_alarm", 0.9), ("false_alarm", "x")):
        api("physics", f"Receiver({arg}={v!r})", arg, lambda a=arg, v=v: Receiver(**{a: v}))
    for arg, v in (("humidity", 101.0), ("humidity", -5), ("pressure", 0.0),
                   ("air_absorption", "iso")):  # fmt: skip
        api("physics", f"Room({arg}={v!r})", arg, lambda a=arg, v=v: Room(**{a: v}))
    api("physics", "System.from_dict(signal bogus)", "bogus",
        lambda: System.from_dict({"signal": {"bogus": 1}}))  # fmt: skip
    for arg, v in (
        ("window", True),
        ("window", 1.5),
        ("fs", "192e3"),
        ("fs", 1e12),
        ("lowpass_cutoff", 1e6),
        ("highpass_order", 0),
    ):
        api("physics", f"Receiver({arg}={v!r})", arg, lambda a=arg, v=v: Receiver(**{a: v}))


def _toml_library_cases(tmp: Path) -> None:
    """TOML files through the library."""
    for fname, text, name in TOML_CASES:
        path = tmp / fname
        api(
            "physics" if name in PHYSICS_KEYS else "wrong-type",
            f"Room.from_toml({text!r})",
            fname,
            lambda p=path: Room.from_toml(p),
        )


def _wrong_type_cases(tmp: Path) -> None:
    """Wrong exception types."""
    for v, name in (
        ({"size": 5}, "size"),
        (5, "room"),
        (None, "room"),
        ({"size": "abc"}, "size"),
        ([1, 2], "room"),
        ({"temperature": [20]}, "temperature"),
        ({"mounting": {"a": 1}}, "mounting"),
    ):
        api("wrong-type", f"Room.from_dict({v!r})", name, lambda v=v: Room.from_dict(v))
    for label, p in (("a directory", tmp), ("a missing file", tmp / "missing.toml"), ("5", 5)):
        api("wrong-type", f"Room.from_toml({label})", "room file", lambda p=p: Room.from_toml(p))
    api(
        "wrong-type",
        "simulate_ranges(rng=5) uses 5 as a seed",
        "rng",
        lambda: simulate_ranges(ROOM, A, NODES, rng=5).shape == (len(NODES), 4),
        check=True,
    )
    for v in ["x", 1.5, -1, object()]:
        api(
            "wrong-type",
            f"simulate_ranges(rng={v!r})",
            "rng",
            lambda v=v: simulate_ranges(ROOM, A, NODES, rng=v),
        )
    for v in [1e-5, 0, -1, "a", np.nan]:
        api(
            "wrong-type",
            f"candidate_grid(room, {v!r})",
            "spacing",
            lambda v=v: placement.candidate_grid(ROOM, v),
        )
    for v in [1e-5, "a", 0]:
        api(
            "wrong-type",
            f"figures.peb_map(resolution={v!r})",
            "resolution",
            lambda v=v: figures.peb_map(ROOM, A, resolution=v),
        )
    api(
        "wrong-type",
        "PhysicalRangeNoise(grid_shape=(10**4,)*3).sigma",
        "shape",
        lambda: analysis.PhysicalRangeNoise(ROOM, grid_shape=(10**4,) * 3).sigma(A, NODES),
    )
    api(
        "wrong-type",
        "evaluate_layout(room='techtile')",
        "room",
        lambda: evaluate_layout("techtile", A),
    )
    api("wrong-type", "relax_select(room=None)", "room", lambda: placement.relax_select(None, 4))
    api(
        "wrong-type",
        "relax_select(spacing=0.01) (200k candidates)",
        "candidates",
        lambda: placement.relax_select(ROOM, 4, spacing=0.01),
    )
    api(
        "wrong-type",
        "calibrated_sigma(method='x')",
        "method",
        lambda: analysis.calibrated_sigma(np.ones((2, 3, 4)), method="x"),
    )
    api(
        "wrong-type",
        "calibrated_sigma(k='3')",
        "k",
        lambda: analysis.calibrated_sigma(np.ones((2, 3, 4)), k="3"),
    )
    api(
        "wrong-type",
        "CalibratedRangeNoise('x')",
        "values",
        lambda: analysis.CalibratedRangeNoise("x"),
    )


def _second_sweep_cases() -> None:
    """Cases a later sweep of the public API found accepted or failing deep inside."""
    from simulation import Chirp, Receiver, System
    from simulation.multipath import compute_paths
    from simulation.received import received_windows

    cand = placement.candidate_grid(ROOM, 0.5)
    twice = np.vstack([cand[[0, 5, 10, 15, 20]], cand[:1]])
    one = NODES[None]
    geometry = [
        ("from_uv(index 7)", "index", lambda: placement.from_uv(ROOM, [7, 0], [[0.5] * 2] * 2)),
        ("from_uv(uv 1e6)", "uv", lambda: placement.from_uv(ROOM, [0], [[1e6, 0.5]])),
        ("from_uv(uv None)", "uv", lambda: placement.from_uv(ROOM, [0], None)),
        ("exhaustive_search(repeated candidate)", "candidates",
         lambda: placement.exhaustive_search(ROOM, 6, candidates=twice, nodes=NODES)),
        ("relax_select(repeated candidate)", "candidates",
         lambda: placement.relax_select(ROOM, 6, candidates=twice, nodes=NODES)),
        ("seed_then_pso(nodes outside)", "nodes",
         lambda: seed_then_pso(ROOM, 4, nodes=[[9.0, 1, 1]], **PLAN_KW)),
        ("PEBCost(nodes outside)", "nodes", lambda: placement.PEBCost(ROOM, nodes=[[9.0, 1, 1]])),
        ("PEBCost(nodes empty)", "nodes", lambda: placement.PEBCost(ROOM, nodes=np.zeros((0, 3)))),
        ("DrawsCost(nodes empty)", "nodes", lambda: placement.DrawsCost(ROOM, np.zeros((0, 3, 3)))),
        ("on_surfaces(tol nan)", "tol", lambda: placement.on_surfaces(ROOM, A, tol=math.nan)),
        ("Room(keepouts=5)", "keepouts", lambda: Room(keepouts=5)),
    ]  # fmt: skip
    physics = [
        ("Receiver(window=33)", "window", lambda: Receiver(window=33)),
        ("dsp chirp above fs/2", "chirp",
         lambda: System(Chirp(f0=1e6, f1=9e5))),
        ("high-pass cutoff 1e-9 Hz", "highpass_cutoff",
         lambda: System(receiver=Receiver(highpass_cutoff=1e-9))),
        ("received_windows(speed_of_sound 0)", "speed_of_sound",
         lambda: received_windows(compute_paths(ROOM, A, NODES[:2]), 0.0)),
        ("calibrated_sigma(no errors)", "range_errors",
         lambda: analysis.calibrated_sigma(np.zeros((0, 5, 4)), method="mad")),
        ("range_std(no realizations)", "range_errors",
         lambda: analysis.range_std(np.zeros((0, 5, 4)))),
        ("DrawsCost(exact_draws 2.5)", "exact_draws",
         lambda: placement.DrawsCost(ROOM, one, exact_draws=2.5)),
        ("DrawsCost(mount_tolerance nan)", "mount_tolerance",
         lambda: placement.DrawsCost(ROOM, one, mount_tolerance=math.nan)),
    ]  # fmt: skip
    wrong = [
        ("PEBCost('x')", "room", lambda: placement.PEBCost("x")),
        ("SimulatedCost(statistic list)", "statistic",
         lambda: placement.SimulatedCost(statistic=["variance"])),
        ("SearchOptions(fine_spacings 0.2)", "fine_spacings",
         lambda: placement.SearchOptions(fine_spacings=0.2)),
        ("relax_select(solver_opts bogus)", "solver_opts",
         lambda: placement.relax_select(ROOM, 4, spacing=1.6, solver_opts={"bogus": 1})),
        ("compute_paths(images 5)", "images", lambda: compute_paths(ROOM, A, NODES, images=5)),
        ("Room.from_dict(signal)", "signal", lambda: Room.from_dict({"signal": {}})),
        ("System(receiver 'r')", "receiver", lambda: System(receiver="r")),
        ("System(positioning 'r')", "positioning", lambda: System(positioning="r")),
        ("sweep(on_row 'x')", "on_row",
         lambda: placement.sweep(ROOM, anchors=[4], on_row="x", **PLAN_KW)),
    ]  # fmt: skip
    for category, cases in (("geometry", geometry), ("physics", physics), ("wrong-type", wrong)):
        for label, name, fn in cases:
            api(category, label, name, fn)


def _empty_input_cases() -> None:
    """Empty and degenerate input to the range-table search and its neighbours (a third
    sweep): refused with the argument's name, or an empty result of the matching shape."""
    from placement.rangetable import table_costs
    from placement.simselect import SearchOptions, refine_on_table, simulated_select
    from placement.validation import validate_layout
    from simulation.evaluation import RangingScene

    cand = placement.candidate_grid(ROOM, 2.0)[:6]
    few = ROOM.grid()[::54]

    def table(n=6, **kw):
        return range_table(ROOM, cand[:n], few, **kw)

    tiny = SearchOptions(chains=2, evaluations=40, random_starts=2, fine_spacings=())
    refused = [
        *[(f"range_table({k}={v!r})", k, lambda k=k, v=v, d=d: table(**{k: v, **d}))
          for k, v, d in [("draws", 0, {}), ("draws", -2, {}), ("draws", 1.7, {}),
                          ("exact_draws", -1, {"draws": 2}), ("exact_draws", 5, {"draws": 2}),
                          ("mount_tolerance", -1.0, {"draws": 2}),
                          ("mount_tolerance", math.nan, {"draws": 2}), ("chunk", 0, {})]],
        ("range_table(nodes (0, P, 3))", "nodes",
         lambda: range_table(ROOM, cand, np.zeros((0, 5, 3)))),
        ("table_costs(index 99)", "layouts", lambda: table_costs(table(), [[0, 1, 2, 99]])),
        ("table_costs(index -1)", "layouts", lambda: table_costs(table(), [[-1, 1, 2, 3]])),
        ("table_costs(index 0.5)", "layouts", lambda: table_costs(table(), [[0.5, 1, 2, 3]])),
        ("refine_on_table(layout (0, 3))", "anchors",
         lambda: refine_on_table(ROOM, table(), [np.zeros((0, 3))])),
        ("simulated_select(workers 0)", "workers",
         lambda: simulated_select(ROOM, 4, options=tiny, table=table(), workers=0)),
        ("seed_then_pso(initial of 6 anchors, M 4)", "initial",
         lambda: seed_then_pso(ROOM, 4, **{**PLAN_KW, "initial": np.zeros((2, 6, 3)) + 1})),
        ("pso(initial of 6 anchors, M 4)", "initial",
         lambda: pso(peb_cost, ROOM, 4, initial=np.zeros((1, 6, 3)) + 1)),
        *[(f"validate_layout(mount_tolerance {v!r})", "mount_tolerance",
           lambda v=v: validate_layout(ROOM, A, rng=0, mount_tolerance=v))
          for v in (math.nan, -0.01, 5.0)],
    ]  # fmt: skip
    for label, name, fn in refused:
        api("empty", label, name, fn)
    handled = [
        ("simulated_select(table of M candidates)", "table",
         lambda: sorted(simulated_select(ROOM, 4, options=tiny, table=table(4)).indices)
         == [0, 1, 2, 3]),
        ("refine_on_table(no layouts)", "layouts",
         lambda: refine_on_table(ROOM, table(), [])[0] == []),
        ("table_costs(no layouts)", "layouts",
         lambda: table_costs(table(), np.zeros((0, 4), int)).shape == (0,)),
        ("locate(no layouts)", "anchors",
         lambda: locate(np.zeros((0, 4, 3)), np.zeros((0, 5, 4))).shape == (0, 5, 3)),
        ("ranges_batch([])", "rngs",
         lambda: RangingScene(ROOM, A, few).ranges_batch([]).shape == (0, len(few), 4)),
    ]  # fmt: skip
    for label, name, fn in handled:
        api("empty", label, name, fn, check=True)


def build_api_cases(tmp: Path) -> None:
    """Every API case, by kind of bad input."""
    _simulation_count_cases()
    _optimizer_count_cases()
    _plan_cases()
    _ignored_option_cases()
    _failed_result_cases()
    _outside_and_duplicate_cases()
    _degenerate_geometry_cases()
    _bound_and_projection_cases()
    _room_physics_cases()
    _signal_physics_cases()
    _toml_library_cases(tmp)
    _wrong_type_cases(tmp)
    _second_sweep_cases()
    _empty_input_cases()


def build_neighbour_cases() -> None:
    """Wrong types for each argument of the public functions (the neighbours of the
    issue's examples): a string, an arbitrary object, a dict and NaN."""
    from simulation import Chirp, Receiver, reference_nodes
    from simulation.multipath import compute_paths

    S = ROOM.grid()[:3]
    table = {
        "Room.grid": (ROOM.grid, {"shape": (9, 6, 5)}),
        "Room.check_anchors": (ROOM.check_anchors, {"anchors": A, "min_anchors": 4}),
        "Room.contains": (ROOM.contains, {"points": A, "margin": 0.0}),
        "Chirp": (Chirp, {"f0": 25e3, "f1": 45e3, "duration": 0.03}),
        "Receiver": (Receiver, {"fs": 192e3, "t_wake": 0.029, "window": 192}),
        "simulate_ranges": (
            simulate_ranges,
            {"room": ROOM, "anchors": A, "nodes": S, "noise": True, "rng": 0, "snr_db": 30.0},
        ),
        "evaluate_layout": (
            evaluate_layout,
            {"room": ROOM, "anchors": A, "realizations": 1, "rng": 0, "nodes": S, "chunk": 1},
        ),
        "locate": (locate, {"anchors": A, "ranges": np.ones((2, 4)), "max_iter": 100}),
        "noise_sigma": (noise_sigma, {"room": ROOM, "anchors": A, "snr_db": 30.0}),
        "reference_nodes": (reference_nodes, {"room": ROOM, "anchors": A}),
        "compute_paths": (compute_paths, {"room": ROOM, "anchors": A, "nodes": S}),
        "peb": (analysis.peb, {"anchors": A, "positions": S, "sigma": 0.04}),
        "crlb": (analysis.crlb, {"anchors": A, "positions": S, "sigma": 0.04}),
        "PhysicalRangeNoise": (analysis.PhysicalRangeNoise, {"room": ROOM, "snr_db": 30.0}),
        "MultipathRangeNoise": (analysis.MultipathRangeNoise, {"room": ROOM, "floor": 0.04}),
        "direct_amplitude": (
            analysis.direct_amplitude,
            {"room": ROOM, "anchors": A, "positions": S},
        ),
        "calibrated_sigma": (analysis.calibrated_sigma, {"range_errors": np.ones((2, 3, 4))}),
        "dop": (
            analysis.dop,
            {"errors": np.ones((2, 3)), "range_errors": np.ones((2, 3, 4))},
        ),
        "candidate_grid": (placement.candidate_grid, {"room": ROOM, "spacing": 0.5}),
        "random_layout": (placement.random_layout, {"room": ROOM, "M": 4, "rng": 0}),
        "project": (placement.project, {"room": ROOM, "points": A}),
        "on_surfaces": (placement.on_surfaces, {"room": ROOM, "points": A}),
        "aim": (placement.aim, {"room": ROOM, "anchors": A}),
        "relax_select": (
            placement.relax_select,
            {"room": ROOM, "M": 4, "criterion": "A", "sigma": 0.04, "spacing": 1.6},
        ),
        "exhaustive_search": (
            placement.exhaustive_search,
            {"room": ROOM, "M": 4, "criterion": "A", "spacing": 3.0},
        ),
        "refine_peb": (
            placement.refine_peb,
            {"room": ROOM, "anchors": A, "objective": "mean", "max_iter": 20},
        ),
        "PSOOptions": (PSOOptions, {"particles": 3, "iterations": 1, "tol": 0.0}),
        "pso": (pso, {"cost": peb_cost, "room": ROOM, "M": 4, "options": FAST, "rng": 0}),
        "peb_plane": (
            figures.peb_plane,
            {"room": ROOM, "anchors": A, "axis": "z", "value": 1.0, "resolution": 0.2},
        ),
    }
    bad = {"'x'": "x", "object()": object(), "{}": {}, "nan": math.nan}
    for fname, (fn, base) in table.items():
        for arg in base:
            for label, v in bad.items():
                if arg == "axis" and label in ("nan", "'x'"):  # 'x' is an axis
                    continue
                kw = {**base, arg: v}
                api("neighbours", f"{fname}({arg}={label})", arg, lambda fn=fn, kw=kw: fn(**kw))


PHYSICS_KEYS = {
    "temperature", "max_order", "size", "sound_speed", "air_absorption", "humidity",
    "duration", "chirp", "window", "corners", "height", "obstacles",
}  # fmt: skip
TOML_CASES = [
    ("empty.toml", "", "empty"),
    ("comment.toml", "# nothing here\n", "empty"),
    ("size5.toml", "size = 5\n", "size"),
    ("size2.toml", "size = [8, 4]\n", "size"),
    ("sizestr.toml", 'size = ["8", 4, 2]\n', "size"),
    ("absorb.toml", "absorption = 0.5\n", "absorption"),
    ("absorb2.toml", "[absorption]\nfloor = 2.0\n", "absorption"),
    ("absorb3.toml", "[absorption]\nroof = 0.2\n", "absorption"),
    ("temp.toml", 'temperature = "hot"\n', "temperature"),
    ("temp2.toml", "temperature = 1e9\n", "temperature"),
    ("temp3.toml", "temperature = -273.1\n", "temperature"),
    ("order.toml", "max_order = true\n", "max_order"),
    ("order2.toml", "max_order = 200\n", "max_order"),
    ("order3.toml", "max_order = 2.5\n", "max_order"),
    ("mount.toml", 'mounting = "attic"\n', "mounting"),
    ("mount2.toml", "mounting = []\n", "mounting"),
    ("mount3.toml", "mounting = 3\n", "mounting"),
    ("typo.toml", "sise = [8, 4, 2.4]\n", "sise"),
    ("syntax.toml", "size = [8, 4\n", "TOML"),
    ("binary.toml", "\udcff\udcfe", "TOML"),
    ("speed.toml", "sound_speed = 0\n", "sound_speed"),
    ("air.toml", 'air_absorption = "x"\n', "air_absorption"),
    ("name.toml", "name = 3\n", "name"),
    ("margin.toml", "node_margin = 3.0\n", "node_margin"),
    ("humid.toml", 'air_absorption = "iso9613"\nhumidity = 140\n', "humidity"),
    ("signal.toml", "[signal]\nduration = 0\n", "duration"),
    ("signal2.toml", "[signal]\nf0 = 50000\nf1 = 30000\n", "chirp"),
    ("signal3.toml", "[signal]\nwindow = 9000\n", "window"),
    ("signal4.toml", "[signal]\nchirp = 1\n", "signal"),
    ("signal5.toml", "signal = 3\n", "signal"),
    # polygonal rooms and obstacles (issue 27)
    ("poly1.toml", "corners = [[0, 0], [4, 0]]\nheight = 3\n", "corners"),
    ("poly2.toml", "corners = [[0, 0], [4, 4], [4, 0], [0, 4]]\nheight = 3\n", "corners"),
    ("poly3.toml", "corners = [[0, 0], [4, 0], [4, 0], [0, 4]]\nheight = 3\n", "corners"),
    ("poly4.toml", "corners = [[0, 0], [4, 0], [0, 4]]\nheight = 0\n", "height"),
    ("poly5.toml", "corners = [[0, 0], [4, 0], [0, 4]]\n", "height"),
    (
        "poly6.toml",
        "corners = [[0, 0], [4, 0], [0, 4]]\nheight = 3\n[absorption]\nroof = 0.2\n",
        "roof",
    ),
    (
        "poly7.toml",
        "corners = [[0, 0], [6, 0], [6, 3], [3, 3], [3, 6], [0, 6]]\nheight = 3\n"
        "[[obstacle]]\nmin = [4, 4, 0]\nmax = [5, 5, 1]\n",
        "obstacles",
    ),
    (
        "poly8.toml",
        "size = [4, 4, 3]\n[[obstacle]]\nmin = [1, 1, 0]\nmax = [1, 2, 1]\n",
        "obstacles",
    ),
    (
        "poly9.toml",
        "size = [4, 4, 3]\n[[obstacle]]\nmin = [0, 0, 0]\nmax = [4, 4, 3]\n",
        "obstacles",
    ),
]


# -- the CLI ------------------------------------------------------------------------------
def _cli_file_cases(tmp: Path) -> None:
    """CLI: room files, directories, missing files and outputs."""
    t = str(tmp)
    d = str(tmp / "adir")
    ok_layout = str(tmp / "ok.json")
    out = str(tmp / "out")
    plan0 = ["plan", "--no-progress", "--out", out]
    for fname, _, name in TOML_CASES:
        cli(
            "physics" if name in PHYSICS_KEYS else "wrong-type",
            ["bounds", "--room", f"{t}/{fname}"],
            fname,
        )
    # directories, missing files and outputs
    for cmd in (
        ["plan", "--no-progress", "--out", out],
        ["bounds"],
        ["peb-map", "--out", f"{t}/m.png"],
        ["evaluate", "--layout", ok_layout, "--out", out],
    ):
        cli("cli-files", [*cmd, "--room", d], "--room")
        cli("cli-files", [*cmd, "--room", f"{t}/missing.toml"], "--room")
    for cmd in (["bounds"], ["peb-map", "--out", f"{t}/m.png"], ["evaluate", "--out", out]):
        cli("cli-files", [*cmd, "--layout", d], "--layout")
        cli("cli-files", [*cmd, "--layout", f"{t}/missing.json"], "--layout")
    for fname, name in (
        ("null.json", "--layout"),
        ("list.json", "--layout"),
        ("nojson.json", "--layout"),
        ("one.json", "--layout"),
        ("dup.json", "--layout"),
        ("outside.json", "--layout"),
        ("nan.json", "--layout"),
        ("strs.json", "--layout"),
        ("empty.json", "--layout"),
        ("ragged.json", "--layout"),
        ("binary.json", "--layout"),
    ):
        cli("cli-files", ["bounds", "--layout", f"{t}/{fname}"], name)
        cli("geometry", ["evaluate", "--layout", f"{t}/{fname}", "--out", out], name)
    cli("cli-files", [*plan0[:-1], f"{t}/afile.txt"], "--out")
    cli("cli-files", ["evaluate", "--layout", ok_layout, "--out", f"{t}/afile.txt"], "--out")
    cli("cli-files", ["evaluate", "--layout", ok_layout, "--out", f"{t}/afile.txt/sub"], "--out")
    cli("cli-files", ["bounds", "--out", d], "--out")
    cli("cli-files", ["bounds", "--out", f"{t}/afile.txt/x.json"], "--out")
    cli("cli-files", ["peb-map", "--out", d], "--out")
    cli("cli-files", ["peb-map", "--out", f"{t}/m.gif"], "--out")
    cli("cli-files", ["report", f"{t}/afile.txt"], "RESULT_DIR")
    cli("cli-files", ["report", f"{t}/missing"], "RESULT_DIR")
    cli("cli-files", ["report", d], "RESULT_DIR")
    cli("cli-files", ["report", f"{t}/badresult"], "RESULT_DIR")
    cli("cli-files", ["report", f"{t}/badresult2"], "RESULT_DIR")
    cli("cli-files", ["report", f"{t}/goodresult", "--out", d], "--out")
    cli("cli-files", ["report", f"{t}/goodresult", "--figures", f"{t}/afile.txt"], "--figures")
    for ck in ("null.json", "trunc.json", "list.json", "partial.json", "binary.json", "adir"):
        cli("cli-files", [*plan0, "--checkpoint", f"{t}/{ck}"], ck if ck != "adir" else "adir")


def _cli_number_cases(tmp: Path) -> None:
    """CLI: numbers out of range or not numbers."""
    t = str(tmp)
    ok_layout = str(tmp / "ok.json")
    out = str(tmp / "out")
    plan0 = ["plan", "--no-progress", "--out", out]
    for opt, vals in (
        ("--anchors", ["3", "300", "0", "-4", "x", "4.5"]),
        ("--particles", ["1", "0", "-5", "3.7", "1000000000"]),
        ("--iterations", ["0", "-1", "1e9"]),
        ("--realizations", ["0", "1000000"]),
        ("--validate-realizations", ["-1", "1000000000"]),
        ("--finalists", ["0", "100"]),
        ("--finalist-exact-draws", ["-1", "13"]),
        ("--finalist-realizations", ["0"]),
        ("--seed", ["-1", "x"]),
        ("--workers", ["-1", "100000"]),
        ("--eval-timeout", ["0", "-1", "nan", "inf", "x"]),
        ("--search-spacing", ["0", "-1", "nan", "1e-4"]),
        ("--chirp-duration", ["0", "-0.03", "5"]),
        ("--fs", ["0", "60000"]),
        ("--t-wake", ["-1"]),
        ("--window", ["5", "100000"]),
        ("--false-alarm", ["0", "0.9"]),
        ("--pick", ["last"]),
        ("--search-starts", ["-1"]),
        ("--search-realizations", ["0", "1000"]),
        ("--cost", ["median"]),
    ):
        for v in vals:
            cli("cli-numbers", [*plan0, opt, v], opt.split("/")[0])
    cli("cli-numbers", [*plan0, "--scheduler", "tcp://127.0.0.1:9"], "--scheduler")
    cli("cli-numbers", [*plan0, "--scheduler", "not an address"], "--scheduler")
    cli(
        "cli-numbers", [*plan0, "--scheduler", "tcp://127.0.0.1:9", "--workers", "2"], "--scheduler"
    )
    for opt, vals in (
        ("--realizations", ["0", "-1", "1000000000"]),
        ("--seed", ["-1"]),
        ("--snr", ["nan", "1e6", "-1e6", "inf"]),
    ):
        for v in vals:
            cli("cli-numbers", ["evaluate", "--layout", ok_layout, "--out", out, opt, v], opt)
    for v in ["0", "-1", "nan", "inf", "1e6", "x"]:
        cli("cli-numbers", ["bounds", "--sigma", v], "--sigma")
    pm = ["peb-map", "--out", f"{t}/m.png"]
    for opt, vals in (
        ("--sigma", ["0", "-1"]),
        ("--height", ["9", "-1", "nan"]),
        ("--x-cut", ["100"]),
        ("--y-cut", ["-1"]),
        ("--resolution", ["0", "-1", "1e-4", "nan"]),
        ("--dpi", ["0", "-5", "100000", "nan"]),
        ("--vmax", ["0", "-1"]),
        ("--scale", ["foo"]),
    ):
        for v in vals:
            cli("cli-numbers", [*pm, opt, v], opt)
    for w, h in (("1000", "1000"), ("0", "5"), ("-1", "3"), ("nan", "3")):
        cli("cli-numbers", [*pm, "--size", w, h], "--size")
    cli("cli-numbers", [*pm, *sum((["--height", "1"] for _ in range(30)), [])], "--height")
    rp = ["report", f"{t}/goodresult", "--out", f"{t}/r.html"]
    for opt, vals in (
        ("--realizations", ["-1", "1000000000"]),
        ("--dpi", ["0", "100000"]),
        ("--sigma", ["0"]),
        ("--seed", ["-1"]),
    ):
        for v in vals:
            cli("cli-numbers", [*rp, opt, v], opt)
    cli("cli-files", ["report", f"{t}/goodresult", "--out", f"{t}/r.txt"], "--out")
    cli("cli-numbers", ["frobnicate"], "frobnicate")
    cli("cli-numbers", [], "COMMAND")


def build_cli_cases(tmp: Path) -> None:
    """Every CLI case."""
    _cli_file_cases(tmp)
    _cli_number_cases(tmp)


def make_files(tmp: Path) -> None:
    (tmp / "adir").mkdir()
    (tmp / "afile.txt").write_text("x")
    for fname, text, _ in TOML_CASES:
        p = tmp / fname
        if fname == "binary.toml":
            p.write_bytes(b"\xff\xfe\x00\x01")
        else:
            p.write_text(text)
    good = ROOM.corners_layout().tolist()
    layouts = {
        "ok.json": {"anchors": good},
        "null.json": None,
        "list.json": [1, 2, 3],
        "one.json": {"anchors": [[1, 1, 1]]},
        "dup.json": {"anchors": [*good, good[0]]},
        "outside.json": {"anchors": [*good[:3], [9, 1, 1]]},
        "strs.json": {"anchors": [["a", "b", "c"]] * 4},
        "ragged.json": {"anchors": [[1, 1, 1], [2, 2]]},
        "partial.json": {"version": 1},
    }
    for name, obj in layouts.items():
        (tmp / name).write_text(json.dumps(obj))
    (tmp / "nan.json").write_text('{"anchors": [[NaN, 1, 1], [1, 1, 1], [2, 2, 2], [3, 3, 1]]}')
    (tmp / "nojson.json").write_text("{anchors: ")
    (tmp / "trunc.json").write_text('{"version": 1, "fingerp')
    (tmp / "empty.json").write_text("")
    (tmp / "binary.json").write_bytes(b"\xff\xfe\x00\x01")
    (tmp / "badresult").mkdir()
    (tmp / "badresult" / "result.json").write_text("{not json")
    (tmp / "badresult2").mkdir()
    (tmp / "badresult2" / "evaluation.json").write_text(json.dumps({"anchors": "x"}))
    (tmp / "goodresult").mkdir()
    (tmp / "goodresult" / "evaluation.json").write_text(json.dumps({"anchors": good}))


# -- running ------------------------------------------------------------------------------
def _child(fn, conn) -> None:
    try:
        value = fn()
        conn.send(("returned", repr(value)[:200], type(value).__name__))
    except BaseException as exc:  # noqa: BLE001 - classify everything
        conn.send(("raised", type(exc).__name__, " ".join(str(exc).split())[:400]))
    finally:
        conn.close()


def run_api(case: dict, timeout: float) -> dict:
    ctx = mp.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    t0 = time.monotonic()
    proc = ctx.Process(target=_child, args=(case["fn"], send))
    proc.start()
    send.close()
    got = recv.recv() if recv.poll(timeout) else None
    seconds = time.monotonic() - t0
    if got is None:
        proc.kill()
    proc.join(5)
    if got is None:
        how = "crash" if proc.exitcode not in (None, -9) and seconds < timeout else "hang"
        return {"outcome": how, "seconds": seconds, "exitcode": proc.exitcode}
    kind, a, b = got
    if case["check"]:
        ok = kind == "returned" and a == "True"
        return {
            "outcome": "handled" if ok else "accepted",
            "seconds": seconds,
            "result": a if kind == "returned" else f"{a}: {b}",
        }
    if kind == "returned":
        return {"outcome": "accepted", "seconds": seconds, "result": f"{b}: {a}"}
    if a != "ValueError":
        return {"outcome": "wrong_type", "seconds": seconds, "error": f"{a}: {b}"}
    named = case["name"].lower() in b.lower()
    outcome = "clear" if named else "unclear"
    if seconds > timeout:
        outcome = "slow"
    return {"outcome": outcome, "seconds": seconds, "error": b}


def _anchorplan() -> list[str]:
    exe = Path(sys.executable).with_name("anchorplan")
    if exe.exists():
        return [str(exe)]
    return [sys.executable, "-c", "import sys; from placement.cli import main; sys.exit(main())"]


def run_cli(case: dict, timeout: float, cwd: Path) -> dict:
    t0 = time.monotonic()
    try:
        p = subprocess.run(
            [*_anchorplan(), *case["argv"]],
            capture_output=True,
            text=True,
            timeout=timeout,
            cwd=cwd,
        )
    except subprocess.TimeoutExpired:
        return {"outcome": "hang", "seconds": time.monotonic() - t0}
    seconds = time.monotonic() - t0
    err = p.stderr.strip()
    res = {"seconds": seconds, "exitcode": p.returncode, "stderr": err[-400:]}
    if "Traceback" in p.stderr:
        res["outcome"] = "traceback"
    elif p.returncode == 0:
        res["outcome"] = "accepted"
    elif p.returncode != 2:
        res["outcome"] = "wrong_type"
    else:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        named = case["name"].lower() in err.lower()
        res["outcome"] = "clear" if named and len(lines) == 1 else "unclear"
    return res


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", help="run one category")
    parser.add_argument("--group", choices=("core", "plan"), help="run one group")
    parser.add_argument("--timeout", type=float, default=5.0, help="seconds per case (5)")
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="anchorplan-bad-"))
    os.environ.setdefault("MPLBACKEND", "Agg")
    try:
        make_files(tmp)
        build_api_cases(tmp)
        build_neighbour_cases()
        build_cli_cases(tmp)
        counts: dict[str, Counter] = {"all": Counter(), "core": Counter(), "plan": Counter()}
        by_category: dict[str, Counter] = {}
        for k, case in enumerate(CASES):
            if args.only and case["category"] != args.only:
                continue
            if args.group and case["group"] != args.group:
                continue
            if case["kind"] == "api":
                res = run_api(case, args.timeout)
            else:
                res = run_cli(case, args.timeout, tmp)
            rec = {
                "case": k,
                "kind": case["kind"],
                "group": case["group"],
                "category": case["category"],
                "input": case["input"],
                "names": case["name"],
                **res,
            }
            rec["seconds"] = round(rec["seconds"], 3)
            print(json.dumps(rec, default=str), flush=True)
            for key in ("all", case["group"]):
                counts[key][res["outcome"]] += 1
            by_category.setdefault(case["category"], Counter())[res["outcome"]] += 1
        good = ("clear", "handled")
        summary = {"summary": True}
        for key, c in counts.items():
            n = sum(c.values())
            summary[key] = {
                "cases": n,
                **dict(c),
                "ok_share": round(sum(c[g] for g in good) / n, 4) if n else None,
            }
        summary["by_category"] = {k: dict(v) for k, v in sorted(by_category.items())}
        print(json.dumps(summary), flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()

"""What if: a planned layout when an anchor fails, the air is warmer or colder than the
receiver assumes, and the anchors are mounted with more or less care.

``stress(room, anchors)`` simulates, with the full chain and its noise (docs/model.md):

- **one anchor down**: for each anchor j, the layout without it: the median, mean and P95
  of the error, the share of verified fixes, σ and availability at the room's nodes (the
  figures of every table), and the share of nodes that still hear 4 anchors
  (:func:`analysis.covered_share`); the worst anchor is the one whose loss leaves the
  largest P95 of the error at the nodes, a node realization without a fix counting as an
  error beyond any (:func:`_worst`: a loss that leaves some tags metres off outranks one
  that leaves a few without a fix);
- **temperature**: the air ``offsets`` °C off the room's temperature (the sound travels at
  the warmer or colder air's speed) while the receiver converts times of flight with the
  room's configured speed of sound: a bias of about 0.17 % of every range per °C;
- **mounting**: the figures with the anchors mounted within each of ``tolerances`` m of
  the plan (in-plane offsets uniform in a disc, :func:`placement.rangetable.mounted_points`)
  while positioning uses the planned coordinates, over ``draws`` draws.

Every figure simulates the plan's system (its chirp, receiver and positioning; default the
paper's). Every figure is reproducible from ``rng`` (an int seed, a Generator drawn once,
or None). ``progress`` shows each table's simulations (:mod:`analysis.progress`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.coverage import covered_share
from analysis.progress import ProgressBar, check_progress
from placement.validation import mounted_errors, summary
from simulation import checks, streams
from simulation.evaluation import RangingScene, evaluate_layout
from simulation.robust import VERIFIED
from simulation.room import Room, as_room
from simulation.system import System, as_system

#: the default temperature offsets (°C) and mounting tolerances (m)
OFFSETS = (-10.0, -5.0, 5.0, 10.0)
TOLERANCES = (0.0, 0.01, 0.03, 0.05, 0.10)


@dataclass(frozen=True)
class StressResult:
    """The what-if tables of :func:`stress`: rows of plain numbers (m; ``verified`` and
    ``availability`` shares), the worst anchor's index (0-based) and the seed they were
    drawn from."""

    anchor_down: list[dict[str, float]]
    worst_anchor: int
    temperature: list[dict[str, float]]
    mounting: list[dict[str, float]]
    seed: int
    settings: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The result as JSON types (``kind`` "stress")."""
        return {"kind": "stress", **dataclasses.asdict(self)}


#: the figures of a row, in the order a user reads them
FIGURES = ("median", "mean", "p95", "verified", "std", "availability")


def _row(errors, verified) -> dict[str, float]:
    """The :data:`FIGURES` (m; shares) of the errors and their fixes' ``verified`` flags."""
    s = summary(errors, verified)
    return {k: float(s[k]) for k in FIGURES}


def _anchor_down(room: Room, system: System, a, nodes, R: int, seed: int, bar):
    """The rows of the one-anchor-down table and the worst anchor (:func:`_worst`)."""
    rows, tails = [], []
    for j in range(len(a)):
        bar.update(j, len(a))
        rest = np.delete(a, j, axis=0)
        ev = evaluate_layout(room, rest, realizations=R, rng=seed, nodes=nodes, system=system)
        rows.append({"anchor": j, **_row(ev.errors, ev.fix_quality == VERIFIED),
                     "covered_share": covered_share(room, rest, nodes, system=system)})  # fmt: skip
        tails.append(_tail(ev.errors))
    bar.close()
    return rows, _worst(rows, tails)


def _tail(errors) -> float:
    """The P95 (m) of ``errors`` with a missing fix (NaN) as an infinite error: inf when
    more than 5 % of the fixes are missing (an order statistic: no interpolation)."""
    e = np.where(np.isnan(errors), np.inf, np.asarray(errors, dtype=float)).ravel()
    return float(np.quantile(e, 0.95, method="inverted_cdf"))


def _worst(rows: list[dict], tails: list[float]) -> int:
    """The anchor whose loss leaves the largest error tail (:func:`_tail`), then the least
    availability, then the largest mean error; the first of equals."""
    key = [(tails[j], -rows[j]["availability"], rows[j]["mean"]) for j in range(len(rows))]
    return max(range(len(rows)), key=lambda j: key[j])


def _temperature(room: Room, system: System, a, nodes, R: int, offsets, seed: int, bar) -> list:
    c = room.speed_of_sound  # what the receiver assumes
    rows = []
    for k, dt in enumerate(offsets):
        bar.update(k, len(offsets))
        t = room.temperature + dt
        # the sound's real speed: c ∝ √(absolute temperature), from the configured one
        real = c * np.sqrt((273.15 + t) / (273.15 + room.temperature))
        air = dataclasses.replace(room, temperature=t, sound_speed=float(real))
        scene = RangingScene(air, a, nodes, system=system)
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(13, k)))
        windows = np.stack([scene.noisy_windows(rng) for _ in range(R)])
        ranges, _ = scene.dsp.detect(windows, c, scene.noise_sigma, system.delays,
                                     scene.distances / air.speed_of_sound)  # fmt: skip
        fix = system.positioning.locate(room, a, ranges, full_output=True)
        rows.append({"offset": float(dt), "temperature": t,
                     **_row(np.linalg.norm(fix.x - nodes, axis=-1), fix.verified)})  # fmt: skip
    bar.close()
    return rows


def _mounting(room: Room, system: System, a, nodes, tolerances, draws: int, seed: int,
              bar) -> list:  # fmt: skip
    rows = []
    for i, tol in enumerate(tolerances):
        out = []
        for d in range(draws):
            bar.update(i * draws + d, len(tolerances) * draws)
            out.append(mounted_errors(room, a, nodes, float(tol), d, seed, stream=14,
                                      system=system))  # fmt: skip
        errors, verified = np.stack(out).transpose(1, 0, 2)  # (draws, P) each
        rows.append({"tolerance": float(tol), **_row(errors, verified > 0.5)})
    bar.close()
    return rows


def stress(
    room,
    anchors,
    *,
    nodes=None,
    realizations: int = 10,
    offsets=OFFSETS,
    tolerances=TOLERANCES,
    draws: int = 10,
    rng=0,
    system=None,
    progress=False,
) -> StressResult:
    """The what-if analyses of a layout (module docstring): anchors (M, 3) on the room's
    mounting surfaces (M ≥ 5, so that one can fail), at ``nodes`` (default the room's
    grid), ``realizations`` noise draws for the anchor-down and temperature figures,
    ``draws`` mounting draws per tolerance (m), temperature ``offsets`` in °C, with
    ``system`` (default the paper's); ``progress`` True (tqdm bars), False or a callable
    ``progress(phase, done, total)``."""
    room = as_room(room)
    system = as_system(system)
    a = room.check_anchors(checks.reals("anchors", anchors), min_anchors=5)
    nodes = room.grid() if nodes is None else room.check_nodes(nodes)
    R = checks.count("realizations", realizations, low=1, high=10_000)
    draws = checks.count("draws", draws, low=1, high=10_000)
    offsets = [checks.real("offsets", v, low=-50.0, high=50.0, unit="°C") for v in offsets]
    tolerances = [checks.real("tolerances", v, low=0.0, high=1.0, unit="m") for v in tolerances]
    for v in offsets:
        checks.real("temperature + offset", room.temperature + v, low=-40.0, high=60.0)
    progress = check_progress(progress)
    seed = streams.entropy("rng", rng)
    down, worst = _anchor_down(room, system, a, nodes, R, seed,
                               ProgressBar(progress, "anchor down"))  # fmt: skip
    return StressResult(
        anchor_down=down,
        worst_anchor=int(worst),
        temperature=_temperature(
            room, system, a, nodes, R, offsets, seed, ProgressBar(progress, "temperature")
        ),  # fmt: skip
        mounting=_mounting(
            room, system, a, nodes, tolerances, draws, seed, ProgressBar(progress, "mounting")
        ),  # fmt: skip
        seed=seed,
        settings={
            "realizations": R,
            "draws": draws,
            "offsets": offsets,
            "tolerances": tolerances,
            "nodes": len(nodes),
            "system": system.to_dict(),
        },  # fmt: skip
    )

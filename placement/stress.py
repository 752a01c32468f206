"""What if: a planned layout when an anchor fails, the air is warmer or colder than the
receiver assumes, and the anchors are mounted with more or less care.

``stress(room, anchors)`` simulates, with the full chain and its noise (docs/model.md):

- **one anchor down**: for each anchor j, the layout without it: σ / mean / P95 and
  availability at the room's nodes, and the share of nodes that still hear 4 anchors
  (:func:`analysis.covered_share`); the worst anchor is the one whose loss leaves the
  largest mean error among the fixes (or the least availability first);
- **temperature**: the air ``offsets`` °C off the room's temperature (the sound travels at
  the warmer or colder air's speed) while the receiver converts times of flight with the
  room's configured speed of sound: a bias of about 0.17 % of every range per °C;
- **mounting**: σ / mean / P95 with the anchors mounted within each of ``tolerances`` m of
  the plan (in-plane offsets uniform in a disc, :func:`placement.rangetable.mounted_points`)
  while positioning uses the planned coordinates, over ``draws`` draws.

Every figure simulates the plan's system (its chirp, receiver and positioning; default the
paper's). Every figure is reproducible from ``rng`` (an int seed, a Generator drawn once,
or None).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.coverage import covered_share
from placement.validation import mounted_errors, summary
from simulation import checks, streams
from simulation.evaluation import RangingScene, evaluate_layout
from simulation.room import Room, as_room
from simulation.system import System, as_system

#: the default temperature offsets (°C) and mounting tolerances (m)
OFFSETS = (-10.0, -5.0, 5.0, 10.0)
TOLERANCES = (0.0, 0.01, 0.03, 0.05, 0.10)


@dataclass(frozen=True)
class StressResult:
    """The what-if tables of :func:`stress`: rows of plain numbers (m; availability a
    share), the worst anchor's index (0-based) and the seed they were drawn from."""

    anchor_down: list[dict[str, float]]
    worst_anchor: int
    temperature: list[dict[str, float]]
    mounting: list[dict[str, float]]
    seed: int
    settings: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The result as JSON types (``kind`` "stress")."""
        return {"kind": "stress", **dataclasses.asdict(self)}


def _row(errors) -> dict[str, float]:
    s = summary(errors)
    return {k: float(s[k]) for k in ("std", "mean", "p95", "availability")}


def _anchor_down(room: Room, system: System, a, nodes, R: int, seed: int) -> list[dict]:
    rows = []
    for j in range(len(a)):
        rest = np.delete(a, j, axis=0)
        ev = evaluate_layout(room, rest, realizations=R, rng=seed, nodes=nodes, system=system)
        rows.append({"anchor": j, **_row(ev.errors),
                     "covered_share": covered_share(room, rest, nodes, system=system)})  # fmt: skip
    return rows


def _temperature(room: Room, system: System, a, nodes, R: int, offsets, seed: int) -> list:
    c = room.speed_of_sound  # what the receiver assumes
    rows = []
    for k, dt in enumerate(offsets):
        t = room.temperature + dt
        # the sound's real speed: c ∝ √(absolute temperature), from the configured one
        real = c * np.sqrt((273.15 + t) / (273.15 + room.temperature))
        air = dataclasses.replace(room, temperature=t, sound_speed=float(real))
        scene = RangingScene(air, a, nodes, system=system)
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(13, k)))
        windows = np.stack([scene.noisy_windows(rng) for _ in range(R)])
        ranges, _ = scene.dsp.detect(windows, c, scene.noise_sigma, system.delays,
                                     scene.distances / air.speed_of_sound)  # fmt: skip
        x = system.positioning.locate(room, a, ranges)
        rows.append({"offset": float(dt), "temperature": t,
                     **_row(np.linalg.norm(x - nodes, axis=-1))})  # fmt: skip
    return rows


def _mounting(room: Room, system: System, a, nodes, tolerances, draws: int, seed: int) -> list:
    rows = []
    for tol in tolerances:
        errors = [mounted_errors(room, a, nodes, float(tol), d, seed, stream=14, system=system)[0]
                  for d in range(draws)]  # fmt: skip
        rows.append({"tolerance": float(tol), **_row(errors)})
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
) -> StressResult:
    """The what-if analyses of a layout (module docstring): anchors (M, 3) on the room's
    mounting surfaces (M ≥ 5, so that one can fail), at ``nodes`` (default the room's
    grid), ``realizations`` noise draws for the anchor-down and temperature figures,
    ``draws`` mounting draws per tolerance (m), temperature ``offsets`` in °C, with
    ``system`` (default the paper's)."""
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
    seed = streams.entropy("rng", rng)
    down = _anchor_down(room, system, a, nodes, R, seed)
    worst = max(range(len(a)), key=lambda j: (-down[j]["availability"], down[j]["mean"]))
    return StressResult(
        anchor_down=down,
        worst_anchor=int(worst),
        temperature=_temperature(room, system, a, nodes, R, offsets, seed),
        mounting=_mounting(room, system, a, nodes, tolerances, draws, seed),
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

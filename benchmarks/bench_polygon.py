"""Polygonal rooms and obstacles: the simulator's cost, its agreement with the peer, and
what the obstacle order changes.

Run: python benchmarks/bench_polygon.py [--quick]

One JSON line per result:

1. ``table``: the range table's time per (candidate, node, draw) window in the L-shaped
   lab (examples/l-shaped-lab.toml) against techtile's, the same number of candidates,
   measured in the same run, one process;
2. ``paths``: the image-source paths' time per (anchor, node) pair, the images per anchor
   and the paths per pair against the number of walls and obstacles (a shoebox by the
   shoebox method and by the polygon method, an L, a U, the L with 2, 4 and 8 columns);
3. ``peer``: pyroomacoustics' general image-source model against ours (omnidirectional
   speakers, the receiver's range) on the L-shaped room and a shoebox with one cabinet:
   the share of pairs within 1 cm, the agreement on the line of sight, and the time per
   pair of both simulators to the received windows (ours: paths and synthesis; the peer:
   impulse responses at 1 MHz, convolution and resampling), and with the receiver's DSP
   (the same for both, float64) to the ranges; ``speed_ratio`` is the windows' ratio;
4. ``obstacle_order``: in the lab and the warehouse (examples/warehouse-aisles.toml), or
   the rooms of ``--rooms`` (with ``--system``), the noise-free ranges of a naive layout
   with 0, 1 and 2 reflections on obstacle faces against the full order: the share of
   pairs whose range moves by more than 1 cm, the images of one anchor and the time per
   pair.
"""

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from _common import emit

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from placement import candidate_grid, naive_layout  # noqa: E402
from placement.rangetable import range_table  # noqa: E402
from simulation import Room, System  # noqa: E402
from simulation.evaluation import RangingScene  # noqa: E402
from simulation.multipath import compute_paths  # noqa: E402
from simulation.polyhedral import images, reflectors  # noqa: E402
from simulation.received import received_windows  # noqa: E402
from simulation.receiver import dsp_for  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
L_CORNERS = [[0, 0], [7, 0], [7, 3], [3, 3], [3, 6], [0, 6]]


def points(room: Room, n: int, rng, margin: float = 0.1) -> np.ndarray:
    out = []
    while len(out) < n:
        p = rng.uniform(0, room.size, (4 * n, 3))
        out += list(p[room.contains(p, margin=margin)])
    return np.array(out[:n])


def table_cost(n_cand: int) -> None:
    lab = Room.from_toml(ROOT / "examples/l-shaped-lab.toml")
    tech = Room.techtile()
    out = {}
    for name, room in (("techtile", tech), ("l-shaped-lab", lab)):
        cand = candidate_grid(room, 0.4)
        cand = cand[np.linspace(0, len(cand) - 1, n_cand).astype(int)]
        range_table(room, cand[:2], room.grid()[:5], draws=1)  # compile
        t0 = time.perf_counter()
        tab = range_table(room, cand, draws=3, exact_draws=2, mount_tolerance=0.03, rng=0)
        seconds = time.perf_counter() - t0
        out[name] = seconds / tab.windows
        emit("polygon", part="table", room=name, candidates=n_cand, nodes=tab.nodes.shape[1],
             draws=3, seconds=seconds, us_per_window=1e6 * out[name])  # fmt: skip
    emit("polygon", part="table", ratio_lab_over_techtile=out["l-shaped-lab"] / out["techtile"])


def rooms_by_complexity() -> dict[str, Room]:
    u = [[0, 0], [9, 0], [9, 6], [6, 6], [6, 2], [3, 2], [3, 6], [0, 6]]
    cols = [[1.5, 1.3], [5.3, 1.3], [1.3, 4.5], [5.8, 2.2], [0.8, 0.7], [4.2, 2.4],
            [6.2, 0.8], [2.2, 3.6]]  # fmt: skip

    def columns(k):
        return [{"min": [x, y, 0.0], "max": [x + 0.4, y + 0.4, 3.0]} for x, y in cols[:k]]

    return {
        "shoebox (shoebox method)": Room(size=(7.0, 6.0, 3.0), absorption={"west": 0.45,
                                                                           "east": 0.45}),
        "shoebox (polygon method)": Room.from_corners([[0, 0], [7, 0], [7, 6], [0, 6]], 3.0),
        "L": Room.from_corners(L_CORNERS, 3.0),
        "U": Room.from_corners(u, 3.0),
        "L + 2 columns": Room.from_corners(L_CORNERS, 3.0, obstacles=columns(2)),
        "L + 4 columns": Room.from_corners(L_CORNERS, 3.0, obstacles=columns(4)),
        "L + 8 columns": Room.from_corners(L_CORNERS, 3.0, obstacles=columns(8)),
    }  # fmt: skip


def paths_cost(n_nodes: int) -> None:
    rng = np.random.default_rng(0)
    for name, room in rooms_by_complexity().items():
        a = points(room, 8, rng)
        p = points(room, n_nodes, rng)
        compute_paths(room, a[:1], p[:2])  # compile
        t0 = time.perf_counter()
        paths = compute_paths(room, a, p)
        seconds = time.perf_counter() - t0
        refl = None if room.is_shoebox and not room.obstacles else reflectors(room)
        n_img = (np.nan if refl is None else
                 float(np.mean([len(images(refl, s, 3, 3)[0]) for s in a])))  # fmt: skip
        emit("polygon", part="paths", room=name, walls=len(room.walls),
             obstacles=len(room.obstacles), reflectors=None if refl is None else len(refl),
             images_per_anchor=n_img, paths_per_pair=float(np.mean(np.sum(paths.amplitude > 0,
                                                                         -1))),
             line_of_sight=float(np.mean(paths.los)),
             us_per_pair=1e6 * seconds / paths.los.size)  # fmt: skip


def peer(n_nodes: int) -> None:
    from peer import pra_general_windows

    rooms = {
        "L-shaped": Room.from_corners(L_CORNERS, 3.0, max_order=2),
        "box obstacle": Room(size=(6.0, 4.0, 3.0), max_order=2,
                             absorption={"west": 0.45, "east": 0.45},
                             obstacles=[{"min": [2.5, 1.5, 0.0], "max": [3.5, 2.5, 2.0]}]),
    }  # fmt: skip
    for name, room in rooms.items():
        rng = np.random.default_rng(7)
        a, p = points(room, 3, rng), points(room, n_nodes, rng)
        t0 = time.perf_counter()
        wp, los_peer = pra_general_windows(room, a, p)
        t_peer = time.perf_counter() - t0
        paper = System.paper()  # the peer simulates the paper's signal
        dsp = dsp_for(paper.chirp, paper.receiver, "float64")
        compute_paths(room, a[:1], p[:1], directivity="omni")  # compile
        t0 = time.perf_counter()
        paths = compute_paths(room, a, p, directivity="omni")
        w = received_windows(paths, room.speed_of_sound, paper.chirp, paper.receiver)
        t_ours = time.perf_counter() - t0
        r_ours = dsp.ranges(w, room.speed_of_sound)
        t_dsp = time.perf_counter() - t0 - t_ours
        r_peer = dsp.ranges(wp, room.speed_of_sound)
        rel = np.linalg.norm(w - wp, axis=-1) / np.maximum(np.linalg.norm(wp, axis=-1), 1e-30)
        emit("polygon", part="peer", room=name, pairs=int(paths.los.size),
             within_1cm=float(np.mean(np.abs(r_ours - r_peer) <= 0.01)),
             line_of_sight_agree=float(np.mean(paths.los == los_peer)),
             pairs_without_sight=int(np.sum(~paths.los)),
             window_relative_difference_median=float(np.median(rel)),
             us_per_pair_ours=1e6 * t_ours / paths.los.size,
             us_per_pair_peer=1e6 * t_peer / paths.los.size,
             us_per_pair_dsp=1e6 * t_dsp / paths.los.size,
             speed_ratio=t_peer / t_ours,
             speed_ratio_to_ranges=(t_peer + t_dsp) / (t_ours + t_dsp))  # fmt: skip


def obstacle_order(n_nodes: int, rooms, system_name=None) -> None:
    for path in rooms:
        room = Room.from_toml(path)
        name = room.name or Path(path).stem
        # the room file's [system], if any, or the one named
        system = System.preset(system_name) if system_name else System.from_toml(path)
        a = naive_layout(room, 8)
        p = room.grid()[np.linspace(0, len(room.grid()) - 1, n_nodes).astype(int)]
        full = None
        for order in sorted({room.max_order, 2, 1, 0}, reverse=True):
            r = dataclasses.replace(room, obstacle_order=order)
            t0 = time.perf_counter()
            scene = RangingScene(r, a, p, system=system)
            seconds = time.perf_counter() - t0
            ranges = scene.ranges(noise=False)
            if full is None:
                full = ranges
            moved = np.abs(np.nan_to_num(ranges, nan=-1) - np.nan_to_num(full, nan=-1)) > 0.01
            paths = compute_paths(r, a, p)
            emit("polygon", part="obstacle_order", room=name, system=system.name,
                 obstacle_order=order, images=len(images(reflectors(r), a[0], r.max_order,
                                                         order)[0]),
                 paths_per_pair=float(np.mean(np.sum(paths.amplitude > 0, -1))),
                 share_moved_over_1cm=float(np.mean(moved)),
                 us_per_pair=1e6 * seconds / ranges.size)  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer nodes and candidates")
    ap.add_argument("--parts", nargs="+", default=["table", "paths", "peer", "obstacle_order"])
    ap.add_argument(
        "--rooms",
        nargs="+",
        metavar="TOML",
        default=[ROOT / "examples/l-shaped-lab.toml", ROOT / "examples/warehouse-aisles.toml"],
        help="the rooms of the obstacle_order part (the lab and the warehouse)",
    )
    ap.add_argument("--system", help="the system of the obstacle_order part (a preset; "
                    "default: each room file's)")  # fmt: skip
    args = ap.parse_args()
    q = args.quick
    if "table" in args.parts:
        table_cost(16 if q else 96)
    if "paths" in args.parts:
        paths_cost(60 if q else 300)
    if "peer" in args.parts:
        peer(10 if q else 100)
    if "obstacle_order" in args.parts:
        obstacle_order(30 if q else 120, args.rooms, args.system)


if __name__ == "__main__":
    main()

"""Figure rendering time: build + render to PNG bytes, each figure type at its default
size and 100 dpi (synthetic data with the shapes of a real 4-anchor result).

Run: python benchmarks/bench_figures.py  (prints one JSON line per figure type)
Target (issue 6): each figure under about 1 s.
"""

import numpy as np
from _common import best_time, emit

import analysis
from analysis import figures as F
from simulation import Room


def main() -> None:
    rng = np.random.default_rng(0)
    room = Room.techtile()
    nodes = room.grid()
    corners = room.corners_layout()
    opt = np.array([[0.6, 0.03, 1.3], [6.1, 0.03, 0.9], [1.2, 3.97, 1.6], [5.7, 3.97, 1.5]])
    R = 100
    err = {k: rng.gamma(2.0, s, (R, 270)) for k, s in (("corners", 0.6), ("optimized", 0.4))}
    axerr = {k: rng.normal(0, s, (R, 270, 3)) for k, s in (("corners", 0.5), ("optimized", 0.3))}
    peb = {"corners": analysis.peb(corners, nodes), "optimized": analysis.peb(opt, nodes)}
    rmse = {k: np.sqrt(np.mean(v**2, axis=0)) for k, v in err.items()}
    T = 40
    hist = np.linspace(1.6, 0.98, T)
    bah = np.array([corners + (opt - corners) * t / (T - 1) for t in range(T)])
    cases = {
        "peb_map_4_panels": lambda: F.peb_map(room, opt, heights=[0.05, 1.2, 2.35], y_cuts=[2.0]),
        "scatter3d": lambda: F.scatter3d(room, nodes, peb["optimized"], opt),
        "scatter3d_panels_2": lambda: F.scatter3d_panels(
            room, nodes, peb, {"corners": corners, "optimized": opt}
        ),
        "error_cdfs_4_panels": lambda: F.error_cdfs(err, axerr),
        "bound_gap_cdfs": lambda: F.bound_gap_cdfs(peb, rmse),
        "plan_view": lambda: F.plan_view(room, opt),
        "dop_difference_layers": lambda: F.dop_difference(
            room, nodes, 2.5 + rng.random(270), 1.7 + rng.random(270)
        ),
        "layout_views_4": lambda: F.layout_views(
            room, {"a": corners, "b": opt, "c": corners[::-1], "d": opt[::-1]}
        ),
        "pso_evolution_3": lambda: F.pso_evolution(room, hist, bah, iterations=[1, 20, 40]),
    }
    F.png_bytes(F.peb_map(room, corners, dpi=20))  # warm up fonts and caches
    for name, make in cases.items():
        t = best_time(lambda make=make: F.png_bytes(make()), repeat=3)
        emit(f"figure_{name}", dpi=100, seconds=t, target_seconds=1.0)


if __name__ == "__main__":
    main()

"""The receiver study's figure from the JSON lines of ``bench_receiver.py``.

Run: python benchmarks/plot_receiver.py docs/benchmarks/receiver.jsonl \
        docs/images/receiver-study.png

Two rows (the paper's 270 nodes; the field figure: random tag points, anchors mounted
within 3 cm), one column per room: the median (solid) and P95 (dashed) error against the
window length, one colour per pick, circles for the layout planned for the paper's
receiver and squares for the layout planned for the receiver it is evaluated with (or,
from a run without ``--own``, for the design its name gives).
"""

import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def _series(row: dict) -> str:
    """The row's layout: "paper", "own" (planned for the design it is evaluated under) or
    the name of the design it was planned for."""
    if row["layout"] == f"{row['window_ms']:g}ms-{row['pick']}":
        return "own"
    return row["layout"]


def main(src: str, dst: str) -> None:
    rows = [json.loads(line) for line in open(src) if line.strip()]
    rooms = sorted({r["room"] for r in rows}, key=lambda n: n != "techtile")
    fig, axes = plt.subplots(2, len(rooms), figsize=(5.2 * len(rooms), 7.2), squeeze=False)
    colours = {"paper": "tab:blue", "first-path": "tab:red"}
    markers = {"paper": "o"}
    for col, room in enumerate(rooms):
        panels = (("nodes270", "the paper's 270 nodes"), ("field", "field: random tags, 3 cm"))
        for row, (key, title) in enumerate(panels):
            ax = axes[row, col]
            for layout in sorted({_series(r) for r in rows if r["room"] == room}):
                for pick, colour in colours.items():
                    pts = sorted(
                        (r["window_ms"], r[key]["median"], r[key]["p95"])
                        for r in rows
                        if r["room"] == room and _series(r) == layout and r["pick"] == pick
                    )
                    if not pts:
                        continue
                    w, med, p95 = zip(*pts, strict=True)
                    m = markers.get(layout, "s")
                    who = {"paper": "the paper's receiver", "own": "that receiver"}.get(
                        layout, layout
                    )
                    lab = f"{pick} pick, layout planned for {who}"
                    ax.plot(w, med, "-", marker=m, color=colour, label=lab, alpha=0.85)
                    ax.plot(w, p95, "--", marker=m, color=colour, alpha=0.5)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xticks([1, 2, 5, 10, 20, 30], ["1", "2", "5", "10", "20", "30"])
            ax.set_xlabel("receiver window (ms), closing with the 30 ms chirp")
            ax.set_ylabel("error (m): median solid, P95 dashed")
            ax.set_title(f"{room}: {title}", fontsize=10)
            ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    fig.savefig(dst, dpi=110)


if __name__ == "__main__":
    main(*sys.argv[1:3])

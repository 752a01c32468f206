"""A planned layout against the naive and the corners layouts of the same room, with the
same system (BENCHMARKS.md, "Rooms with obstacles").

Run:

    python benchmarks/bench_against_naive.py docs/examples/l-shaped-lab-recommended \\
        --room examples/l-shaped-lab.toml --system recommended

The plan's layout (RESULT_DIR/layout.json), ``placement.naive_layout(room, M)`` and the
room's corners layout are each evaluated in the field (the plan's validation's field check:
``--draws`` draws of 300 random tags in the zones with the anchors mounted within 3 cm, one
noise realization, the same streams for every layout; other draws with ``--seed``). One
JSON line per layout: median, mean, P95, RMS and the share of verified fixes, and the RMS
error's reduction against the plan's.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from _common import FIELD_SEED, emit, error_summary, field_draws, room_and_system, room_parser

from placement import naive_layout


def main() -> None:
    ap = room_parser(__doc__)
    ap.add_argument("result_dir")
    ap.add_argument("--draws", type=int, default=10)
    ap.add_argument("--seed", type=int, default=FIELD_SEED,
                    help=f"the field draws' seed ({FIELD_SEED})")  # fmt: skip
    args = ap.parse_args()
    room, system = room_and_system(args)
    planned = np.array(json.loads((Path(args.result_dir) / "layout.json").read_text())["anchors"])
    layouts = {"planned": planned, "naive": naive_layout(room, len(planned)),
               "corners": room.corners_layout()}  # fmt: skip
    rms = {}
    for name, a in layouts.items():
        E = field_draws(room, a, system, args.draws, args.seed)
        summary = error_summary(E[0])
        if not summary:  # no tag has a fix (e.g. corners beyond the signal's reach)
            emit("against_naive", room=room.name, system=system.name, layout=name, M=len(a),
                 seed=args.seed, fixes=int(E[0].size), found=0)  # fmt: skip
            continue
        rms[name] = summary["rms"]
        emit("against_naive", room=room.name, system=system.name, layout=name, M=len(a),
             seed=args.seed, **summary, verified=float(np.mean(E[1] > 0)),
             rms_reduction_by_plan=1 - rms["planned"] / rms[name])  # fmt: skip


if __name__ == "__main__":
    main()

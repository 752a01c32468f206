"""The field check of finished plans under both positioning conventions.

Run: python benchmarks/field_conventions.py RUNS.jsonl [...]   (lines of bench_effort.py)

For every run (its anchors, M and seed) the field check of its validation is drawn again,
exactly as the plan drew it (``validate_layout``'s field stream of the plan's validation
seed; 10 draws of 300 tags, the anchors mounted within 3 cm), and summarized with the
positions solved as every figure solves them (started inside the room, unbounded) and with
the iterates kept inside the room: one JSON line per run, then the medians and worst per
preset and M.
"""

from __future__ import annotations

import json
import statistics
import sys

import numpy as np
from _common import emit, read_lines

from placement.streams import phase_seed
from placement.validation import ValidationOptions, field_errors, summary
from simulation import Room


def main() -> None:
    room, opt = Room.techtile(), ValidationOptions()
    out: dict[tuple, list] = {}
    for r in read_lines(sys.argv[1:]):
        seed = phase_seed(r["seed"], "validation")
        # the field check's stream, as validate_layout derives it (its fifth child)
        child = int(np.random.SeedSequence(seed).spawn(5)[4].generate_state(1)[0])
        a = np.array(r["anchors"])
        e = np.concatenate([field_errors(room, a, opt.random_nodes, 0.03, d, child)
                            for d in range(opt.field_draws)], axis=1)  # fmt: skip
        s, b = summary(e[0]), summary(e[1])
        label = r["effort"] + "".join(f", {k} {json.dumps(c)}" for k, c in r["variant"].items())
        out.setdefault((label, r["M"]), []).append((s["std"], b["std"]))
        emit("field_conventions", preset=label, M=r["M"], seed=r["seed"],
             reported_std=r["field"]["std"], std=s["std"], bounded_std=b["std"],
             p95=s["p95"], bounded_p95=b["p95"])  # fmt: skip
    for (label, M), v in out.items():
        u, b = [x[0] for x in v], [x[1] for x in v]
        print(f"| {label} | {M} | {len(v)} | {statistics.median(u):.3f} / {max(u):.3f} | "
              f"{statistics.median(b):.3f} / {max(b):.3f} |")  # fmt: skip


if __name__ == "__main__":
    main()

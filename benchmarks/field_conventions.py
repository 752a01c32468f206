"""The field check of finished plans under both positioning conventions.

Run: python benchmarks/field_conventions.py RUNS.jsonl [...]   (lines of bench_effort.py)

For every run (its anchors, M and seed) the field check of its validation is drawn again
with the plan's validation stream (``validate_layout`` with the default options: 10
draws of 300 tags, the anchors mounted within 3 cm) and summarized with the positions
solved as every figure solves them (started inside the room, unbounded) and with the
iterates kept inside the room (``validation.field.bounded``): one JSON line per run, then
the medians and worst per preset and M.
"""

from __future__ import annotations

import json
import statistics
import sys

import numpy as np
from _common import emit, read_lines

from placement.streams import phase_seed
from placement.validation import ValidationOptions, validate_layout
from simulation import Room

#: the field check alone (the grid check's one realization is the least validate_layout runs)
FIELD_ONLY = ValidationOptions(realizations=1, held_out_realizations=0, mount_draws=0)


def main() -> None:
    room = Room.techtile()
    out: dict[tuple, list] = {}
    for r in read_lines(sys.argv[1:]):
        v = validate_layout(room, np.array(r["anchors"]), options=FIELD_ONLY,
                            rng=phase_seed(r["seed"], "validation"))  # fmt: skip
        f = v.field
        label = r["effort"] + "".join(f", {k} {json.dumps(c)}" for k, c in r["variant"].items())
        out.setdefault((label, r["M"]), []).append((f.std, f.bounded.std))
        emit("field_conventions", preset=label, M=r["M"], seed=r["seed"],
             reported_std=r["field"]["std"], std=f.std, bounded_std=f.bounded.std,
             p95=f.p95, bounded_p95=f.bounded.p95)  # fmt: skip
    for (label, M), v in out.items():
        u, b = [x[0] for x in v], [x[1] for x in v]
        print(f"| {label} | {M} | {len(v)} | {statistics.median(u):.3f} / {max(u):.3f} | "
              f"{statistics.median(b):.3f} / {max(b):.3f} |")  # fmt: skip


if __name__ == "__main__":
    main()

"""Where a layout's field error comes from: the anchors each tag sees in line of sight and
their geometry (BENCHMARKS.md, "Where the warehouse's field error comes from").

Run:

    python benchmarks/bench_field_geometry.py docs/examples/warehouse-sweep/layouts.json \\
        --M 20 --room examples/warehouse-aisles.toml \\
        --system docs/benchmarks/robust/warehouse-recommended.toml

The layout (a plan's layout.json, or a sweep's layouts.json with ``--M``) is evaluated in
the field as ``bench_against_naive.py`` does (``--draws`` draws of 300 random tags in the
zones, anchors mounted within 3 cm, one noise realization, the same streams; other draws
with ``--seed``). For each tag
it counts the anchors in line of sight and reach and their dilution of precision, GDOP =
√tr (HᵀH)⁻¹ over those anchors only (∞ with fewer than 3 or a singular H). JSON lines: one
per count of anchors in line of sight (tags, median error, verified share), one per GDOP
band (share of the tags, share of the squared error, median error), and a summary (median,
mean, P95, RMS, the share of verified fixes and of those farther off than the system's
alert limit, GDOP percentiles).
"""

from __future__ import annotations

import json

import numpy as np
from _common import FIELD_SEED, emit, room_and_system, room_parser

from analysis.fim import peb
from placement.rangetable import sight
from placement.validation import field_errors, field_tags

TAGS = 300


def load_layout(path: str, M: int | None) -> np.ndarray:
    """(M, 3) anchors of a plan's layout.json or of a sweep's layouts.json (key ``M``)."""
    with open(path) as f:
        data = json.load(f)
    if "anchors" in data:
        return np.asarray(data["anchors"], dtype=float)
    if M is None:
        raise SystemExit(f"--M: {path} holds the layouts of M = {', '.join(data)}; choose one")
    return np.asarray(data[str(M)], dtype=float)


def tag_geometry(room, system, anchors, draws: int, seed: int = FIELD_SEED):
    """Per tag of the field draws (of ``seed``): errors (m), verified, anchors in sight
    (n,), GDOP (n,)."""
    parts = []
    for d in range(draws):
        E = field_errors(room, anchors, TAGS, 0.03, d, seed, system=system)
        tags = field_tags(room, TAGS, d, seed)  # the tags of field_errors' draw d
        seen = sight(room, system, anchors, tags)  # line of sight and reach
        g = peb(anchors, tags, sigma=np.where(seen, 1.0, np.inf))  # GDOP of the seen
        parts.append((E[0], E[1] > 0, seen.sum(axis=1), g))
    return [np.concatenate(p) for p in zip(*parts, strict=True)]


def main() -> None:
    ap = room_parser(__doc__)
    ap.add_argument("layout", help="a plan's layout.json or a sweep's layouts.json")
    ap.add_argument("--M", type=int, default=None, help="the sweep's M (layouts.json)")
    ap.add_argument("--draws", type=int, default=10)
    ap.add_argument("--seed", type=int, default=FIELD_SEED,
                    help=f"the field draws' seed ({FIELD_SEED})")  # fmt: skip
    args = ap.parse_args()
    room, system = room_and_system(args)
    anchors = load_layout(args.layout, args.M)
    e, verified, seen, g = tag_geometry(room, system, anchors, args.draws, args.seed)
    ok = np.isfinite(e)
    e2 = np.where(ok, e, 0.0) ** 2
    tag = {"room": room.name, "system": system.name, "layout": args.layout,
           "M": len(anchors), "seed": args.seed}  # fmt: skip
    for k in np.unique(seen):
        s = (seen == k) & ok
        if s.any():
            emit("field_sight", **tag, in_sight=int(k), tags=int(s.sum()),
                 median=float(np.median(e[s])), verified=float(verified[s].mean()))  # fmt: skip
    for lo, hi in ((0, 2), (2, 3), (3, 5), (5, 10), (10, 20), (20, np.inf)):
        s = (g >= lo) & (g < hi) & ok
        emit("field_gdop", **tag, gdop_from=lo, gdop_to=float(hi), share=float(s.mean()),
             share_of_squared_error=float(e2[s].sum() / e2.sum()),
             median=float(np.median(e[s])) if s.any() else None)  # fmt: skip
    gf = g[np.isfinite(g)]
    emit("field_geometry", **tag, tags=int(e.size), fixes=int(ok.sum()),
         median=float(np.median(e[ok])), mean=float(e[ok].mean()),
         p95=float(np.percentile(e[ok], 95)), rms=float(np.sqrt(e2[ok].mean())),
         verified=float(verified.mean()),
         # a verified fix beyond the alert limit its verification vouches for is wrong
         verified_wrong=float(np.mean(e[verified] > system.positioning.alert_limit))
         if verified.any() else 0.0,
         gdop_median=float(np.median(gf)),
         gdop_p90=float(np.percentile(gf, 90)), gdop_p97=float(np.percentile(gf, 97)),
         no_gdop=float(np.mean(~np.isfinite(g))))  # fmt: skip


if __name__ == "__main__":
    main()

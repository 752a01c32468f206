"""Compare two results (``result.json``, ``sweep.json``, ...) as results, not as bits.

Two machines round floating-point sums differently (another BLAS kernel, another SIMD
width); the planner's choices and the receiver's picks do not depend on it (docs/model.md,
"Results on every machine"), but the last digits of its figures do. Two results are the
same when

- every string, integer, boolean and null is equal, every list has the same length and
  every object the same keys (measured times and resume markers left out: :data:`SKIP`);
- every anchor coordinate (keys :data:`COORDINATES`) agrees to 1 µm;
- every other number agrees to a relative 1e-6 (:data:`RTOL`), or to :data:`ATOL` near
  zero: positions are solved to a tolerance, so a node's statistic near zero may differ
  by 1e-7 m between machines; the validation's ``errors`` are written to the micrometre,
  so they agree to 1 µm.

Usable as a script: ``python tests/drift.py OLD.json NEW.json`` prints the differences
and exits 1 when there are any.
"""

from __future__ import annotations

import json
import math
import sys

#: keys whose values are measured times or say that a run was resumed, not results
SKIP = {"timings", "seconds", "elapsed", "resumed", "resumed_from"}
#: keys holding anchor coordinates (m): compared to 1 µm
COORDINATES = {"anchors", "best_anchors_history", "pbest", "gbest"}
#: relative tolerance of every other number
RTOL = 1e-6
#: absolute tolerance near zero: positions solved to a tolerance (1e-7 m), and values
#: written to the micrometre (the validation's ``errors``)
ATOL = {"default": 1e-7, "errors": 1e-6 + 1e-12, "coordinates": 1e-6}


def results(x):
    """``x`` without the keys of :data:`SKIP`."""
    if isinstance(x, dict):
        return {k: results(v) for k, v in x.items() if k not in SKIP}
    if isinstance(x, list):
        return [results(v) for v in x]
    return x


def _close(a: float, b: float, kind: str) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    if math.isinf(a) or math.isinf(b):
        return a == b
    rtol = 0.0 if kind == "coordinates" else RTOL
    return abs(a - b) <= rtol * max(abs(a), abs(b)) + ATOL[kind]


def differences(old, new, path: str = "", kind: str = "default") -> list[str]:
    """The differences between two results (module docstring), one line each."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = [f"{path}/{k}: missing on one side" for k in sorted(set(old) ^ set(new))]
        for k in sorted(set(old) & set(new)):
            sub = "coordinates" if k in COORDINATES else ("errors" if k == "errors" else kind)
            out += differences(old[k], new[k], f"{path}/{k}", sub)
        return out
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            return [f"{path}: {len(old)} items against {len(new)}"]
        return [d for i, (u, v) in enumerate(zip(old, new, strict=True))
                for d in differences(u, v, f"{path}[{i}]", kind)]  # fmt: skip
    differ = [f"{path}: {old!r} against {new!r}"]
    if isinstance(old, float) or isinstance(new, float):
        both = all(isinstance(x, int | float) and not isinstance(x, bool) for x in (old, new))
        return [] if both and _close(float(old), float(new), kind) else differ
    return [] if old == new and type(old) is type(new) else differ


def compare(old, new) -> list[str]:
    """:func:`differences` of two results without their times and resume markers."""
    return differences(results(old), results(new))


if __name__ == "__main__":
    a, b = (json.loads(open(p).read()) for p in sys.argv[1:3])
    found = compare(a, b)
    print("\n".join(found) if found else "the same (to the tolerances of tests/drift.py)")
    sys.exit(1 if found else 0)

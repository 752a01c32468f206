"""The results check of tests/drift.py: it passes what another machine's rounding changes
and fails what a real change changes."""

import copy
import json
from pathlib import Path

from drift import compare

QUICK = Path(__file__).resolve().parents[1] / "docs" / "examples" / "quick" / "result.json"


def _result():
    return json.loads(QUICK.read_text())


def test_rounding_passes():
    old, new = _result(), _result()
    new["cost"] *= 1 + 5e-7
    new["anchors"][0][0] += 5e-7  # half a micrometre
    new["validation"]["std"] *= 1 - 9e-7
    new["validation"]["errors"][0][0] = round(new["validation"]["errors"][0][0] + 1e-6, 6)
    new["timings"]["total"] *= 3  # a slower machine
    new["phases"]["search"]["seconds"] += 10
    assert compare(old, new) == []


def test_real_changes_fail():
    old = _result()
    changes = {
        "a figure 1e-5 off": lambda d: d.__setitem__("cost", d["cost"] * (1 + 1e-5)),
        "an anchor 2 µm away": lambda d: d["anchors"][1].__setitem__(2, d["anchors"][1][2] + 2e-6),
        "another count": lambda d: d.__setitem__("nfev", d["nfev"] + 1),
        "another message": lambda d: d.__setitem__("message", d["message"] + "!"),
        "a key more": lambda d: d["validation"].__setitem__("new", 1.0),
        "a list shorter": lambda d: d["history"].pop(),
        "an error 3 µm off": lambda d: d["validation"]["errors"][2].__setitem__(
            5, d["validation"]["errors"][2][5] + 3e-6
        ),
        "a flag flipped": lambda d: d.__setitem__("success", not d["success"]),
        "a NaN for a number": lambda d: d.__setitem__("cost", float("nan")),
    }
    for what, change in changes.items():
        new = copy.deepcopy(old)
        change(new)
        assert compare(old, new), what

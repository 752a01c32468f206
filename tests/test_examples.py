"""The committed examples are what the code produces: the small one is planned again here
(scripts/regenerate_examples.sh regenerates them all)."""

import json
import math
import shlex
from pathlib import Path

import pytest

from placement.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "regenerate_examples.sh"
#: keys whose values are measured times, not results
TIMES = {"timings", "seconds", "elapsed"}


def _results(x):
    """``x`` without its measured times."""
    if isinstance(x, dict):
        return {k: _results(v) for k, v in x.items() if k not in TIMES}
    if isinstance(x, list):
        return [_results(v) for v in x]
    return x


def _same(a, b, path="") -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{path}/{k}: missing on one side" for k in set(a) ^ set(b)]
        return out + [d for k in set(a) & set(b) for d in _same(a[k], b[k], f"{path}/{k}")]
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} items against {len(b)}"]
        return [
            d
            for i, (u, v) in enumerate(zip(a, b, strict=True))
            for d in _same(u, v, f"{path}[{i}]")
        ]
    nan = isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b)
    return [] if a == b or nan else [f"{path}: {a!r} against {b!r}"]


@pytest.mark.slow
def test_the_quick_example_is_what_the_code_plans(tmp_path, capsys):
    """The command of scripts/regenerate_examples.sh for docs/examples/quick, run again:
    the same result.json but for the times. If this fails after a change that alters
    results on purpose, run the script and commit the examples."""
    line = next(ln for ln in SCRIPT.read_text().split("\n\n") if "--out $E/quick" in ln)
    argv = shlex.split(line.split("\n", 1)[1].replace("\\\n", " "))[1:]  # drop "$AP"
    argv[argv.index("$E/quick")] = str(tmp_path / "quick")
    assert main(argv) == 0
    capsys.readouterr()
    new = json.loads((tmp_path / "quick" / "result.json").read_text())
    old = json.loads((EXAMPLES / "quick" / "result.json").read_text())
    differences = _same(_results(old), _results(new))
    assert not differences, "docs/examples/quick is stale: " + "; ".join(differences[:5])

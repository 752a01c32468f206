"""The committed examples are what the code produces: the small one is planned again here
(scripts/regenerate_examples.sh regenerates them all)."""

import json
import shlex
from pathlib import Path

import pytest
from drift import compare

from placement.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "regenerate_examples.sh"


def quick_argv(out) -> list[str]:
    """The command of scripts/regenerate_examples.sh for docs/examples/quick, writing to
    ``out`` (the script's ``$AP`` dropped)."""
    line = next(ln for ln in SCRIPT.read_text().split("\n\n") if "--out $E/quick" in ln)
    argv = shlex.split(line.split("\n", 1)[1].replace("\\\n", " "))[1:]
    argv[argv.index("$E/quick")] = str(out)
    return argv


@pytest.mark.slow
def test_the_quick_example_is_what_the_code_plans(tmp_path, capsys):
    """The command of scripts/regenerate_examples.sh for docs/examples/quick, run again:
    the same result.json but for the times, compared as results (tests/drift.py: anchors
    to 1 µm, figures to a relative 1e-6), so that it holds on any machine. If this fails
    after a change that alters results on purpose, run the script and commit the examples."""
    assert main(quick_argv(tmp_path / "quick")) == 0
    capsys.readouterr()
    new = json.loads((tmp_path / "quick" / "result.json").read_text())
    old = json.loads((EXAMPLES / "quick" / "result.json").read_text())
    differences = compare(old, new)
    assert not differences, "docs/examples/quick is stale: " + "; ".join(differences[:5])

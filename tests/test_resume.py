"""A plan killed with SIGKILL in any phase and started again with the same --checkpoint
ends with the uninterrupted plan's layout and figures (tests/drift.py's tolerances)."""

import json

import pytest
from drift import compare
from killing import run, run_and_kill

#: a small plan with a swarm of three iterations, so that every phase takes a moment (the
#: validation too: a kill 0.3 s after its bar must find it running)
ARGS = ["plan", "--anchors", "4", "--search-spacing", "1.0", "--search-chains", "2",
        "--search-evaluations", "300", "--refine-layouts", "1", "--iterations", "3",
        "--validate-realizations", "30", "--workers", "2"]  # fmt: skip


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("plain") / "out"
    _, done = run([*ARGS, "--no-progress", "--out", str(out)])
    assert done.returncode == 0, done.stderr
    return json.loads((out / "result.json").read_text())


@pytest.mark.slow
@pytest.mark.parametrize("phase", ["search", "swarm", "refinement", "finalists", "validation"])
def test_a_plan_killed_in_any_phase_resumes_to_the_same_result(phase, tmp_path, uninterrupted):
    ckpt, out = tmp_path / "state.json", tmp_path / "out"
    argv = [*ARGS, "--checkpoint", str(ckpt), "--out", str(out)]
    _, killed, err = run_and_kill(argv, phase, delay=0.3)
    assert killed, f"the plan ended before its {phase} phase: {err[-500:]}"
    assert not (out / "result.json").exists()
    _, done = run([*argv, "--no-progress"])
    assert done.returncode == 0, done.stderr
    if phase != "search":  # the search had finished: the rerun reads it
        assert "search: resumed from" in done.stdout
    resumed = json.loads((out / "result.json").read_text())
    differences = compare(uninterrupted, resumed)
    assert not differences, "; ".join(differences[:5])

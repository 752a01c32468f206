import json

import numpy as np
import pytest

import placement
from placement.cli import main
from simulation import Room


@pytest.mark.slow
def test_plan_end_to_end_with_seeds_and_simulated_cost(tmp_path, capsys):
    out = tmp_path / "run"
    argv = [
        "plan",
        "--anchors",
        "4",
        "--particles",
        "4",
        "--iterations",
        "2",
        "--validate-realizations",
        "2",
        "--no-progress",
        "--seed",
        "3",
        "--search-starts",
        "1",
        "--search-realizations",
        "1",
        "--search-spacing",
        "2.0",
        "--finalists",
        "3",
        "--finalist-realizations",
        "1",
        "--workers",
        "1",
        "--out",
        str(out),
    ]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "validation over 2 realizations" in text
    res = json.loads((out / "result.json").read_text())
    layout = json.loads((out / "layout.json").read_text())
    room = Room.techtile()
    anchors = np.array(layout["anchors"])
    np.testing.assert_array_equal(anchors, np.array(res["anchors"]))
    assert placement.on_surfaces(room, anchors).all()
    assert res["cost_name"] == "variance" and res["nfev"] == 8
    # the simulation-driven seeds come first, then the analytic ones (at most particles // 2);
    # all were placed in the swarm and scored with the simulated cost
    assert [s["name"] for s in res["seeds"]] == ["simulated-1", "relax-A"]
    assert res["settings"]["seed_search"]["nfev"] > 0
    # on this coarse grid the simulated seed is 4 collinear ceiling points (PEB inf): the
    # swarm scores a degenerate layout inf (null in the JSON), so it is never the answer
    costs = [s["cost"] for s in res["seeds"]]
    assert all(c is None or c > 0 for c in costs)
    assert res["history"][-1] <= min(c for c in costs if c is not None)
    # the finalists were re-scored and the lowest re-scored one is the answer
    best = min(res["finalists"], key=lambda f: f["cost"])
    np.testing.assert_array_equal(anchors, np.array(best["anchors"]))
    assert res["cost"] == best["pso_cost"] and "finalist 1" in text
    v = res["validation"]
    assert v["realizations"] == 2 and len(v["errors"]) == 2 and len(v["errors"][0]) == 270
    assert abs(v["std"] - np.std(np.array(v["errors"]))) < 1e-5


def test_plan_bad_input_exit_2(tmp_path, capsys):
    assert main(["plan", "--anchors", "3", "--out", str(tmp_path)]) == 2
    assert "--anchors" in capsys.readouterr().err
    assert main(["plan", "--particles", "1", "--out", str(tmp_path)]) == 2
    assert "particles" in capsys.readouterr().err

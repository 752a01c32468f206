"""plan -> result.json -> PlacementResult.from_dict and -> the HTML report, round trip."""

import dataclasses
import json

import numpy as np

from analysis.report import write_report
from placement.plan import LOCAL_SWARM, seed_then_pso
from placement.plan_result import PlacementResult
from placement.simselect import SearchOptions
from placement.surfaces import naive_layout
from placement.validation import ValidationOptions
from simulation import Room

ROOM = Room.techtile()


def test_result_json_round_trip_and_report(tmp_path):
    search = SearchOptions(
        spacing=2.0, chains=1, evaluations=30, random_starts=3, neighbours=8, batch=4,
        patience=3, fine_spacings=(1.0,),
    )  # fmt: skip
    quick = ValidationOptions(realizations=2, held_out_realizations=1, random_nodes=10,
                              mount_draws=1)  # fmt: skip
    swarm = dataclasses.replace(LOCAL_SWARM, particles=3, iterations=1)
    res = seed_then_pso(ROOM, 4, search=search, swarm=swarm, validation=quick, rng=0,
                        progress=False)  # fmt: skip
    (tmp_path / "result.json").write_text(res.to_json(indent=1))
    back = PlacementResult.from_dict(json.loads((tmp_path / "result.json").read_text()))
    assert json.loads(back.to_json()) == {**json.loads(res.to_json()), "costs": None}
    np.testing.assert_array_equal(back.anchors, res.anchors)
    assert back.x.shape == (12,) and back.fun == back.cost and back.cost_unit == "m²"
    assert back.describe_status() == "a layout was planned"
    path, _ = write_report(tmp_path, realizations=0, comparisons={"naive": naive_layout(ROOM, 4)})
    page = path.read_text()
    for a in res.anchors:
        assert f"{a[0]:.3f}" in page
    assert "held-out" in page.lower() and "mounting" in page.lower()

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
    back = PlacementResult.read(tmp_path)  # the report's reader of result folders
    assert json.loads(back.to_json()) == {**json.loads(res.to_json()), "costs": None}
    np.testing.assert_array_equal(back.anchors, res.anchors)
    # typed, as planned: the validation's checks and the options objects come back
    assert back.validation.field == res.validation.field and back.validation.field is not None
    assert back.validation.held_out == res.validation.held_out
    assert back.settings == res.settings and back.settings.swarm.particles == 3
    assert back.x.shape == (12,) and back.fun == back.cost and back.cost_unit == "m²"
    assert back.describe_status() == "a layout was planned"
    path, _ = write_report(tmp_path, realizations=0, comparisons={"naive": naive_layout(ROOM, 4)})
    page = path.read_text()
    for a in res.anchors:
        assert f"{a[0]:.3f}" in page
    assert "held-out" in page.lower() and "mounting" in page.lower()


def test_reading_a_folder_without_a_plan_is_a_value_error_naming_it(tmp_path):
    import pytest

    with pytest.raises(ValueError, match="RESULT_DIR.*neither result.json"):
        PlacementResult.read(tmp_path)
    (tmp_path / "evaluation.json").write_text(json.dumps({"anchors": [[0, 0, 0]]}))
    with pytest.raises(ValueError, match="has no result.json"):
        PlacementResult.read(tmp_path)

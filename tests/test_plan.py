import json

import numpy as np
import pytest

import placement
from placement.plan import seed_then_pso
from simulation import Room

ROOM = Room.techtile()


def test_seed_then_pso_bound_driven_with_user_seeds():
    seeds = ROOM.corners_layout()[None]
    res = seed_then_pso(
        ROOM,
        4,
        particles=6,
        iterations=5,
        cost="peb",
        seeds=seeds,
        seed=0,
        progress=False,
        validate_realizations=0,
    )
    assert res.anchors.shape == (4, 3)
    assert placement.on_surfaces(ROOM, res.anchors).all()
    assert res.seeds[0].name == "user-1"
    assert res.seeds[0].cost == pytest.approx(res.seeds[0].mean_peb)
    assert res.cost <= res.seeds[0].cost
    assert np.all(np.diff(res.history) <= 0)
    d = json.loads(res.to_json())
    assert d["settings"]["M"] == 4 and len(d["history"]) == res.nit
    assert set(res.timings) >= {"seeding", "pso", "validation", "total"}


def test_seed_then_pso_rejects_bad_input():
    with pytest.raises(ValueError, match="M"):
        seed_then_pso(ROOM, 3, cost="peb", seeds=None, progress=False)
    with pytest.raises(ValueError, match="seeds"):
        seed_then_pso(ROOM, 4, cost="peb", seeds="best", progress=False)
    with pytest.raises(ValueError, match="validate_realizations"):
        seed_then_pso(ROOM, 4, cost="peb", seeds=None, validate_realizations=-1)

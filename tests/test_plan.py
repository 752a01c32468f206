import json
from itertools import combinations

import numpy as np
import pytest

import placement
from placement.costs import SimulatedCost
from placement.plan import rescore_finalists, seed_then_pso
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


def test_seed_then_pso_keeps_the_finalist_with_the_lowest_rescored_cost():
    nodes = ROOM.grid()[::27]
    kw = dict(particles=6, iterations=3, seeds=None, seed=3, progress=False, nodes=nodes)
    res = seed_then_pso(
        ROOM, 4, finalists=3, finalist_realizations=2, validate_realizations=0, **kw
    )
    f = res.finalists
    assert 2 <= len(f) <= 3
    assert f[0]["pso_cost"] == res.pso.cost
    assert np.all(np.diff([d["pso_cost"] for d in f]) >= 0)
    assert not any(np.allclose(a["anchors"], b["anchors"]) for a, b in combinations(f, 2))
    best = min(f, key=lambda d: d["cost"])
    assert np.array_equal(res.anchors, best["anchors"]) and res.cost == best["pso_cost"]
    # re-scored on common draws: the cost is the simulated statistic with that seed
    scorer = SimulatedCost(ROOM, "variance", realizations=2, nodes=nodes)
    again = rescore_finalists(res.pso, scorer, 3, 2, seed=7)
    assert [d["cost"] for d in again] == [
        scorer(d["anchors"], np.random.default_rng(7)) for d in again
    ]
    # one finalist: the swarm's best as it is
    one = seed_then_pso(ROOM, 4, finalists=1, validate_realizations=0, **kw)
    assert np.array_equal(one.anchors, res.pso.anchors) and one.finalists == []
    with pytest.raises(ValueError, match="finalists"):
        seed_then_pso(ROOM, 4, finalists=0, **kw)

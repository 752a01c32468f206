import itertools
import json
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import simulation
from placement.simselect import range_table, simulated_select, table_cost, table_costs
from placement.surfaces import candidate_grid, on_surfaces
from simulation import Room

ROOM = Room.techtile()
NODES = ROOM.grid()[::9]  # 30 nodes: small and fast
CAND = candidate_grid(ROOM, 2.0)


def test_a_range_depends_on_its_own_anchor_only():
    # the premise of the range table: TDM anchors, per-anchor noise level (paper §V-A)
    a, b = CAND[[0, 5, 11, 17]], CAND[[0, 3, 8, 20]]
    ra = simulation.simulate_ranges(ROOM, a, NODES, noise=False)
    rb = simulation.simulate_ranges(ROOM, b, NODES, noise=False)
    np.testing.assert_array_equal(ra[:, 0], rb[:, 0])
    assert not np.allclose(ra[:, 1], rb[:, 1])


def test_range_table_is_independent_of_chunking_and_executor():
    t1 = range_table(ROOM, CAND[:10], NODES, realizations=2, seed=4, chunk=3)
    with ThreadPoolExecutor(2) as ex:
        t2 = range_table(ROOM, CAND[:10], NODES, realizations=2, seed=4, chunk=7, executor=ex)
    np.testing.assert_array_equal(t1.ranges, t2.ranges)
    assert t1.ranges.shape == (2, len(NODES), 10) and t1.windows == 2 * len(NODES) * 10
    # two realizations differ (noise), and both scatter around the true ranges
    assert not np.array_equal(t1.ranges[0], t1.ranges[1])
    err = t1.ranges - t1.distances
    assert np.mean(np.abs(err) < 0.5) > 0.5  # this room: about a quarter are outliers
    t3 = range_table(ROOM, CAND[:10], NODES, realizations=2, seed=5, chunk=3)
    assert not np.array_equal(t1.ranges, t3.ranges)


def test_table_cost_is_the_simulated_statistic_of_the_located_nodes():
    t = range_table(ROOM, CAND, NODES, realizations=2, seed=1)
    S = np.array([0, 6, 12, 19])
    x = simulation.locate(
        CAND[S], t.ranges[:, :, S], region=(np.zeros(3), np.asarray(ROOM.size, dtype=float))
    )
    e = np.linalg.norm(x - NODES, axis=-1)
    assert table_cost(t, S, "variance") == pytest.approx(np.var(e))
    assert table_cost(t, S, "p95") == pytest.approx(np.percentile(e, 95))


def test_simulated_select_returns_a_swap_local_optimum():
    cand = CAND[:10]
    t = range_table(ROOM, cand, NODES, realizations=1, seed=2)
    sel = simulated_select(ROOM, 4, table=t, starts=2, random_starts=3, neighbours=9, seed=0)
    assert sel.message == "local optima reached"
    assert sel.anchors.shape == (4, 3) and on_surfaces(ROOM, sel.anchors).all()
    assert sel.cost == pytest.approx(table_cost(t, sel.indices))
    # no single swap with any unused candidate improves the returned layout
    for i, j in itertools.product(range(4), range(10)):
        if j in sel.indices:
            continue
        T = sel.indices.copy()
        T[i] = j
        assert table_cost(t, T) >= sel.cost
    # and it beats the typical random layout by a margin
    rng = np.random.default_rng(0)
    random_costs = [table_cost(t, rng.choice(10, 4, replace=False)) for _ in range(20)]
    assert sel.cost < np.median(random_costs)
    costs = [c for _, c in sel.optima]
    assert costs == sorted(costs) and costs[0] == sel.cost
    d = json.loads(json.dumps(sel.to_dict()))
    assert d["indices"] == sel.indices.tolist() and d["nfev"] == sel.nfev > 0


def test_simulated_select_is_reproducible_serial_or_parallel():
    kw = dict(candidates=CAND, nodes=NODES, realizations=1, starts=2, random_starts=3, seed=11)
    s1 = simulated_select(ROOM, 4, **kw)
    with ThreadPoolExecutor(2) as ex:
        s2 = simulated_select(ROOM, 4, executor=ex, **kw)
    np.testing.assert_array_equal(s1.indices, s2.indices)
    assert s1.cost == s2.cost and s1.nfev == s2.nfev
    assert s1.equivalent_evaluations == pytest.approx(len(CAND) * len(NODES) / (len(NODES) * 4))


def test_simulated_select_rejects_bad_input():
    with pytest.raises(ValueError, match="statistic"):
        simulated_select(ROOM, 4, statistic="median", candidates=CAND, nodes=NODES)
    with pytest.raises(ValueError, match="M"):
        simulated_select(ROOM, 3, candidates=CAND, nodes=NODES)
    with pytest.raises(ValueError, match="starts"):
        simulated_select(ROOM, 4, starts=-1, candidates=CAND, nodes=NODES)
    with pytest.raises(ValueError, match="realizations"):
        range_table(ROOM, CAND, NODES, realizations=0)
    t = range_table(ROOM, CAND[:6], NODES, realizations=1, seed=0)
    with pytest.raises(ValueError, match="initial"):
        simulated_select(ROOM, 4, table=t, initial=[[0, 1, 2, 2]])
    with pytest.raises(ValueError, match="candidates"):
        simulated_select(ROOM, 8, table=t)


def test_layouts_scored_in_one_batch_score_as_one_by_one():
    t = range_table(ROOM, CAND[:12], NODES, realizations=2, seed=3)
    rng = np.random.default_rng(2)
    layouts = np.stack([rng.choice(12, 4, replace=False) for _ in range(6)])
    np.testing.assert_array_equal(table_costs(t, layouts), [table_cost(t, S) for S in layouts])

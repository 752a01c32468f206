import itertools
import json
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import simulation
from placement.plan import seed_then_pso
from placement.rangetable import (
    MAX_TABLE_DRAWS,
    extend_table,
    mounted_points,
    node_draws,
    range_table,
    table_cost,
    table_costs,
    table_errors,
)
from placement.simselect import (
    Chain,
    SearchOptions,
    descend,
    nearest,
    refine_on_table,
    simulated_select,
    spread_layout,
    spread_starts,
)
from placement.surfaces import MAX_ANCHORS, candidate_grid, on_surfaces, surface_index
from simulation import Room

ROOM = Room.techtile()
NODES = ROOM.grid()[::9]  # 30 nodes: small and fast
CAND = candidate_grid(ROOM, 2.0)
REGION = (np.zeros(3), np.asarray(ROOM.size, dtype=float))


def test_a_range_depends_on_its_own_anchor_only():
    # the premise of the range table: TDM anchors, per-anchor noise level
    a, b = CAND[[0, 5, 11, 17]], CAND[[0, 3, 8, 20]]
    ra = simulation.simulate_ranges(ROOM, a, NODES, noise=False)
    rb = simulation.simulate_ranges(ROOM, b, NODES, noise=False)
    np.testing.assert_array_equal(ra[:, 0], rb[:, 0])
    assert not np.allclose(ra[:, 1], rb[:, 1])


def test_range_table_is_independent_of_chunking_and_executor():
    kw = dict(draws=3, exact_draws=1, mount_tolerance=0.03, rng=4)
    t1 = range_table(ROOM, CAND[:10], NODES, chunk=3, **kw)
    with ThreadPoolExecutor(2) as ex:
        t2 = range_table(ROOM, CAND[:10], NODES, chunk=7, executor=ex, **kw)
    np.testing.assert_array_equal(t1.ranges, t2.ranges)
    assert t1.ranges.shape == (3, len(NODES), 10) and t1.windows == 3 * len(NODES) * 10
    assert not np.array_equal(t1.ranges[0], t1.ranges[1])
    t3 = range_table(ROOM, CAND[:10], NODES, chunk=3, **{**kw, "rng": 5})
    assert not np.array_equal(t1.ranges, t3.ranges)


def test_extended_table_equals_the_bigger_table():
    kw = dict(draws=2, exact_draws=1, mount_tolerance=0.03, rng=1)
    small = range_table(ROOM, CAND[:6], NODES, **kw)
    grown = extend_table(ROOM, small, CAND[6:11])
    whole = range_table(ROOM, CAND[:11], NODES, **kw)
    np.testing.assert_array_equal(grown.ranges, whole.ranges)
    np.testing.assert_array_equal(grown.distances, whole.distances)


def test_draws_move_nodes_within_their_cells_and_anchors_within_the_tolerance():
    nodes = ROOM.grid()
    sets = node_draws(ROOM, nodes, 3, 1, rng=2)
    np.testing.assert_array_equal(sets[0], nodes)
    step = np.array([0.9875, 0.78, 0.575])
    move = np.abs(sets[1:] - nodes)
    assert np.all(move <= step / 2 + 1e-9) and np.mean(move > 0.01) > 0.7  # walls clip
    assert np.all(ROOM.contains(sets.reshape(-1, 3), margin=ROOM.node_margin - 1e-12))
    c = CAND[:12]
    m = mounted_points(ROOM, c, np.arange(12), 1, 0.03, False, rng=3)
    d = np.linalg.norm(m - c, axis=1)
    assert np.all(d <= 0.03 + 1e-12) and np.all(on_surfaces(ROOM, m))
    # in the plane of its own surface: the coordinate across the plane does not move
    same = surface_index(ROOM, m) == surface_index(ROOM, c)
    assert same.mean() > 0.8
    np.testing.assert_array_equal(mounted_points(ROOM, c, np.arange(12), 0, 0.03, True, 3), c)


def test_table_errors_are_the_located_nodes_of_every_draw():
    """The table's errors are the planner's fixes, solved by the system's positioning: the
    paper's started in the room, unbounded; a system that keeps them in the room."""
    S = np.array([0, 6, 12, 19])
    kept = simulation.System(positioning=simulation.Positioning(keep_in_room=True))
    t = range_table(ROOM, CAND, NODES, draws=2, exact_draws=1, mount_tolerance=0.03, rng=1,
                    system=kept)  # fmt: skip
    x = simulation.locate(CAND[S], t.ranges[:, :, S], region=REGION, bounded=True)
    assert np.all((x >= REGION[0]) & (x <= REGION[1]))
    paper = range_table(ROOM, CAND, NODES, draws=2, exact_draws=1, mount_tolerance=0.03, rng=1)
    free = simulation.locate(CAND[S], paper.ranges[:, :, S], region=REGION)
    np.testing.assert_allclose(
        table_errors(paper, S[None])[0], np.linalg.norm(free - paper.nodes, axis=-1).ravel()
    )
    e = np.linalg.norm(x - t.nodes, axis=-1).ravel()
    np.testing.assert_allclose(table_errors(t, S[None])[0], e)
    assert table_cost(t, S, "variance") == pytest.approx(np.var(e))
    assert table_cost(t, S, "p95") == pytest.approx(np.percentile(e, 95))


def test_layouts_scored_in_one_batch_score_as_one_by_one():
    t = range_table(ROOM, CAND[:12], NODES, draws=2, rng=3)
    rng = np.random.default_rng(2)
    layouts = np.stack([rng.choice(12, 4, replace=False) for _ in range(6)])
    np.testing.assert_array_equal(table_costs(t, layouts), [table_cost(t, S) for S in layouts])
    # no layouts: nothing to score, not an error
    none = np.zeros((0, 4), dtype=int)
    assert table_costs(t, none).shape == (0,)
    assert table_errors(t, none).shape == (0, t.draws * len(NODES))


def test_descent_returns_a_local_optimum_of_its_neighbourhood():
    t = range_table(ROOM, CAND[:14], NODES, rng=2)
    nbr = nearest(t.candidates, 6)
    from placement.simselect import _Scorer

    score = _Scorer(t, "variance", 10**6)
    start = np.array([0, 1, 2, 3])
    S, f, local = descend(start, table_cost(t, start), nbr, score, np.random.default_rng(0))
    assert local and f == pytest.approx(table_cost(t, S)) and f <= table_cost(t, start)
    for i, j in itertools.product(range(4), range(6)):
        k = nbr[S[i], j]
        if k in S:
            continue
        T = S.copy()
        T[i] = k
        assert table_cost(t, T) >= f


def _small(**kw):
    base = dict(spacing=2.0, chains=2, evaluations=60, random_starts=3, neighbours=8, batch=4)
    base.update(patience=3, draws=1, exact_draws=1)
    base.update(kw)
    return SearchOptions(**base)


def test_simulated_select_returns_local_optima_better_than_random():
    sel = simulated_select(ROOM, 4, options=_small(), nodes=NODES, rng=0)
    t = sel.table
    assert sel.success and sel.status == 0 and sel.fun == sel.cost
    assert sel.anchors.shape == (4, 3) and on_surfaces(ROOM, sel.anchors).all()
    assert sel.cost == pytest.approx(table_cost(t, sel.indices))
    nbr = nearest(t.candidates, 8)
    for i, j in itertools.product(range(4), range(8)):  # no swap with a neighbour improves
        k = nbr[sel.indices[i], j]
        if k not in sel.indices:
            T = sel.indices.copy()
            T[i] = k
            assert table_cost(t, T) >= sel.cost
    rng = np.random.default_rng(0)
    N = len(t.candidates)
    random_costs = [table_cost(t, rng.choice(N, 4, replace=False)) for _ in range(20)]
    assert sel.cost < np.median(random_costs)
    costs = [c for _, c in sel.optima]
    assert costs == sorted(costs) and costs[0] == sel.cost
    d = json.loads(json.dumps(sel.to_dict()))
    assert d["indices"] == sel.indices.tolist() and d["nfev"] == sel.nfev > 0


def test_spread_layout_is_farthest_point_sampling_with_stable_ties():
    line = np.column_stack([np.arange(11.0), np.zeros(11), np.zeros(11)])
    np.testing.assert_array_equal(spread_layout(line, 3), [0, 5, 10])
    box = np.array(list(itertools.product([0.0, 1.0], repeat=3)))  # corner 0 first, 7 next
    np.testing.assert_array_equal(spread_layout(box, 2), [0, 7])
    # the six other corners tie at 1 m from the two chosen: the lowest index wins, and a
    # difference in the last digits (another machine's rounding) does not change it
    nudged = box.copy()
    nudged[1, 2] -= 1e-12  # a plain argmax would take corner 2
    for pts in (box, nudged):
        np.testing.assert_array_equal(spread_layout(pts, 3), [0, 1, 7])
    twice = np.repeat(box[:2], 3, axis=0)  # two distinct points, each three times
    assert len(set(spread_layout(twice, 4))) == 4


def test_four_anchor_searches_also_start_from_the_corners_and_the_spread_layout():
    t = range_table(ROOM, candidate_grid(ROOM, 0.4), NODES, draws=1, exact_draws=1, rng=0)
    corners, spread = spread_starts(t, 4)
    gaps = np.linalg.norm(ROOM.corners_layout()[:, None] - t.candidates[corners][None], axis=-1)
    assert np.all(gaps.min(axis=1) < 0.3)  # each corner anchor on a candidate near it
    np.testing.assert_array_equal(spread, spread_layout(t.candidates, 4))
    assert len(np.unique(np.concatenate([corners, spread]))) > 4  # two different starts
    assert spread_starts(t, 5) == ()


def test_simulated_select_is_the_same_serially_with_an_executor_and_any_workers():
    kw = dict(options=_small(chains=3), nodes=NODES, rng=11)
    s1 = simulated_select(ROOM, 4, **kw)
    with ThreadPoolExecutor(2) as ex:
        s2 = simulated_select(ROOM, 4, executor=ex, workers=2, **kw)
    np.testing.assert_array_equal(s1.indices, s2.indices)
    assert s1.cost == s2.cost and s1.nfev == s2.nfev
    assert [c for _, c in s1.optima] == [c for _, c in s2.optima]


def test_a_chain_advanced_in_segments_equals_one_go():
    t = range_table(ROOM, CAND, NODES, rng=0)
    nbr = nearest(t.candidates, 8)
    kw = dict(batch=4, patience=3, budget=120)
    one = Chain.start(t, 4, "variance", 3, np.random.default_rng(5))
    one.advance(t, "variance", nbr, until=120, **kw)
    seg = Chain.start(t, 4, "variance", 3, np.random.default_rng(5))
    for until in (17, 50, 51, 90, 120):
        seg.advance(t, "variance", nbr, until=until, **kw)
    np.testing.assert_array_equal(one.best, seg.best)
    assert one.fbest == seg.fbest and one.nfev == seg.nfev <= 120


def test_refinement_grows_the_table_descends_and_never_worsens():
    sel = simulated_select(ROOM, 4, options=_small(), nodes=NODES, rng=3)
    opt = _small(fine_spacings=(1.0, 0.5))
    start = sel.layouts(2)
    out, grown, nfev = refine_on_table(ROOM, sel.table, start, options=opt, rng=1)
    assert len(grown.candidates) > len(sel.table.candidates) and nfev > 0
    assert on_surfaces(ROOM, grown.candidates).all()
    for (a, f, local), s0 in zip(out, start, strict=True):
        assert local and on_surfaces(ROOM, a).all()
        idx = [int(np.argmin(np.linalg.norm(grown.candidates - p, axis=1))) for p in a]
        assert f == pytest.approx(table_cost(grown, idx))
        s_idx = [int(np.argmin(np.linalg.norm(grown.candidates - p, axis=1))) for p in s0]
        assert f <= table_cost(grown, s_idx) + 1e-12
    with ThreadPoolExecutor(2) as ex:
        again, _, n2 = refine_on_table(ROOM, sel.table, start, options=opt, rng=1, executor=ex,
                                       workers=2)  # fmt: skip
    assert [f for _, f, _ in again] == [f for _, f, _ in out] and n2 == nfev


def test_search_options_are_checked():
    for kw, name in (
        ({"spacing": 0}, "spacing"),
        ({"chains": 0}, "chains"),
        ({"batch": 100}, "batch"),
        ({"draws": True}, "draws"),
        ({"exact_draws": 4}, "exact_draws"),
        ({"fine_spacings": (0.0,)}, "fine_spacings"),
    ):
        with pytest.raises(ValueError, match=name):
            SearchOptions(**kw)
    t = range_table(ROOM, CAND[:6], NODES, rng=0)
    with pytest.raises(ValueError, match="candidates"):
        simulated_select(ROOM, 8, table=t, options=_small())
    with pytest.raises(ValueError, match="M"):
        simulated_select(ROOM, 3, table=t, options=_small())


def test_search_bounds_are_those_of_the_table_and_the_plan():
    """The search accepts what the table and the plan accept, and no more."""
    assert SearchOptions(draws=MAX_TABLE_DRAWS).draws == MAX_TABLE_DRAWS
    for call in (
        lambda: SearchOptions(draws=MAX_TABLE_DRAWS + 1),
        lambda: range_table(ROOM, CAND[:6], NODES, draws=MAX_TABLE_DRAWS + 1, rng=0),
    ):
        with pytest.raises(ValueError, match=f"draws: .*1, {MAX_TABLE_DRAWS}"):
            call()
    t = range_table(ROOM, CAND[:6], NODES, rng=0)
    for call in (
        lambda: simulated_select(ROOM, MAX_ANCHORS + 1, table=t, options=_small()),
        lambda: seed_then_pso(ROOM, M=MAX_ANCHORS + 1),
    ):
        with pytest.raises(ValueError, match=f"M: .*{MAX_ANCHORS}"):
            call()

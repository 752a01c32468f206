"""A coverage target (placement.coverage.CoverageTarget): layouts below it cost more than
any layout that meets it, in the range table's costs, the scene draws' cost and the search,
and the sweep plans every M for its coverage target."""

import dataclasses
import math

import numpy as np
import pytest

from placement.costs import DrawsCost
from placement.coverage import BELOW_TARGET_COST, CoverageTarget, constrain, visibility
from placement.dilution import poor_sight_share
from placement.rangetable import (
    node_draws,
    range_table,
    sight_counts,
    table_costs,
    table_errors,
)
from placement.simselect import SearchOptions, simulated_select
from placement.surfaces import candidate_grid
from simulation import Room
from simulation.statistics import NO_FIX_COST

ROOM = Room(
    size=(6.0, 4.0, 3.0),
    max_order=1,
    obstacles=[{"min": [2.2, 1.2, 0.0], "max": [3.8, 2.8, 2.4], "name": "cabinet"}],
)
NODES = ROOM.grid()[::4]
CAND = candidate_grid(ROOM, 1.5)
SEARCH = SearchOptions(draws=1, exact_draws=1, chains=2, evaluations=150, random_starts=4,
                       neighbours=12, batch=6, patience=4, fine_spacings=(), keep=2)  # fmt: skip


@pytest.fixture(scope="module")
def table():
    return range_table(ROOM, CAND, NODES, draws=1, exact_draws=1, rng=3)


def test_below_the_target_costs_more_than_any_layout_that_meets_it():
    target = CoverageTarget(k=2, share=0.5)
    counts = np.array([[2, 2, 0, 0], [2, 1, 0, 0], [3, 3, 3, 3]])  # 50 %, 25 %, 100 %
    costs = np.array([2 * NO_FIX_COST + 1e6, 0.001, 0.3])  # the worst allowed, then good ones
    out = constrain(costs, counts, target)
    assert out[0] == costs[0] and out[2] == costs[2]  # meeting it: unchanged
    assert out[1] >= BELOW_TARGET_COST > out[0]
    # further below costs more, whatever the statistic
    assert constrain([0.0], [[0, 0, 0, 0]], target)[0] > constrain([9.0], [[2, 0, 0, 0]], target)[0]
    np.testing.assert_array_equal(constrain(costs, counts, None), costs)


def test_the_cli_reads_a_penalized_cost_as_what_it_means():
    from placement.cli.common import cost_text
    from simulation.statistics import row_statistics

    # 1 node of 10 without a fix: the statistic's penalty, read back as its share
    errors = np.array([[0.1, 0.2, np.nan, 0.1, 0.3, 0.2, 0.1, 0.2, 0.1, 0.1]])
    assert cost_text(row_statistics("rms", errors)[0]) == "10 % without a fix"
    below = constrain([0.01], [[0, 5, 5, 5]], CoverageTarget(k=5, share=1.0))[0]
    assert cost_text(below) == "below the coverage target"
    assert cost_text(0.5699) == "0.5699" and cost_text(math.nan) == "–"


NEEDED = [(0.95, 300, 285), (0.95, 20, 19), (0.0, 7, 0), (1.0, 7, 7), (0.5, 7, 4)]


@pytest.mark.parametrize(("share", "P", "needed"), NEEDED)
def test_the_nodes_needed_are_the_share_rounded_up(share, P, needed):
    assert CoverageTarget(5, share).needed(P) == needed


def test_sight_counts_are_the_anchors_each_node_sees(table):
    rng = np.random.default_rng(0)
    layouts = np.stack([rng.choice(len(CAND), 5, replace=False) for _ in range(6)])
    V = visibility(table)
    expected = np.array([[int(np.sum(V[p, S])) for p in range(len(NODES))] for S in layouts])
    np.testing.assert_array_equal(sight_counts(table, layouts), expected)
    assert 0 < np.mean(V) < 1  # the cabinet hides some candidates from some nodes


def test_the_table_costs_keep_to_the_target(table):
    rng = np.random.default_rng(1)
    layouts = np.stack([rng.choice(len(CAND), 5, replace=False) for _ in range(40)])
    shares = np.mean(sight_counts(table, layouts) >= 4, axis=1)
    share = float(np.median(shares))
    assert 0 < share < 1
    free = table_costs(table, layouts, "rms")
    kept = table_costs(table.__class__(**{**table.__dict__,
                                          "coverage_target": CoverageTarget(4, share)}),
                       layouts, "rms")  # fmt: skip
    meets = shares >= share - 1e-12
    np.testing.assert_array_equal(kept[meets], free[meets])
    assert np.all(kept[~meets] >= BELOW_TARGET_COST)


def test_the_search_keeps_to_a_target_it_can_reach_and_ignores_one_it_cannot(table):
    M = 5
    free = simulated_select(ROOM, M, statistic="rms", options=SEARCH, table=table, rng=2)
    reach = free.coverage.covered  # what M anchors can cover with k = 5
    assert free.coverage_target is None and "coverage_target" not in free.to_dict()
    opts = SearchOptions(**{**SEARCH.__dict__, "min_coverage": reach})
    kept = simulated_select(ROOM, M, statistic="rms", options=opts, table=table, rng=2)
    assert kept.coverage_target == CoverageTarget(5, reach)
    assert kept.to_dict()["coverage_target"] == {
        "k": 5, "share": reach, "sight_k": 4, "shadow_error": 0.0, "gdop_limit": None
    }  # fmt: skip
    meets = [np.mean(sight_counts(table, S[None])[0] >= 5) >= reach - 1e-12 for S, _ in kept.optima]
    costs = [cost for _, cost in kept.optima]
    assert meets[0] and np.array_equal(kept.indices, kept.optima[0][0])
    # the optima that meet it first, at their own statistic; a chain that did not reach it after
    assert meets == sorted(meets, reverse=True)
    assert all((c < BELOW_TARGET_COST) == m for c, m in zip(costs, meets, strict=True))
    assert reach < 1.0  # so that a target beyond M anchors' reach exists: the search is free
    above = SearchOptions(**{**SEARCH.__dict__, "min_coverage": reach + 1 / len(NODES)})
    same = simulated_select(ROOM, M, statistic="rms", options=above, table=table, rng=2)
    assert same.coverage_target is None
    np.testing.assert_array_equal(same.indices, free.indices)


def test_the_draws_cost_keeps_to_the_target(table):
    sets = node_draws(ROOM, NODES, 1, 1, 5)
    cost = DrawsCost(ROOM, sets, exact_draws=1, seed=4, statistic="rms")
    rng = np.random.default_rng(2)
    layouts = [CAND[rng.choice(len(CAND), 5, replace=False)] for _ in range(12)]
    shares = []
    for a in layouts:
        V = visibility(range_table(ROOM, a, sets, exact_draws=1, rng=4, chunk=len(a)))
        shares.append(float(np.mean(np.sum(V, axis=1) >= 4)))
    share = float(np.median(shares))
    kept = DrawsCost(ROOM, sets, exact_draws=1, seed=4, statistic="rms",
                     coverage_target=CoverageTarget(4, share))  # fmt: skip
    for a, s in zip(layouts, shares, strict=True):
        if s >= share:
            assert kept(a) == cost(a)
        else:
            assert kept(a) >= BELOW_TARGET_COST and math.isfinite(cost(a))


def test_the_sweep_plans_for_its_coverage_target_unless_the_search_says_otherwise():
    from placement.anchor_sweep import _kept_to

    assert _kept_to(None, "quick", 0.9).min_coverage == 0.9
    assert _kept_to(SearchOptions(min_coverage=0.0), "quick", 0.9).min_coverage == 0.0
    assert _kept_to(SearchOptions(), "default", 0.8) == SearchOptions(min_coverage=0.8)


@pytest.mark.parametrize("bad", [-0.1, 1.5, math.nan, "all"])
def test_a_bad_min_coverage_is_refused_by_name(bad):
    with pytest.raises(ValueError, match="min_coverage"):
        SearchOptions(min_coverage=bad)


def test_a_plan_keeps_every_phase_to_the_target_and_says_so():
    from placement.plan import LOCAL_SWARM, Planner
    from placement.validation import ValidationOptions

    share = simulated_select(ROOM, 5, statistic="rms", options=SEARCH, nodes=NODES,
                             rng=2).coverage.covered  # fmt: skip
    opts = SearchOptions(**{**SEARCH.__dict__, "min_coverage": share, "fine_spacings": (0.75,)})
    planner = Planner(ROOM, 5, cost="rms", search=opts, nodes=NODES, rng=2, progress=False,
                      swarm=LOCAL_SWARM, validation=ValidationOptions(realizations=0))  # fmt: skip
    res = planner.solve()
    target = CoverageTarget(5, share)
    assert res.settings.search_result["coverage_target"] == target.to_dict()
    assert planner.coverage_target == target
    assert planner.draws_cost(1, 1, "finalists", "finalist_nodes").coverage_target == target
    # the chosen layout meets it at the exact nodes, and so does every finalist scored below
    # the penalty
    chosen = range_table(ROOM, res.anchors, NODES, draws=1, exact_draws=1, chunk=5)
    assert np.mean(np.sum(visibility(chosen), axis=1) >= 5) >= share - 1e-12
    assert res.cost < BELOW_TARGET_COST and planner.refined


def _slab_hits(p, a, lo, hi):
    """(Q, n) bool: the segment from each point p (Q, 3) to each anchor a (n, 3) enters the
    open box (lo, hi): the slab test, in numpy."""
    d = a[None] - p[:, None]  # (Q, n, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (lo - p[:, None]) / d, (hi - p[:, None]) / d
    enter = np.nanmax(np.where(d == 0, -np.inf, np.minimum(t0, t1)), axis=-1)
    leave = np.nanmin(np.where(d == 0, np.inf, np.maximum(t0, t1)), axis=-1)
    parallel_out = np.any((d == 0) & ((p[:, None] <= lo) | (p[:, None] >= hi)), axis=-1)
    return (enter < leave) & (leave > 0) & (enter < 1) & ~parallel_out


def test_the_sight_points_see_what_the_slab_test_says(table):
    """The table's sight (Q, N): the cabinet blocks a sight point's direct path to a
    candidate exactly where the segment enters the box (numpy slab test), everything else
    in reach is seen; the points are the room's (the same for every table), in the room and
    outside the cabinet; a grown table's sight is the bigger table's."""
    from placement.rangetable import SIGHT_POINTS, extend_table, sight_points

    pts = sight_points(ROOM)
    assert pts.shape == (SIGHT_POINTS, 3) and np.all(ROOM.contains(pts))
    np.testing.assert_array_equal(pts, sight_points(ROOM))
    ((lo, hi),) = [(np.array(o.lo), np.array(o.hi)) for o in ROOM.obstacles]
    blocked = _slab_hits(pts, CAND, lo, hi)
    assert table.sight.shape == (SIGHT_POINTS, len(CAND)) and 0.05 < blocked.mean() < 0.6
    np.testing.assert_array_equal(table.sight, ~blocked)  # all within reach in this room
    half = range_table(ROOM, CAND[:7], NODES, draws=1, exact_draws=1, rng=3)
    grown = extend_table(ROOM, half, CAND[7:])
    np.testing.assert_array_equal(grown.sight, table.sight)


@pytest.mark.parametrize("name", ["mean", "rms", "variance", "p95"])
@pytest.mark.parametrize("E", [0.05, 2.0])
def test_the_mixed_statistic_is_that_of_the_errors_with_the_shadows_tags_added(name, E):
    """m tags of error E beside n errors: the statistic of the n + m errors, for the share
    h = m / (n + m) (the P95 within the two order statistics around it)."""
    from simulation.statistics import STATISTICS, mixed_statistic

    e = np.random.default_rng(5).gamma(2.0, 0.02, 190)
    m = 10
    both = np.concatenate([e, np.full(m, E)])
    got = mixed_statistic(name, e, m / len(both), E)
    if name == "p95":
        s = np.sort(both)
        k = 0.95 * (len(both) - 1)
        assert s[int(np.floor(k)) - 1] - 1e-12 <= got <= s[int(np.ceil(k)) + 1] + 1e-12
    else:
        assert got == pytest.approx(STATISTICS[name](both), rel=1e-12)
    assert mixed_statistic(name, e, 0.0, E) == pytest.approx(STATISTICS[name](e), rel=1e-12)


def test_the_shadows_tags_count_in_the_table_costs(table):
    """Under a target with a shadow error, a layout's table cost is the statistic of its
    errors with the share of sight points seeing fewer than its ``sight_k`` anchors at that
    error; a layout whose every sight point sees them costs what it costs without the target."""
    from simulation.statistics import mixed_statistic

    rng = np.random.default_rng(4)
    layouts = np.stack([rng.choice(len(CAND), 5, replace=False) for _ in range(40)])
    counts = sight_counts(table, layouts, points=True)
    np.testing.assert_array_equal(counts, table.sight[:, layouts].sum(axis=-1).T)
    h = np.mean(counts < 2, axis=1)  # 2: some layouts leave no sight point short
    assert np.any(h == 0) and np.any(h > 0)
    free = table_costs(table, layouts, "rms")
    target = CoverageTarget(5, 0.0, sight_k=2, shadow_error=1.5)
    shaded = table.__class__(**{**table.__dict__, "coverage_target": target})
    kept = table_costs(shaded, layouts, "rms")
    np.testing.assert_array_equal(kept[h == 0], free[h == 0])
    e = table_errors(table, layouts)
    for i in np.flatnonzero(h > 0)[:5]:
        assert kept[i] == pytest.approx(mixed_statistic("rms", e[i], h[i], 1.5), rel=1e-12)
    assert CoverageTarget.from_dict(target.to_dict()) == target
    # with a GDOP limit the points seeing their anchors in a poor geometry count too
    poor = dataclasses.replace(target, gdop_limit=2.0)
    hp = poor_sight_share(table.sight_points, CAND, table.sight, layouts, 2, 2.0)
    assert np.all(hp >= h) and np.any(hp > h)
    graded = table_costs(dataclasses.replace(table, coverage_target=poor), layouts, "rms")
    for i in np.flatnonzero(hp > h)[:5]:
        assert graded[i] == pytest.approx(mixed_statistic("rms", e[i], hp[i], 1.5), rel=1e-12)
    assert CoverageTarget.from_dict(poor.to_dict()) == poor
    assert CoverageTarget.from_dict({"k": 5, "share": 0.5}) == CoverageTarget(5, 0.5)


def test_a_robust_search_counts_the_shadows_tags_least_squares_does_not(table):
    """With positioning that rejects echoes the search counts the tags in the shadows at
    the error that fixes in shadows have in random layouts, and starts a chain from the
    sight selection; least squares counts nothing."""
    from placement.coverage import SHADOW_GDOP, covered_share, greedy
    from placement.simselect import shadow_error
    from simulation import System

    robust = System.preset("recommended")
    t = range_table(ROOM, CAND, NODES, draws=1, exact_draws=1, rng=3, system=robust)
    sel = simulated_select(ROOM, 5, statistic="rms", options=SEARCH, table=t, rng=2)
    E = shadow_error(t, 5, 2)
    assert E > 0.1  # a fix on an echo: decimetres to metres off
    assert sel.coverage_target == CoverageTarget(5, 0.0, 4, E, SHADOW_GDOP)
    assert sel.sight.covered >= covered_share(t.sight, greedy(t.sight, 5, 4), 4) - 1e-12
    assert sel.to_dict()["sight"]["covered"] == sel.sight.covered
    ls = simulated_select(ROOM, 5, statistic="rms", options=SEARCH, table=table, rng=2)
    assert ls.sight is None and ls.coverage_target is None

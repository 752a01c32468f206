"""Near-ties cannot flip a choice between machines (placement.ties): costs perturbed by
1e-9 relative, as another machine's rounding would, leave every choice as it was."""

import numpy as np
import pytest

from placement import ties
from placement.anchor_sweep import recommend
from placement.simselect import SearchOptions, search_table, simulated_select
from simulation import Room

PERTURB = 1e-9


def _perturbed(costs, rng):
    c = np.asarray(costs, dtype=float)
    return c * (1 + PERTURB * rng.uniform(-1, 1, c.shape))


def test_ties_go_to_the_first_index_whatever_the_rounding():
    rng = np.random.default_rng(0)
    for _ in range(200):
        base = rng.choice([0.4, 0.5, 0.7, np.inf, np.nan], size=9)
        order = ties.order(base)
        assert ties.argmin(base) == order[0]
        for _ in range(5):
            noisy = _perturbed(base, rng)
            assert np.array_equal(ties.order(noisy), order)
            assert ties.argmin(noisy) == order[0]
        finite = np.isfinite(base)
        # ties in index order, lower costs first, failures last
        key = [
            (0 if f else 1, c if f else 0, i)
            for i, (c, f) in enumerate(zip(base, finite, strict=True))
        ]
        assert list(order) == [i for *_, i in sorted(key)]


def test_a_difference_above_the_tolerance_decides():
    assert ties.argmin([0.5, 0.5 * (1 - 1e-5)]) == 1
    assert ties.argmin([0.5, 0.5 * (1 - 1e-7)]) == 0  # a tie: the first
    assert ties.improves(0.5 * (1 - 1e-5), 0.5)
    assert not ties.improves(0.5 * (1 - 1e-7), 0.5)
    assert ties.improves(1.0, np.inf) and not ties.improves(np.inf, np.inf)
    assert not ties.improves(np.nan, 1.0)
    with pytest.raises(ValueError, match="costs"):
        ties.argmin([])


def test_the_sweeps_recommendation_keeps_a_p95_at_its_target():
    class Row:
        def __init__(self, M, p95, availability=1.0):
            self.M, self.p95, self.availability = M, p95, availability

    rng = np.random.default_rng(1)
    for _ in range(50):
        rows = [Row(4, 1.3), Row(5, float(_perturbed(1.0, rng))), Row(6, 0.8)]
        assert recommend(rows, 1.0, 0.99) == 5
        rows = [Row(4, 0.9, float(_perturbed(0.99, rng))), Row(5, 0.9)]
        assert recommend(rows, 1.0, 0.99) == 4


@pytest.fixture(scope="module")
def table():
    options = SearchOptions(spacing=1.0, draws=1, exact_draws=1)
    return search_table(Room.techtile(), options, rng=0)


def _mirror_cost(table, rng):
    """A cost with exact ties between mirror images: each candidate's distance from the
    room's centre in plan, to the decimetre, summed over the layout (in its own order, so
    that equal sums round differently), times 1 + 1e-9 noise drawn from ``rng``."""
    c = table.candidates
    q = np.round(np.hypot(c[:, 0] - 4.0, c[:, 1] - 2.0), 1) + np.round(c[:, 2], 1)

    def cost(tab, layouts, statistic="variance"):
        layouts = np.atleast_2d(layouts)
        f = np.array([np.sum(q[S]) for S in layouts])
        return f if rng is None else _perturbed(f, rng)

    return cost


def _search(table, monkeypatch, rng):
    import placement.simselect as simselect

    monkeypatch.setattr(simselect, "table_costs", _mirror_cost(table, rng))
    options = SearchOptions(spacing=1.0, draws=1, exact_draws=1, chains=2, evaluations=200)
    sel = simulated_select(Room.techtile(), 4, options=options, table=table, rng=0)
    return [tuple(S) for S, _ in sel.optima]


def test_the_searchs_choices_stay_under_perturbed_costs(table, monkeypatch):
    """The swap search on a cost with exact ties between mirror layouts: every swap, every
    chain's best and the optima's order are the same with costs perturbed by 1e-9; without
    the tie rule (a tolerance of 0) the perturbation decides them."""
    exact = _search(table, monkeypatch, None)
    for seed in range(3):
        assert _search(table, monkeypatch, np.random.default_rng(seed)) == exact
    monkeypatch.setattr(ties, "TIE_RTOL", 0.0)
    runs = [_search(table, monkeypatch, np.random.default_rng(seed)) for seed in range(3)]
    assert any(r != runs[0] for r in runs[1:])  # the test can fail


def test_the_swarms_bests_stay_under_perturbed_costs():
    from placement.pso import PSOOptions, _Swarm

    rng = np.random.default_rng(2)
    K, M = 6, 4
    x = rng.uniform(0, 2, (K, M, 3))
    costs = np.array([0.6, 0.5, 0.5, 0.7, 0.5, 0.9])
    picks = set()
    for _ in range(20):
        swarm = _Swarm.start(0, x, np.zeros_like(x), _perturbed(costs, rng), 0, {})
        swarm.x = x[::-1].copy()
        swarm.record(_perturbed(costs[::-1], rng), 0, PSOOptions())
        picks.add(
            (tuple(swarm.gbest.ravel()), tuple(np.flatnonzero(swarm.pbest[:, 0, 0] == x[:, 0, 0])))
        )
    assert len(picks) == 1
    gbest, kept = picks.pop()
    assert np.array_equal(np.reshape(gbest, (M, 3)), x[1])  # the first of the tied
    assert kept == (0, 1, 2, 4)  # a tie (2, 4) is no improvement: those keep their bests

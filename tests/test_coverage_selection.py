"""The coverage selection (placement.coverage): the integer program's optimum against brute
force on small candidate sets, never below the greedy pick, its bound, its groups."""

import itertools

import numpy as np
import pytest

from placement.coverage import covered_share, greedy, plane_groups, select_coverage


def _brute_force(V, M, k, groups=()):
    best = -1.0
    for S in itertools.combinations(range(V.shape[1]), M):
        if any(set(g) >= set(S) for g in groups):
            continue
        best = max(best, covered_share(V, S, k))
    return best


@pytest.mark.parametrize("seed", range(4))
def test_the_optimum_is_brute_forces(seed):
    rng = np.random.default_rng(seed)
    V = rng.random((40, 12)) < 0.45
    M, k = 5, 3
    groups = [np.arange(0, 6)]  # the first six may not hold all five
    sel = select_coverage(V, M, k, groups=groups)
    best = _brute_force(V, M, k, groups)
    assert sel.status == "optimal"
    assert sel.covered == pytest.approx(best) and sel.bound == pytest.approx(best)
    assert sel.covered >= sel.greedy
    assert not set(sel.indices) <= set(range(6))
    assert covered_share(V, sel.indices, k) == sel.covered


def test_never_below_greedy_and_the_bound_bounds():
    rng = np.random.default_rng(9)
    V = rng.random((150, 120)) < 0.2
    sel = select_coverage(V, 8, 5, time_limit=1.0)
    g = greedy(V, 8, 5)
    assert sel.covered >= covered_share(V, g, 5) == sel.greedy
    assert sel.bound >= sel.covered
    assert len(set(sel.indices.tolist())) == 8


def test_full_coverage_when_possible_and_the_largest_share_when_not():
    V = np.zeros((6, 8), dtype=bool)
    V[:, :5] = True  # every node sees the first five
    V[0, :5] = [True, True, True, True, False]  # node 0 sees only four of them
    sel = select_coverage(V, 5, 5)
    assert sel.covered == pytest.approx(5 / 6) and sel.bound == pytest.approx(5 / 6)
    assert select_coverage(V, 5, 4).covered == 1.0


def test_plane_groups_keep_anchors_off_one_plane():
    from simulation import Room

    room = Room.techtile()
    c = np.array([[1, 0.03, 2.37], [3, 0.03, 2.37], [5, 3.97, 2.37], [2, 2, 2.37], [4, 0.03, 1.0]])
    groups = plane_groups(room, c)
    # the four at 2.37 m form one group, the three on the south wall another
    assert any(set(g) == {0, 1, 2, 3} for g in groups)
    assert any(set(g) == {0, 1, 4} for g in groups)


@pytest.mark.parametrize(
    ("kw", "name"),
    [({"M": 0}, "M"), ({"M": 20}, "M"), ({"k": 9}, "k"), ({"time_limit": 0}, "time_limit")],
)
def test_bad_input_names_the_argument(kw, name):
    V = np.ones((5, 10), dtype=bool)
    args = {"M": 4, "k": 3, **kw}
    with pytest.raises(ValueError, match=name):
        select_coverage(
            V, args["M"], args["k"], **{k: v for k, v in kw.items() if k == "time_limit"}
        )

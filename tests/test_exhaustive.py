"""Exhaustive subset search: against brute force through analysis.fim/crlb_trace."""

import itertools
import math

import numpy as np
import pytest

import analysis
import placement
from placement.selection import criterion_values, fim_table
from simulation import Room


def _small_set(room, n, seed):
    cand = placement.candidate_grid(room, 1.0)
    rng = np.random.default_rng(seed)
    return cand[np.sort(rng.choice(len(cand), n, replace=False))]


def _brute_force(room, cand, M, criterion, sigma):
    """Every M-subset scored by the analysis package (independent code path)."""
    subsets = np.array(list(itertools.combinations(range(len(cand)), M)))
    layouts = cand[subsets]  # (L, M, 3)
    nodes = room.grid()
    sig = np.broadcast_to(np.asarray(sigma, float), (len(cand),))[subsets][:, None, :]
    if criterion == "D":
        J = analysis.fim(layouts, nodes, sig)  # (L, P, 3, 3)
        sign, logdet = np.linalg.slogdet(J)
        values = np.exp(-np.mean(np.where(sign > 0, logdet, -np.inf), axis=1) / 3)
    else:
        t = analysis.crlb_trace(layouts, nodes, sig)  # (L, P)
        values = t.max(axis=1) if criterion == "minimax" else t.mean(axis=1)
    return subsets, values


@pytest.mark.parametrize("criterion", ["A", "D", "minimax"])
def test_matches_brute_force(criterion):
    room = Room(size=(5.0, 4.0, 3.0), mounting=("ceiling", "west", "north"), name="small")
    cand = _small_set(room, 13, seed=3)
    subsets, values = _brute_force(room, cand, 4, criterion, 0.05)
    res = placement.exhaustive_search(
        room, 4, candidates=cand, criterion=criterion, sigma=0.05, top_k=5
    )
    order = np.argsort(values, kind="stable")
    assert res.nfev == math.comb(13, 4) == len(values)
    assert res.success and res.status == 0 and res.fun == res.cost_m2
    assert res.to_dict()["top_costs_m2"] == res.top_costs_m2.tolist()
    assert res.cost_m2 == pytest.approx(values[order[0]], rel=1e-9)
    np.testing.assert_allclose(res.top_costs_m2, values[order[:5]], rtol=1e-9)
    assert np.all(np.diff(res.top_costs_m2) >= 0)
    # the reported subsets have the reported values
    for idx, v in zip(res.top_indices, res.top_costs_m2, strict=True):
        k = np.flatnonzero(np.all(subsets == np.sort(idx), axis=1))[0]
        assert values[k] == pytest.approx(v, rel=1e-9)
    np.testing.assert_allclose(res.anchors, cand[res.indices])


def test_M5_and_per_candidate_sigma():
    room = Room.techtile()
    cand = _small_set(room, 11, seed=5)
    sigma = np.linspace(0.03, 0.06, len(cand))
    subsets, values = _brute_force(room, cand, 5, "A", sigma)
    res = placement.exhaustive_search(room, 5, candidates=cand, sigma=sigma)
    assert res.cost_m2 == pytest.approx(values.min(), rel=1e-9)
    got = analysis.crlb_trace(res.anchors, room.grid(), sigma[res.indices]).mean()
    assert res.cost_m2 == pytest.approx(got, rel=1e-12)


def test_value_scales_with_sigma_squared():
    room = Room.techtile()
    cand = _small_set(room, 10, seed=1)
    for criterion in ("A", "D", "minimax"):
        a = placement.exhaustive_search(room, 4, candidates=cand, criterion=criterion, sigma=0.02)
        b = placement.exhaustive_search(room, 4, candidates=cand, criterion=criterion, sigma=0.06)
        assert b.cost_m2 == pytest.approx(9 * a.cost_m2, rel=1e-9)
        np.testing.assert_array_equal(a.indices, b.indices)


def test_singular_subsets_are_inf():
    # all candidates on the ceiling and one node in the ceiling plane: u has no z component
    room = Room.techtile()
    cand = placement.candidate_grid(room, 2.0)
    cand = cand[np.isclose(cand[:, 2], 2.37)][:8]
    nodes = np.array([[4.0, 2.0, 2.37], [4.0, 2.0, 1.0]])
    res = placement.exhaustive_search(room, 4, candidates=cand, nodes=nodes, top_k=3)
    assert np.isinf(res.cost_m2) and np.all(np.isinf(res.top_costs_m2))
    assert res.status == 1 and not res.success and res.message.startswith("singular")
    J = fim_table(cand, nodes)[:, :4].sum(axis=1)
    assert np.isinf(criterion_values(J, "D"))


def test_fim_table_matches_analysis_fim():
    room = Room.techtile()
    cand = _small_set(room, 6, seed=2)
    nodes = room.grid()
    G = fim_table(cand, nodes, sigma=0.04)  # (6, N, P)
    J = analysis.fim(cand, nodes, 0.04)  # (P, 3, 3)
    iu = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
    for k, (i, j) in enumerate(iu):
        np.testing.assert_allclose(G[k].sum(axis=0), J[:, i, j], rtol=1e-12)


def test_bad_input():
    room = Room.techtile()
    cand = _small_set(room, 8, seed=0)
    with pytest.raises(ValueError, match="M"):
        placement.exhaustive_search(room, 3, candidates=cand)
    with pytest.raises(ValueError, match="M"):
        placement.exhaustive_search(room, 9, candidates=cand)
    with pytest.raises(ValueError, match="max_subsets"):
        placement.exhaustive_search(room, 4, candidates=cand, max_subsets=10)
    off = cand.copy()
    off[2] = [4.0, 2.0, 1.2]  # the middle of the room
    with pytest.raises(ValueError, match="mounting surface"):
        placement.exhaustive_search(room, 4, candidates=off)
    nan = cand.copy()
    nan[0, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        placement.exhaustive_search(room, 4, candidates=nan)
    with pytest.raises(ValueError, match="criterion"):
        placement.exhaustive_search(room, 4, candidates=cand, criterion="E")
    with pytest.raises(ValueError, match="sigma"):
        placement.exhaustive_search(room, 4, candidates=cand, sigma=np.ones(3))
    with pytest.raises(ValueError, match="top_k"):
        placement.exhaustive_search(room, 4, candidates=cand, top_k=0)

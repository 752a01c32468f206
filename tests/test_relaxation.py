"""Convex-relaxation selection: exhaustive optimum, certified bounds, rounding, failures."""

import dataclasses
import json

import numpy as np
import pytest

import analysis
import placement
import placement.relaxation as relaxation
from placement.selection import criterion_values, design_inputs
from simulation import Room

SHOEBOX = Room(
    size=(6.0, 5.0, 3.0), mounting=("west", "east", "south", "north", "ceiling"), name="shoebox"
)
#: (room, candidate spacing) giving about 60 candidates: 56 in techtile, 57 in the shoebox
SETS = {"techtile": (Room.techtile(), 1.4), "shoebox": (SHOEBOX, 1.5)}


@pytest.fixture(scope="module", params=sorted(SETS))
def case(request):
    room, spacing = SETS[request.param]
    cand = placement.candidate_grid(room, spacing)
    assert 55 <= len(cand) <= 70
    return room, cand


@pytest.fixture(scope="module")
def exact(case):
    """The exhaustive M = 4 optimum (about 3 s per room): only the slow tests use it."""
    room, cand = case
    return placement.exhaustive_search(room, 4, candidates=cand, criterion="A")


@pytest.mark.slow
def test_M4_finds_exhaustive_optimum_with_valid_bound(case, exact):
    room, cand = case
    sel = placement.relax_select(room, 4, candidates=cand, criterion="A", rng=0)
    assert sel.message == "optimal" and sel.status == 0 and sel.success
    assert sel.cost_m2 <= exact.cost_m2 * 1.005
    assert sel.cost_m2 >= exact.cost_m2 * (1 - 1e-12)  # cannot beat the exhaustive optimum
    assert sel.lower_bound_m2 <= exact.cost_m2
    assert 0 < sel.lower_bound_m2 <= sel.relaxed_cost_m2 * (1 + 1e-9)
    # units: the value is the mean over the grid of tr J⁻¹ (m²) at σ = 0.04 m
    got = analysis.crlb_trace(sel.anchors, room.grid(), 0.04).mean()
    assert sel.cost_m2 == pytest.approx(got, rel=1e-10)


def test_M8_certified_gap_within_5_percent(case):
    room, cand = case
    sel = placement.relax_select(room, 8, candidates=cand, criterion="A", rng=0)
    assert sel.message == "optimal" and sel.status == 0 and sel.success
    assert 0 <= sel.gap <= 0.05
    assert sel.gap == pytest.approx((sel.cost_m2 - sel.lower_bound_m2) / sel.lower_bound_m2)
    # the bound holds against any other selection
    rng = np.random.default_rng(1)
    subsets = np.array([rng.choice(len(cand), 8, replace=False) for _ in range(300)])
    others = analysis.crlb_trace(cand[subsets], room.grid(), 0.04).mean(axis=1)
    assert np.all(others >= sel.lower_bound_m2)


@pytest.mark.slow
def test_top_M_rounding_alone_fails_on_symmetric_room(case, exact):
    # the relaxed weights tie in symmetric groups; the top four are a poor (near-coplanar)
    # layout, which is why relax_select samples and runs a swap local search
    room, cand = case
    inp = design_inputs(room, 4, cand, "A", 0.04, None)
    G = inp.table()
    w, *_ = relaxation._solve(G, 4, "A", None)
    assert w.sum() == pytest.approx(4, abs=1e-6) and np.all((w >= 0) & (w <= 1))
    top = np.argsort(-w, kind="stable")[:4]
    top_value = inp.scale(criterion_values(G[:, top].sum(axis=1), "A"))
    assert top_value > 1.5 * exact.cost_m2


@pytest.mark.parametrize("criterion", ["D", "minimax"])
def test_other_criteria_bounds_hold(criterion):
    room = Room.techtile()
    cand = placement.candidate_grid(room, 1.0)
    rng = np.random.default_rng(7)
    cand = cand[np.sort(rng.choice(len(cand), 28, replace=False))]
    exact = placement.exhaustive_search(room, 4, candidates=cand, criterion=criterion)
    sel = placement.relax_select(room, 4, candidates=cand, criterion=criterion, rng=0)
    assert sel.success and sel.status in (0, 1)
    assert sel.lower_bound_m2 <= exact.cost_m2 <= sel.cost_m2 * (1 + 1e-12)  # summation order
    if criterion == "D":
        # the documented value: exp(−Σ log det J / (3P)); details carry Σ log det J itself
        J = analysis.fim(sel.anchors, room.grid(), 0.04)
        logdet = np.linalg.slogdet(J)[1].sum()
        assert sel.details["logdet_sum"] == pytest.approx(logdet, rel=1e-10)
        assert sel.cost_m2 == pytest.approx(np.exp(-logdet / (3 * len(J))), rel=1e-10)
        assert sel.details["logdet_upper_bound"] >= logdet
        assert sel.cost_m2 == pytest.approx(exact.cost_m2, rel=0.005)
    else:
        worst = analysis.crlb_trace(sel.anchors, room.grid(), 0.04).max()
        assert sel.cost_m2 == pytest.approx(worst, rel=1e-10)


def test_D_gap_small_at_M8():
    room = Room.techtile()
    sel = placement.relax_select(
        room, 8, candidates=placement.candidate_grid(room, 1.6), criterion="D", rng=0
    )
    assert sel.success and sel.gap <= 0.05


def test_sigma_scaling_and_per_candidate_sigma():
    room = Room.techtile()
    cand = placement.candidate_grid(room, 1.6)
    a = placement.relax_select(room, 6, candidates=cand, sigma=0.02, rng=3)
    b = placement.relax_select(room, 6, candidates=cand, sigma=0.06, rng=3)
    np.testing.assert_array_equal(a.indices, b.indices)
    assert b.cost_m2 == pytest.approx(9 * a.cost_m2, rel=1e-9)
    assert b.lower_bound_m2 == pytest.approx(9 * a.lower_bound_m2, rel=1e-5)
    sig = np.where(cand[:, 2] > 2.0, 0.08, 0.03)  # noisy ceiling, accurate walls
    c = placement.relax_select(room, 6, candidates=cand, sigma=sig, rng=3)
    assert c.success
    got = analysis.crlb_trace(c.anchors, room.grid(), sig[c.indices]).mean()
    assert c.cost_m2 == pytest.approx(got, rel=1e-10)
    assert np.sum(c.anchors[:, 2] > 2.0) < np.sum(a.anchors[:, 2] > 2.0)


def test_result_fields_and_reproducibility():
    room = Room.techtile()
    cand = placement.candidate_grid(room, 1.6)
    a = placement.relax_select(room, 5, candidates=cand, rng=11)
    b = placement.relax_select(room, 5, candidates=cand, rng=11)
    np.testing.assert_array_equal(a.indices, b.indices)
    assert a.M == 5 and len(set(a.indices.tolist())) == 5
    np.testing.assert_allclose(a.anchors, cand[a.indices])
    assert a.weights.shape == (len(cand),)
    assert np.all(a.weights >= 0) and np.all(a.weights <= 1)
    assert a.weights.sum() == pytest.approx(5, abs=1e-6)
    assert a.compile_time > 0 and a.solve_time > 0 and a.total_time >= a.solve_time
    d = json.loads(json.dumps(a.to_dict()))
    assert d["criterion"] == "A" and d["indices"] == a.indices.tolist()
    # the optimizer result convention (placement.result): scipy-like names, frozen
    assert d["fun"] == d["cost_m2"] == a.fun == a.cost_m2
    assert {"success", "status", "message", "nit", "lower_bound_m2"} <= set(d)
    np.testing.assert_array_equal(a.x, a.anchors.ravel())
    assert a.status in a.STATUS and a.describe_status().startswith(a.message.split(":")[0])
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.cost_m2 = 0.0


def test_default_candidates_and_nodes():
    room = Room.techtile()
    sel = placement.relax_select(room, 4, rng=0)
    assert len(sel.candidates) == len(placement.candidate_grid(room, 0.75))
    assert placement.on_surfaces(room, sel.anchors).all()
    assert sel.success and sel.cost_m2 >= sel.lower_bound_m2


def test_solver_failure_is_a_status(monkeypatch):
    import cvxpy as cp

    def boom(self, *args, **kwargs):
        raise cp.error.SolverError("simulated failure")

    monkeypatch.setattr(cp.Problem, "solve", boom)
    room = Room.techtile()
    sel = placement.relax_select(room, 4, candidates=placement.candidate_grid(room, 1.6), rng=0)
    assert sel.message.startswith("solver_failed") and sel.status == 4 and not sel.success
    assert sel.lower_bound_m2 == 0.0 and np.isinf(sel.gap)
    assert np.isfinite(sel.cost_m2) and len(set(sel.indices.tolist())) == 4


def test_bound_above_value_is_not_a_certificate(monkeypatch):
    real = relaxation._certified_bound

    def too_high(*args, **kwargs):
        bound, f = real(*args, **kwargs)
        return 10 * f, f

    monkeypatch.setattr(relaxation, "_certified_bound", too_high)
    room = Room.techtile()
    sel = placement.relax_select(room, 4, candidates=placement.candidate_grid(room, 1.6), rng=0)
    assert sel.message == "bound_above_value" and sel.status == 2 and not sel.success
    assert sel.lower_bound_m2 == 0.0 and np.isinf(sel.gap)


def test_bad_input():
    room = Room.techtile()
    cand = placement.candidate_grid(room, 1.6)
    with pytest.raises(ValueError, match="M"):
        placement.relax_select(room, 3, candidates=cand)
    with pytest.raises(ValueError, match="M"):
        placement.relax_select(room, len(cand) + 1, candidates=cand)
    with pytest.raises(ValueError, match="M"):
        placement.relax_select(room, 4.5, candidates=cand)
    off = cand.copy()
    off[5] = [4.0, 2.0, 1.2]  # the middle of the room
    with pytest.raises(ValueError, match="mounting surface"):
        placement.relax_select(room, 4, candidates=off)
    nan = cand.copy()
    nan[1, 2] = np.nan
    with pytest.raises(ValueError, match="finite"):
        placement.relax_select(room, 4, candidates=nan)
    with pytest.raises(ValueError, match="sigma"):
        placement.relax_select(room, 4, candidates=cand, sigma=np.nan)
    with pytest.raises(ValueError, match="sigma"):
        placement.relax_select(room, 4, candidates=cand, sigma=np.full(3, 0.04))
    with pytest.raises(ValueError, match="criterion"):
        placement.relax_select(room, 4, candidates=cand, criterion="E")
    with pytest.raises(ValueError, match="nodes"):
        placement.relax_select(room, 4, candidates=cand, nodes=np.full((3, 3), np.nan))


def test_per_pair_sigma_equals_per_candidate_sigma_when_constant_over_nodes():
    from placement import candidate_grid, relax_select

    room = Room.techtile()
    cand = candidate_grid(room, 1.5)
    nodes = room.grid()[::5]
    rng = np.random.default_rng(0)
    s_n = rng.uniform(0.02, 0.08, size=len(cand))
    a = relax_select(room, 4, candidates=cand, sigma=s_n, nodes=nodes, rng=1)
    b = relax_select(
        room, 4, candidates=cand, sigma=np.tile(s_n, (len(nodes), 1)), nodes=nodes, rng=1
    )
    assert sorted(a.indices) == sorted(b.indices)
    assert a.cost_m2 == pytest.approx(b.cost_m2, rel=1e-9)
    with pytest.raises(ValueError, match="sigma"):
        relax_select(room, 4, candidates=cand, sigma=np.ones((3, len(cand))), nodes=nodes)

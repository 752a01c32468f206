"""Gradient refinement on the surfaces: improvement, surfaces kept, stationarity, failures."""

import numpy as np
import pytest

import analysis
import placement
import placement.refine as refine
from simulation import Room

ROOM = Room.techtile()


def _on_own_surfaces(room, before, after, tol=1e-9):
    """Every anchor lies on the rectangle of the surface it started on."""
    idx, _ = placement.to_uv(room, before)
    surfs = placement.mounting_surfaces(room)
    for a, k in zip(after, idx, strict=True):
        s = surfs[k]
        if abs(a[s.axis] - s.offset) > tol:
            return False
        uv = a[list(s.uv_axes)]
        if np.any(uv < np.array(s.lower) - tol) or np.any(uv > np.array(s.upper) + tol):
            return False
    return True


def test_lowers_mean_peb_of_random_layout_and_keeps_surfaces():
    for M, seed in ((6, 1), (10, 2)):
        a0 = placement.random_layout(ROOM, M, seed)
        res = placement.refine_peb(ROOM, a0, return_info=True)
        assert res.success and res.accepted
        nodes = ROOM.grid()
        before = analysis.peb(a0, nodes, 0.04).mean()
        after = analysis.peb(res.anchors, nodes, 0.04).mean()
        assert after <= 0.9 * before  # substantial: ≥ 10 % on these starts
        assert res.mean_peb_m == pytest.approx(after) and res.initial_mean_peb_m == pytest.approx(
            before
        )
        assert res.objective_m == pytest.approx(after)  # objective "mean" = mean of √tr J⁻¹
        assert res.fun == res.objective_m and res.status == 0 and res.nit > 0
        assert res.nfev >= res.nit and res.message == "Solve_Succeeded"
        np.testing.assert_array_equal(res.x, res.anchors.ravel())
        assert res.to_dict()["mean_peb_m"] == res.mean_peb_m
        assert _on_own_surfaces(ROOM, a0, res.anchors)
        assert placement.on_surfaces(ROOM, res.anchors).all()


def test_default_returns_anchors_array():
    a0 = placement.random_layout(ROOM, 5, 4)
    out = placement.refine_peb(ROOM, a0)
    assert isinstance(out, np.ndarray) and out.shape == (5, 3)
    assert analysis.peb(out, ROOM.grid()).mean() < analysis.peb(a0, ROOM.grid()).mean()


def _mean_peb_in_uv(room, a0, x):
    idx, _ = placement.to_uv(room, a0)
    # central differences at an edge step 10 µm past it: allow that much
    a = placement.from_uv(room, idx, x.reshape(-1, 2), tol=1e-4)
    return analysis.peb(a, room.grid(), 0.04).mean()


@pytest.mark.parametrize("hessian", ["limited-memory", "exact"])
def test_result_is_stationary(hessian):
    # at a local minimum the finite-difference gradient vanishes along every free coordinate
    a0 = placement.random_layout(ROOM, 6, 7)
    res = placement.refine_peb(ROOM, a0, hessian=hessian, tol=1e-9, return_info=True)
    assert res.success
    idx, uv = placement.to_uv(ROOM, res.anchors)
    surfs = placement.mounting_surfaces(ROOM)
    lo = np.concatenate([surfs[k].lower for k in idx])
    hi = np.concatenate([surfs[k].upper for k in idx])
    x = uv.ravel()
    h = 1e-5
    grad = np.array(
        [
            (_mean_peb_in_uv(ROOM, a0, x + h * e) - _mean_peb_in_uv(ROOM, a0, x - h * e)) / (2 * h)
            for e in np.eye(x.size)
        ]
    )
    free = (x > lo + 1e-3) & (x < hi - 1e-3)
    assert free.sum() >= 2
    scale = np.abs(grad).max() + res.mean_peb_m  # m per m
    assert np.all(np.abs(grad[free]) < 1e-3 * scale)
    # at an active bound the gradient points outward (moving inward would not help)
    at_lo, at_hi = x <= lo + 1e-6, x >= hi - 1e-6
    assert np.all(grad[at_lo] > -1e-3 * scale) and np.all(grad[at_hi] < 1e-3 * scale)


def test_smoothmax_lowers_worst_node_more_than_mean():
    a0 = placement.random_layout(ROOM, 8, 1)
    mean = placement.refine_peb(ROOM, a0, objective="mean", return_info=True)
    smooth = placement.refine_peb(ROOM, a0, objective="smoothmax", return_info=True)
    assert smooth.success and smooth.accepted
    assert smooth.max_peb_m < mean.max_peb_m
    assert smooth.max_peb_m < smooth.initial_max_peb_m
    # log-mean-exp lies between the mean and the max PEB
    assert smooth.mean_peb_m <= smooth.objective_m <= smooth.max_peb_m
    assert _on_own_surfaces(ROOM, a0, smooth.anchors)


def test_multistart_and_per_anchor_sigma():
    a0 = placement.random_layout(ROOM, 4, 3)
    sig = np.array([0.03, 0.04, 0.05, 0.06])
    one = placement.refine_peb(ROOM, a0, sigma=sig, return_info=True)
    many = placement.refine_peb(ROOM, a0, sigma=sig, multistart=3, rng=0, return_info=True)
    assert many.starts == 4 and one.starts == 1
    assert many.objective_m <= one.objective_m * (1 + 1e-9)
    got = analysis.peb(many.anchors, ROOM.grid(), sig).mean()
    assert many.objective_m == pytest.approx(got)


def test_other_room_and_nodes():
    room = Room(size=(6.0, 5.0, 3.0), mounting=("west", "east", "ceiling"), name="other")
    nodes = room.grid((5, 4, 3))
    a0 = placement.random_layout(room, 5, 0)
    res = placement.refine_peb(room, a0, nodes=nodes, return_info=True)
    assert res.accepted and res.mean_peb_m < res.initial_mean_peb_m
    assert _on_own_surfaces(room, a0, res.anchors)


def test_singular_start_returns_input_unchanged():
    a0 = placement.random_layout(ROOM, 4, 0)
    a0[:, 2] = 2.37  # all four in the ceiling plane (wall anchors on its edges) ...
    nodes = np.array([[4.0, 2.0, 2.37], [4.0, 2.0, 1.0]])  # ... and a node in that plane
    res = placement.refine_peb(ROOM, a0, nodes=nodes, return_info=True)
    assert res.status == 3 and res.message == "singular_start" and not res.accepted
    np.testing.assert_array_equal(res.anchors, a0)


def test_solver_error_returns_input_unchanged(monkeypatch):
    def broken(*args, **kwargs):
        def solve(**kw):
            raise RuntimeError("simulated IPOPT crash")

        solve.stats = dict
        return solve

    monkeypatch.setattr(refine, "_build_solver", broken)
    a0 = placement.random_layout(ROOM, 6, 0)
    res = placement.refine_peb(ROOM, a0, return_info=True)
    assert res.status == 5 and res.message.startswith("error")
    assert not res.accepted and not res.success
    np.testing.assert_array_equal(res.anchors, a0)


def test_ipopt_is_silent_unless_verbose(capfd):
    a0 = placement.random_layout(ROOM, 4, 5)
    placement.refine_peb(ROOM, a0)
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    placement.refine_peb(ROOM, a0, verbose=True, max_iter=3)
    out, _ = capfd.readouterr()
    assert "Ipopt" in out


def test_bad_input():
    a0 = placement.random_layout(ROOM, 5, 0)
    with pytest.raises(ValueError, match="anchors"):
        placement.refine_peb(ROOM, a0[:3])
    off = a0.copy()
    off[0] = [4.0, 2.0, 1.2]
    with pytest.raises(ValueError, match="surface"):
        placement.refine_peb(ROOM, off)
    nan = a0.copy()
    nan[1, 1] = np.nan
    with pytest.raises(ValueError, match="finite"):
        placement.refine_peb(ROOM, nan)
    with pytest.raises(ValueError, match="objective"):
        placement.refine_peb(ROOM, a0, objective="max")
    with pytest.raises(ValueError, match="sigma"):
        placement.refine_peb(ROOM, a0, sigma=np.ones(2))
    with pytest.raises(ValueError, match="multistart"):
        placement.refine_peb(ROOM, a0, multistart=-1)
    with pytest.raises(ValueError, match="hessian"):
        placement.refine_peb(ROOM, a0, hessian="bfgs")

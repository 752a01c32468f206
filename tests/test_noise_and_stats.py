import numpy as np
import pytest

import analysis
from analysis.noise import PhysicalRangeNoise, direct_amplitude
from simulation import Room
from simulation.statistics import STATISTICS, row_statistics


def test_physical_sigma_matches_explicit_sum_and_snr_reference():
    room = Room.techtile()
    model = PhysicalRangeNoise(room)
    anchors = room.corners_layout()
    nodes = room.grid()
    s = model.sigma(anchors, nodes)
    assert s.shape == (270, 4) and np.all(s > 0) and np.all(np.isfinite(s))
    # brute force: σ_τ² = σ_w² / (A² Σ (2π f)² / 2) with σ_w² = (A_ref²/2)/SNR
    c = room.speed_of_sound
    rx, ch = model.receiver, model.chirp
    t = rx.window_times
    A = direct_amplitude(room, anchors, nodes)
    ref = model.reference_amplitude(anchors)
    for p in (0, 77, 269):
        for j in range(4):
            tau = np.linalg.norm(nodes[p] - anchors[j]) / c
            f = ch.frequency(t - tau)
            var_tau = (ref[j] ** 2 / 2 / 1e3) / (A[p, j] ** 2 * np.sum((2 * np.pi * f) ** 2) / 2)
            assert s[p, j] == pytest.approx(c * np.sqrt(var_tau), rel=1e-9)
    # at the reference node the SNR is 30 dB by construction: closest node gets the
    # smallest σ of that anchor
    closest = np.argmin(np.linalg.norm(nodes[:, None] - anchors[None], axis=-1), axis=0)
    np.testing.assert_array_equal(np.argmin(s, axis=0), closest)


def test_physical_sigma_grows_with_distance_and_off_axis():
    room = Room.techtile()
    model = PhysicalRangeNoise(room)
    a = np.array([[4.0, 0.03, 1.2]])  # south wall, aimed along +y
    near, far = np.array([[4.0, 1.0, 1.2]]), np.array([[4.0, 3.9, 1.2]])
    assert model.sigma(a, far)[0, 0] > 3 * model.sigma(a, near)[0, 0]
    assert PhysicalRangeNoise(room, snr_db=10).sigma(a, far)[0, 0] == pytest.approx(
        np.sqrt(100) * model.sigma(a, far)[0, 0]
    )
    # usable as sigma in the PEB
    nodes = room.grid()
    pb = analysis.peb(room.corners_layout(), nodes, model.sigma(room.corners_layout(), nodes))
    assert np.all(np.isfinite(pb)) and pb.max() < 0.04


def test_error_stats_and_ecdf():
    e = np.array([0.1, 0.2, 0.3, 0.4, np.inf])
    st = analysis.error_stats(e)
    assert st["n"] == 4 and st["n_invalid"] == 1  # the failed fix is counted, not hidden
    assert st["mean"] == pytest.approx(0.25)
    assert st["std"] == pytest.approx(np.std([0.1, 0.2, 0.3, 0.4]))
    assert st["rms"] == pytest.approx(np.sqrt(np.mean(np.array([0.1, 0.2, 0.3, 0.4]) ** 2)))
    assert st["p95"] == pytest.approx(np.percentile([0.1, 0.2, 0.3, 0.4], 95))
    assert st["median"] == pytest.approx(0.25) and st["max"] == pytest.approx(0.4)
    empty = analysis.error_stats([np.nan])
    assert np.isnan(empty["std"]) and empty["n"] == 0 and empty["n_invalid"] == 1
    x, F = analysis.ecdf([0.3, 0.1, 0.2])
    np.testing.assert_allclose(x, [0.1, 0.2, 0.3])
    np.testing.assert_allclose(F, [1 / 3, 2 / 3, 1])
    x, F = analysis.ecdf([0.3, np.inf, 0.1, 0.2])  # a failure keeps the CDF below 1
    np.testing.assert_allclose(F, [1 / 4, 2 / 4, 3 / 4])


def test_cost_statistics_are_inf_for_a_failed_fix():
    e = np.array([[0.1, 0.2], [0.3, 0.4]])
    st = analysis.error_stats(e)
    assert STATISTICS["variance"](e) == pytest.approx(st["std"] ** 2)
    for name in ("mean", "p95", "rms"):
        assert STATISTICS[name](e) == pytest.approx(st[name])
    bad = e.copy()
    bad[0, 0] = np.inf  # a failed fix: the layout cannot be scored
    assert all(STATISTICS[k](bad) == np.inf for k in STATISTICS)


def test_a_no_fix_costs_more_than_any_layout_with_full_availability():
    from simulation.statistics import NO_FIX_COST

    fixed = np.array([[0.1, 0.2], [0.3, 0.4]])
    worst = np.array([[500.0, 0.0], [0.0, 500.0]])  # a dreadful layout, but every node fixed
    missing = fixed.copy()
    missing[0, 0] = np.nan  # one node realization without a fix
    more = missing.copy()
    more[1, 1] = np.nan
    for name in STATISTICS:
        full, bad = STATISTICS[name](worst), STATISTICS[name](missing)
        assert full < NO_FIX_COST < bad < STATISTICS[name](more)
        # the rule: the statistic of the fixes on top of the penalty for the share missing
        stat = STATISTICS[name](np.array([0.2, 0.3, 0.4]))
        assert bad == pytest.approx(NO_FIX_COST * (1 + 1 / 4) + stat)
    assert STATISTICS["mean"](np.full(3, np.nan)) == 2 * NO_FIX_COST  # no fix at all
    st = analysis.error_stats(missing)
    assert st["availability"] == 0.75 and st["n"] == 3 and st["n_invalid"] == 1
    assert st["mean"] == pytest.approx(0.3)  # the fixes only: no no-fix averaged in


def test_row_statistics_equal_the_statistic_of_each_row():
    rng = np.random.default_rng(3)
    e = np.abs(rng.standard_normal((7, 810))) * rng.uniform(0.1, 2.0, (7, 1))
    e[2, 5] = np.nan  # no fix: that row is penalized
    e[4, 0] = np.inf  # a failed fix: that row only is +inf
    for name in STATISTICS:
        rows = row_statistics(name, e)
        assert rows.shape == (7,) and np.isinf(rows[4]) and np.isfinite(rows[2])
        assert rows[2] > max(np.delete(rows, [2, 4]))
        # equal, not approximately: the search's choices must not depend on the batching
        np.testing.assert_array_equal(rows, [STATISTICS[name](r) for r in e])
    assert row_statistics("variance", e[:0]).shape == (0,)
    # no errors at all: nothing to score, +inf (never NaN)
    assert np.isinf(row_statistics("mean", e[:, :0])).all() and STATISTICS["p95"]([]) == np.inf
    with pytest.raises(ValueError, match="statistic"):
        row_statistics("median", e)


def test_per_node_statistics_use_the_finite_errors():
    e = np.array([[1.0, 2.0, np.inf], [3.0, 2.0, np.nan], [5.0, np.inf, np.nan]])
    np.testing.assert_allclose(analysis.node_mean(e), [3.0, 2.0, np.inf])
    np.testing.assert_allclose(analysis.node_std(e), [np.std([1, 3, 5]), 0.0, np.inf])
    np.testing.assert_allclose(analysis.node_rmse(e), [np.sqrt(35 / 3), 2.0, np.inf])
    with pytest.raises(ValueError, match="errors"):
        analysis.node_std(np.ones(3))


def test_dop_is_the_papers_and_dop_rms_adds_the_bias():
    rng = np.random.default_rng(0)
    R, P, M = 2000, 3, 4
    range_err = rng.normal(0, 0.05, size=(R, P, M))
    pos = rng.normal(0, 0.1, size=(R, P, 3))
    e = np.linalg.norm(pos, axis=-1)
    sr = np.mean(np.std(range_err, axis=0), axis=-1)
    np.testing.assert_allclose(analysis.range_std(range_err), sr)
    np.testing.assert_allclose(analysis.dop_rms(e, range_err), np.sqrt(3) * 0.1 / 0.05, rtol=0.05)
    np.testing.assert_allclose(analysis.dop(e, range_err), np.std(e, axis=0) / sr)
    # a steady bias of 1 m leaves the paper's DOP unchanged and raises the RMS-based one
    np.testing.assert_allclose(analysis.dop(e + 1.0, range_err), analysis.dop(e, range_err))
    assert np.all(analysis.dop_rms(e + 1.0, range_err) > 5 * analysis.dop_rms(e, range_err))
    # one realization: σ_r = 0, both +inf
    assert np.all(np.isinf(analysis.dop(e[:1], range_err[:1])))
    assert np.all(np.isinf(analysis.dop_rms(e[:1], range_err[:1])))
    # a receiver that picks the same range every time: σ_r is the rounding of equal values
    # (range errors 0.1 + 0.2 - 0.3 and the like), not a spread to divide by
    same = np.broadcast_to(np.array([0.1, 0.7, 0.3, 0.05]) * 3, (R, P, M)) + 1e-3
    assert 0 < np.max(analysis.range_std(same)) < 1e-12  # rounding: a ratio to it is ~1e12
    assert np.all(np.isinf(analysis.dop_rms(e, same))) and np.all(np.isinf(analysis.dop(e, same)))
    truth = np.zeros((P, 3))
    np.testing.assert_allclose(analysis.axis_errors(pos, truth), np.abs(pos))
    np.testing.assert_allclose(analysis.euclidean_errors(pos, truth), e)


def test_multipath_sigma_is_floor_plus_simulated_bias():
    from simulation import simulate_ranges

    room = Room.techtile()
    anchors = room.corners_layout()
    nodes = room.grid()[::27]
    model = analysis.MultipathRangeNoise(room, floor=0.04)
    s = model.sigma(anchors, nodes)
    assert s.shape == (len(nodes), 4)
    r = simulate_ranges(room, anchors, nodes, noise=False)
    d = np.linalg.norm(nodes[:, None] - anchors[None], axis=-1)
    np.testing.assert_allclose(s, np.sqrt(0.04**2 + (r - d) ** 2))
    assert np.all(s >= 0.04)
    # usable as a per-pair sigma in the bound
    assert np.all(np.isfinite(analysis.peb(anchors, nodes, s)))
    with pytest.raises(ValueError, match="floor"):
        analysis.MultipathRangeNoise(room, floor=0.0)

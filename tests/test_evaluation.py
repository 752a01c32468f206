import json

import numpy as np
import pytest

import analysis
from analysis.noise import CalibratedRangeNoise, calibrated_sigma
from placement.cli.common import to_jsonable
from simulation import Room, evaluate_layout, simulate_ranges
from simulation.evaluation import RangingScene
from simulation.multipath import compute_paths
from simulation.noise import noise_sigma, reference_nodes
from simulation.received import received_windows

ROOM = Room.techtile()
ALL = ("floor", "ceiling", "south", "north", "west", "east")


def test_simulate_ranges_shapes_and_determinism():
    a = ROOM.corners_layout()
    nodes = ROOM.grid()[::9]
    r0 = simulate_ranges(ROOM, a, nodes, noise=False)
    assert r0.shape == (len(nodes), 4)
    assert np.array_equal(r0, simulate_ranges(ROOM, a, nodes, noise=False))
    r1 = simulate_ranges(ROOM, a, nodes, rng=np.random.default_rng(5))
    r2 = simulate_ranges(ROOM, a, nodes, rng=np.random.default_rng(5))
    assert np.array_equal(r1, r2) and not np.array_equal(r1, r0)
    d = np.linalg.norm(nodes[:, None] - a[None], axis=-1)
    assert np.median(np.abs(r0 - d)) < 0.1  # most ranges hit the direct path


def test_noise_rule_gives_the_snr_at_the_closest_grid_node():
    a = np.array([[0.03, 0.03, 0.03], [4.0, 3.97, 1.0], [2.0, 0.03, 2.0], [6.0, 2.0, 2.37]])
    grid = ROOM.grid()
    ref = reference_nodes(ROOM, a)
    d = np.linalg.norm(grid[:, None] - a[None], axis=-1)
    assert np.array_equal(ref, grid[np.argmin(d, axis=0)])
    w = received_windows(compute_paths(ROOM, a, ref), ROOM.speed_of_sound)
    power = np.mean(w[np.arange(4), np.arange(4)] ** 2, axis=-1)
    for snr in (30.0, 10.0):
        s = noise_sigma(ROOM, a, snr_db=snr)
        assert np.allclose(10 * np.log10(power / s**2), snr, atol=1e-9)
    # the drawn noise has that variance at every node, per anchor
    scene = RangingScene(ROOM, a, grid)
    noise = scene.noisy_windows(np.random.default_rng(0)) - scene.windows  # (P, M, N)
    var = np.var(noise, axis=(0, 2))
    assert np.allclose(var, scene.noise_sigma**2, rtol=0.02)
    far, near = np.argmax(d, axis=0), np.argmin(d, axis=0)
    assert np.allclose(
        noise[far].std(axis=-1).diagonal(), noise[near].std(axis=-1).diagonal(), rtol=0.3
    )


def test_same_seed_same_result_whatever_the_chunking():
    a = ROOM.corners_layout()
    nodes = ROOM.grid()[::6]
    e1 = evaluate_layout(ROOM, a, realizations=3, rng=4, nodes=nodes, chunk=1)
    e2 = evaluate_layout(ROOM, a, realizations=3, rng=4, nodes=nodes, chunk=2)
    e3 = evaluate_layout(ROOM, a, realizations=3, rng=4, nodes=nodes)
    for e in (e2, e3):
        assert np.array_equal(e.ranges, e1.ranges)
        assert np.array_equal(e.estimates, e1.estimates)
    # the first realizations do not depend on how many follow
    e4 = evaluate_layout(ROOM, a, realizations=1, rng=4, nodes=nodes)
    assert np.array_equal(e4.ranges[0], e1.ranges[0])
    e5 = evaluate_layout(ROOM, a, realizations=1, rng=5, nodes=nodes)
    assert not np.array_equal(e5.ranges[0], e1.ranges[0])


def test_progress_is_told_each_chunk_and_changes_nothing():
    a = ROOM.corners_layout()
    nodes = ROOM.grid()[::6]
    calls = []
    e1 = evaluate_layout(ROOM, a, realizations=3, rng=4, nodes=nodes, chunk=2,
                         progress=lambda done, total: calls.append((done, total)))  # fmt: skip
    assert calls == [(2, 3), (3, 3)]
    e2 = evaluate_layout(ROOM, a, realizations=3, rng=4, nodes=nodes, chunk=2)
    assert np.array_equal(e1.estimates, e2.estimates)
    with pytest.raises(ValueError, match="progress: expected a callable"):
        evaluate_layout(ROOM, a, realizations=1, nodes=nodes, progress=True)


def test_rng_int_reproduces_the_former_seed_streams():
    """rng=s draws realization r from SeedSequence(s).spawn(R)[r], exactly as seed=s did."""
    a = ROOM.corners_layout()
    nodes = ROOM.grid()[::9]
    ev = evaluate_layout(ROOM, a, realizations=2, rng=11, nodes=nodes)
    scene = RangingScene(ROOM, a, nodes)
    streams = [np.random.default_rng(s) for s in np.random.SeedSequence(11).spawn(2)]
    assert np.array_equal(ev.ranges, scene.ranges_batch(streams))
    assert ev.seed == 11
    with pytest.raises(TypeError):  # the alias of an unreleased version is gone
        evaluate_layout(ROOM, a, realizations=2, seed=11, nodes=nodes)
    # a Generator is drawn once for the integer seed, kept in Evaluation.seed
    g = evaluate_layout(ROOM, a, realizations=2, rng=np.random.default_rng(2), nodes=nodes)
    assert g.seed == int(np.random.default_rng(2).integers(2**63))
    again = evaluate_layout(ROOM, a, realizations=2, rng=g.seed, nodes=nodes)
    assert np.array_equal(again.ranges, g.ranges)
    fresh = evaluate_layout(ROOM, a, realizations=1, rng=None, nodes=nodes)
    assert 0 <= fresh.seed < 2**63


def test_evaluation_statistics_match_analysis():
    a = ROOM.corners_layout()
    ev = evaluate_layout(ROOM, a, realizations=3, rng=1, nodes=ROOM.grid()[::4])
    P = len(ev.nodes)
    assert ev.errors.shape == (3, P) and ev.estimates.shape == (3, P, 3)
    assert ev.range_errors.shape == (3, P, 4) and ev.converged.shape == (3, P)
    st = analysis.error_stats(ev.errors)
    assert ev.std == pytest.approx(st["std"]) and ev.mean == pytest.approx(st["mean"])
    assert ev.p95 == pytest.approx(st["p95"]) and ev.rms == pytest.approx(st["rms"])
    # the paper's DOP (std of the error / σ_r) and the RMS-based one (RMSE / σ_r)
    sr = np.mean(np.std(ev.range_errors, axis=0), axis=-1)
    np.testing.assert_allclose(ev.range_std, sr)
    np.testing.assert_allclose(ev.dop, np.std(ev.errors, axis=0) / sr)
    np.testing.assert_allclose(ev.dop_rms, ev.rmse / sr)
    np.testing.assert_allclose(ev.dop, analysis.dop(ev.errors, ev.range_errors))
    np.testing.assert_allclose(ev.dop_rms, analysis.dop_rms(ev.errors, ev.range_errors))
    assert np.all(ev.dop <= ev.dop_rms)
    np.testing.assert_allclose(ev.axis_errors, analysis.axis_errors(ev.estimates, ev.nodes))
    np.testing.assert_allclose(ev.errors, analysis.euclidean_errors(ev.estimates, ev.nodes))
    np.testing.assert_allclose(ev.rmse, np.sqrt(np.mean(ev.errors**2, axis=0)))
    d = ev.to_dict()
    text = json.dumps(to_jsonable(d), allow_nan=False)
    back = json.loads(text)
    assert {
        "room",
        "anchors",
        "nodes",
        "realizations",
        "seed",
        "stats",
        "per_node",
        "errors",
    } <= set(back)
    assert back["stats"]["std"] == pytest.approx(ev.std)
    assert len(back["per_node"]["dop"]) == P and np.array(back["errors"]).shape == (3, P)
    assert back["per_node"]["dop_rms"] == pytest.approx(ev.dop_rms.tolist())
    assert back["stats"]["n"] == 3 * P and back["stats"]["n_invalid"] == 0


def test_corners_layout_sanity_figure():
    """Paper: σ = 1.362 m for the corners layout with noise (R = 500)."""
    ev = evaluate_layout(ROOM, ROOM.corners_layout(), realizations=3, rng=0)
    assert ev.errors.shape == (3, 270)
    assert 1.0 < ev.std < 1.9
    assert ev.n_unconverged <= 0.01 * ev.errors.size


def test_anechoic_noise_free_corners():
    """Anechoic and noise-free, positions follow the (centimetre) receiver-chain ranges."""
    room = Room(absorption={k: 1.0 for k in ALL})
    ev = evaluate_layout(room, room.corners_layout(), noise=False)
    assert np.median(np.abs(ev.range_errors)) < 0.015
    assert np.median(ev.errors) < 0.04
    assert ev.converged.all()
    reverberant = evaluate_layout(ROOM, ROOM.corners_layout(), noise=False)
    assert reverberant.std > 10 * ev.std


def test_bad_layouts():
    with pytest.raises(ValueError, match="at least 4"):
        evaluate_layout(ROOM, ROOM.corners_layout()[:3])
    with pytest.raises(ValueError, match="outside"):
        evaluate_layout(ROOM, ROOM.corners_layout() + [0, 0, 5])
    with pytest.raises(ValueError, match="realizations"):
        evaluate_layout(ROOM, ROOM.corners_layout(), realizations=0)
    with pytest.raises(ValueError, match="nodes"):
        simulate_ranges(ROOM, ROOM.corners_layout(), np.zeros((3, 2)))


def test_calibrated_sigma_is_robust_to_outliers():
    rng = np.random.default_rng(0)
    core = np.array([0.02, 0.04, 0.03, 0.05])
    e = rng.normal(0, core, size=(200, 50, 4))
    out = rng.random(e.shape) < 0.1
    e[out] += rng.uniform(-4, 4, out.sum())
    assert np.all(np.std(e.reshape(-1, 4), axis=0) > 10 * core)
    for method, tol in (("mad", 0.2), ("inlier", 0.03)):
        s = calibrated_sigma(e, method=method)
        assert s.shape == (4,)
        assert np.allclose(s, core, rtol=tol)
    assert calibrated_sigma(e, per_node=True).shape == (50, 4)
    model = CalibratedRangeNoise.from_range_errors(e)
    a, p = ROOM.corners_layout(), ROOM.grid()
    np.testing.assert_array_equal(analysis.peb(a, p, sigma=model), analysis.peb(a, p, model.values))
    np.testing.assert_array_equal(model.sigma(a, p), model.values)
    with pytest.raises(ValueError, match="anchors"):
        model.sigma(np.zeros((5, 3)), p)
    with pytest.raises(ValueError, match="method"):
        calibrated_sigma(e, method="std")
    with pytest.raises(ValueError, match="per_node"):
        calibrated_sigma(e[0], per_node=True)


def test_calibrated_sigma_from_simulation_is_centimetres():
    ev = evaluate_layout(ROOM, ROOM.corners_layout(), realizations=2, rng=3)
    s = calibrated_sigma(ev.range_errors)
    raw = np.std(ev.range_errors.reshape(-1, 4), axis=0)
    assert np.all((s > 0.005) & (s < 0.3))  # paper: 0.03–0.045 m for its layouts
    assert np.all(raw > 3 * s)  # the outliers dominate the plain standard deviation


def test_other_room_chirp_receiver_and_snr():
    from simulation import Chirp, Receiver, System

    chirp = Chirp(f0=20e3, f1=40e3, duration=20e-3)
    rx = Receiver(t_wake=19e-3, window=256)
    room = Room(
        size=(6.0, 5.0, 3.0),
        absorption={"west": 0.3, "east": 0.3},
        max_order=2,
    )
    system = System(chirp, rx)
    a = room.corners_layout()
    nodes = room.grid((4, 3, 3))
    ev = evaluate_layout(room, a, realizations=2, rng=0, nodes=nodes, snr_db=20.0, system=system)
    d = np.linalg.norm(nodes[:, None] - a[None], axis=-1)
    # the 1.33 ms window opens at 19 ms, 0.33 ms before the 20 ms chirp would leave it:
    # it holds 1 ms of a path's chirp from ranges 0 to c·(19 + 1.33 − 1) ms = 6.6 m (the
    # room's diagonal is 8.4 m); a node fixes when 4 anchors are within them
    c = room.speed_of_sound
    in_reach = (d >= system.near_limit(c)) & (d <= system.reach(c))
    assert system.reach(c) == pytest.approx(c * (19e-3 + 255 / 192e3 - 1e-3))
    assert system.near_limit(c) == 0.0
    assert 0 < in_reach.mean() < 1
    assert ev.errors.shape == (2, 36) and ev.range_errors.shape == (2, 36, 4)
    np.testing.assert_array_equal(np.isfinite(ev.ranges), np.broadcast_to(in_reach, (2, 36, 4)))
    np.testing.assert_array_equal(np.isfinite(ev.errors[0]), in_reach.all(axis=1))
    clean = simulate_ranges(room, a, nodes, noise=False, system=system)
    assert np.all(np.isnan(clean[~in_reach]))
    assert np.median(np.abs(clean - d)[in_reach]) < 0.1

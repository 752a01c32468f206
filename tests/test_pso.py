import json
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import placement
from placement.costs import PEBCost, make_cost
from placement.pso import PSOOptions, pso
from simulation import Room

ROOM = Room.techtile()
FAST = PSOOptions(particles=8, iterations=12, tol=0.0)


def noisy_peb(anchors, rng):
    """Mean PEB times a random factor: a stochastic, picklable cost."""
    return float(np.mean(placement_peb(anchors)) * (1 + 0.1 * rng.standard_normal()))


def placement_peb(anchors):
    import analysis

    return analysis.peb(anchors, ROOM.grid())


def flaky_peb(anchors, rng):
    if rng.random() < 0.3:
        raise RuntimeError("simulated evaluation failure")
    return float(np.mean(placement_peb(anchors)))


def test_every_evaluated_layout_is_on_the_surfaces():
    seen = []

    def cost(anchors):
        seen.append(anchors.copy())
        return float(np.mean(placement_peb(anchors)))

    res = pso(make_cost(cost, ROOM), ROOM, 5, options=FAST, rng=3)
    assert len(seen) == res.nfev == FAST.particles * FAST.iterations
    assert placement.on_surfaces(ROOM, np.concatenate(seen)).all()
    assert placement.on_surfaces(ROOM, res.anchors).all()


def test_history_non_increasing_and_improves():
    res = pso(PEBCost(ROOM), ROOM, 4, options=PSOOptions(tol=0.0), rng=0)
    h = np.array(res.history)
    assert len(h) == res.nit == 40
    assert np.all(np.diff(h) <= 0)
    assert h[-1] < h[0]
    assert res.cost == pytest.approx(np.mean(placement_peb(res.anchors)))
    # the corners layout is beaten on the bound
    assert res.cost < np.mean(placement_peb(ROOM.corners_layout()))
    np.testing.assert_array_equal(res.x, res.anchors.ravel())
    json.dumps(res.to_dict(), allow_nan=True)


def test_same_seed_same_result_and_seed_layouts_used():
    a = pso(noisy_peb, ROOM, 4, options=FAST, rng=11)
    b = pso(noisy_peb, ROOM, 4, options=FAST, rng=11)
    np.testing.assert_array_equal(a.anchors, b.anchors)
    assert a.history == b.history
    c = pso(noisy_peb, ROOM, 4, options=FAST, rng=12)
    assert a.history != c.history
    seed_layout = ROOM.corners_layout()[None]
    d = pso(PEBCost(ROOM), ROOM, 4, initial=seed_layout, options=FAST, rng=1)
    assert d.costs[0][0] == pytest.approx(np.mean(placement_peb(ROOM.corners_layout())))


def test_serial_equals_process_pool():
    serial = pso(noisy_peb, ROOM, 4, options=FAST, rng=5)
    with ProcessPoolExecutor(max_workers=2) as ex:
        parallel = pso(noisy_peb, ROOM, 4, options=FAST, rng=5, executor=ex)
        chunked = pso(noisy_peb, ROOM, 4, options=FAST, rng=5, executor=ex, chunksize=3)
    for other in (parallel, chunked):
        np.testing.assert_array_equal(serial.anchors, other.anchors)
        assert serial.history == other.history
        np.testing.assert_array_equal(serial.costs, other.costs)


def test_failing_cost_does_not_stop_the_run(caplog):
    res = pso(flaky_peb, ROOM, 4, options=FAST, rng=2)
    assert res.success and np.isfinite(res.cost)
    assert res.failures > 0
    assert np.isinf(res.costs).sum() == res.failures
    assert "simulated evaluation failure" in caplog.text


class Kill(BaseException):
    """Stands for the process being killed (not caught by the swarm)."""


@pytest.mark.parametrize("kill_at", [1, 5, 9])
def test_resume_equals_uninterrupted(tmp_path, kill_at):
    full = pso(noisy_peb, ROOM, 4, options=FAST, rng=7)
    ckpt = tmp_path / "state.json"
    calls = {"n": 0}

    def dying(anchors, rng):
        calls["n"] += 1
        # die in the middle of an iteration's evaluations
        if calls["n"] == kill_at * FAST.particles + 3:
            raise Kill
        return noisy_peb(anchors, rng)

    with pytest.raises(Kill):
        pso(dying, ROOM, 4, options=FAST, rng=7, checkpoint=ckpt, cost_label="noisy")
    assert ckpt.exists()
    resumed = pso(noisy_peb, ROOM, 4, options=FAST, rng=7, checkpoint=ckpt, cost_label="noisy")
    np.testing.assert_array_equal(resumed.anchors, full.anchors)
    assert resumed.history == full.history
    np.testing.assert_array_equal(resumed.costs, full.costs)


def test_checkpoint_of_other_run_is_not_used(tmp_path):
    ckpt = tmp_path / "state.json"
    pso(noisy_peb, ROOM, 4, options=FAST, rng=7, checkpoint=ckpt)
    other = pso(noisy_peb, ROOM, 4, options=FAST, rng=8, checkpoint=ckpt)
    fresh = pso(noisy_peb, ROOM, 4, options=FAST, rng=8)
    assert other.history == fresh.history


def test_callback_can_stop():
    seen = []
    res = pso(
        PEBCost(ROOM),
        ROOM,
        4,
        options=FAST,
        rng=0,
        callback=lambda r: seen.append(r.nit) or r.nit >= 4,
    )
    assert res.nit == 4 and seen == [2, 3, 4]
    assert "callback" in res.message


def test_tolerance_stops_early():
    res = pso(PEBCost(ROOM), ROOM, 4, options=PSOOptions(tol=0.5, patience=3), rng=0)
    assert res.nit == 4 and "improved by less" in res.message


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"particles": 1}, "particles"),
        ({"iterations": 0}, "iterations"),
        ({"inertia": -1}, "inertia"),
    ],
)
def test_bad_options(kwargs, field):
    with pytest.raises(ValueError, match=field):
        PSOOptions(**kwargs)


def test_bad_cost_name():
    with pytest.raises(ValueError, match="cost"):
        make_cost("median", ROOM)


def test_serial_equals_dask():
    from dask import distributed

    serial = pso(noisy_peb, ROOM, 4, options=FAST, rng=5)
    with distributed.Client(processes=False, n_workers=2, dashboard_address=None) as client:
        on_dask = pso(noisy_peb, ROOM, 4, options=FAST, rng=5, executor=client.get_executor())
    np.testing.assert_array_equal(serial.anchors, on_dask.anchors)
    assert serial.history == on_dask.history

"""Bad input to seed_then_pso and its costs (issue #13): the optimizer's part."""

import time

import numpy as np
import pytest

import placement
from placement.finalists import FinalistOptions
from placement.plan import seed_then_pso
from placement.pso import PSOOptions
from placement.validation import ValidationOptions
from simulation import Room
from simulation.degeneracy import geometry

ROOM = Room.techtile()
NODES = ROOM.grid()[::27]
TINY = dict(cost="peb", initial=None, swarm=PSOOptions(particles=3, iterations=1))
TINY.update(validation=ValidationOptions(realizations=0), progress=False, rng=0)


def refused(name, fn, within=5.0):
    t0 = time.monotonic()
    with pytest.raises(ValueError) as exc:
        fn()
    assert time.monotonic() - t0 < within
    assert name in str(exc.value) and "\n" not in str(exc.value), str(exc.value)


@pytest.mark.parametrize(
    ("name", "make"),
    [
        ("particles", lambda: PSOOptions(particles=3.7)),
        ("particles", lambda: PSOOptions(particles=True)),
        ("iterations", lambda: PSOOptions(iterations=1.9)),
        ("iterations", lambda: PSOOptions(iterations="2")),
        ("eval_timeout", lambda: PSOOptions(eval_timeout=0)),
        ("rng", lambda: seed_then_pso(ROOM, 4, **{**TINY, "rng": 1.7})),
        ("M", lambda: seed_then_pso(ROOM, True, **TINY)),
        ("M", lambda: seed_then_pso(ROOM, 300, **TINY)),
        ("count", lambda: FinalistOptions(count=1.5)),
        ("draws", lambda: FinalistOptions(draws=0)),
        ("exact_draws", lambda: FinalistOptions(exact_draws=-1)),
        ("exact_draws", lambda: FinalistOptions(exact_draws=13)),
        ("realizations", lambda: ValidationOptions(realizations=-1)),
        ("finalists", lambda: seed_then_pso(ROOM, 4, **{**TINY, "finalists": 1})),
        ("validation", lambda: seed_then_pso(ROOM, 4, **{**TINY, "validation": 0})),
        ("callback", lambda: seed_then_pso(ROOM, 4, **{**TINY, "callback": 3})),
    ],
)
def test_seed_then_pso_counts_and_numbers(name, make):
    refused(name, make)


def test_options_are_honoured_not_overridden_by_the_defaults():
    kw = {k: v for k, v in TINY.items() if k != "swarm"}
    res = seed_then_pso(ROOM, 4, swarm=PSOOptions(particles=4, iterations=2), **kw)
    assert res.phases["pso"]["nfev"] == 8 and res.settings.swarm.particles == 4


def test_options_must_be_pso_options():
    refused("swarm", lambda: seed_then_pso(ROOM, 4, **{**TINY, "swarm": {"particles": 4}}))


@pytest.mark.parametrize(
    ("search", "name"),
    [
        ({"start": 1}, "search"),
        ({"chains": -1}, "chains"),
        ({"spacing": 0}, "spacing"),
        ({"chains": 0}, "chains"),
        ({"fine_spacings": 0.2}, "fine_spacings"),
        ("starts", "search"),
    ],  # fmt: skip
)
def test_search_options_checked_before_any_work(search, name):
    from placement.simselect import SearchOptions

    def run():
        options = (
            SearchOptions(**search)
            if isinstance(search, dict) and "start" not in search
            else search
        )
        kw = {**TINY, "cost": "variance", "initial": "auto", "nodes": NODES}
        seed_then_pso(ROOM, 4, search=options, **kw)

    refused(name, run, within=2)


@pytest.mark.parametrize("sigma", [0, -0.04, "x"])
def test_peb_cost_sigma_is_an_error_not_a_failed_run(sigma):
    refused("sigma", lambda: placement.PEBCost(ROOM, sigma=sigma))


@pytest.mark.parametrize("value", [True, 0, 1.5])
def test_simulated_cost_realizations(value):
    refused("realizations", lambda: placement.SimulatedCost(ROOM, realizations=value))


def test_never_returns_a_degenerate_layout():
    """A mounting rectangle 1 mm wide: every layout is collinear (PEB inf everywhere)."""
    narrow = Room(size=(8.0, 4.0, 2.4), mounting=("south",), anchor_offset=1.1996)
    try:
        res = seed_then_pso(narrow, 4, **{**TINY, "swarm": PSOOptions(particles=4, iterations=2)})
    except ValueError as exc:
        assert "collinear" in str(exc) or "degenerate" in str(exc)
        return
    assert not res.success or geometry(res.anchors) not in ("collinear", "coincident")


def test_resume_skips_the_search(tmp_path, monkeypatch):
    from placement.plan import LOCAL_SWARM
    from placement.simselect import SearchOptions

    ckpt = tmp_path / "state.json"
    swarm = PSOOptions(**{**LOCAL_SWARM.__dict__, "particles": 3, "iterations": 2})
    kw = dict(cost="variance", swarm=swarm, rng=0, progress=False)
    kw.update(nodes=NODES, checkpoint=ckpt)
    kw["validation"] = ValidationOptions(realizations=0)
    kw["search"] = SearchOptions(
        spacing=2.0,
        chains=1,
        evaluations=20,
        random_starts=2,
        neighbours=6,
        batch=3,
        fine_spacings=(),
    )
    first = seed_then_pso(ROOM, 4, **kw)
    import placement.simselect as simselect

    def no_search(*a, **k):
        raise AssertionError("the search ran again")

    monkeypatch.setattr(simselect, "simulated_select", no_search)
    again = seed_then_pso(ROOM, 4, **kw)
    np.testing.assert_array_equal(first.anchors, again.anchors)
    assert [s.name for s in first.initial] == [s.name for s in again.initial]
    assert again.settings.search_result["resumed"]


def test_room_none_is_the_default_room_and_anything_else_is_refused():
    # the signature's default: None plans in the embedded room, like an explicit techtile
    default = seed_then_pso(None, 4, **TINY)
    explicit = seed_then_pso(Room.techtile(), 4, **TINY)
    np.testing.assert_array_equal(default.anchors, explicit.anchors)
    refused("room", lambda: seed_then_pso("techtile", 4, **TINY))
    refused("room", lambda: placement.sweep(ROOM.to_dict(), anchors=[4], **TINY))


# -- the range-table search and its neighbours: empty and degenerate input -----------------
CORNERS = ROOM.corners_layout()
FEW = ROOM.grid()[::54]  # 5 nodes


def _tiny_table(n=4, **kw):
    from placement.rangetable import range_table
    from placement.surfaces import candidate_grid

    return range_table(ROOM, candidate_grid(ROOM, 2.0)[:n], FEW, **kw)


@pytest.mark.parametrize(
    ("name", "kw"),
    [
        ("draws", {"draws": 0}),
        ("draws", {"draws": -2}),
        ("draws", {"draws": 1.7}),
        ("exact_draws", {"draws": 2, "exact_draws": -1}),
        ("exact_draws", {"draws": 2, "exact_draws": 5}),
        ("mount_tolerance", {"draws": 2, "mount_tolerance": -1.0}),
        ("mount_tolerance", {"draws": 2, "mount_tolerance": 5.0}),
        ("mount_tolerance", {"draws": 2, "exact_draws": 1, "mount_tolerance": np.nan}),
        ("chunk", {"chunk": 0}),
        ("nodes", {"nodes": np.zeros((0, 5, 3))}),
        ("precision", {"precision": "float16"}),
    ],
)
def test_range_table_arguments_are_checked(name, kw):
    from placement.rangetable import range_table

    refused(name, lambda: range_table(ROOM, CORNERS, kw.pop("nodes", FEW), **kw), within=2)


def test_table_layouts_must_be_candidate_indices():
    from placement.rangetable import table_costs

    t = _tiny_table(6)
    for bad in ([[0, 1, 2, 6]], [[-1, 1, 2, 3]], [[0.5, 1, 2, 3]], [0, 1, 2, 3]):
        refused("layouts", lambda bad=bad: table_costs(t, bad))


def test_a_table_of_exactly_M_candidates_is_searched_not_a_crash():
    from placement.simselect import SearchOptions, refine_on_table, simulated_select

    t = _tiny_table(4)  # every neighbour of an anchor is in the layout: no swap exists
    opt = SearchOptions(chains=2, evaluations=40, random_starts=2, fine_spacings=())
    res = simulated_select(ROOM, 4, options=opt, table=t, rng=0)
    assert sorted(res.indices) == [0, 1, 2, 3] and np.isfinite(res.fun)
    # no layouts to refine: nothing to do, with or without fine spacings
    assert refine_on_table(ROOM, t, [], options=SearchOptions(), rng=0) == ([], t, 0)
    refused("anchors", lambda: refine_on_table(ROOM, t, [np.zeros((0, 3))]))
    refused("workers", lambda: simulated_select(ROOM, 4, options=opt, table=t, workers=0))


def test_initial_layouts_must_have_M_anchors():
    six = np.stack([ROOM.corners_layout()[:3]] * 2).reshape(1, 6, 3)
    refused(
        "initial", lambda: seed_then_pso(ROOM, 4, **{**TINY, "initial": np.concatenate([six] * 2)})
    )
    refused("initial", lambda: placement.pso(placement.PEBCost(ROOM), ROOM, 4, initial=six))
    one = seed_then_pso(ROOM, 4, **{**TINY, "initial": CORNERS})  # one (M, 3) layout
    assert [s.name for s in one.initial] == ["user-1"]


@pytest.mark.parametrize("tolerance", [np.nan, -0.01, 5.0])
def test_validation_mount_tolerance_is_checked(tolerance):
    from placement.validation import validate_layout

    refused(
        "mount_tolerance", lambda: validate_layout(ROOM, CORNERS, rng=0, mount_tolerance=tolerance)
    )


def test_no_realizations_are_an_empty_batch():
    from simulation.evaluation import RangingScene

    scene = RangingScene(ROOM, CORNERS, FEW)
    assert scene.ranges_batch([]).shape == (0, len(FEW), 4)
    assert scene.ranges_batch([], noise=False).shape == (0, len(FEW), 4)


def test_user_initial_layouts_are_reported_as_the_swarm_uses_them():
    off = CORNERS + [0.0, 0.0, 1.5]  # above the ceiling: the swarm projects them
    res = seed_then_pso(ROOM, 4, **{**TINY, "initial": off[None]})
    seed = res.initial[0]
    assert placement.on_surfaces(ROOM, seed.anchors).all()
    from analysis import peb

    assert seed.mean_peb == pytest.approx(np.mean(peb(seed.anchors, ROOM.grid(), 0.04)))
    assert seed.mean_peb < 10  # the PEB of the layout in the room, not of the one above it

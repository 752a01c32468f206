import dataclasses
import json
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import placement
from placement.costs import DrawsCost
from placement.finalists import FinalistOptions, score_finalists
from placement.plan import LOCAL_SWARM, seed_then_pso
from placement.pso import PSOOptions
from placement.rangetable import node_draws, range_table, table_errors
from placement.simselect import DEFAULT_KEEP, SMALL_M_KEEP, SearchOptions
from placement.validation import Validation, ValidationOptions, validate_layout
from simulation import Room

ROOM = Room.techtile()
NODES = ROOM.grid()[::27]  # 10 nodes
SMALL = SearchOptions(
    spacing=2.0,
    chains=2,
    evaluations=40,
    random_starts=3,
    neighbours=8,
    batch=4,
    patience=3,
    fine_spacings=(1.0,),
)
QUICK = ValidationOptions(realizations=2, held_out_realizations=1, random_nodes=10, mount_draws=2)


def _swarm(particles=4, iterations=2):
    return dataclasses.replace(LOCAL_SWARM, particles=particles, iterations=iterations)


def _plan(**kw):
    base = dict(search=SMALL, swarm=_swarm(), validation=QUICK, rng=0)
    base.update(progress=False, nodes=NODES)
    base.update(kw)
    return seed_then_pso(ROOM, 4, **base)


def test_seed_then_pso_bound_driven_with_user_initial_layouts():
    initial = ROOM.corners_layout()[None]
    res = seed_then_pso(
        ROOM, 4, swarm=PSOOptions(particles=6, iterations=5), cost="peb", initial=initial,
        rng=0, progress=False, validation=ValidationOptions(realizations=0),
    )  # fmt: skip
    assert res.anchors.shape == (4, 3)
    assert placement.on_surfaces(ROOM, res.anchors).all()
    assert res.initial[0].name == "user-1"
    assert res.initial[0].cost == pytest.approx(res.initial[0].mean_peb)
    assert res.cost <= res.initial[0].cost
    assert np.all(np.diff(res.history) <= 0)
    d = json.loads(res.to_json())
    assert d["settings"]["M"] == 4 and len(d["history"]) == res.nit
    assert set(res.timings) >= {"pso", "validation", "total"}


def test_the_drawn_cost_is_a_range_table_of_the_layout():
    sets = node_draws(ROOM, NODES, 2, 1, rng=3)
    cost = DrawsCost(ROOM, sets, exact_draws=1, mount_tolerance=0.03, seed=9)
    a = ROOM.corners_layout()
    t = range_table(ROOM, a, sets, exact_draws=1, mount_tolerance=0.03, rng=9)
    e = table_errors(t, np.arange(4)[None])[0]
    assert cost(a) == pytest.approx(np.var(e)) and cost(a) == cost(a, None)  # deterministic
    assert DrawsCost(ROOM, sets, exact_draws=1, mount_tolerance=0.03, seed=10)(a) != cost(a)


def test_seed_then_pso_simulated_chain_and_its_phases():
    res = _plan()
    assert res.success and placement.on_surfaces(ROOM, res.anchors).all()
    assert [s.name for s in res.initial][:1] == ["search-1"]
    assert set(res.timings) >= {"search", "pso", "finalists", "validation", "total"}
    n = {k: p["nfev"] for k, p in res.phases.items()}
    assert n["search"] > 0 and n["pso"] == 8 and res.nfev == sum(n.values())
    # grid, held-out grid and points, mounting and field draws
    assert n["validation"] == 2 + 2 * 1 + 2 + QUICK.field_draws
    v = res.validation
    assert v.realizations == 2 and np.shape(v.errors) == (2, len(NODES))
    assert v.std == pytest.approx(np.std(v.errors), abs=1e-5)
    assert v.held_out.grid.nodes > 0 and v.mounting.draws == 2
    assert v.field.draws == QUICK.field_draws
    json.loads(res.to_json())


def test_the_chosen_layout_is_the_finalist_with_the_lowest_cost_on_fresh_draws():
    res = _plan(finalists=FinalistOptions(count=3))
    f = res.finalists
    # the starting layouts always compete (under a refined layout's name where the
    # refinement left one where it was)
    assert all(any(np.allclose(s.anchors, d["anchors"]) for d in f) for s in res.initial)
    assert any(d["source"].startswith("refined-") for d in f)  # so do the refined layouts
    assert not any(
        np.allclose(a["anchors"], b["anchors"]) for i, a in enumerate(f) for b in f[i + 1 :]
    )
    best = min(f, key=lambda d: d["cost"])
    np.testing.assert_array_equal(res.anchors, best["anchors"])
    # the fresh draws are not the swarm's: the scores differ from the swarm's costs
    assert any(d["cost"] != d["pso_cost"] for d in f)


def test_the_finalists_draws_are_new_noise_at_the_exact_nodes_unless_asked_otherwise():
    from simulation import streams

    def fresh(draws, exact):
        sets = node_draws(ROOM, NODES, draws, exact, streams.substream(0, 6))
        return DrawsCost(ROOM, sets, exact_draws=exact, mount_tolerance=0.03,
                         seed=streams.substream(0, 5))  # fmt: skip

    none = ValidationOptions(realizations=0)
    res = _plan(finalists=FinalistOptions(draws=3), validation=none)
    assert res.settings.finalists == FinalistOptions(count=1, draws=3, exact_draws=None)
    assert [d["cost"] for d in res.finalists] == [fresh(3, 3)(d["anchors"]) for d in res.finalists]
    mixed = _plan(finalists=FinalistOptions(draws=3, exact_draws=1), validation=none)
    assert [d["cost"] for d in mixed.finalists] == [
        fresh(3, 1)(d["anchors"]) for d in mixed.finalists
    ]
    assert [d["cost"] for d in mixed.finalists] != [d["cost"] for d in res.finalists]
    with pytest.raises(ValueError, match=r"exact_draws.*\[0, 3\]"):
        FinalistOptions(draws=3, exact_draws=4)


def test_the_finalists_are_scored_on_the_given_cost_serially_or_in_parallel():
    res = _plan()
    fresh = DrawsCost(ROOM, node_draws(ROOM, NODES, 2, 1, rng=1), exact_draws=1, seed=4)
    one = score_finalists(res.pso, res.initial, fresh, 2)
    with ThreadPoolExecutor(2) as ex:
        two = score_finalists(res.pso, res.initial, fresh, 2, ex)
    assert [d["cost"] for d in one] == [d["cost"] for d in two]
    assert [d["cost"] for d in one] == [fresh(d["anchors"]) for d in one]


def test_same_result_serially_and_with_an_executor():
    a = _plan(rng=5)
    with ThreadPoolExecutor(2) as ex:
        b = _plan(rng=5, executor=ex)
    np.testing.assert_array_equal(a.anchors, b.anchors)
    assert a.validation.std == b.validation.std
    assert a.validation.held_out == b.validation.held_out


def test_the_swarm_options_are_honoured_and_checked():
    res = _plan(swarm=placement.PSOOptions(4, 2))
    assert res.phases["pso"]["nfev"] == 8 and res.settings.swarm.particles == 4
    with pytest.raises(ValueError, match="^swarm: must be a PSOOptions"):
        _plan(swarm={"particles": 4})
    with pytest.raises(ValueError, match=r"^finalists.count: must be an integer in \[1, 4\]"):
        _plan(finalists=FinalistOptions(count=5))


def test_each_refined_layout_is_refined_on_its_own_columns():
    """With two layouts refined, the first is what refining it alone gives."""

    def refined(res):
        return {f["source"]: f["anchors"] for f in res.finalists if f["source"].startswith("ref")}

    one = refined(_plan(search=dataclasses.replace(SMALL, fine_optima=1), swarm=_swarm(4, 1)))
    two = refined(_plan(search=dataclasses.replace(SMALL, fine_optima=2), swarm=_swarm(4, 1)))
    assert sorted(one) == ["refined-1"] and sorted(two) == ["refined-1", "refined-2"]
    np.testing.assert_array_equal(one["refined-1"], two["refined-1"])
    assert not np.array_equal(two["refined-1"], two["refined-2"])


def test_four_anchors_start_from_more_optima_and_refine_every_layout():
    """At M = 4 the defaults start the swarm from SMALL_M_KEEP search optima and refine
    every distinct swarm layout (None: however many particles the swarm has); at M = 5
    from DEFAULT_KEEP and one refined; given values win."""
    assert (SMALL.keep_for(4), SMALL.fine_optima_for(4)) == (SMALL_M_KEEP, None)
    assert (SMALL.keep_for(5), SMALL.fine_optima_for(5)) == (DEFAULT_KEEP, 1)
    given = dataclasses.replace(SMALL, keep=2, fine_optima=3)
    assert (given.keep_for(4), given.fine_optima_for(4)) == (2, 3)
    # a particle more than the search optima: it starts at random and is refined too
    res = _plan(search=dataclasses.replace(SMALL, chains=6), swarm=_swarm(SMALL_M_KEEP + 1, 1))
    refined = [f["source"] for f in res.finalists if f["source"].startswith("refined")]
    assert 1 < len(res.initial) <= SMALL_M_KEEP
    assert len(refined) == SMALL_M_KEEP + 1  # every particle distinct: all refined


def test_the_mounting_tolerance_is_set_once_and_reaches_every_stage():
    res = _plan(search=dataclasses.replace(SMALL, mount_tolerance=0.0), swarm=_swarm(4, 1))
    assert res.settings.search.mount_tolerance == 0.0 == res.settings.mount_tolerance
    assert res.validation.mounting is None  # nothing to check with exact mounting
    t = range_table(ROOM, ROOM.corners_layout(), NODES, draws=2, exact_draws=1,
                    mount_tolerance=0.03, rng=0)  # fmt: skip
    with pytest.raises(ValueError, match="table: built with mount_tolerance 0.03"):
        placement.Planner(ROOM, 4, search=SearchOptions(mount_tolerance=0.05), table=t)


def test_seed_then_pso_rejects_bad_input():
    with pytest.raises(ValueError, match="M"):
        seed_then_pso(ROOM, 3, cost="peb", initial=None, progress=False)
    with pytest.raises(ValueError, match="initial"):
        seed_then_pso(ROOM, 4, cost="peb", initial="best", progress=False)
    with pytest.raises(ValueError, match="realizations"):
        ValidationOptions(realizations=-1)
    with pytest.raises(ValueError, match="^search: must be a SearchOptions"):
        seed_then_pso(ROOM, 4, search={"start": 1}, progress=False)
    with pytest.raises(ValueError, match="count"):
        FinalistOptions(count=0)
    with pytest.raises(TypeError):  # the keywords of an unreleased version are gone
        seed_then_pso(ROOM, 4, particles=4)


def test_validation_checks_are_reproducible_and_independent_of_the_executor():
    a = ROOM.corners_layout()
    v1 = validate_layout(ROOM, a, rng=3, options=QUICK, nodes=NODES)
    with ThreadPoolExecutor(2) as ex:
        v2 = validate_layout(ROOM, a, rng=3, options=QUICK, nodes=NODES, executor=ex)
    assert v1.to_dict() == v2.to_dict()
    assert v1.held_out.grid.nodes == 420
    assert v1.mounting.n == 2 * len(NODES)
    v3 = validate_layout(ROOM, a, rng=4, options=QUICK, nodes=NODES)
    assert v3.std != v1.std


def test_progress_bars_can_be_switched_off(capsys):
    _plan(progress=False)
    assert capsys.readouterr().err == ""
    _plan(progress=True)
    err = capsys.readouterr().err
    for phase in ("range table", "search", "PSO", "finalists", "validation"):
        assert phase in err


def test_progress_can_be_a_function_of_phase_done_and_total(capsys):
    seen = []
    _plan(progress=lambda phase, done, total: seen.append((phase, done, total)))
    assert capsys.readouterr().err == ""  # no bars when a function takes the reports
    phases = list(dict.fromkeys(p for p, _, _ in seen))
    assert phases == ["range table", "search", "swarm", "refinement", "finalists", "validation"]
    for phase in phases:
        done = [d for p, d, _ in seen if p == phase]
        total = [t for p, _, t in seen if p == phase]
        assert done == sorted(done) and done[-1] == total[-1] > 0, phase
    with pytest.raises(ValueError, match="progress"):
        _plan(progress="yes")


def test_the_grid_check_solves_with_the_systems_positioning():
    """The grid check simulates the system it is given: its errors are those of
    ``evaluate_layout`` with that system on the same noise streams; the paper's system
    (not kept in the room) and one that keeps positions in the room differ."""
    from simulation import Positioning, System, evaluate_layout

    a = ROOM.corners_layout()
    opt = ValidationOptions(realizations=2, held_out_realizations=0, mount_draws=0,
                            field_draws=0)  # fmt: skip
    child = int(np.random.SeedSequence(4).spawn(5)[0].generate_state(1)[0])
    halves = [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(child).spawn(2)]
    kept = System(positioning=Positioning(keep_in_room=True))
    out = {}
    for system in (System(), kept):
        v = validate_layout(ROOM, a, rng=4, options=opt, nodes=NODES, system=system)
        runs = [evaluate_layout(ROOM, a, 1, rng=s, nodes=NODES, system=system) for s in halves]
        np.testing.assert_allclose(v.errors, np.concatenate([ev.errors for ev in runs]),
                                   rtol=0, atol=1e-12)  # fmt: skip
        assert Validation.from_dict(v.to_dict()).to_dict() == v.to_dict()
        out[system.positioning.keep_in_room] = v.std
    assert out[True] != out[False]  # the corners layout: some fixes leave the room


def test_the_field_check_draws_random_tags_and_mounting_error_together():
    """The field figure: per draw, random tags (not the grid) with the anchors mounted
    within the tolerance, one noise realization; reproducible from ``rng``."""
    from placement.validation import field_errors, field_tags, mounted_errors, random_nodes, summary

    a = ROOM.corners_layout()
    opt = ValidationOptions(realizations=2, held_out_realizations=0, random_nodes=15,
                            mount_draws=0, field_draws=3)  # fmt: skip
    v = validate_layout(ROOM, a, rng=3, options=opt, nodes=NODES)
    child = np.random.SeedSequence(3).spawn(5)[4].generate_state(1)[0]
    errors = np.concatenate([field_errors(ROOM, a, 15, 0.03, d, int(child)) for d in range(3)],
                            axis=1)  # fmt: skip
    assert v.field.to_dict() == {"draws": 3, "tags_per_draw": 15, "tolerance_m": 0.03,
                                 **summary(errors[0], errors[1] > 0)}  # fmt: skip
    # row 0 the errors, row 1 whether each fix is verified (least squares verifies none)
    assert errors.shape == (2, 45) and not errors[1].any() and v.field.verified == 0
    assert v.field.n == 45 and v.mounting is None
    assert validate_layout(ROOM, a, rng=3, options=opt, nodes=NODES).field == v.field
    # field_tags are the tags of field_errors' draw: the same errors at them
    tags = [field_tags(ROOM, 15, d, int(child)) for d in range(2)]
    assert ROOM.contains(tags[0]).all() and not np.allclose(tags[0], tags[1])
    again = mounted_errors(ROOM, a, tags[1], 0.03, 1, int(child), None, 1)
    np.testing.assert_allclose(again, errors[:, 15:30], rtol=0, atol=1e-12)
    # the tags of a draw are random points of the node region, a new set per draw
    t0 = random_nodes(ROOM, len(NODES), np.random.default_rng(0))
    assert ROOM.contains(t0).all() and not np.allclose(t0, NODES)

"""Positioning that rejects echoes (simulation.robust): against an exhaustive reference on
small cases, one echo found with 5 anchors, the quality of every fix, the floor plan as
the bounds, bad input."""

import itertools
from pathlib import Path

import numpy as np
import pytest

from simulation import Positioning, Room, locate
from simulation.robust import NO_FIX, UNVERIFIED, VERIFIED, bias_scales, thresholds

ANCHORS = np.array(
    [
        [0, 0, 2.4],
        [8, 0, 2.4],
        [8, 4, 2.4],
        [0, 4, 2.4],
        [0, 0, 0.5],
        [8, 4, 0.5],
        [4, 0, 1.2],
        [4, 4, 1.8],
    ],
    float,
)
REGION = (np.zeros(3), np.array([8.0, 4.0, 2.4]))
SIGMA = 0.01


def _nodes(rng, n):
    return rng.uniform([0.5, 0.5, 0.5], [7.5, 3.5, 2.0], (n, 3))


def _exhaustive(a, rho, sigma=SIGMA, false_alarm=1e-3):
    """The reference: the largest subset of the heard anchors that passes the χ² test,
    the one with the smallest residual at that size, by solving every subset."""
    thr = thresholds(false_alarm, len(a))
    heard = [j for j in range(len(a)) if np.isfinite(rho[j])]
    for size in range(len(heard), 4, -1):
        best = None
        for S in itertools.combinations(heard, size):
            r = np.full(len(a), np.nan)
            r[list(S)] = rho[list(S)]
            fix = locate(a, r[None], region=REGION, bounded=True, full_output=True)
            T = 2 * fix.cost[0] / sigma**2
            if T <= thr[size - 3] and (best is None or T < best[0]):
                best = (T, set(S), fix.x[0])
        if best is not None:
            return best
    return None


def _protection_level(a, x, sigma=SIGMA, false_alarm=1e-3):
    """σ √λ max_j ‖k_j‖ / √(1 − h_jj) of the anchors a (n, 3) at x (3,), with numpy (the
    module docstring's formula: K = (UᵀU)⁻¹Uᵀ, h_jj = u_jᵀk_j)."""
    U = (x - a) / np.linalg.norm(x - a, axis=1, keepdims=True)
    K = np.linalg.solve(U.T @ U, U.T)
    h = np.sum(U * K.T, axis=1)
    lam = bias_scales(false_alarm, len(a))[len(a) - 3]
    return sigma * lam * np.max(np.linalg.norm(K, axis=0) / np.sqrt(1 - h))


def _quality(a, x, alert_limit=0.5):
    """The quality a fix at x (3,) resting on the anchors a (n ≥ 5, 3) that pass the test
    gets: verified where its protection level is within the alert limit."""
    return VERIFIED if _protection_level(a, x) <= alert_limit else UNVERIFIED


def test_it_finds_the_consistent_subset_the_exhaustive_search_finds():
    """Up to three echoes among eight anchors (ranges 0.3–3 m too long, as an echo makes
    them): the anchors kept are those of the exhaustive search, the fix lies within
    centimetres of the node (positions kept in the room, as an installed system keeps
    them: five anchors of this layout can leave a mirror position above the ceiling) and
    is verified where its protection level is within the alert limit (0.5 m), as it is
    for most."""
    rng = np.random.default_rng(1)
    verified = 0
    for trial in range(40):
        x = _nodes(rng, 1)[0]
        rho = np.linalg.norm(x - ANCHORS, axis=1) + SIGMA * rng.standard_normal(8)
        echoes = rng.choice(8, size=trial % 4, replace=False)
        rho[echoes] += rng.uniform(0.3, 3.0, len(echoes))
        ref = _exhaustive(ANCHORS, rho)
        fix = locate(
            ANCHORS,
            rho[None],
            method="robust",
            region=REGION,
            bounded=True,
            range_sigma=SIGMA,
            full_output=True,
        )
        assert ref is not None
        assert set(np.flatnonzero(fix.used[0])) == ref[1], trial
        assert fix.quality[0] == _quality(ANCHORS[fix.used[0]], fix.x[0]), trial
        verified += fix.quality[0] == VERIFIED
        assert np.linalg.norm(fix.x[0] - x) < 0.05
        assert np.allclose(fix.x[0], ref[2], atol=1e-6)
    assert verified >= 35


def test_one_echo_is_found_with_five_anchors_and_not_with_four():
    rng = np.random.default_rng(2)
    x = np.array([3.0, 2.0, 1.2])
    for k in (5, 4):
        a = ANCHORS[:k]
        rho = np.linalg.norm(x - a, axis=1) + 0.002 * rng.standard_normal(k)
        rho[1] += 1.5  # an echo
        fix = locate(
            a, rho[None], method="robust", region=REGION, range_sigma=SIGMA, full_output=True
        )
        if k == 5:  # the four others agree: the echo is dropped, the fix verified
            assert not fix.used[0, 1] and fix.used[0].sum() == 4
            assert fix.quality[0] == UNVERIFIED  # 4 anchors kept: no redundancy left
            assert np.linalg.norm(fix.x[0] - x) < 0.02
        else:  # no redundancy to tell the echo: unverified, and it shows in the error
            assert fix.quality[0] == UNVERIFIED
            assert np.linalg.norm(fix.x[0] - x) > 0.1


def test_with_six_anchors_one_echo_leaves_a_verified_fix():
    x = np.array([5.0, 1.0, 1.0])
    rho = np.linalg.norm(x - ANCHORS[:6], axis=1)
    rho[4] += 0.8
    fix = locate(ANCHORS[:6], rho[None], method="robust", region=REGION, full_output=True)
    assert fix.quality[0] == VERIFIED and not fix.used[0, 4]
    assert np.linalg.norm(fix.x[0] - x) < 1e-6


def test_no_consistent_subset_is_flagged():
    """Ranges that no subset of 5 or more anchors agrees with: unverified, not verified."""
    rng = np.random.default_rng(3)
    rho = np.linalg.norm(np.array([4, 2, 1.0]) - ANCHORS, axis=1) + rng.uniform(0, 3, 8)
    assert _exhaustive(ANCHORS, rho) is None
    fix = locate(ANCHORS, rho[None], method="robust", region=REGION, full_output=True)
    assert fix.quality[0] == UNVERIFIED


def test_every_fix_has_a_quality_and_least_squares_verifies_nothing():
    rng = np.random.default_rng(4)
    x = _nodes(rng, 50)
    rho = np.linalg.norm(x[:, None] - ANCHORS[None], axis=-1)
    rho[:10, :5] = np.nan  # 3 heard: no fix
    robust = locate(ANCHORS, rho, method="robust", region=REGION, full_output=True)
    ls = locate(ANCHORS, rho, region=REGION, full_output=True)
    assert np.all(robust.quality[:10] == NO_FIX) and np.all(ls.quality[:10] == NO_FIX)
    assert np.all(robust.quality[10:] == VERIFIED) and np.all(ls.quality[10:] == UNVERIFIED)
    assert np.array_equal(ls.used, np.isfinite(rho))
    assert np.allclose(robust.x[10:], ls.x[10:], atol=1e-9)  # nothing to reject: least squares


def test_the_robust_solver_equals_least_squares_without_echoes():
    """Without echoes the test passes on every anchor and the fix is least squares'."""
    rng = np.random.default_rng(5)
    x = _nodes(rng, 200)
    rho = np.linalg.norm(x[:, None] - ANCHORS[None], axis=-1) + 0.003 * rng.standard_normal(
        (200, 8)
    )
    robust = locate(ANCHORS, rho, method="robust", region=REGION, full_output=True)
    ls = locate(ANCHORS, rho, region=REGION, full_output=True)
    kept_all = robust.used.all(axis=1)
    assert kept_all.mean() > 0.99  # the test rejects at 1e-3 false alarm
    assert np.allclose(robust.x[kept_all], ls.x[kept_all], atol=1e-9)


def test_positions_kept_in_the_floor_plan_not_its_box():
    """An L-shaped room: a fix kept in the room never lands in the missing corner."""
    room = Room.from_corners([[0, 0], [7, 0], [7, 3], [3, 3], [3, 6], [0, 6]], 3.0)
    a = np.array(
        [
            [0.03, 0.03, 2.9],
            [6.9, 0.03, 0.5],
            [6.9, 2.9, 2.9],
            [2.9, 5.9, 0.5],
            [0.03, 5.9, 2.9],
            [1.5, 0.03, 1.5],
        ]
    )
    rng = np.random.default_rng(6)
    x = np.array([[2.5, 3.5, 1.2]] * 300)  # near the inner corner
    rho = np.linalg.norm(x[:, None] - a[None], axis=-1) + 0.5 * rng.standard_normal((300, 6))
    rho = np.maximum(rho, 0.0)
    kept = Positioning(keep_in_room=True).locate(room, a, rho)
    free = locate(a, rho, region=(np.zeros(3), np.asarray(room.size)), bounded=True)

    def in_plan(p):
        return room.contains(np.c_[p[:, :2], np.full(len(p), 1.5)])

    assert np.all(in_plan(kept))
    assert not np.all(in_plan(free))  # the box alone lets some into the missing corner


# sixteen anchors on the walls and ceiling of a 12 x 8 x 4 m hall
HALL = (np.zeros(3), np.array([12.0, 8.0, 4.0]))
SIXTEEN = np.array(
    [[0.03, y, z] for y, z in ((1, 1), (4, 3.5), (7, 2))]
    + [[11.97, y, z] for y, z in ((1.5, 3), (4.5, 0.8), (6.5, 3.6))]
    + [[x, 0.03, z] for x, z in ((3, 2.5), (6, 0.6), (9, 3.2))]
    + [[x, 7.97, z] for x, z in ((2.5, 0.9), (6.5, 3.3), (10, 1.7))]
    + [[x, y, 3.97] for x, y in ((3, 2), (9, 6), (6, 4.5), (2, 6.5))]
)


def test_with_sixteen_anchors_half_of_them_echoes_the_direct_ones_are_found():
    """Up to 8 of 16 ranges lengthened by an echo (0.3–3 m): step 4's consensus finds the
    direct ranges, whatever their number of subsets, and the fix is verified within
    centimetres of the node."""
    rng = np.random.default_rng(11)
    for trial in range(30):
        x = rng.uniform([1, 1, 0.5], [11, 7, 2.0])
        rho = np.linalg.norm(x - SIXTEEN, axis=1) + SIGMA * rng.standard_normal(16)
        echoes = rng.choice(16, size=4 + trial % 5, replace=False)
        rho[echoes] += rng.uniform(0.3, 3.0, len(echoes))
        fix = locate(SIXTEEN, rho[None], method="robust", region=HALL, bounded=True,
                     range_sigma=SIGMA, full_output=True)  # fmt: skip
        assert fix.quality[0] == VERIFIED, trial
        assert not fix.used[0, echoes].any(), trial
        assert np.linalg.norm(fix.x[0] - x) < 0.05, trial


def test_a_direct_range_shorter_than_the_fix_puts_it_elsewhere():
    """A range shorter than its anchor's distance from a fix contradicts the fix (no path is
    shorter than the direct one): the fixes kept have no such range."""
    rng = np.random.default_rng(12)
    for _ in range(30):
        x = rng.uniform([1, 1, 0.5], [11, 7, 2.0])
        rho = np.linalg.norm(x - SIXTEEN, axis=1) + SIGMA * rng.standard_normal(16)
        echoes = rng.choice(16, size=8, replace=False)
        rho[echoes] += rng.uniform(0.3, 3.0, 8)
        fix = locate(SIXTEEN, rho[None], method="robust", region=HALL, bounded=True,
                     range_sigma=SIGMA, full_output=True)  # fmt: skip
        assert np.all(np.linalg.norm(fix.x[0] - SIXTEEN, axis=1) - rho <= 0.1 + 1e-9)


def test_four_direct_ranges_among_four_echoes_are_found_unverified():
    """A tag that sees 4 of 8 anchors: no 5 agree, but the 4 direct ranges are the minimal
    set whose fix no echo contradicts (every echo is longer than its anchor's distance from
    it): they are kept, and the fix is unverified (nothing is left to check it)."""
    rng = np.random.default_rng(13)
    for trial in range(40):
        x = _nodes(rng, 1)[0]
        rho = np.linalg.norm(x - ANCHORS, axis=1) + SIGMA * rng.standard_normal(8)
        echoes = rng.choice(8, size=4, replace=False)
        rho[echoes] += rng.uniform(0.3, 3.0, 4)
        fix = locate(ANCHORS, rho[None], method="robust", region=REGION, bounded=True,
                     range_sigma=SIGMA, full_output=True)  # fmt: skip
        assert set(np.flatnonzero(fix.used[0])) == set(range(8)) - set(echoes), trial
        assert fix.quality[0] == UNVERIFIED
        assert np.linalg.norm(fix.x[0] - x) < 0.3, trial  # 4 anchors: σ times their DOP


def test_five_anchors_on_one_line_do_not_verify_a_fix():
    """Five anchors within centimetres of one line agree with nearly a whole circle of
    positions: their consensus is not a verified fix (the dilution of precision is in the
    hundreds), however well they agree; sixteen anchors around the hall verify it."""
    a = np.array([[x, 4.0, 3.97 - dz] for x, dz in ((1, 0), (3.5, 0.02), (6, 0), (8.5, 0.01),
                                                     (11, 0.02))])  # fmt: skip
    x = np.array([5.0, 2.5, 1.2])
    fix = locate(a, np.linalg.norm(x - a, axis=1)[None], method="robust", region=HALL,
                 bounded=True, full_output=True)  # fmt: skip
    assert fix.used[0].all() and 2 * fix.cost[0] / SIGMA**2 < thresholds(1e-3, 5)[2]  # agree
    assert fix.quality[0] == UNVERIFIED
    good = locate(SIXTEEN, np.linalg.norm(x - SIXTEEN, axis=1)[None], method="robust",
                  region=HALL, bounded=True, full_output=True)  # fmt: skip
    assert good.quality[0] == VERIFIED


@pytest.mark.parametrize(
    ("kw", "names"),
    [
        ({"method": "median"}, "method"),
        ({"method": "robust", "range_sigma": 0}, "range_sigma"),
        ({"method": "robust", "range_sigma": -0.1}, "range_sigma"),
        ({"method": "robust", "false_alarm": 0.7}, "false_alarm"),
        ({"method": "robust", "alert_limit": 0.0}, "alert_limit"),
        ({"method": "robust", "alert_limit": float("nan")}, "alert_limit"),
        ({"floor_plan": [[0, 0], [1, 1]]}, "floor_plan"),
    ],
)
def test_bad_input_names_the_argument(kw, names):
    with pytest.raises(ValueError, match=names):
        locate(ANCHORS, np.linalg.norm(ANCHORS - 1.0, axis=1)[None], region=REGION, **kw)


def test_too_few_anchors_are_refused_and_a_bad_positioning_too():
    with pytest.raises(ValueError, match="anchors"):
        locate(ANCHORS[:2], np.ones((1, 2)), method="robust")
    for kw, name in (
        ({"method": "lms"}, "method"),
        ({"range_sigma": 0.0}, "range_sigma"),
        ({"false_alarm": 1.0}, "false_alarm"),
        ({"alert_limit": -0.5}, "alert_limit"),
    ):
        with pytest.raises(ValueError, match=name):
            Positioning(**kw)


def test_a_fix_reports_the_status_of_the_solve_that_gave_it():
    # two echoes; 3 iterations: least squares on every range stops at the iteration limit,
    # the consensus search's minimal set is exact and its refined solve ends on a zero
    # residual: the fix is the refined one, and so is its status
    tag = np.array([6.6, 1.3, 1.3])
    rho = np.linalg.norm(ANCHORS - tag, axis=1) + np.array([0, 0, 0, 1.0, 0, 0, 0, 1.2])
    plain = locate(ANCHORS, rho[None], region=REGION, bounded=True, max_iter=3,
                   full_output=True)  # fmt: skip
    assert plain.status[0] == 0 and not plain.converged[0]
    fix = locate(ANCHORS, rho[None], method="robust", region=REGION, bounded=True,
                 range_sigma=SIGMA, max_iter=3, full_output=True)  # fmt: skip
    assert fix.used[0].tolist() == [True, True, True, False, True, True, True, False]
    assert np.linalg.norm(fix.x[0] - tag) < 1e-9
    assert fix.converged[0] and fix.status[0] > 0


# -- the map check (simulation.map_check) ---------------------------------------------------
RACK_ROOM = Room(
    size=(10.0, 10.0, 3.0),
    name="rack",
    obstacles=({"min": [4.0, 1.0, 0.0], "max": [4.5, 9.0, 3.0], "name": "rack"},),
)
WEST = np.array(
    [[0.03, 1.0, 1.0], [0.03, 9.0, 2.5], [3.5, 0.03, 2.9], [1.0, 9.97, 0.5], [2.0, 5.0, 2.97]]
)
EAST = np.array(
    [
        [9.97, 2.0, 1.0],
        [9.97, 8.0, 2.5],
        [7.0, 1.5, 2.97],
        [6.0, 8.5, 0.3],
        [8.0, 5.0, 2.97],
        [9.97, 5.0, 0.2],
    ]
)
MAPPED = Positioning(method="robust", keep_in_room=True, range_sigma=0.01)


def test_a_consistent_set_the_fix_cannot_see_is_not_verified():
    from simulation.polyhedral import line_of_sight

    fake = np.array([2.0, 3.0, 1.2])  # west of the rack: every east anchor is hidden from it
    assert not line_of_sight(RACK_ROOM, EAST, fake[None]).any()
    ranges = np.linalg.norm(EAST - fake, axis=1)[None]
    alone = locate(EAST, ranges, method="robust", range_sigma=0.01, full_output=True)
    assert alone.verified.all()  # the ranges agree: the residual test alone vouches for it
    fix = MAPPED.locate(RACK_ROOM, EAST, ranges, full_output=True)
    assert not fix.verified.any() and fix.quality[0] == UNVERIFIED


@pytest.mark.parametrize(
    ("tag", "mirror"),
    [((3.5, 5.0, 1.2), (1.5, 4.5, 1.2)), ((3.0, 6.0, 1.2), (1.0, 5.5, 1.2)),
     ((3.8, 3.0, 1.0), (2.0, 3.0, 2.0))],
)  # fmt: skip
def test_echoes_that_agree_at_a_point_hidden_from_their_anchors_are_rejected(tag, mirror):
    from simulation.polyhedral import line_of_sight

    # the west anchors see the tag (direct ranges); the east ones are hidden from it and
    # their echoes agree at a point that none of them sees, not farther from the west
    # anchors than the tag: no range contradicts either point
    tag, mirror = np.array(tag), np.array(mirror)
    anchors = np.concatenate([WEST, EAST])
    assert line_of_sight(RACK_ROOM, WEST, tag[None]).all()
    assert not line_of_sight(RACK_ROOM, EAST, tag[None]).any()
    assert not line_of_sight(RACK_ROOM, EAST, mirror[None]).any()
    echoes = np.linalg.norm(EAST - mirror, axis=1)
    assert np.all(echoes > np.linalg.norm(EAST - tag, axis=1) + 0.3)
    direct = np.linalg.norm(WEST - tag, axis=1)
    assert np.all(np.linalg.norm(WEST - mirror, axis=1) < direct + 0.05)
    ranges = np.concatenate([direct, echoes])[None]
    box = (np.zeros(3), np.array(RACK_ROOM.size))
    blind = locate(anchors, ranges, method="robust", range_sigma=0.01, region=box, bounded=True,
                   full_output=True)  # fmt: skip
    assert np.linalg.norm(blind.x[0] - tag) > 0.5  # without the map the mirror wins
    fix = locate(anchors, ranges, method="robust", range_sigma=0.01, region=box, bounded=True,
                 room=RACK_ROOM, full_output=True)  # fmt: skip
    assert np.linalg.norm(fix.x[0] - tag) < 1e-3 and fix.quality[0] == _quality(WEST, fix.x[0])
    assert fix.used[0].tolist() == [True] * 5 + [False] * 6
    same = MAPPED.locate(RACK_ROOM, anchors, ranges, full_output=True)
    np.testing.assert_allclose(same.x, fix.x, atol=1e-9)


def test_a_fix_that_passes_the_test_on_an_anchor_it_cannot_see_leaves_that_anchor_out():
    # the end of step 3: a range bent round the rack's edge is only 3 cm long, so least squares on
    # all seven passes the test, but the map hides that anchor from the fix: it is left
    # out and the six west anchors fix the tag. With five in sight the step leaves the
    # choice to the consensus search.
    from simulation.least_squares import scratch
    from simulation.polyhedral import blocking_map, facing, line_of_sight
    from simulation.robust import LOOSE, SHORT, _drop_hidden, row_map

    tag = np.array([3.0, 5.0, 1.2])
    west = np.concatenate([WEST, [[3.0, 9.97, 2.9]]])
    anchors = np.concatenate([west, EAST[:1]])
    assert line_of_sight(RACK_ROOM, west, tag[None]).all()
    assert not line_of_sight(RACK_ROOM, EAST[:1], tag[None]).any()
    rho = np.linalg.norm(anchors - tag, axis=1) + np.array([0, 0, 0, 0, 0, 0, 0.03])
    box = (np.zeros(3), np.array(RACK_ROOM.size))
    first = locate(anchors, rho[None], region=box, bounded=True, full_output=True)
    thr = thresholds(1e-3, len(anchors))
    T = 2 * first.cost[0] / SIGMA**2
    assert T <= thr[4]  # the test alone does not see the bent range
    geo, M = row_map(blocking_map(RACK_ROOM), facing(RACK_ROOM, anchors[None])[0]), len(anchors)
    loose, short = max(LOOSE[0], LOOSE[1] * SIGMA), max(SHORT[0], SHORT[1] * SIGMA)

    def drop(r):
        x, kept, used = first.x[0].copy(), r.copy(), np.isfinite(r)
        out = _drop_hidden(anchors, r, kept, x, T, int(used.sum()), 0, *box, True,
                           np.empty((0, 2)), 30, 1e-10, 1e-12, 1e-10, SIGMA, thr, loose, short,
                           used, scratch(M), geo, np.empty(M), np.empty(3),
                           np.zeros(1, np.int64))  # fmt: skip
        return out, x, kept, used

    (clean, T6, n, _), x, kept, used = drop(rho)
    assert clean and n == 6 and used.tolist() == [True] * 6 + [False]
    assert np.isnan(kept[6]) and T6 <= thr[3] and np.linalg.norm(x - tag) < 1e-3
    five = rho.copy()
    five[0] = np.nan  # 5 west anchors and the hidden one: left to the consensus search
    (clean, T5, n, _), x, kept, used = drop(five)
    assert not clean and n == 6 and T5 == T and np.array_equal(x, first.x[0])
    assert used.tolist() == [False] + [True] * 6
    fix = MAPPED.locate(RACK_ROOM, anchors, rho[None], full_output=True)
    assert fix.used[0].tolist() == [True] * 6 + [False]
    assert np.linalg.norm(fix.x[0] - tag) < 1e-3 and fix.quality[0] == _quality(west, fix.x[0])


def test_a_room_that_is_not_a_room_is_refused_by_name():
    ranges = np.linalg.norm(WEST - np.array([3.0, 5.0, 1.2]), axis=1)[None]
    with pytest.raises(ValueError, match="room: expected a simulation.Room"):
        locate(WEST, ranges, method="robust", room="rack")


def test_a_position_grazing_an_edge_sees_the_anchor_beyond_it():
    from simulation.polyhedral import blocking_map, facing, sees, sees_near

    geo = blocking_map(RACK_ROOM)
    anchor = np.array([9.97, 0.5, 1.0])  # the segment from (3, y, 1) clears the rack's
    # south-west edge (4, 1) for y below 1.0838
    cases = ((1.0, True, True, True), (1.05, True, True, False), (1.10, False, True, False),
             (1.3, False, False, False))  # fmt: skip
    for y, seen, near, surely in cases:
        p = np.array([3.0, y, 1.0])
        assert sees(geo, p, anchor) == seen
        front = facing(RACK_ROOM, anchor[None, None])[0, 0]  # the faces the anchor faces
        assert sees_near(geo, p, anchor, front, 0.05, False) == near  # from one point 5 cm away
        assert sees_near(geo, p, anchor, front, 0.05, True) == surely  # from all of them
    empty = blocking_map(Room(size=(4.0, 4.0, 3.0)))
    assert empty[0].size == 0 and sees(empty, np.zeros(3), np.ones(3))


def test_a_rooms_map_is_built_once_and_each_room_gets_its_own():
    import dataclasses

    from simulation.polyhedral import _map, blocking_map

    geo = blocking_map(RACK_ROOM)
    assert blocking_map(RACK_ROOM) is geo  # the same room: the same arrays
    lower = dataclasses.replace(RACK_ROOM, obstacles=[
        {"min": [4.0, 1.0, 0.0], "max": [8.0, 2.0, 1.0], "name": "low rack"}])  # fmt: skip
    other = blocking_map(lower)
    assert other is not geo and float(other[3][:, 5].max()) == 1.0  # its own rack's top
    for a, b in zip(blocking_map(RACK_ROOM), _map(RACK_ROOM), strict=True):
        np.testing.assert_array_equal(a, b)  # mapped again after another room, the same


def test_a_range_longer_than_another_by_more_than_their_anchors_distance_is_tried_last():
    from simulation.robust import _order_key

    anchors = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    ranges = np.array([2.0, 1.5, 3.1, np.nan])  # 3.1 − 2.0 > |a2 − a0| = 1: an echo
    key = _order_key(anchors, ranges, 0.1)
    assert np.argsort(key).tolist() == [1, 0, 2, 3] and key[3] == np.inf
    ranges[2] = 2.9  # 2.9 − 1.5 < |a2 − a1| = √2: no proof; ranked by its range
    assert np.argsort(_order_key(anchors, ranges, 0.1)).tolist() == [1, 0, 2, 3]
    ranges[2] = 1.8
    assert np.argsort(_order_key(anchors, ranges, 0.1)).tolist() == [1, 2, 0, 3]


def test_ranges_proved_echoes_are_left_out_before_the_first_fit():
    """proved_echoes against the triangle inequality in numpy: range j goes where
    r_j − r_k − |a_j − a_k| exceeds PROVED (0.4 m or 12σ) for some heard k, and only
    where 5 or more heard ranges remain."""
    from simulation.robust import PROVED, proved_echoes

    rng = np.random.default_rng(7)
    x = _nodes(rng, 300)
    R = np.linalg.norm(x[:, None] - ANCHORS[None], axis=-1) + SIGMA * rng.standard_normal((300, 8))
    R += np.where(rng.random((300, 8)) < 0.25, rng.uniform(0.0, 4.0, (300, 8)), 0.0)
    R[rng.random((300, 8)) < 0.05] = np.nan
    for sigma in (SIGMA, 0.1):
        F = proved_echoes(ANCHORS[None], np.zeros(300, np.int64), R, sigma)
        D = np.linalg.norm(ANCHORS[:, None] - ANCHORS[None], axis=-1)
        bound = R[:, :, None] - R[:, None, :] - D[None]
        excess = np.max(np.where(np.isnan(bound), -np.inf, bound), axis=2)
        echo = excess > max(PROVED[0], PROVED[1] * sigma)
        keep = np.isfinite(R).sum(axis=1) - echo.sum(axis=1) >= 5
        want = np.where(echo & keep[:, None], np.nan, R)
        # a bound within rounding of the margin may fall either way (compiled norm)
        sure = np.all(np.abs(excess - max(PROVED[0], PROVED[1] * sigma)) > 1e-9, axis=1)
        assert sure.sum() > 290
        np.testing.assert_array_equal(F[sure], want[sure])
        assert 0 < np.sum(np.isnan(F) & np.isfinite(R)) < np.sum(np.isfinite(R))


def test_a_proved_echo_does_not_pull_the_first_fit():
    """A range 5 m too long, proved an echo by a nearer anchor's range, is left out of the
    least squares the robust search starts from: the start is the linear solution of the
    other seven (exact here), the echo's anchor is not used, the fix is the node's and
    verified; least squares on every range is metres off."""
    x = np.array([2.0, 1.5, 1.1])
    rho = np.linalg.norm(x - ANCHORS, axis=1)
    rho[2] += 5.0
    fix = locate(ANCHORS, rho[None], method="robust", region=REGION, bounded=True,
                 range_sigma=SIGMA, full_output=True)  # fmt: skip
    np.testing.assert_allclose(fix.start[0], x, atol=1e-9)
    assert not fix.used[0, 2] and fix.used[0].sum() == 7
    np.testing.assert_allclose(fix.x[0], x, atol=1e-9)
    assert fix.quality[0] == VERIFIED
    ls = locate(ANCHORS, rho[None], region=REGION, bounded=True)
    assert np.linalg.norm(ls[0] - x) > 0.3


def test_the_map_check_vouches_only_for_fixes_that_see_their_anchors():
    from simulation.map_check import map_check

    tag, fake = np.array([3.0, 6.0, 1.2]), np.array([1.0, 4.0, 1.2])
    anchors = np.concatenate([WEST, EAST])
    used = np.array([[True] * 5 + [False] * 6, [False] * 5 + [True] * 6])
    fix = {
        "x": np.stack([tag, fake]),
        "used": used,
        "cost": np.zeros(2),
        "quality": np.array([VERIFIED, VERIFIED], dtype=np.int8),
    }
    out = map_check(RACK_ROOM, anchors[None], np.zeros(2, int), fix)
    # the tag sees the west anchors it rests on; the fake point sees none of the east ones
    assert out["quality"].tolist() == [VERIFIED, UNVERIFIED]
    assert out["x"] is fix["x"] and fix["quality"].tolist() == [VERIFIED, VERIFIED]
    # inside the rack: not in the room, so not verified whatever it rests on
    inside = {**fix, "x": np.array([[4.25, 5.0, 1.0], tag])}
    inside["used"] = np.array([used[0], used[0]])
    out = map_check(RACK_ROOM, anchors[None], np.zeros(2, int), inside)
    assert out["quality"].tolist() == [UNVERIFIED, VERIFIED]


def test_the_map_check_keeps_the_rows_of_many_layouts_apart():
    tag = np.array([3.0, 6.0, 1.2])
    anchors = np.concatenate([WEST, EAST[:1]])
    ranges = np.linalg.norm(anchors - tag, axis=1)[None]
    one = MAPPED.locate(RACK_ROOM, anchors, ranges, full_output=True)
    many = MAPPED.locate(
        RACK_ROOM, np.stack([anchors, anchors]), np.stack([ranges, ranges]), full_output=True
    )
    np.testing.assert_allclose(many.x[1], one.x, atol=1e-9)
    assert many.quality.shape == (2, 1) and MAPPED.locate(RACK_ROOM, anchors, ranges).shape == (
        1,
        3,
    )


def test_the_direct_anchors_are_found_when_their_minimal_sets_come_late():
    # 13 anchors above the tag report echoes a little longer than their distance (no
    # triangle inequality proves them), 5 far ones on the walls see it: the far ranges
    # come last in the range order, their first minimal set after 2 000 others
    rng = np.random.default_rng(0)
    tag = np.array([5.0, 5.0, 1.0])
    far = np.array([[0.03, 0.5, 2.5], [9.97, 1.0, 0.4], [0.5, 9.97, 1.8], [9.5, 9.97, 2.7],
                    [0.03, 8.0, 0.6]])  # fmt: skip
    box = (np.zeros(3), np.array([10.0, 10.0, 3.0]))
    found = 0
    for _ in range(10):
        near = np.column_stack([rng.uniform(3, 7, (13, 2)), np.full(13, 2.9)])
        a = np.concatenate([near, far])
        d = np.linalg.norm(a - tag, axis=1)
        r = d + np.concatenate([rng.uniform(0.3, 1.5, 13), np.zeros(5)])
        r += rng.normal(0, 0.005, 18)
        fix = locate(a, r[None], method="robust", region=box, bounded=True, full_output=True)
        right = np.linalg.norm(fix.x[0] - tag) < 0.05
        found += right and fix.used[0, 13:].all()
        # the first far anchor alone fixes a direction (leverage 0.96): an echo on it of
        # 0.3 m would pass the test and move the fix 0.7 m, so the fix is not vouched for
        if right:
            assert fix.quality[0] == _quality(a[fix.used[0]], fix.x[0])
        assert right or fix.quality[0] != VERIFIED  # never a wrong fix called verified
    assert found >= 9


def test_the_missed_echo_scale_is_the_non_centrality_the_test_misses():
    from scipy.stats import norm

    from simulation.robust import MISSED_DETECTION

    s, q = bias_scales(1e-3, 6), thresholds(1e-3, 6)
    # one degree of freedom in closed form: T = (z + √λ)², z standard normal
    missed = norm.cdf(np.sqrt(q[1]) - s[1]) - norm.cdf(-np.sqrt(q[1]) - s[1])
    assert missed == pytest.approx(MISSED_DETECTION, rel=1e-6)
    # three, by sampling: a bias of √λ along one axis of three standard normals
    z = np.random.default_rng(0).standard_normal((2_000_000, 3))
    z[:, 0] += s[3]
    assert np.mean(np.sum(z**2, axis=1) <= q[3]) == pytest.approx(MISSED_DETECTION, rel=0.1)
    assert np.all(np.diff(s[1:]) > 0)  # more redundancy, a larger echo goes unseen


def test_the_protection_level_is_the_move_of_the_largest_echo_the_test_misses():
    # each anchor in turn gets the echo that raises T to λ (what the test misses with
    # probability MISSED_DETECTION): least squares moves the fix by b_j ‖k_j‖, and the
    # largest such move is the protection level; a fix is verified within the alert
    # limit only
    a, x = ANCHORS[:6], np.array([3.0, 1.5, 1.0])
    d = np.linalg.norm(x - a, axis=1)
    U = (x - a) / d[:, None]
    K = np.linalg.solve(U.T @ U, U.T)
    h = np.sum(U * K.T, axis=1)
    root_lam = bias_scales(1e-3, 6)[3]
    moves = []
    for j in range(6):
        b = SIGMA * root_lam / np.sqrt(1 - h[j])
        rho = d.copy()
        rho[j] += b
        fix = locate(a, rho[None], region=REGION, bounded=True, full_output=True)
        assert 2 * fix.cost[0] / SIGMA**2 == pytest.approx(root_lam**2, rel=0.05)
        moves.append(np.linalg.norm(fix.x[0] - x))
        assert moves[-1] == pytest.approx(b * np.linalg.norm(K[:, j]), rel=0.05)
    level = _protection_level(a, x)
    assert max(moves) == pytest.approx(level, rel=0.05)
    for limit, quality in ((1.01 * level, VERIFIED), (0.99 * level, UNVERIFIED)):
        fix = locate(a, d[None], method="robust", region=REGION, bounded=True, range_sigma=SIGMA,
                     alert_limit=limit, full_output=True)  # fmt: skip
        assert fix.quality[0] == quality and np.linalg.norm(fix.x[0] - x) < 1e-6


def test_a_receiver_of_decimetres_cannot_vouch_for_a_fix_to_half_a_metre():
    # the same anchors and tag, ranges good to a decimetre (a peak-pick receiver): the
    # echo the test misses could move the fix by metres
    a, x = ANCHORS, np.array([3.0, 1.5, 1.0])
    rho = np.linalg.norm(x - a, axis=1)[None]
    fine, coarse = (
        locate(a, rho, method="robust", region=REGION, bounded=True, range_sigma=s,
               full_output=True)
        for s in (0.01, 0.1)
    )  # fmt: skip
    assert fine.quality[0] == VERIFIED and coarse.quality[0] == UNVERIFIED
    assert _protection_level(a, x, sigma=0.1) > 0.5 >= _protection_level(a, x)


def test_a_direct_range_left_out_is_added_back_and_an_echo_within_reach_is_not():
    # step 5 from a fix on 4 direct anchors: the fifth direct range (2 cm of mounting
    # error) joins it; an echo 15 cm long, within the loose inlier distance, fails the test;
    # an echo of a metre is not tried
    from simulation.least_squares import scratch
    from simulation.polyhedral import NO_MAP
    from simulation.robust import LOOSE, SHORT, _grow, row_map

    tag = np.array([3.0, 1.5, 1.0])
    a = ANCHORS[:7]
    rho = np.linalg.norm(a - tag, axis=1) + np.array([0, 0, 0, 0, 0.02, 0.15, 1.0])
    four = rho.copy()
    four[4:] = np.nan
    x = locate(a, four[None], region=REGION, bounded=True)[0].copy()
    used = np.isfinite(four)
    thr = thresholds(1e-3, len(a))
    loose, short = max(LOOSE[0], LOOSE[1] * SIGMA), max(SHORT[0], SHORT[1] * SIGMA)
    T, n, _ = _grow(a, rho, x, 0.0, 4, 0, *REGION, True, np.empty((0, 2)), 30, 1e-10, 1e-12,
                    1e-10, SIGMA, thr, loose, short, used, scratch(len(a)),
                    row_map(NO_MAP, np.zeros((len(a), 0), bool)),
                    np.empty(len(a)), np.empty(3), np.empty(len(a)),
                    np.zeros(1, np.int64))  # fmt: skip
    assert n == 5 and used.tolist() == [True] * 5 + [False] * 2
    assert T <= thr[2] and np.linalg.norm(x - tag) < 0.05
    # the echo was within reach of the fix, so tried: with it the test fails
    assert abs(np.linalg.norm(x - a[5]) - rho[5]) <= loose
    r = np.where(np.arange(len(a)) < 6, rho, np.nan)
    T_echo = 2 * locate(a, r[None], region=REGION, bounded=True, full_output=True).cost[0]
    assert T_echo / SIGMA**2 > thr[3]


def test_the_mirror_images_of_coplanar_anchors_fit_their_ranges():
    """Ranges from anchors in one plane (a ceiling, a tilted plane) fix a position only up
    to its mirror image in that plane: both images fit every range (closed form), one is
    the node; ranges too short to reach off the plane put the images the least distance
    asked for off it, on either side; collinear anchors or fewer than 3 fix no plane."""
    from simulation.least_squares import linear_fix, mirror_fixes

    rng = np.random.default_rng(21)
    tilt = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
    for normal in (np.array([0.0, 0.0, 1.0]), tilt):
        e1 = np.cross(normal, [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(normal, e1)
        for k in (3, 4, 6):
            a = np.array([4.0, 3.0, 4.0]) + rng.uniform(-3, 3, (k, 1)) * e1 + rng.uniform(
                -3, 3, (k, 1)) * e2  # fmt: skip
            x = rng.uniform([1, 1, 0.5], [7, 5, 2.0])
            rho = np.linalg.norm(a - x, axis=1)
            p, q = np.empty(3), np.empty(3)
            assert not linear_fix(a, rho, p, 1e-12)  # no linear solution off the plane
            assert mirror_fixes(a, rho, p, q, 0.1)
            for y in (p, q):
                assert np.allclose(np.linalg.norm(a - y, axis=1), rho, atol=1e-6)
            assert min(np.linalg.norm(p - x), np.linalg.norm(q - x)) < 1e-6
            assert np.isclose(p @ normal + q @ normal, 2 * a[0] @ normal)  # mirrored
            foot = x - ((x - a[0]) @ normal) * normal  # a point of the plane
            assert mirror_fixes(a, np.linalg.norm(a - foot, axis=1), p, q, 0.1)  # h = 0
            assert np.isclose(abs((p - q) @ normal), 0.2)
            assert np.isclose(p @ normal + q @ normal, 2 * a[0] @ normal)
    line = np.outer(np.linspace(0, 6, 4), [1.0, 0.5, 0.0]) + [0, 0, 3.0]
    for a in (line, line[:2]):
        rho = np.linalg.norm(a - [2, 2, 1], axis=1)
        assert not mirror_fixes(a, rho, np.empty(3), np.empty(3), 0.1)


# the 20 anchors the warehouse sweep planned at M = 20 before the examples were planned again
# (docs/benchmarks/robust/warehouse-geometry/sweep-M20-layout.json), 12 on its ceiling
WAREHOUSE_20 = np.array(
    [[9.04, 0.03, 3.73], [0.03, 3.34, 4.35], [0.03, 9.31, 1.26], [15.97, 1.36, 4.97],
     [15.97, 9.31, 3.73], [2.11, 6.66, 4.97], [2.8, 4.01, 4.97], [3.5, 6.66, 4.97],
     [6.27, 1.36, 4.97], [7.65, 1.36, 4.97], [10.43, 5.99, 4.97], [12.5, 2.02, 4.97],
     [13.2, 0.03, 4.62], [3.5, 9.97, 3.47], [10.08, 9.97, 2.77], [15.97, 4.01, 4.0],
     [1.76, 4.01, 4.97], [3.5, 8.96, 4.97], [5.23, 5.99, 4.97], [11.47, 6.66, 4.97]]
)  # fmt: skip
# three tags of its field check (tag, simulated ranges with the anchors mounted within
# 3 cm): each sees 5 or 6 anchors, all or all but one on the ceiling; the rest are echoes
WAREHOUSE_TAGS = [
    ([7.592, 7.38, 1.33], [11.191, 10.304, 9.447, 12.611, 9.235, 6.609, 7.7, 5.523, 9.454,
                           9.381, 4.838, 10.055, 12.125, 6.942, 6.921, 10.719, 8.366, 5.733,
                           4.568, 5.375]),
    ([6.394, 2.579, 0.8], [7.493, 7.336, np.nan, 10.897, 14.46, 8.964, 5.694, 8.396, 5.175,
                           5.339, 8.366, 7.416, 8.984, 11.888, np.nan, 10.195, 6.413, 10.985,
                           7.413, 9.371]),
    ([10.785, 7.736, 1.624], [11.056, 12.583, 13.033, 10.919, 6.561, 9.374, 9.734, 8.065,
                              10.593, 10.113, 3.796, 9.148, 11.006, 8.571, 9.807, 7.732,
                              10.605, 8.118, 6.738, 3.581]),
]  # fmt: skip


def test_direct_ranges_from_ceiling_anchors_are_found_below_the_ceiling():
    """Tags under the warehouse's racks that see only the ceiling anchors near them (and
    one on a wall): the minimal sets of those anchors are coplanar (no linear solution) or
    nearly so (a badly conditioned one), and are solved from their mirror images in the
    ceiling: the image below it is the tag, and the anchors that see it are kept. Solved
    from the first fit instead, which the echoes pull up to the ceiling, these fixes were
    2–4 m off."""
    room = Room.from_toml(Path(__file__).resolve().parents[1] / "examples/warehouse-aisles.toml")
    tags = np.array([t for t, _ in WAREHOUSE_TAGS])
    ranges = np.array([r for _, r in WAREHOUSE_TAGS])
    fix = Positioning(method="robust", keep_in_room=True).locate(
        room, WAREHOUSE_20, ranges, full_output=True
    )
    direct = np.abs(ranges - np.linalg.norm(WAREHOUSE_20 - tags[:, None], axis=-1)) < 0.05
    # within the anchors' mounting error (3 cm) of the tag
    assert np.all(np.linalg.norm(fix.x - tags, axis=1) < 0.1)
    assert np.array_equal(fix.used, direct)


# two aisle nodes of the warehouse that see 4 anchors in line of sight (one realization
# each of the sweep's M = 20 layout): the direct set of the first includes the anchor
# 12.4 m away at the far wall, which comes late in the order of the ranges
WAREHOUSE_FOUR = [
    ([4.0, 1.0, 1.8], [5.49, 6.419, 13.03, 12.395, 16.416, 8.507, 6.046, 8.309, 3.909, 4.851,
                       10.017, 9.57, 9.727, 11.957, 13.673, 13.167, 6.346, 10.862, 7.767,
                       11.14]),
    ([11.0, 2.5, 0.5], [7.553, 11.663, 16.634, 7.388, 12.102, 12.039, 9.458, 11.05, 7.235,
                        6.404, 7.569, 4.746, 6.465, 13.933, 12.155, 6.269, 10.452, 19.375,
                        9.508, 8.12]),
]  # fmt: skip
# the L-shaped lab's recommended layout and a tag of its field check that sees 4 anchors:
# the other four ranges are echoes, and a set with two of them agrees at the floor
L_LAB_8 = np.array(
    [[5.042, 0.03, 2.235], [6.97, 1.132, 0.398], [5.37, 2.97, 1.5], [0.03, 2.406, 0.398],
     [0.03, 4.386, 1.132], [0.03, 4.386, 2.97], [1.187, 3.594, 2.97], [6.584, 0.822, 2.97]]
)  # fmt: skip
L_LAB_TAG = ([2.95, 1.012, 1.335], [2.467, 4.127, 3.114, 4.595, 6.158, 6.342, 5.2, 4.018])


@pytest.mark.parametrize("room_file", ["warehouse-aisles", "l-shaped-lab"])
def test_tags_that_see_four_anchors_get_the_direct_set(room_file):
    """Where a tag sees exactly 4 anchors, the fix is a minimal set that nothing
    contradicts, and a wrong one can agree as well as the direct one (T has one degree of
    freedom): a set whose fix the map says another anchor sees with a long range, or whose
    fix the room's boundary holds (a mirror image's mark), ranks below one that passes the
    test cleanly, and the search goes on past such a set. Before, these fixes were
    0.29 m, 3.8 m and 1.8 m off (the last held on the floor)."""
    room = Room.from_toml(Path(__file__).resolve().parents[1] / f"examples/{room_file}.toml")
    if room_file == "warehouse-aisles":
        anchors, cases = WAREHOUSE_20, WAREHOUSE_FOUR
    else:
        anchors, cases = L_LAB_8, [L_LAB_TAG]
    tags = np.array([t for t, _ in cases])
    ranges = np.array([r for _, r in cases])
    fix = Positioning(method="robust", keep_in_room=True).locate(
        room, anchors, ranges, full_output=True
    )
    direct = np.abs(ranges - np.linalg.norm(anchors - tags[:, None], axis=-1)) < 0.05
    assert np.all(direct.sum(axis=1) == 4)
    assert np.all(np.linalg.norm(fix.x - tags, axis=1) < 0.05)
    assert np.array_equal(fix.used, direct)


def test_a_tag_that_sees_only_the_anchors_on_one_wall_is_fixed_off_the_wall():
    """A tag 0.74 m from a wall of the L-shaped lab that sees only the 4 anchors on that
    wall (a field check's tag, anchors mounted within 3 cm; the fifth range heard is an
    echo): the set's mirror images lie 0.74 m either side of the wall, and the one behind
    it, moved into the room, lies on the wall and fits the ranges no more. Before, that
    image was taken (it had one inlier more, the echo) and the fix stayed on the wall."""
    room = Room.from_toml(Path(__file__).resolve().parents[1] / "examples/l-shaped-lab.toml")
    anchors = np.array(
        [[6.97, 0.765, 1.132], [4.97, 2.97, 1.132], [0.03, 0.822, 0.398], [0.03, 2.406, 2.602],
         [0.03, 4.386, 0.765], [0.03, 4.386, 2.235], [5.428, 2.406, 2.97], [5.813, 0.426, 2.97]]
    )  # fmt: skip
    tag = np.array([0.738, 5.594, 1.204])
    ranges = np.array([np.nan, np.nan, 4.901, 3.554, 1.468, 1.757, np.nan, 8.056])
    fix = Positioning(method="robust", keep_in_room=True).locate(
        room, anchors, ranges, full_output=True
    )
    assert np.linalg.norm(fix.x - tag) < 0.05
    assert np.array_equal(np.flatnonzero(fix.used), [2, 3, 4, 5])


def test_a_tag_that_sees_three_anchors_is_fixed_on_them_where_the_map_rules_out_the_rest():
    """Step 4's last resort: the tag sees 3 of 9 anchors, the rack hides the other 6, whose
    echoes are long; every set of 4 rests on an echo and is contradicted. The 3 direct
    ranges fix two mirror images, and the map tells them apart (one is hidden from its
    anchors, or seen by anchors with echo ranges). Without the map the fix rests on echoes."""
    from simulation.polyhedral import line_of_sight

    tag = np.array([3.0, 5.0, 1.2])
    anchors = np.concatenate([WEST[[0, 1, 4]], EAST])
    assert line_of_sight(RACK_ROOM, anchors, tag[None])[0].tolist() == [True] * 3 + [False] * 6
    excess = np.array([0, 0, 0, 0.9, 1.7, 1.2, 2.3, 0.8, 1.5])  # echoes only lengthen
    ranges = (np.linalg.norm(anchors - tag, axis=1) + excess)[None]
    fix = MAPPED.locate(RACK_ROOM, anchors, ranges, full_output=True)
    assert np.linalg.norm(fix.x[0] - tag) < 1e-6
    assert fix.used[0].tolist() == [True] * 3 + [False] * 6
    assert fix.quality[0] == UNVERIFIED and fix.converged[0]
    box = (np.zeros(3), np.array(RACK_ROOM.size))
    blind = locate(anchors, ranges, method="robust", range_sigma=0.01, region=box, bounded=True,
                   full_output=True)  # fmt: skip
    assert np.linalg.norm(blind.x[0] - tag) > 0.5


#: the committed L-lab plan (recommended system) and two field-check tags of its draws
#: (anchors mounted within 3 cm of these): one behind the columns that sees 3 anchors, one
#: that sees only the 4 on the west wall
L_LAB_PLAN = np.array(
    [[6.97, 0.765, 1.1325], [4.97, 2.97, 1.1325], [0.03, 0.822, 0.3975],
     [0.03, 2.406, 2.6025], [0.03, 4.386, 0.765], [0.03, 4.386, 2.235],
     [5.4278, 2.406, 2.97], [5.8133, 0.426, 2.97]]
)  # fmt: skip
L_LAB_FIELD = (
    ([2.535, 1.243, 1.553], [4.4837, 4.8902, 2.8023, 4.5661, 6.2206, 6.1991, 5.807, 3.6493]),
    ([1.144, 4.646, 0.941], [7.9325, 9.6944, 4.0217, 2.9921, 1.1621, 1.7369, 9.7177, 7.1589]),
)


def test_field_tags_that_see_three_or_four_anchors_in_the_l_lab_are_fixed_at_centimetres():
    """The first tag sees anchors 0, 2 and 7 (the columns hide the rest): it was fixed on an
    echo set 1.7 m off, at the room's south wall. The second sees the 4 west-wall anchors
    and stands 1.1 m off the wall; a wrong set with two echoes fixed it 1.5 m off, on the
    wall, because no anchor counted as surely seeing a fix within 5 cm of a wall (the
    points beyond the wall, hidden from everything, were counted): the map's misses of
    that set went unseen."""
    room = Room.from_toml(Path(__file__).resolve().parents[1] / "examples/l-shaped-lab.toml")
    tags = np.array([t for t, _ in L_LAB_FIELD])
    ranges = np.array([r for _, r in L_LAB_FIELD])
    fix = Positioning(method="robust", keep_in_room=True).locate(
        room, L_LAB_PLAN, ranges, full_output=True
    )
    assert np.all(np.linalg.norm(fix.x - tags, axis=1) < 0.05)
    assert [np.flatnonzero(u).tolist() for u in fix.used] == [[0, 2, 7], [2, 3, 4, 5]]
    assert np.all(fix.quality == UNVERIFIED)


def test_a_position_beside_a_wall_is_surely_seen_by_the_anchors_that_see_it():
    # points 5 cm from a fix 4.6 cm from the L-lab's west wall lie beyond the wall; they are
    # no place for a tag and do not decide whether an anchor surely sees it
    from simulation.polyhedral import blocking_map, facing, line_of_sight, sees_near

    room = Room.from_toml(Path(__file__).resolve().parents[1] / "examples/l-shaped-lab.toml")
    p = np.array([0.046, 4.544, 1.918])
    geo, front = blocking_map(room), facing(room, L_LAB_PLAN[None])[0]
    seen = line_of_sight(room, L_LAB_PLAN, p[None])[0]
    surely = [sees_near(geo, p, a, f, 0.05, True) for a, f in zip(L_LAB_PLAN, front, strict=True)]
    assert surely == seen.tolist() and sum(surely) == 6
    inside = np.array([0.5, 4.544, 1.918])  # away from the wall: all seven points tested
    assert sees_near(geo, inside, L_LAB_PLAN[3], front[3], 0.05, True)


#: 4 anchors close to the plane y = 0.15 (a wall's), the south wall at y = 0, and a tag
#: 0.45 m in front of them: its mirror image across their plane lies beyond the wall
NEAR_WALL = np.array([[1.0, 0.12, 2.8], [5.0, 0.22, 2.9], [2.0, 0.15, 0.5], [4.5, 0.1, 1.2]])
NEAR_WALL_TAG = np.array([3.0, 0.6, 1.5])
NEAR_WALL_BOX = (np.zeros(3), np.array([6.0, 4.0, 3.0]))


@pytest.mark.parametrize("start", [[3.0, -0.3, 1.5], [3.0, 0.01, 1.5], [3.0, 0.3, 1.5]])
def test_a_fix_on_four_anchors_held_at_the_wall_is_moved_to_its_interior_image(start):
    """A tag near the plane of its 4 anchors: its ranges fit it and its mirror image
    across that plane, which lies beyond the south wall. Least squares kept in the room
    and started on the wrong side runs into the wall and stops there, 0.6 m off; the
    robust fix, on the same 4 ranges from the same start, is moved to the interior image:
    the tag (unverified: 4 anchors)."""
    ranges = np.linalg.norm(NEAR_WALL - NEAR_WALL_TAG, axis=1)
    kw = {"region": NEAR_WALL_BOX, "bounded": True, "x0": np.array(start), "full_output": True}
    ls = locate(NEAR_WALL, ranges, **kw)
    fix = locate(NEAR_WALL, ranges, method="robust", **kw)
    if start[1] < 0.15:  # behind the anchors' plane: least squares stops on the wall
        assert ls.x[1] == pytest.approx(0.0, abs=1e-9)
        assert np.linalg.norm(ls.x - NEAR_WALL_TAG) > 0.5
    assert np.linalg.norm(fix.x - NEAR_WALL_TAG) < 1e-6
    assert fix.quality == UNVERIFIED and fix.used.all()


def test_a_fix_held_at_the_wall_stays_where_no_interior_image_fits_its_ranges():
    """The same 4 anchors with the ranges of the tag's mirror image in the wall (0.6 m
    beyond it): the best point in the room fits them to 2.8 cm RMS (0.88 m from the wall;
    the anchors are not quite coplanar), more than the 2 cm a fix moved off the wall may
    miss, so the fix stays on the wall where least squares puts it."""
    beyond = NEAR_WALL_TAG * [1, -1, 1]
    ranges = np.linalg.norm(NEAR_WALL - beyond, axis=1)
    kw = {"region": NEAR_WALL_BOX, "bounded": True, "x0": np.array([3.0, -0.3, 1.5]),
          "full_output": True}  # fmt: skip
    ls = locate(NEAR_WALL, ranges, **kw)
    fix = locate(NEAR_WALL, ranges, method="robust", **kw)
    assert ls.x[1] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(fix.x, ls.x, atol=1e-9)


#: the committed L-lab plan of the recommended system (anchors 2–5 near the south wall,
#: nearly in one plane) and three field-check tags of its draws (seed 9) by that wall that
#: see only anchors 2–5, with their ranges (anchors mounted within 3 cm)
SOUTH_WALL_PLAN = np.array(
    [[0.03, 3.594, 0.3975], [1.1867, 3.198, 2.97], [1.0011, 0.03, 0.765], [6.3844, 0.822, 2.97],
     [5.1422, 0.03, 0.4975], [5.1422, 0.526, 2.97], [6.97, 2.235, 0.8325], [0.03, 4.386, 2.135]]
)  # fmt: skip
SOUTH_WALL_FIELD = (
    ([3.438, 0.48, 0.866], [5.3343, 5.7604, 2.489, 3.6618, 1.7906, 2.7038, 4.4622, 6.0792]),
    ([3.159, 0.458, 1.555], [5.2537, 4.3906, 2.3511, 3.5687, 2.2759, 2.4299, 4.7272, 5.7962]),
    ([3.09, 0.589, 1.599], [5.3253, 4.4569, 2.326, 3.6045, 2.3762, 2.4621, 4.8651, 5.8607]),
)


def test_field_tags_by_the_l_labs_south_wall_are_fixed_off_the_wall():
    """Each tag is about half a metre from the south wall and sees anchors 2–5 only. Their
    4 ranges fit the tag and a point beyond the wall; least squares from the first fit
    stopped on the wall, 0.47–0.60 m off, and the fix on those 4 anchors is now moved to
    the interior image."""
    from simulation import System

    room = Room.from_toml(Path(__file__).resolve().parents[1] / "examples/l-shaped-lab.toml")
    tags = np.array([t for t, _ in SOUTH_WALL_FIELD])
    ranges = np.array([r for _, r in SOUTH_WALL_FIELD])
    fix = System.recommended().positioning.locate(room, SOUTH_WALL_PLAN, ranges,
                                                  full_output=True)  # fmt: skip
    assert np.all(np.linalg.norm(fix.x - tags, axis=1) < 0.03)
    assert np.all(fix.x[:, 1] > 0.3)
    assert [np.flatnonzero(u).tolist() for u in fix.used] == [[2, 3, 4, 5]] * 3
    assert np.all(fix.quality == UNVERIFIED)

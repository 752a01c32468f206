import numpy as np
import pytest
import scipy.optimize

from placement import random_layout
from simulation import Room, locate
from simulation.positioning import linear_start

ROOM = Room.techtile()
REGION = (np.zeros(3), np.array(ROOM.size))


def _ranges(anchors, nodes):
    return np.linalg.norm(nodes[:, None, :] - anchors[None], axis=-1)


@pytest.mark.parametrize("M", [4, 6, 8])
def test_exact_ranges_recover_positions(M):
    rng = np.random.default_rng(M)
    nodes = ROOM.grid()
    for anchors in (ROOM.corners_layout() if M == 4 else random_layout(ROOM, M, rng),):
        fix = locate(anchors, _ranges(anchors, nodes), region=REGION, full_output=True)
        assert fix.success
        assert np.max(np.linalg.norm(fix.x - nodes, axis=-1)) < 1e-6


def test_exact_ranges_from_the_room_centre_and_coplanar_anchors():
    nodes = ROOM.grid()
    nodes = nodes[nodes[:, 2] < 2.0]
    # all anchors on the ceiling: the linear start is undefined and every node has a
    # mirror image above the anchors' plane; from the room centre LM finds the one below
    # (nodes just under the plane, 2 cm here, can flip: the problem is near-degenerate)
    anchors = np.array([[1, 1, 2.37], [7, 1, 2.37], [7, 3, 2.37], [1, 3, 2.37], [4, 2, 2.37]])
    assert linear_start(anchors, _ranges(anchors, nodes)) is None
    fix = locate(anchors, _ranges(anchors, nodes), region=REGION, full_output=True)
    assert fix.success
    assert np.allclose(fix.start, ROOM.centroid)
    assert np.max(np.linalg.norm(fix.x - nodes, axis=-1)) < 1e-6


def test_linear_start_is_exact_for_exact_ranges():
    a = ROOM.corners_layout()
    nodes = ROOM.grid()
    assert np.allclose(linear_start(a, _ranges(a, nodes)), nodes, atol=1e-9)


def test_batched_shapes_and_matches_scipy_on_outliers():
    rng = np.random.default_rng(0)
    a = ROOM.corners_layout()
    nodes = ROOM.grid()[::10]
    r = np.broadcast_to(_ranges(a, nodes), (3, *_ranges(a, nodes).shape)).copy()
    # reverberant-like errors: centimetre noise plus metre outliers
    r += rng.normal(0, 0.03, r.shape)
    out = rng.random(r.shape) < 0.2
    r[out] += rng.uniform(0.5, 4.0, out.sum())
    fix = locate(a, r, region=REGION, full_output=True)
    assert fix.x.shape == (3, len(nodes), 3) and fix.converged.shape == (3, len(nodes))
    assert fix.converged.mean() > 0.95
    # same local minimum as scipy's MINPACK LM from the same start
    for i in np.ndindex(*fix.converged.shape):
        if not fix.converged[i]:
            continue
        res = scipy.optimize.least_squares(
            lambda x, i=i: np.linalg.norm(x - a, axis=1) - r[i], fix.start[i], method="lm"
        )
        assert fix.cost[i] <= res.cost * (1 + 1e-6) + 1e-12
    # plain call returns only the positions
    x = locate(a, r, region=REGION)
    assert np.array_equal(x, fix.x)


def test_nonconvergence_is_flagged_with_best_iterate():
    a = ROOM.corners_layout()
    nodes = ROOM.grid()[::7]
    r = _ranges(a, nodes) + 1.5 * (np.arange(4) % 2)  # inconsistent ranges
    fix = locate(a, r, region=REGION, max_iter=1, full_output=True)
    assert not fix.success
    assert np.all(fix.status[~fix.converged] == 0)
    start_cost = 0.5 * np.sum((_ranges(a, fix.start) - r) ** 2, axis=-1)
    assert np.all(fix.cost <= start_cost + 1e-12)
    assert np.all(np.isfinite(fix.x))


def test_bounded_keeps_estimates_in_the_box():
    a = ROOM.corners_layout()
    nodes = ROOM.grid()
    r = _ranges(a, nodes) + 2.0  # every range too long: unbounded LS leaves the room
    free = locate(a, r, region=REGION)
    box = locate(a, r, region=REGION, bounded=True)
    assert not np.all(ROOM.contains(free))
    assert np.all(ROOM.contains(box))


def test_bounded_converges_to_the_box_constrained_optimum():
    """With the optimum on the box, the bounded fix converges (no iteration limit) to the
    minimum scipy's bounded trust-region solver finds from the same start."""
    rng = np.random.default_rng(5)
    a = ROOM.corners_layout()
    nodes = ROOM.grid()[::6]
    r = _ranges(a, nodes) + rng.normal(0, 0.8, (len(nodes), 4))  # outliers: fixes leave the box
    fix = locate(a, r, region=REGION, bounded=True, full_output=True)
    assert fix.success and np.all(fix.nit < 100)
    at_bound = np.any((fix.x <= REGION[0] + 1e-9) | (fix.x >= REGION[1] - 1e-9), axis=1)
    assert at_bound.mean() > 0.3
    for p, rho, x0, x in zip(nodes, r, fix.start, fix.x, strict=True):
        ref = scipy.optimize.least_squares(
            lambda q, rho=rho: np.linalg.norm(q - a, axis=1) - rho, x0, bounds=REGION,
            method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12,
        )  # fmt: skip
        cost = 0.5 * np.sum((np.linalg.norm(x - a, axis=1) - rho) ** 2)
        assert cost <= ref.cost + 1e-9 or np.linalg.norm(x - ref.x) < 1e-5, p


def test_bad_input():
    a = ROOM.corners_layout()
    with pytest.raises(ValueError, match="ranges"):
        locate(a, np.full((5, 3), 1.0))
    for bad in (np.inf, 1e300):
        with pytest.raises(ValueError, match="ranges"):
            locate(a, np.array([[1.0, bad, 2.0, 3.0]]))
    with pytest.raises(ValueError, match="anchors"):
        locate(a[:2], np.ones((1, 2)))
    with pytest.raises(ValueError, match="max_iter"):
        locate(a, np.ones((1, 4)), max_iter=0)


def test_several_layouts_at_once_match_one_by_one():
    rng = np.random.default_rng(4)
    room = Room.techtile()
    anchors = np.stack([room.corners_layout(), room.corners_layout()[::-1] * 0.9 + 0.1])
    nodes = room.grid()[::9]
    true = np.linalg.norm(nodes[:, None] - anchors[:, None], axis=-1)  # (2, P, M)
    ranges = true[:, None] + rng.normal(0, 0.3, (2, 3, *true.shape[1:]))  # (2, R, P, M)
    for kw in ({}, {"region": (np.zeros(3), np.array(room.size))}, {"bounded": True}):
        both = locate(anchors, ranges, **kw)
        assert both.shape == (2, 3, len(nodes), 3)
        for i in range(2):
            np.testing.assert_allclose(both[i], locate(anchors[i], ranges[i], **kw), atol=1e-6)
    with pytest.raises(ValueError, match="layouts"):
        locate(anchors, ranges[:1])
    # no layouts at all: empty positions of the matching shape, with or without a region
    for kw in ({}, {"region": (np.zeros(3), np.array(room.size))}):
        fix = locate(anchors[:0], ranges[:0], full_output=True, **kw)
        assert fix.x.shape == (0, 3, len(nodes), 3) and fix.status.shape == (0, 3, len(nodes))


def test_each_node_is_solved_as_if_alone():
    """A node's fix, iterations and status do not depend on the other rows of the batch
    (damping and state restart for every node), and a converged fix is a stationary point
    of F: its gradient Jᵀr vanishes."""
    rng = np.random.default_rng(7)
    a = random_layout(ROOM, 6, rng=rng)
    nodes = ROOM.grid()[::5]
    ranges = _ranges(a, nodes) + rng.normal(0, 0.05, (len(nodes), 6))
    ranges[::4, 0] += 2.0  # outliers make some nodes take many damped steps
    x0 = np.array(ROOM.size) / 2  # the same start (a batched linear start may round apart)
    fix = locate(a, ranges, region=REGION, x0=x0, full_output=True)
    for p in (0, 3, len(nodes) - 1):
        one = locate(a, ranges[p : p + 1], region=REGION, x0=x0, full_output=True)
        assert np.array_equal(one.x[0], fix.x[p])
        assert (one.nit[0], one.status[0]) == (fix.nit[p], fix.status[p])
    d = fix.x[:, None, :] - a[None]
    dist = np.linalg.norm(d, axis=-1)
    grad = np.sum(((dist - ranges) / dist)[..., None] * d, axis=1)
    ok = fix.converged
    assert ok.mean() > 0.9
    assert np.max(np.abs(grad[ok])) < 1e-5


def test_one_compiled_loop_for_every_caller():
    """The compiled loop has one signature whether the caller gives a region or not: a
    process compiles it (or loads it from numba's cache) once."""
    from simulation import positioning

    rng = np.random.default_rng(3)
    a = random_layout(ROOM, 5, rng=rng)
    ranges = _ranges(a, ROOM.grid()[:7])
    free = locate(a, ranges)
    boxed = locate(a, ranges, region=REGION, bounded=True)
    assert len(positioning.lm_rows.signatures) == 1
    assert np.all(np.isfinite(free)) and np.all(np.isfinite(boxed))


def test_missing_ranges_equal_locating_from_the_heard_anchors():
    """A NaN range is an anchor not heard: the node is solved from the others alone, as if
    only they had been given; fewer than 4 heard (or collinear ones) give no fix."""
    rng = np.random.default_rng(1)
    room = Room.techtile()
    a = rng.uniform(0, room.size, (8, 3))
    p = rng.uniform(0, room.size, (300, 3))
    r = np.linalg.norm(p[:, None] - a[None], axis=-1) + rng.normal(0, 0.05, (300, 8))
    missing = rng.random((300, 8)) < 0.35
    for region in ((np.zeros(3), np.array(room.size)), None):
        fix = locate(a, np.where(missing, np.nan, r), region=region, full_output=True)
        solved = 0
        for i in range(len(p)):
            heard = ~missing[i]
            if heard.sum() < 4:
                assert fix.status[i] == -2 and np.isnan(fix.x[i]).all() and not fix.converged[i]
                continue
            alone = locate(a[heard], r[i : i + 1, heard], region=region, full_output=True)
            np.testing.assert_allclose(fix.x[i], alone.x[0], atol=1e-7)
            assert fix.status[i] > 0 and alone.status[0] > 0
            solved += 1
        assert 100 < solved < 300  # both kinds of node were exercised


def test_missing_ranges_with_collinear_heard_anchors_give_no_fix():
    line = np.array([[1.0, 2.0, 2.37], [3.0, 2.0, 2.37], [5.0, 2.0, 2.37], [7.0, 2.0, 2.37]])
    a = np.vstack([line, [[4.0, 0.03, 1.0]]])
    p = np.array([[4.0, 1.0, 1.2]])
    r = np.linalg.norm(p[:, None] - a[None], axis=-1)
    r[0, 4] = np.nan  # the only anchor off the line is not heard
    fix = locate(a, r, full_output=True)
    assert fix.status[0] == -2 and np.isnan(fix.x).all()
    r[0, 4] = np.linalg.norm(p[0] - a[4])
    assert locate(a, r, full_output=True).status[0] > 0


#: the L-shaped lab's floor plan (examples/l-shaped-lab.toml), as test_polygon_rooms has it
L_CORNERS = [[0, 0], [7, 0], [7, 3], [3, 3], [3, 6], [0, 6]]


@pytest.mark.parametrize(
    "corners",
    [
        L_CORNERS,  # the L-shaped lab
        [[0, 0], [6, 1], [8, 5], [4, 3.5], [1, 6]],  # slanted edges, one reflex corner
    ],
)
def test_floor_plan_tests_agree_with_shapely(corners):
    """The compiled floor-plan helpers that keep positions in the room agree with shapely:
    a point inside or on the boundary is in the floor plan (corners and edges included),
    one outside is not; the nearest boundary point is at shapely's distance."""
    import shapely

    from simulation.least_squares import inside_floor_plan, into_floor_plan, nearest_on_boundary

    poly = np.array(corners, dtype=float)
    shape = shapely.Polygon(poly)
    rng = np.random.default_rng(7)
    pts = rng.uniform(-1, 9, size=(4000, 2))
    edges = np.roll(poly, -1, axis=0) - poly
    on = poly[rng.integers(len(poly), size=200)]
    t = rng.uniform(0, 1, size=(200, 1))
    on_edges = on + t * edges[[np.flatnonzero((poly == c).all(1))[0] for c in on]]
    inside = np.array([inside_floor_plan(x, y, poly) for x, y in pts])
    assert np.array_equal(inside, shapely.covers(shape, shapely.points(pts)))
    assert all(inside_floor_plan(x, y, poly) for x, y in np.vstack([poly, on_edges]))
    for x, y in pts[:300]:
        d2, bx, by = nearest_on_boundary(x, y, poly)
        assert np.sqrt(d2) == pytest.approx(shape.exterior.distance(shapely.Point(x, y)), abs=1e-12)
        p = np.array([x, y, 1.5])
        into_floor_plan(p, poly)
        assert p[2] == 1.5 and inside_floor_plan(p[0], p[1], poly)
        assert (p[0], p[1]) == ((x, y) if inside_floor_plan(x, y, poly) else (bx, by))


def test_without_reference_counts_where_numba_knows_the_option(monkeypatch):
    """The compiled helpers that create no array drop numba's reference counts where this
    numba knows the option, and keep them (the same results, slower) where it does not."""
    import numba.core.cpu

    from simulation import least_squares

    poly = np.array(L_CORNERS, dtype=float)
    knows = hasattr(numba.core.cpu.CPUTargetOptions, "_nrt")
    assert least_squares.NO_REFCOUNT == (
        {"cache": True, "_nrt": False} if knows else {"cache": True}
    )
    # where the option is honoured, the compiled code has no reference counting left
    # (compiled here without numba's cache: a test writes nothing beside the module)
    options = {k: v for k, v in least_squares.NO_REFCOUNT.items() if k != "cache"}
    helper = numba.njit(**options)(least_squares.inside_floor_plan.py_func)
    helper(1.0, 1.0, poly)
    code = "".join(helper.inspect_llvm().values())
    assert ("NRT_incref" in code) is not knows

    class Options:  # a numba without the option
        pass

    monkeypatch.setattr(numba.core.cpu, "CPUTargetOptions", Options)
    assert least_squares._without_refcounts() == {"cache": True}
    counted = numba.njit(least_squares.inside_floor_plan.py_func)
    counted(1.0, 1.0, poly)
    assert "NRT_incref" in "".join(counted.inspect_llvm().values())
    pts = np.random.default_rng(5).uniform(-1, 8, size=(500, 2))
    assert [counted(x, y, poly) for x, y in pts] == [
        least_squares.inside_floor_plan(x, y, poly) for x, y in pts
    ]

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import placement
from simulation import Room


def test_surfaces_of_techtile():
    room = Room.techtile()
    s = {m.name: m for m in placement.mounting_surfaces(room)}
    assert set(s) == {"south", "north", "ceiling"}
    assert s["south"].offset == pytest.approx(0.03) and s["south"].axis == 1
    assert s["north"].offset == pytest.approx(3.97)
    assert s["ceiling"].offset == pytest.approx(2.37) and s["ceiling"].axis == 2
    assert s["ceiling"].area == pytest.approx(7.94 * 3.94)
    assert s["south"].upper == pytest.approx((7.97, 2.37))


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_projection_lands_on_nearest_surface(seed):
    rng = np.random.default_rng(seed)
    room = Room.techtile()
    pts = rng.uniform(-1, 9, size=(40, 3))
    proj = placement.project(room, pts)
    assert placement.on_surfaces(room, proj).all()
    # no sample point of any surface is closer than the projection
    cand = placement.candidate_grid(room, 0.25)
    d_proj = np.linalg.norm(proj - pts, axis=1)
    d_cand = np.linalg.norm(cand[None] - pts[:, None], axis=-1).min(axis=1)
    assert np.all(d_proj <= d_cand + 1e-12)
    # idempotent
    np.testing.assert_allclose(placement.project(room, proj), proj)


def test_projection_jumps_surface():
    room = Room.techtile()
    # near the ceiling edge above the south wall: the ceiling is closer than the wall
    p = np.array([[4.0, 0.5, 2.3]])
    assert (
        placement.mounting_surfaces(room)[
            placement.surface_index(room, placement.project(room, p))[0]
        ].name
        == "ceiling"
    )


def test_uv_round_trip_and_candidates():
    room = Room.techtile()
    cand = placement.candidate_grid(room, 0.5)
    idx, uv = placement.to_uv(room, cand)
    np.testing.assert_allclose(placement.from_uv(room, idx, uv), cand)
    assert placement.on_surfaces(room, cand).all()
    with pytest.raises(ValueError):
        placement.to_uv(room, np.array([[4.0, 2.0, 1.2]]))


def test_random_layout_area_counts():
    room = Room.techtile()
    assert placement.area_counts(room, 4).tolist() == [1, 1, 2]
    assert placement.area_counts(room, 8).sum() == 8
    a = placement.random_layout(room, 4, np.random.default_rng(0))
    names = [placement.mounting_surfaces(room)[i].name for i in placement.surface_index(room, a)]
    assert sorted(names) == ["ceiling", "ceiling", "north", "south"]
    np.testing.assert_array_equal(a, placement.random_layout(room, 4, np.random.default_rng(0)))
    aims = placement.aim(room, a)
    np.testing.assert_allclose(np.linalg.norm(aims, axis=1), 1)
    np.testing.assert_allclose(
        aims, (room.centroid - a) / np.linalg.norm(room.centroid - a, axis=1)[:, None]
    )


def test_naive_layout_spreads_anchors_along_the_top_of_the_mounting_walls():
    room = Room.techtile()  # south, north walls and ceiling: the two long walls' top edges
    a = placement.naive_layout(room, 4)
    np.testing.assert_allclose(
        a, [[2.015, 0.03, 2.37], [5.985, 0.03, 2.37], [2.015, 3.97, 2.37], [5.985, 3.97, 2.37]]
    )
    for M in (5, 8, 13):
        a = placement.naive_layout(room, M)
        assert a.shape == (M, 3) and placement.allowed(room, a, tol=1e-6).all()
        assert np.allclose(a[:, 2], 2.37)  # all along the top edges
        assert len(np.unique(a.round(6), axis=0)) == M
    # no mounting wall: around the edge of the ceiling
    ceiling = Room(mounting=("ceiling",))
    b = placement.naive_layout(ceiling, 4)
    np.testing.assert_allclose(b, [[3.0, 0.03, 2.37], [7.97, 1.0, 2.37], [5.0, 3.97, 2.37],
                                   [0.03, 3.0, 2.37]])  # fmt: skip
    # keep-outs: anchors are moved to the nearest allowed point
    window = Room(keepouts=[((1.0, 0.0, 2.0), (3.0, 0.1, 2.4))])
    c = placement.naive_layout(window, 4)
    assert placement.allowed(window, c, tol=1e-6).all()
    moved = np.linalg.norm(c - placement.naive_layout(room, 4), axis=1)
    assert moved[0] == pytest.approx(0.07, abs=1e-5) and np.all(moved[1:] == 0)  # to the ceiling
    with pytest.raises(ValueError, match="M"):
        placement.naive_layout(room, 0)


@pytest.mark.parametrize(
    "mounting", [("south", "north", "ceiling"), ("west", "east", "south", "north", "ceiling")]
)
def test_candidate_grid_lists_each_shared_edge_point_once(mounting):
    # a wall and the ceiling (or two walls) meet along a line that both grids contain
    room = Room(size=(6.0, 5.0, 3.0), mounting=mounting)
    cand = placement.candidate_grid(room, 0.5)
    d = np.linalg.norm(cand[:, None] - cand[None], axis=-1)
    d[np.diag_indices(len(cand))] = np.inf
    assert d.min() > 1e-3
    # and nothing is lost: every surface's own grid is in the union
    for name in mounting:
        own = placement.candidate_grid(Room(size=room.size, mounting=(name,)), 0.5)
        gap = np.linalg.norm(own[:, None] - cand[None], axis=-1).min(axis=1)
        assert gap.max() < 1e-9

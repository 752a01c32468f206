"""Polygonal rooms and obstacles: the floor plan, its validation, line of sight, the
image sources against the shoebox's and against pyroomacoustics, and placement in them."""

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from peer import pra_general_windows

import analysis
import placement
from placement.plan import LOCAL_SWARM
from simulation import Room, simulate_ranges
from simulation.multipath import compute_paths
from simulation.polyhedral import blocking_map, facing, hidden_anchors, line_of_sight, sees_near
from simulation.received import received_windows
from simulation.receiver import dsp_for

L_CORNERS = [[0, 0], [7, 0], [7, 3], [3, 3], [3, 6], [0, 6]]
L_ROOM = Room.from_corners(L_CORNERS, 3.0, max_order=2)
BOX_ROOM = Room(
    size=(6.0, 4.0, 3.0),
    max_order=2,
    absorption={"west": 0.45, "east": 0.45},
    obstacles=[{"min": [2.5, 1.5, 0.0], "max": [3.5, 2.5, 2.0], "name": "cabinet"}],
)


def _points(room: Room, n: int, rng, margin: float = 0.1) -> np.ndarray:
    out = []
    while len(out) < n:
        p = rng.uniform(0, room.size, (4 * n, 3))
        out += list(p[room.contains(p, margin=margin)])
    return np.array(out[:n])


# -- the floor plan ------------------------------------------------------------------------
def test_corners_are_normalized_to_counter_clockwise_with_their_wall_names():
    names = ["a", "b", "c", "d", "e", "f"]
    ccw = Room.from_corners(L_CORNERS, 3.0, wall_names=names)
    cw = Room.from_corners(L_CORNERS[::-1], 3.0, wall_names=[names[(4 - i) % 6] for i in range(6)])
    assert ccw.corners == cw.corners or set(ccw.corners) == set(cw.corners)
    # the same wall (the same edge) keeps its name whichever way the corners were given
    for w in cw.walls:
        twin = next(v for v in ccw.walls if {tuple(v.start), tuple(v.end)} ==
                    {tuple(w.start), tuple(w.end)})  # fmt: skip
        assert twin.name == w.name
    assert ccw.size == (7.0, 6.0, 3.0) and not ccw.is_convex
    assert ccw.surface_names == (*names, "floor", "ceiling")
    assert ccw.mounting == (*names, "ceiling")
    # every wall's normal points into the room
    for w in ccw.walls:
        mid = (w.start + w.end) / 2 + 0.01 * w.normal[:2]
        assert ccw.contains(np.array([[*mid, 1.0]]))[0]


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: Room.from_corners([[0, 0], [1, 0]], 3.0), "corners"),
        (lambda: Room.from_corners([[0, 0], [4, 0], [4, 0], [0, 3]], 3.0), "repeat"),
        (lambda: Room.from_corners([[0, 0], [2, 0], [4, 0]], 3.0), "zero area"),
        # one wall drawn as two: named, not "insetting drops a wall"
        (
            lambda: Room.from_corners([[0, 0], [2, 0], [4, 0], [4, 3], [0, 3]], 3.0),
            r"corner 1 \[2.0, 0.0\] lies on the straight line",
        ),
        (lambda: Room.from_corners([[0, 0], [4, 4], [4, 0], [0, 4]], 3.0), "intersects"),
        (lambda: Room.from_corners([[-1, 0], [4, 0], [4, 3]], 3.0), "negative"),
        (lambda: Room.from_corners(L_CORNERS, 0.0), "height"),
        (lambda: Room.from_corners(L_CORNERS, 3.0, absorption={"roof": 0.2}), "roof"),
        (lambda: Room.from_corners(L_CORNERS, 3.0, mounting=["south"]), "south"),
        (lambda: Room.from_corners(L_CORNERS, 3.0, wall_names=["a", "b"]), "wall_names"),
        (lambda: Room.from_corners(L_CORNERS, 3.0, wall_names=["a"] * 6), "wall_names"),
        (
            lambda: Room.from_corners(
                L_CORNERS, 3.0, obstacles=[{"min": [4, 4, 0], "max": [5, 5, 1]}]
            ),
            "obstacles\\[0\\].*floor plan",
        ),  # outside the L
        (
            lambda: Room.from_corners(
                L_CORNERS, 3.0, obstacles=[{"min": [2, 2, 0], "max": [4, 4, 1]}]
            ),
            "obstacles\\[0\\].*cutting a wall",
        ),
        (
            lambda: Room.from_corners(
                L_CORNERS, 3.0, obstacles=[{"min": [1, 1, 0], "max": [1, 2, 1]}]
            ),
            "obstacles\\[0\\]",
        ),  # no volume
        (
            lambda: Room.from_corners(
                L_CORNERS, 3.0, obstacles=[{"min": [1, 1, 0], "max": [2, 2, 4]}]
            ),
            "obstacles\\[0\\]",
        ),  # through the ceiling
        (
            lambda: Room.from_corners(
                L_CORNERS, 3.0, obstacles=[{"min": [1, 1, 0], "max": [2, 2, 1], "colour": "red"}]
            ),
            "obstacles\\[0\\]",
        ),
        (
            lambda: Room.from_corners(L_CORNERS, 3.0, zones=[{"min": [4, 4, 1], "max": [6, 5, 2]}]),
            "zones\\[0\\]",
        ),  # outside the floor plan
        (
            lambda: Room(
                size=(4.0, 4.0, 3.0),
                zones=[{"min": [1, 1, 0.5], "max": [2, 2, 1.5]}],
                obstacles=[{"min": [0.8, 0.8, 0], "max": [2.2, 2.2, 2]}],
            ),
            "zones\\[0\\]",
        ),
        (
            lambda: Room(size=(4.0, 4.0, 3.0), obstacles=[{"min": [0, 0, 0], "max": [4, 4, 3]}]),
            "obstacles",
        ),  # no tag node left
        (
            lambda: Room(
                size=(4.0, 4.0, 3.0),
                mounting=["south"],
                obstacles=[{"min": [0, 0, 0], "max": [4, 0.5, 3]}],
            ),
            "surface 'south'",
        ),
        (lambda: Room.from_dict({"corners": L_CORNERS}), "height"),
        (lambda: Room.from_dict({"corners": L_CORNERS, "height": 3, "size": [7, 6, 3]}), "size"),
        (
            lambda: Room(
                size=(6.0, 5.0, 3.0),
                obstacles=[
                    {"min": [0.5, 0.5, 0], "max": [2.5, 1.1, 1.1], "name": "long"},
                    {"min": [0.5, 0.5, 0], "max": [1.1, 2.5, 1.1], "name": "return"},
                ],
            ),
            r"obstacles\[1\] \('return'\): overlaps obstacles\[0\] \('long'\) in x 0.5–1.1, "
            "y 0.5–1.1, z 0–1.1 m",
        ),  # an L-shaped counter as two overlapping boxes
    ],  # fmt: skip
)
def test_bad_floor_plans_and_obstacles_are_refused(make, name):
    with pytest.raises(ValueError, match=name):
        make()


def test_one_solid_made_of_touching_boxes_sounds_the_same_however_it_is_cut():
    # an L-shaped counter cut at x = 1.1 or at y = 1.1: the common face lies inside the
    # solid and reflects nothing, so the paths (lengths, energies, line of sight) agree
    base = Room(size=(6.0, 5.0, 3.0), max_order=3)

    def box(lo, hi):
        return {"min": lo, "max": hi}

    cuts = (
        [box([0.5, 0.5, 0], [2.5, 1.1, 1.1]), box([0.5, 1.1, 0], [1.1, 2.5, 1.1])],
        [box([0.5, 0.5, 0], [1.1, 2.5, 1.1]), box([1.1, 0.5, 0], [2.5, 1.1, 1.1])],
    )
    rng = np.random.default_rng(3)
    nodes = _points(dataclasses.replace(base, obstacles=cuts[0]), 150, rng)
    anchors = np.array([[0.8, 0.8, 2.9], [3.0, 3.0, 2.9], [0.03, 0.8, 2.0], [5.97, 4.0, 1.0]])
    out = []
    for cut in cuts:
        paths = compute_paths(dataclasses.replace(base, obstacles=cut), anchors, nodes)
        live = paths.amplitude > 0
        out.append((np.sort(np.where(live, paths.length, np.inf), -1),
                    np.sum(paths.amplitude**2, -1), paths.los, live.sum(-1)))  # fmt: skip
    np.testing.assert_array_equal(out[0][3], out[1][3])
    np.testing.assert_allclose(out[0][0], out[1][0], rtol=1e-12)
    np.testing.assert_allclose(out[0][1], out[1][1], rtol=1e-9)
    np.testing.assert_array_equal(out[0][2], out[1][2])
    assert not out[0][2].all()  # the counter hides some anchors from some nodes


def test_the_images_of_an_anchor_are_the_mirrors_on_the_air_side_and_many_obstacles_warn(
    caplog,
):
    from placement.plan import MANY_IMAGES, image_check
    from simulation.polyhedral import image_count

    # order 1, an anchor above (3, 3): itself, the 6 room planes and the 3 faces of the box
    # that face it (its top and the faces at x = 2 and y = 2; its bottom is on the floor)
    box = [{"min": [1, 1, 0], "max": [2, 2, 1]}]
    walls = {"west": 0.45, "east": 0.45}  # the default's 1.0 there reflects nothing
    one = Room(size=(6.0, 6.0, 3.0), max_order=1, obstacles=box, absorption=walls)
    assert image_count(one) == 10
    assert image_count(one, 0) == 7  # no reflection on obstacle faces
    assert image_count(dataclasses.replace(one, absorption={})) == 8  # west, east: α = 1
    # a room of 25 desks: hundreds of thousands of images at order 3, each lower order fewer
    desks = [
        {"min": [1 + 2 * i, 1 + 2 * j, 0], "max": [2 + 2 * i, 1.8 + 2 * j, 0.75]}
        for i in range(5)
        for j in range(5)
    ]
    office = Room(size=(11.0, 11.0, 3.0), max_order=3, obstacles=desks)
    counts = [image_count(office, k) for k in range(4)]
    assert counts == sorted(counts) and counts[3] > MANY_IMAGES >= counts[1]
    with caplog.at_level("WARNING", logger="placement.plan"):
        assert image_check(office) == counts[3]
    assert f"{counts[3]:,} image sources up to order 3" in caplog.text
    assert f"gives {counts[2]:,} (2) or {counts[1]:,} (1)" in caplog.text
    caplog.clear()
    with caplog.at_level("WARNING", logger="placement.plan"):
        assert 0 < image_check(L_ROOM) <= MANY_IMAGES
        assert image_check(Room(size=(4.0, 4.0, 3.0))) == 0  # a shoebox: no tracing
    assert not caplog.text


def test_floor_plans_and_obstacles_round_trip_through_toml(tmp_path):
    room = Room.from_corners(
        L_CORNERS,
        3.0,
        wall_names=["s", "e", "bay", "wing", "n", "w"],
        absorption={"s": 0.2, "ceiling": 0.6},
        obstacles=[
            {
                "min": [1, 1, 0],
                "max": [1.4, 1.4, 3],
                "name": "col",
                "mountable": True,
                "absorption": 0.05,
            }
        ],  # fmt: skip
        obstacle_order=1,
        keepouts=[{"min": [1, 0, 1], "max": [2, 0.1, 2], "name": "window"}],
    )
    path = tmp_path / "lab.toml"
    room.to_toml(path)
    text = path.read_text()
    assert "corners = " in text and "[[obstacle]]" in text and "height = 3.0" in text
    back = Room.from_toml(path)
    assert back.to_dict() == room.to_dict()
    assert back.corners == room.corners and back.wall_names == room.wall_names
    assert back.obstacles == room.obstacles and back.obstacle_order == 1
    assert Room.from_dict(room.to_dict()).to_dict() == room.to_dict()


def test_nodes_and_anchors_stay_out_of_obstacles_and_outside_the_plan():
    g = L_ROOM.grid()
    assert len(g) and L_ROOM.contains(g, margin=0.049).all()
    assert not np.any((g[:, 0] > 3) & (g[:, 1] > 3))  # the missing corner of the L
    assert not BOX_ROOM.obstacles[0].contains(BOX_ROOM.grid(), 0.0).any()
    with pytest.raises(ValueError, match="obstacle"):
        BOX_ROOM.check_anchors([[3.0, 2.0, 1.0], [0.03, 1, 1], [1, 0.03, 1], [5, 3.97, 2]])
    with pytest.raises(ValueError, match="floor plan"):
        L_ROOM.check_anchors([[5.0, 5.0, 1.0], [0.03, 1, 1], [1, 0.03, 1], [5, 2.97, 2]])
    with pytest.raises(ValueError, match="nodes"):
        L_ROOM.check_nodes([[5.0, 5.0, 1.0]])


# -- line of sight -------------------------------------------------------------------------
def test_line_of_sight_against_hand_computed_cases():
    # around the L's reflex corner (3, 3): from the bay's far east to the wing's north
    a = np.array([[6.5, 1.0, 1.5], [2.0, 2.0, 1.5]])
    p = np.array([[1.0, 5.5, 1.5], [6.0, 2.0, 1.5], [2.9, 5.9, 1.0]])
    los = line_of_sight(L_ROOM, a, p)
    # (1, 5.5) → (6.5, 1): the line passes x = 3 at y ≈ 3.86, beyond the wall: blocked;
    # (2.9, 5.9) → (6.5, 1): at x = 3, y ≈ 5.76: blocked; (2, 2) sees everything
    np.testing.assert_array_equal(los, [[False, True], [True, True], [False, True]])
    # the cabinet (2.5–3.5, 1.5–2.5, up to 2 m): through it, rising through it, beside it;
    # at 2.5 m over it
    b = np.array([[0.5, 2.0, 1.0], [0.5, 2.0, 2.5]])
    q = np.array([[5.5, 2.0, 1.0], [5.5, 2.0, 2.6], [5.5, 0.5, 1.0], [5.5, 2.0, 2.5]])
    np.testing.assert_array_equal(
        line_of_sight(BOX_ROOM, b, q), [[False, False], [False, True], [True, True], [False, True]]
    )
    # a shoebox without obstacles: everything in sight
    assert line_of_sight(Room.techtile(), a * 0.5, p * 0.4).all()
    # the simulation's paths say the same
    assert (compute_paths(L_ROOM, a, p).los == los).all()


@pytest.mark.parametrize("room", [L_ROOM, BOX_ROOM, Room.techtile()], ids=["L", "box", "shoebox"])
def test_hidden_anchors_are_the_used_pairs_out_of_sight(room):
    # two layouts, points of each, a random half of the pairs used: hidden where used and
    # line_of_sight says blocked, nowhere else
    rng = np.random.default_rng(3)
    layouts = np.stack([_points(room, 5, rng), _points(room, 5, rng)])
    owner = rng.integers(0, 2, 200)
    points = _points(room, 200, rng)
    used = rng.random((200, 5)) < 0.5
    los = np.stack([line_of_sight(room, layouts[o], points[i : i + 1])[0]
                    for i, o in enumerate(owner)])  # fmt: skip
    hidden = hidden_anchors(room, layouts, owner, points, used)
    np.testing.assert_array_equal(hidden, used & ~los)
    assert hidden.any() == (bool(room.obstacles) or not room.is_convex)  # some are hidden


@pytest.mark.parametrize("room", [L_ROOM, BOX_ROOM], ids=["L", "box"])
def test_the_faces_behind_an_anchor_never_decide_its_line_of_sight(room):
    # from points anywhere in the room's box (outside the L, inside the cabinet too) to
    # anchors in the air, the faces each anchor faces answer as all of the map's faces do
    rng = np.random.default_rng(7)
    geo = blocking_map(room)
    anchors = _points(room, 12, rng, margin=0.02)[None]
    front = facing(room, anchors)[0]
    assert front.shape == (12, len(geo[0])) and 0 < front.sum() < front.size
    blocked = 0
    for p in rng.uniform(0, room.size, (60, 3)):
        for j, a in enumerate(anchors[0]):
            for every in (False, True):
                got = sees_near(geo, p, a, front[j], 0.05, every)
                assert got == sees_near(geo, p, a, geo[4], 0.05, every)
                blocked += not got
    assert blocked > 0  # some paths are blocked, so the comparison means something
    # an anchor outside the air (outside the floor plan, inside the cabinet) keeps every face
    outside = np.array([[[5.0, 5.0, 1.0], [3.0, 2.0, 1.0]]])
    assert facing(room, outside)[0, 1 if room.obstacles else 0].all()


def test_the_bound_counts_only_the_anchors_in_sight():
    a = np.array([[6.9, 0.5, 2.9], [6.9, 2.5, 0.1], [4.0, 0.05, 2.9], [5.0, 2.95, 1.0],
                  [0.05, 5.0, 1.0]])  # fmt: skip
    p = np.array([[1.0, 5.5, 1.5], [5.5, 1.5, 1.5]])
    # the wing's node sees its own anchor and, past the reflex corner (3, 3), the one at
    # (4, 0.05); the bay's node sees the bay's four, not the wing's (its line crosses x = 3
    # at y ≈ 3.1, outside the L)
    counts = analysis.coverage(L_ROOM, a, p)
    np.testing.assert_array_equal(counts, [2, 4])
    pebs = analysis.bound(L_ROOM, a, p)
    assert np.isinf(pebs[0]) and np.isfinite(pebs[1])
    assert np.isclose(pebs[1], analysis.peb(a[:4], p[1:], 0.04)[0])


# -- image sources -------------------------------------------------------------------------
def test_a_rectangle_of_corners_gives_the_shoeboxs_ranges():
    """The polygon method (images with visibility tests) on the four corners of a
    rectangle: the shoebox's paths and noise-free ranges."""
    shoe = Room(size=(6.0, 4.0, 2.8), absorption={"west": 0.3, "east": 0.6})
    poly = Room.from_corners(
        [[0, 0], [6, 0], [6, 4], [0, 4]],
        2.8,
        wall_names=["south", "east", "north", "west"],
        absorption=dict(shoe.absorption),
        mounting=["south", "north", "ceiling"],
    )
    rng = np.random.default_rng(4)
    a = _points(shoe, 4, rng)
    nodes = _points(shoe, 40, rng)
    ps, pp = compute_paths(shoe, a, nodes), compute_paths(poly, a, nodes)
    for i in range(len(nodes)):
        for m in range(len(a)):
            s = np.sort(ps.length[i, m][ps.amplitude[i, m] > 0])
            t = np.sort(pp.length[i, m][pp.amplitude[i, m] > 0])
            np.testing.assert_allclose(t, s, rtol=1e-12)
    r_shoe = simulate_ranges(shoe, a, nodes, noise=False)
    r_poly = simulate_ranges(poly, a, nodes, noise=False)
    np.testing.assert_allclose(r_poly, r_shoe, atol=1e-9)
    # and the placement geometry of both is the same
    np.testing.assert_allclose(placement.candidate_grid(poly, 0.5),
                               placement.candidate_grid(shoe, 0.5))  # fmt: skip


@pytest.mark.parametrize("room", [L_ROOM, BOX_ROOM], ids=["L-shaped", "box obstacle"])
def test_the_peer_gives_the_same_ranges_and_line_of_sight(room):
    """pyroomacoustics' general image-source model (the same walls, omnidirectional
    speakers) against ours: the receiver's range within 1 cm for at least 90 % of random
    pairs, pairs without a line of sight included, and the same line of sight."""
    rng = np.random.default_rng(2)
    a = _points(room, 3, rng)
    nodes = _points(room, 16, rng)
    if room is L_ROOM:  # make sure some pairs look around the reflex corner
        a[0] = [6.5, 1.0, 1.5]
        nodes[:3] = [[1.0, 5.5, 1.5], [2.0, 5.0, 1.0], [0.5, 4.0, 2.0]]
    wp, los_peer = pra_general_windows(room, a, nodes)
    paths = compute_paths(room, a, nodes, directivity="omni")
    w = received_windows(paths, room.speed_of_sound)
    dsp = dsp_for(precision="float64")
    r_ours = dsp.ranges(w, room.speed_of_sound)
    r_peer = dsp.ranges(wp, room.speed_of_sound)
    assert np.mean(np.abs(r_ours - r_peer) <= 0.01) >= 0.9
    np.testing.assert_array_equal(paths.los, los_peer)
    assert not paths.los.all()  # pairs without a line of sight were compared


# -- placement -----------------------------------------------------------------------------
LAB = Room.from_toml(__file__.rsplit("/tests/", 1)[0] + "/examples/l-shaped-lab.toml")


def test_mounting_surfaces_of_a_polygonal_room_with_a_mountable_column():
    names = [s.name for s in placement.mounting_surfaces(LAB)]
    assert names[:7] == [*LAB.wall_names, "ceiling"]
    assert {"column-1:-x", "column-1:+x", "column-1:-y", "column-1:+y"} <= set(names)
    assert not any(n.startswith("shelf") for n in names)  # not mountable
    cand = placement.candidate_grid(LAB, 0.4)
    assert placement.allowed(LAB, cand).all()
    assert not np.any(LAB.in_keepout(cand)) and not np.any(LAB.in_obstacle(cand))
    # the ceiling's candidates lie over the floor plan only
    ceiling = cand[np.isclose(cand[:, 2], 2.97)]
    assert LAB.contains(ceiling).all() and not np.any((ceiling[:, 0] > 3) & (ceiling[:, 1] > 3))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.floats(-2, 10), st.floats(-2, 9), st.floats(-1, 4)), min_size=1,
                max_size=20),
       st.integers(0, 2**31 - 1))  # fmt: skip
def test_projection_and_random_layouts_never_land_in_an_obstacle_or_keepout(points, seed):
    p = placement.project(LAB, np.array(points))
    assert placement.allowed(LAB, p, tol=1e-6).all()
    r = placement.random_layout(LAB, 8, seed)
    assert placement.allowed(LAB, r, tol=1e-6).all()


def test_a_short_plan_in_the_l_shaped_lab_places_allowed_anchors():
    from placement.simselect import SearchOptions
    from placement.validation import ValidationOptions

    search = SearchOptions(spacing=1.0, chains=2, evaluations=80, random_starts=4,
                           neighbours=10, batch=5, patience=4, fine_spacings=(0.5,))  # fmt: skip
    quick = ValidationOptions(realizations=2, held_out_realizations=1, random_nodes=20,
                              mount_draws=1)  # fmt: skip
    nodes = LAB.grid()[::6]
    res = placement.seed_then_pso(LAB, 6, rng=0, search=search, validation=quick, nodes=nodes,
                                  swarm=dataclasses.replace(LOCAL_SWARM, particles=3),
                                  progress=False)  # fmt: skip
    assert res.success and placement.allowed(LAB, res.anchors, tol=1e-6).all()
    assert not LAB.in_obstacle(res.anchors).any() and not LAB.in_keepout(res.anchors).any()
    for block in (res.validation, res.validation.mounting):
        assert 0 < block.availability <= 1

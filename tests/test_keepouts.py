"""Keep-outs and tag zones of the room model, and that every placement step respects them."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import placement
from placement.cli import main
from placement.plan import LOCAL_SWARM
from placement.pso import PSOOptions, pso
from simulation import SURFACES, Room

OFFICE = Path(__file__).resolve().parents[1] / "examples" / "office.toml"

# fractions of the room size: exact grid-like values (box edges on candidate points,
# on the anchors' planes, on the room's faces) as well as arbitrary ones
FRACTION = st.one_of(
    st.sampled_from([0.0, 0.003, 0.1, 0.25, 0.5, 0.75, 0.9, 1.0]), st.floats(0.0, 1.0)
)


@st.composite
def boxes(draw, size, n_max=5, max_extent=0.7):
    """Boxes in the room: thin boxes against a plane (windows, doors) and free boxes."""
    out = []
    for _ in range(draw(st.integers(1, n_max))):
        lo, hi = [], []
        for axis in range(3):
            a = draw(FRACTION) * size[axis]
            b = a + draw(FRACTION) * max_extent * size[axis]
            lo.append(a)
            hi.append(min(b, size[axis]))
        if draw(st.booleans()):  # against a plane, a few cm thick
            axis, side = SURFACES[draw(st.sampled_from(list(SURFACES)))]
            t = draw(st.sampled_from([0.0, 0.03, 0.05, 0.15]))
            lo[axis], hi[axis] = (0.0, t) if side == 0 else (size[axis] - t, size[axis])
        out.append((tuple(lo), tuple(hi)))
    return out


@st.composite
def rooms_with_keepouts(draw):
    size = tuple(draw(st.sampled_from([2.0, 3.0, 4.5, 8.0])) for _ in range(3))
    mounting = draw(st.lists(st.sampled_from(list(SURFACES)), min_size=1, max_size=4, unique=True))
    keepouts = draw(boxes(size))
    try:
        return Room(size=size, mounting=tuple(mounting), keepouts=keepouts)
    except ValueError:  # a surface covered entirely: rejected (tested separately)
        assume(False)


_LOCAL3 = dataclasses.replace(LOCAL_SWARM, particles=3, iterations=2)


def assert_allowed(room, points):
    p = np.asarray(points).reshape(-1, 3)
    assert not room.in_keepout(p).any()
    assert placement.allowed(room, p).all()


@settings(max_examples=60, deadline=None)
@given(rooms_with_keepouts(), st.integers(0, 2**32 - 1))
def test_project_never_lands_in_a_keepout(room, seed):
    rng = np.random.default_rng(seed)
    L = np.array(room.size)
    box_pts = [np.array(b) for b in room.keepouts]
    pts = np.concatenate(
        [
            rng.uniform(-0.5, 1.5, size=(60, 3)) * L,
            np.array([(lo + hi) / 2 for lo, hi in box_pts]),  # inside the boxes
            np.array([lo for lo, _ in box_pts]),  # on their faces
            np.array([hi for _, hi in box_pts]),
        ]
    )
    proj = placement.project(room, pts)
    assert_allowed(room, proj)
    np.testing.assert_allclose(placement.project(room, proj), proj, atol=1e-12)
    # nearest allowed point, up to the 1 µm margin kept around the boxes
    cand = placement.candidate_grid(room, 0.25)
    d_proj = np.linalg.norm(proj - pts, axis=1)
    d_cand = np.linalg.norm(cand[None] - pts[:, None], axis=-1).min(axis=1)
    assert np.all(d_proj <= d_cand + 3e-6)


@settings(max_examples=60, deadline=None)
@given(rooms_with_keepouts(), st.sampled_from([0.2, 0.5, 0.75, 1.6]))
def test_candidate_grid_has_no_forbidden_point(room, spacing):
    cand = placement.candidate_grid(room, spacing)
    assert_allowed(room, cand)
    # every surface keeps candidates
    idx = placement.surface_index(room, cand)
    assert set(idx.tolist()) == set(range(len(room.mounting)))


@settings(max_examples=60, deadline=None)
@given(rooms_with_keepouts(), st.integers(1, 12), st.integers(0, 2**32 - 1))
def test_random_layout_is_allowed_and_area_proportional(room, M, seed):
    a = placement.random_layout(room, M, np.random.default_rng(seed))
    assert a.shape == (M, 3)
    assert_allowed(room, a)
    counts = np.bincount(placement.surface_index(room, a), minlength=len(room.mounting))
    np.testing.assert_array_equal(counts, placement.area_counts(room, M))


def test_random_layout_uniform_over_allowed_area():
    # south wall 8 x 2.4 m minus a 4 x 2.34 m block on its left half: every anchor lands
    # on the right half, in proportion to the free area
    room = Room(mounting=("south",), keepouts=[((0.0, 0.0, 0.0), (4.0, 0.1, 2.4))])
    a = placement.random_layout(room, 4000, np.random.default_rng(1))
    assert_allowed(room, a)
    assert a[:, 0].min() > 4.0
    assert placement.allowed_area(room)[0] == pytest.approx((7.97 - 4.000001) * 2.34)
    # uniform: quarters of the free band get a quarter each
    q = np.histogram(a[:, 0], bins=np.linspace(4.000001, 7.97, 5))[0] / len(a)
    np.testing.assert_allclose(q, 0.25, atol=0.03)


@settings(max_examples=12, deadline=None)
@given(rooms_with_keepouts(), st.integers(0, 2**32 - 1))
def test_refine_peb_stays_out_of_keepouts(room, seed):
    a0 = placement.random_layout(room, 5, np.random.default_rng(seed))
    nodes = room.grid((3, 3, 2))
    res = placement.refine_peb(room, a0, nodes=nodes, max_iter=30, return_info=True)
    assert_allowed(room, res.anchors)
    # each anchor stays on its own plane
    surfs = placement.mounting_surfaces(room)
    for a, b, k in zip(a0, res.anchors, placement.surface_index(room, a0), strict=True):
        assert b[surfs[k].axis] == a[surfs[k].axis]


@settings(max_examples=8, deadline=None)
@given(rooms_with_keepouts(), st.integers(0, 2**16))
def test_pso_never_evaluates_a_forbidden_layout(room, seed):
    from analysis import peb

    nodes = room.grid((3, 3, 2))
    seen = []

    def cost(anchors):
        seen.append(np.array(anchors))
        return float(np.mean(peb(anchors, nodes)))

    # seeds inside the keep-outs are projected out of them
    inside = np.array([(np.array(lo) + hi) / 2 for lo, hi in room.keepouts])
    initial = np.resize(inside, (1, 4, 3))
    res = pso(
        placement.make_cost(cost, room),
        room,
        4,
        initial=initial,
        options=PSOOptions(particles=4, iterations=4, tol=0.0),
        rng=seed,
    )
    assert len(seen) == 16
    assert_allowed(room, np.array(seen))
    assert_allowed(room, res.anchors)


def test_pso_with_peb_cost_respects_the_office_keepouts():
    room = Room.from_toml(OFFICE)
    cost = placement.make_cost("peb", room)
    res = pso(cost, room, 6, options=PSOOptions(particles=5, iterations=5, tol=0.0), rng=0)
    assert_allowed(room, res.anchors)
    assert_allowed(room, np.array(res.best_anchors_history))
    assert_allowed(room, res.pbest)


# -- zones ---------------------------------------------------------------------------------
@st.composite
def zone_boxes(draw, size, n_max=3):
    """Boxes where tags are expected, possibly touching the room's faces or flat."""
    out = []
    for _ in range(draw(st.integers(1, n_max))):
        lo, hi = [], []
        for axis in range(3):
            a = draw(FRACTION) * 0.9 * size[axis]
            b = min(a + draw(FRACTION) * size[axis], size[axis])
            lo.append(a)
            hi.append(b)
        out.append((tuple(lo), tuple(hi)))
    return out


@st.composite
def rooms_with_zones(draw):
    size = tuple(draw(st.sampled_from([2.0, 3.0, 4.5, 8.0])) for _ in range(3))
    zones = draw(zone_boxes(size))
    spacing = draw(st.sampled_from([0.3, 0.5, 0.75, 1.0]))
    try:
        return Room(size=size, zones=zones, zone_spacing=spacing)
    except ValueError:  # a zone without a node inside the node margin
        assume(False)


@settings(max_examples=80, deadline=None)
@given(rooms_with_zones())
def test_zone_grid_inside_the_zones(room):
    g = room.grid()
    assert g.ndim == 2 and g.shape[1] == 3 and len(g) > 0
    lo = np.array([z[0] for z in room.zones])
    hi = np.array([z[1] for z in room.zones])
    inside = np.all((g[:, None] >= lo - 1e-9) & (g[:, None] <= hi + 1e-9), axis=-1)
    assert inside.any(axis=1).all()
    assert room.contains(g, margin=room.node_margin - 1e-9).all()
    assert len(np.unique(np.round(g, 9), axis=0)) == len(g)  # no duplicates
    # the explicit shape still gives the regular room grid (held-out nodes, SNR rule)
    assert room.grid((9, 6, 5)).shape == (270, 3)


def test_zone_grid_rule():
    room = Room(zones=[((1.0, 1.0, 0.8), (3.0, 2.0, 1.6))], zone_spacing=0.5)
    g = room.grid()
    # x: 2 m → 5 levels, y: 1 m → 3 levels, z: 0.8 m → round(1.6) + 1 = 3 levels (0.4 m)
    assert g.shape == (5 * 3 * 3, 3)
    np.testing.assert_allclose(np.unique(g[:, 0]), [1.0, 1.5, 2.0, 2.5, 3.0])
    np.testing.assert_allclose(np.unique(g[:, 2]), [0.8, 1.2, 1.6])
    np.testing.assert_array_equal(g[0], [1.0, 1.0, 0.8])  # x slowest, z fastest
    np.testing.assert_allclose(g[1], [1.0, 1.0, 1.2])
    # overlapping zones: shared nodes once, first zone's order first
    two = Room(zones=[((1.0, 1.0, 0.8), (3.0, 2.0, 1.6)), ((2.0, 1.0, 0.8), (4.0, 2.0, 1.6))])
    g2 = two.grid()
    assert len(g2) == 5 * 9 + 2 * 9
    np.testing.assert_array_equal(g2[: len(g)], g)
    # faces beyond the node margin are dropped; a thin side gets its middle
    edge = Room(zones=[((0.0, 0.0, 1.0), (1.0, 1.0, 1.2))])
    ge = edge.grid()
    np.testing.assert_allclose(np.unique(ge[:, 0]), [0.5, 1.0])
    np.testing.assert_allclose(np.unique(ge[:, 2]), [1.1])
    # without zones: the techtile grid
    assert Room().grid().shape == (270, 3)
    np.testing.assert_array_equal(Room().zone_grid(), np.empty((0, 3)))


def test_evaluation_uses_the_zone_nodes():
    from analysis import peb
    from placement.costs import PEBCost

    room = Room(zones=[((1.0, 1.0, 0.8), (3.0, 2.0, 1.6))])
    a = room.corners_layout()
    cost = PEBCost(room)(a, np.random.default_rng(0))
    assert cost == pytest.approx(float(np.mean(peb(a, room.grid()))))
    assert cost != pytest.approx(float(np.mean(peb(a, Room().grid()))))


# -- round trip ------------------------------------------------------------------------------
NAMES = st.text(
    alphabet=st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"),
    max_size=12,
)


@settings(max_examples=60, deadline=None)
@given(rooms_with_keepouts(), st.data())
def test_toml_and_dict_round_trip_exact(tmp_path_factory, room, data):
    import dataclasses

    zones = data.draw(zone_boxes(room.size))
    try:
        room = dataclasses.replace(
            room,
            zones=zones,
            zone_spacing=data.draw(st.sampled_from([0.25, 0.5, 0.7])),
            keepout_names=data.draw(
                st.lists(NAMES, min_size=len(room.keepouts), max_size=len(room.keepouts))
            ),
            zone_names=data.draw(st.lists(NAMES, min_size=len(zones), max_size=len(zones))),
        )
    except ValueError:
        assume(False)
    path = tmp_path_factory.mktemp("rt") / "room.toml"
    room.to_toml(path)
    back = Room.from_toml(path)
    assert back == room
    assert back.keepouts == room.keepouts and back.zones == room.zones
    assert back.keepout_names == room.keepout_names and back.zone_names == room.zone_names
    assert Room.from_dict(json.loads(json.dumps(room.to_dict()))) == room
    assert Room.from_dict(room.to_dict()).to_dict() == room.to_dict()


def test_dict_form_and_toml_tables(tmp_path):
    room = Room(
        keepouts=[((2.0, 0.0, 1.0), (5.0, 0.1, 2.0))],
        keepout_names=["window"],
        zones=[{"min": [1, 1, 0.8], "max": [3, 3, 1.6]}],
        zone_spacing=0.4,
    )
    d = room.to_dict()
    assert d["keepouts"] == [{"min": [2.0, 0.0, 1.0], "max": [5.0, 0.1, 2.0], "name": "window"}]
    assert d["zones"] == [{"min": [1.0, 1.0, 0.8], "max": [3.0, 3.0, 1.6]}]
    assert d["zone_spacing"] == 0.4
    assert room.keepouts == (((2.0, 0.0, 1.0), (5.0, 0.1, 2.0)),)
    assert room.zone_names == ("",)
    room.to_toml(tmp_path / "r.toml")
    text = (tmp_path / "r.toml").read_text()
    assert "[[keepout]]" in text and "[[zone]]" in text
    # a plain room's dictionary is unchanged (no new keys)
    assert not {"keepouts", "zones", "zone_spacing"} & set(Room().to_dict())
    # the TOML spelling is accepted by from_dict as well; both spellings at once is an error
    assert Room.from_dict({"keepout": d["keepouts"]}).keepouts == room.keepouts
    with pytest.raises(ValueError, match="either"):
        Room.from_dict({"keepout": d["keepouts"], "keepouts": d["keepouts"]})


def test_room_pickles_and_replaces():
    import dataclasses
    import pickle

    room = Room.from_toml(OFFICE)
    assert pickle.loads(pickle.dumps(room)) == room
    assert dataclasses.replace(room, name="x").keepouts == room.keepouts


# -- bad input -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"keepouts": [((5.0, 0.0, 1.0), (2.0, 0.1, 2.0))]}, r"keepouts\[0\]: inverted"),
        ({"keepouts": [((2.0, 0.0, float("nan")), (5.0, 0.1, 2.0))]}, r"keepouts\[0\] min.*finite"),
        ({"keepouts": [((2.0, 0.0, 1.0), (9.0, 0.1, 2.0))]}, r"keepouts\[0\].*not inside the room"),
        ({"keepouts": [((2.0, -0.1, 1.0), (5.0, 0.1, 2.0))]}, r"not inside the room.*\[0, 8\]"),
        ({"keepouts": [((2.0, 0.0), (5.0, 0.1, 2.0))]}, r"keepouts\[0\] min: expected 3"),
        ({"keepouts": [(1.0, 2.0, 3.0)]}, r"keepouts\[0\]: expected a box"),
        ({"keepouts": [{"min": [0, 0, 0]}]}, r"keepouts\[0\]: expected keys"),
        (  # the box's footprint in plain numbers
            {"keepouts": [((0.0, 0.0, 0.0), (8.0, 0.1, 2.4))]},
            r"\(\[\[\[0\.0, 0\.0\], \[8\.0, 2\.4\]\]\] in the plane\).*whole .*'south'",
        ),
        (  # two boxes together cover the ceiling
            {"keepouts": [((0, 0, 2.3), (4.0, 4, 2.4)), ((3.9, 0, 2.3), (8, 4, 2.4))]},
            r"boxes \[0, 1\].*'ceiling'",
        ),
        ({"zones": [((3.0, 1.0, 0.8), (1.0, 3.0, 1.6))]}, r"zones\[0\]: inverted"),
        ({"zones": [((1.0, 1.0, 0.8), (3.0, 3.0, float("inf")))]}, r"zones\[0\] max.*finite"),
        ({"zones": [((1.0, 1.0, 0.8), (3.0, 5.0, 1.6))]}, r"zones\[0\].*not inside the room"),
        ({"zones": [((1.0, 1.0, 0.0), (3.0, 3.0, 0.02))]}, r"zones\[0\]: no node"),
        ({"zones": [{"min": [1, 1, 1], "max": [2, 2, 2], "weight": 2.0}]}, "weights are not"),
        ({"zone_spacing": 0.0}, "zone_spacing"),
        ({"zone_spacing": float("nan")}, "zone_spacing"),
        ({"keepouts": [((1, 0, 1), (2, 0.1, 2))], "keepout_names": ["a", "b"]}, "keepout_names"),
    ],
)
def test_bad_keepouts_and_zones(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Room(**kwargs)


def test_keepout_that_misses_the_anchor_plane_leaves_the_wall_free():
    # a 2 cm box against the south wall does not reach the anchors' plane at y = 0.03
    room = Room(keepouts=[((0.0, 0.0, 0.0), (8.0, 0.02, 2.4))])
    assert placement.allowed_area(room)[0] == pytest.approx(7.94 * 2.34)
    # a box ending exactly on that plane catches it (closed boxes)
    with pytest.raises(ValueError, match="south"):
        Room(keepouts=[((0.0, 0.0, 0.0), (8.0, 0.03, 2.4))])


def test_check_anchors_rejects_anchors_in_keepouts():
    room = Room(keepouts=[((0.0, 0.0, 0.0), (0.5, 0.1, 0.5))], keepout_names=["socket"])
    with pytest.raises(ValueError, match=r"anchor\(s\) \[0\].*keepouts\[0\] \('socket'\)"):
        room.check_anchors(room.corners_layout())
    moved = placement.project(room, room.corners_layout())
    room.check_anchors(moved)
    with pytest.raises(ValueError, match="keep-out"):
        placement.refine_peb(room, room.corners_layout())


def test_fewer_allowed_candidates_than_anchors():
    # a 1.6 m grid on a ceiling-only room with the middle blocked: few candidates left
    room = Room(mounting=("ceiling",), keepouts=[((0.5, 0.5, 2.0), (7.5, 3.5, 2.4))])
    cand = placement.candidate_grid(room, 1.6)
    assert_allowed(room, cand)
    with pytest.raises(ValueError, match="M: number of anchors"):
        placement.exhaustive_search(room, len(cand) + 1, candidates=cand)
    with pytest.raises(ValueError, match="M: number of anchors"):
        placement.relax_select(room, len(cand) + 1, candidates=cand)
    inside = np.array([[4.0, 2.0, 2.37], *cand[:4]])
    with pytest.raises(ValueError, match="keep-out"):
        placement.exhaustive_search(room, 4, candidates=inside)


def test_candidate_grid_keeps_small_allowed_regions():
    # the ceiling is blocked except a 0.3 m gap between two boxes: no 1.6 m grid point
    # falls in the gap, so its centre is added
    room = Room(
        mounting=("ceiling",),
        keepouts=[((0.0, 0.0, 2.3), (3.0, 4.0, 2.4)), ((3.3, 0.0, 2.3), (8.0, 4.0, 2.4))],
    )
    cand = placement.candidate_grid(room, 1.6)
    assert len(cand) >= 1
    assert_allowed(room, cand)
    assert np.all((cand[:, 0] > 3.0) & (cand[:, 0] < 3.3))


def test_no_keepouts_changes_nothing():
    room = Room.techtile()
    lo, hi, idx = placement.allowed_rectangles(room)
    assert idx.tolist() == [0, 1, 2]
    for s, a, b in zip(placement.mounting_surfaces(room), lo, hi, strict=True):
        np.testing.assert_array_equal(a, s.lower)  # (u, v) of the surface itself
        np.testing.assert_array_equal(b, s.upper)
    np.testing.assert_array_equal(
        placement.allowed_area(room), [s.area for s in placement.mounting_surfaces(room)]
    )


# -- example room and CLI --------------------------------------------------------------------
def test_office_example():
    room = Room.from_toml(OFFICE)
    assert room.size == (10.0, 6.0, 3.0) and room.mounting == ("south", "north", "ceiling")
    assert len(room.keepouts) == 8 and room.keepout_names[0] == "windows"
    nodes = room.grid()
    assert 200 <= len(nodes) <= 400
    lo = np.array([z[0] for z in room.zones])
    hi = np.array([z[1] for z in room.zones])
    inside = np.all((nodes[:, None] >= lo - 1e-9) & (nodes[:, None] <= hi + 1e-9), axis=-1)
    assert inside.any(axis=1).all()
    assert nodes[:, 2].min() == pytest.approx(0.8) and nodes[:, 2].max() == pytest.approx(1.6)
    cand = placement.candidate_grid(room, 0.5)
    assert_allowed(room, cand)
    # the window band and the lights do remove grid points
    assert len(cand) < sum(
        len(placement.candidate_grid(Room(size=room.size, mounting=(m,)), 0.5))
        for m in room.mounting
    )
    assert_allowed(room, placement.random_layout(room, 10, np.random.default_rng(0)))
    room.check_anchors(room.corners_layout())
    # round trip of the example
    assert Room.from_dict(json.loads(json.dumps(room.to_dict()))) == room


def test_cli_bad_room_exits_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        "size = [8.0, 4.0, 2.4]\n\n[[keepout]]\nmin = [5.0, 0.0, 1.0]\nmax = [2.0, 0.1, 2.0]\n"
    )
    assert main(["bounds", "--room", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "keepouts[0]: inverted box" in err
    bad.write_text(
        "size = [8.0, 4.0, 2.4]\n\n[[zone]]\nmin = [1, 1, 1]\nmax = [2, 2, 2]\nweight = 2\n"
    )
    assert main(["bounds", "--room", str(bad)]) == 2
    assert "weights are not supported" in capsys.readouterr().err


def test_cli_bounds_uses_the_zone_nodes(tmp_path, capsys):
    out = tmp_path / "b.json"
    assert main(["bounds", "--room", str(OFFICE), "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    assert len(data["peb"]) == len(Room.from_toml(OFFICE).grid())
    assert Room.from_dict(data["room"]) == Room.from_toml(OFFICE)


# -- figures and report ----------------------------------------------------------------------
def _gids(fig, gid):
    return [a for ax in fig.axes for a in [*ax.patches, *ax.collections] if a.get_gid() == gid]


def test_figures_draw_keepouts_and_zones():
    from analysis import figures as F
    from analysis import peb

    room = Room.from_toml(OFFICE)
    a = placement.random_layout(room, 6, np.random.default_rng(0))
    fig = F.peb_map(room, a, heights=[1.2], y_cuts=[3.0], resolution=0.25, dpi=30)
    assert len(_gids(fig, "keepouts")) == 2 * len(room.keepouts)
    assert len(_gids(fig, "zones")) == 2 * len(room.zones)
    nodes = room.grid()
    fig = F.scatter3d(room, nodes, peb(a, nodes), a, dpi=30)
    assert len(_gids(fig, "keepouts")) == 1 and len(_gids(fig, "zones")) == 1
    fig = F.layout_views(room, {"a": a}, dpi=30)
    assert len(_gids(fig, "keepouts")) == 1
    # a plain room draws neither
    plain = Room()
    fig = F.peb_map(plain, plain.corners_layout(), resolution=0.5, dpi=30)
    assert not _gids(fig, "keepouts") and not _gids(fig, "zones")


def test_report_lists_keepouts_and_zones(tmp_path):
    from analysis import report as rp

    room = Room.from_toml(OFFICE)
    a = placement.random_layout(room, 6, np.random.default_rng(0))
    (tmp_path / "evaluation.json").write_text(
        json.dumps({"room": room.to_dict(), "anchors": a.tolist()})
    )
    rep = rp.build_report(tmp_path, realizations=0, dpi=30)
    assert "Keep-outs and tag zones" in rep.html
    for name in ("windows", "door", "light 6", "desks", "meeting table"):
        assert name in rep.html
    assert f"The {len(room.grid())} evaluation nodes" in rep.html
    assert "Keep-outs (hatched) and tag zones (dashed)" in rep.html


@settings(max_examples=4, deadline=None)
@given(rooms_with_keepouts(), st.integers(0, 2**16))
def test_a_short_seed_then_pso_never_returns_a_point_in_a_keepout(room, seed):
    from placement.simselect import SearchOptions
    from placement.validation import ValidationOptions

    search = SearchOptions(
        spacing=1.0, chains=1, evaluations=20, random_starts=3, neighbours=6, batch=3,
        patience=2, fine_spacings=(0.5,),
    )  # fmt: skip
    try:
        res = placement.seed_then_pso(
            room, 4, search=search, swarm=_LOCAL3, rng=seed, progress=False,
            nodes=room.grid((3, 3, 2)), validation=ValidationOptions(realizations=0),
        )  # fmt: skip
    except ValueError as exc:  # too few candidate points for 4 anchors in this room
        assert "candidate" in str(exc) or "anchors" in str(exc)
        return
    layouts = (
        [res.anchors] + [s.anchors for s in res.initial] + [f["anchors"] for f in res.finalists]
    )
    for a in layouts:
        assert_allowed(room, a)

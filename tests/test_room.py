import json

import numpy as np
import pytest

from simulation import Room


def test_techtile_defaults():
    room = Room.techtile()
    assert room.size == (8.0, 4.0, 2.4)
    assert room.absorption["floor"] == 0.45 and room.absorption["east"] == 1.0
    assert room.reflection("west") == 0.0
    assert room.reflection("north") == pytest.approx(np.sqrt(0.55))
    assert room.speed_of_sound == pytest.approx(343.2, abs=0.05)
    assert room.max_order == 3
    assert room.mounting == ("south", "north", "ceiling")
    np.testing.assert_allclose(room.centroid, [4.0, 2.0, 1.2])


def test_grid_shape_spacing_and_margins():
    room = Room.techtile()
    g = room.grid()
    assert g.shape == (270, 3)
    for axis, (n, spacing) in enumerate(zip((9, 6, 5), (0.9875, 0.78, 0.575), strict=True)):
        levels = np.unique(np.round(g[:, axis], 9))
        assert len(levels) == n
        np.testing.assert_allclose(np.diff(levels), spacing)
        assert levels[0] == pytest.approx(0.05)
        assert levels[-1] == pytest.approx(room.size[axis] - 0.05)
    assert room.contains(g, margin=0.05 - 1e-12).all()


def test_other_shoebox_grid():
    room = Room(size=(5.0, 3.0, 3.0), node_margin=0.1)
    g = room.grid((3, 4, 2))
    assert g.shape == (24, 3)
    assert g.min() == pytest.approx(0.1)
    np.testing.assert_allclose(g.max(axis=0), [4.9, 2.9, 2.9])


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"size": (8.0, -1.0, 2.4)}, "size"),
        ({"size": (8.0, 4.0)}, "size"),
        ({"absorption": {"floor": 1.5}}, "absorption"),
        ({"absorption": {"roof": 0.5}}, "absorption"),
        ({"mounting": ("south", "attic")}, "mounting"),
        ({"node_margin": 1.3}, "node_margin"),
        ({"anchor_offset": -0.01}, "anchor_offset"),
        ({"max_order": -1}, "max_order"),
        ({"temperature": -300.0}, "temperature"),
        ({"air_absorption": -1.0}, "air_absorption"),
    ],
)
def test_validation_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        Room(**kwargs)


def test_toml_and_dict_round_trip(tmp_path):
    room = Room(
        size=(6.0, 5.0, 3.0),
        absorption={"floor": 0.2, "west": 0.7},
        temperature=25.0,
        max_order=2,
        mounting=("ceiling", "west"),
        name="lab",
    )
    path = tmp_path / "room.toml"
    room.to_toml(path)
    assert Room.from_toml(path) == room
    assert Room.from_dict(json.loads(json.dumps(room.to_dict()))) == room
    with pytest.raises(ValueError, match="unknown field"):
        Room.from_dict({"sise": [1, 2, 3]})


def test_check_anchors():
    room = Room.techtile()
    room.check_anchors(room.corners_layout())
    with pytest.raises(ValueError, match="at least 4"):
        room.check_anchors(room.corners_layout()[:3])
    bad = room.corners_layout()
    bad[0, 0] = 9.0
    with pytest.raises(ValueError, match="outside"):
        room.check_anchors(bad)
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        room.check_anchors(bad)

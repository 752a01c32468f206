import math

import numpy as np
import pytest

from simulation import Room
from simulation.multipath import ImageSet, compute_paths, image_indices, wall_hits

ALL = ("floor", "ceiling", "south", "north", "west", "east")


def _mirror_chain(a: float, L: float, n: int) -> tuple[float, int, int]:
    """Image coordinate of a for index n by explicit unfolding, and the hits (low, high).

    The line from the image to the room crosses the unfolded planes L, 2L, …, nL (n > 0)
    or 0, −L, …, (n+1)L (n < 0); mirroring the source across them one after the other
    gives the image, and the plane at m·L is the real wall at 0 for even m, at L for odd m.
    """
    x, low, high = a, 0, 0
    for i in range(abs(n)):
        m = i + 1 if n > 0 else -i
        x = 2 * m * L - x
        if m % 2 == 0:
            low += 1
        else:
            high += 1
    return x, low, high


def test_image_count_and_order():
    for N in range(5):
        n = image_indices(N)
        assert len(n) == (2 * N + 1) * (2 * N * N + 2 * N + 3) // 3
        assert np.all(np.abs(n).sum(axis=1) <= N)
        assert np.array_equal(n[0], [0, 0, 0])
        assert len({tuple(r) for r in n}) == len(n)
    with pytest.raises(ValueError, match="max_order"):
        image_indices(-1)


def test_image_positions_and_wall_hits_match_explicit_unfolding():
    L, a = 4.0, 1.3
    for n in range(-5, 6):
        x, low, high = _mirror_chain(a, L, n)
        hl, hh = wall_hits(np.array([n]))
        assert (hl[0], hh[0]) == (low, high)
        room = Room(size=(8.0, L, 2.4), max_order=5, absorption={k: 0.0 for k in ALL})
        im = ImageSet(
            indices=np.array([[0, n, 0]]),
            reflection=np.ones(1),
            mirror=np.array([[1.0, (-1.0) ** n, 1.0]]),
        )
        q = im.positions(room, np.array([[2.0, a, 1.0]]))
        assert q[0, 0, 1] == pytest.approx(x, abs=1e-12)


def test_zero_reflection_images_are_dropped():
    room = Room.techtile()  # west and east absorb everything
    im = ImageSet.for_room(room)
    assert np.all(im.indices[:, 0] == 0)
    assert len(im) == len([n for n in image_indices(3) if n[0] == 0]) == 25
    assert np.all(im.reflection > 0)
    # a wall product is β^hits over the four wooden walls: β = √0.55
    beta = math.sqrt(0.55)
    assert np.allclose(im.reflection, beta ** np.abs(im.indices).sum(axis=1))
    rigid = Room(absorption={k: 0.0 for k in ALL})
    assert len(ImageSet.for_room(rigid)) == 63


def test_direct_and_first_order_paths_closed_form():
    room = Room.techtile()
    anchor = np.array([[2.0, 0.03, 1.5]])
    node = np.array([[3.0, 2.0, 0.5]])
    paths = compute_paths(room, anchor, node)
    im = ImageSet.for_room(room)
    aim = room.centroid - anchor[0]
    aim /= np.linalg.norm(aim)
    a_air = room.air_absorption

    def amp(image, emit, refl):
        d = np.linalg.norm(node[0] - image)
        cos = emit @ aim / np.linalg.norm(emit)
        return d, refl * 0.5 * (1 + cos) * math.exp(-0.5 * a_air * d) / (4 * math.pi * d)

    # direct path
    d, A = amp(anchor[0], node[0] - anchor[0], 1.0)
    assert paths.length[0, 0, 0] == pytest.approx(d, rel=1e-12)
    assert paths.amplitude[0, 0, 0] == pytest.approx(A, rel=1e-12)
    # floor reflection (n = (0, 0, -1)): image at z = −1.5, ray leaves the speaker downward
    i = int(np.flatnonzero((im.indices == [0, 0, -1]).all(axis=1))[0])
    img = anchor[0] * [1, 1, -1]
    hit = img + (node[0] - img) * (0 - img[2]) / (node[0, 2] - img[2])  # floor point
    d, A = amp(img, hit - anchor[0], math.sqrt(1 - 0.45))
    assert paths.length[0, 0, i] == pytest.approx(d, rel=1e-12)
    assert paths.amplitude[0, 0, i] == pytest.approx(A, rel=1e-12)
    # the mirrored emission direction is the real ray's: speaker → floor point
    emit = (node[0] - img) * im.mirror[i]
    assert np.allclose(
        emit / np.linalg.norm(emit), (hit - anchor[0]) / np.linalg.norm(hit - anchor[0])
    )


def test_mirror_symmetry_of_paths():
    room = Room.techtile()
    a = np.array([[4.0, 0.03, 1.2]])  # mid-south wall: the room is symmetric in x about 4
    nodes = np.array([[1.5, 2.2, 0.7], [6.5, 2.2, 0.7]])
    p = compute_paths(room, a, nodes)
    assert np.allclose(np.sort(p.length[0, 0]), np.sort(p.length[1, 0]), rtol=1e-12)
    assert np.allclose(np.sort(p.amplitude[0, 0]), np.sort(p.amplitude[1, 0]), rtol=1e-12)


def test_cardioid_null_gives_zero_amplitude_and_shapes():
    room = Room.techtile()
    a = np.array([[4.0, 0.03, 1.2]])  # aims along +y at the centroid
    behind = np.array([[4.0, -1.0, 1.2]])  # straight behind the speaker (outside the room)
    p = compute_paths(room, a, behind)
    assert p.amplitude[0, 0, 0] == 0.0
    nodes, anchors = room.grid(), room.corners_layout()
    p = compute_paths(room, anchors, nodes)
    assert p.length.shape == p.amplitude.shape == (270, 4, 25)
    assert np.all(np.isfinite(p.amplitude)) and np.all(p.amplitude >= 0)
    # the direct path is the shortest
    assert np.all(p.length[:, :, 0] <= p.length.min(axis=-1) + 1e-12)
    with pytest.raises(ValueError, match="nodes"):
        compute_paths(room, anchors, nodes[:, :2])


def test_air_absorption_scales_every_path():
    dry = Room(air_absorption=0.0)
    wet = Room(air_absorption=0.2)
    a, n = Room.techtile().corners_layout(), Room.techtile().grid()[::17]
    p0, p1 = compute_paths(dry, a, n), compute_paths(wet, a, n)
    assert np.allclose(p1.amplitude, p0.amplitude * np.exp(-0.1 * p0.length), rtol=1e-12)

"""Our simulator against the peer: pyroomacoustics (ISM, 1 MHz impulse responses)."""

import numpy as np
import pyroomacoustics as pra
from peer import pra_windows

from placement import random_layout
from simulation import Room
from simulation.multipath import ImageSet, compute_paths
from simulation.received import received_windows
from simulation.receiver import dsp_for

ALL = ("floor", "ceiling", "south", "north", "west", "east")


def _pairs(room, rng, n_nodes):
    layouts = [room.corners_layout(), random_layout(room, 4, rng)]
    nodes = room.grid()[rng.choice(270, n_nodes, replace=False)]
    return layouts, nodes


def test_image_sources_and_wall_products_match_pyroomacoustics():
    room = Room(absorption={"floor": 0.3, "ceiling": 0.6, "south": 0.1, "north": 0.45})
    anchor = np.array([2.1, 0.03, 1.7])
    box = pra.ShoeBox(
        list(room.size),
        fs=16000,
        max_order=room.max_order,
        materials={k: pra.Material(energy_absorption=room.absorption[k]) for k in ALL},
    )
    box.add_source(anchor.tolist())
    box.add_microphone([4.0, 2.0, 1.2])
    box.image_source_model()
    src = box.sources[0]
    keep = src.damping[0] > 0
    theirs = src.images[:, keep].T
    their_damping = src.damping[0, keep]
    im = ImageSet.for_room(room)
    ours = im.positions(room, anchor[None])[0]
    assert len(ours) == len(theirs)
    o, t = np.lexsort(ours.T[::-1]), np.lexsort(theirs.T[::-1])
    np.testing.assert_allclose(ours[o], theirs[t], atol=1e-5)  # pyroomacoustics: float32
    np.testing.assert_allclose(im.reflection[o], their_damping[t], rtol=1e-5)


def test_received_windows_and_ranges_agree_with_pyroomacoustics():
    """Noise-free, reverberant techtile room, 2 layouts × 20 nodes × 4 anchors = 160 pairs."""
    room = Room.techtile()
    rng = np.random.default_rng(2023)
    layouts, nodes = _pairs(room, rng, 20)
    dsp = dsp_for()
    c = room.speed_of_sound
    dr, rel = [], []
    for a in layouts:
        ours = received_windows(compute_paths(room, a, nodes), c)
        peer = pra_windows(room, a, nodes)
        rel.append(np.abs(ours - peer).max(axis=-1) / np.abs(ours).max(axis=-1))
        dr.append(np.abs(dsp.ranges(ours, c) - dsp.ranges(peer, c)))
    dr, rel = np.concatenate(dr).ravel(), np.concatenate(rel).ravel()
    assert dr.size == 160
    assert np.mean(dr <= 0.01) >= 0.95
    assert np.mean(dr <= 0.005) >= 0.80
    # the waveforms themselves: pyroomacoustics' float32 sinc-table fractional delays
    # leave ~0.1 % differences; a wrong directivity, order, absorption or sound speed
    # gives tens of per cent
    assert np.median(rel) < 0.005 and np.percentile(rel, 95) < 0.02


def test_reflective_room_with_all_six_walls_agrees():
    room = Room(absorption={k: 0.3 for k in ALL}, air_absorption=0.0)
    rng = np.random.default_rng(5)
    layouts, nodes = _pairs(room, rng, 6)
    dsp = dsp_for()
    c = room.speed_of_sound
    dr = []
    for a in layouts:
        ours = received_windows(compute_paths(room, a, nodes), c)
        peer = pra_windows(room, a, nodes)
        rel = np.abs(ours - peer).max(axis=-1) / np.abs(ours).max(axis=-1)
        assert np.percentile(rel, 95) < 0.02
        dr.append(np.abs(dsp.ranges(ours, c) - dsp.ranges(peer, c)))
    assert np.mean(np.concatenate(dr) <= 0.01) >= 0.95


def test_a_long_window_agrees_with_pyroomacoustics_on_held_out_pairs():
    """A 20 ms window (from t_wake = 10 ms) with either pick, in the techtile room and in
    the same box without absorbers (α = 0.2 everywhere): random layouts and random tag
    points, none of them used to choose the first-path pick's settings; the ranges agree
    within 1 cm for at least 90 % of pairs."""
    import dataclasses

    from placement.validation import random_nodes
    from simulation import Receiver

    rng = np.random.default_rng(28)
    rx = Receiver(window=3840, t_wake=0.01)
    for room in (Room.techtile(), Room(absorption={k: 0.2 for k in ALL})):
        c = room.speed_of_sound
        a = random_layout(room, 4, rng)
        nodes = random_nodes(room, 12, rng)
        ours = received_windows(compute_paths(room, a, nodes), c, receiver=rx)
        peer = pra_windows(room, a, nodes, receiver=rx)
        rel = np.abs(ours - peer).max(axis=-1) / np.abs(ours).max(axis=-1)
        assert np.percentile(rel, 95) < 0.02
        for pick in ("paper", "first-path"):
            dsp = dsp_for(receiver=dataclasses.replace(rx, pick=pick))
            dr = np.abs(dsp.ranges(ours, c) - dsp.ranges(peer, c))
            assert dr.size == 48 and np.mean(dr <= 0.01) >= 0.90, (room.name, pick)

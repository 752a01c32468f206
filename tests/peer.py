"""The peer simulator: received windows from pyroomacoustics impulse responses.

Used by the tests and benchmarks to hold :mod:`simulation.received` against an
independent implementation. It is not part of the installed package: pyroomacoustics is a
test/benchmark dependency only (imported inside the function). The tests import it as
``peer`` (pytest puts ``tests/`` on ``sys.path``); ``benchmarks/bench_simulator.py`` adds
``tests/`` to ``sys.path`` itself.

Pipeline per anchor: a ``pra.ShoeBox`` with the room's size, sound speed, image-source
order and the same materials per wall (``pra.Material(energy_absorption=α)``, names
west/east/south/north/floor/ceiling), the anchor as a source with a cardioid
(``CardioidFamily`` p = ½, gain 1) aimed at the room centroid, every node a microphone;
impulse responses at ``fs_rir`` (1 MHz) without pyroomacoustics' RIR high-pass; the chirp
sampled at ``fs_rir`` convolved with each response; the fractional-delay filter's
``frac_delay_length // 2`` samples of delay removed (the response's time zero); resampled
to the receiver's fs (``resample_poly``, zero-phase); the 1 ms window cut at t_wake.

Air absorption: pyroomacoustics scales each image by exp(−½·a_band·d) per octave band; a
single band with a = ``room.air_absorption`` reproduces our flat factor exactly, so it is
set that way (``air_absorption=False`` disables it in the peer, as ``room.air_absorption
= 0`` does in ours). pyroomacoustics' spreading is 1/d instead of 1/(4πd): a common
factor per anchor, so the windows are compared up to that scale (``scale_to_ours``).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from simulation.chirp import Chirp
from simulation.directivity import aim_vectors
from simulation.receiver import Receiver
from simulation.room import SURFACES, Room


def pra_windows(
    room: Room,
    anchors,
    nodes,
    chirp: Chirp | None = None,
    receiver: Receiver | None = None,
    fs_rir: float = 1e6,
    air_absorption: bool = True,
    scale_to_ours: bool = True,
    truncate: bool = True,
) -> np.ndarray:
    """(P, M) windows of N samples, (P, M, N), simulated with pyroomacoustics.

    With ``scale_to_ours`` the windows are divided by 4π so that amplitudes match
    :func:`simulation.received.received_windows`. ``truncate`` convolves only the part of
    the response and output that can reach the window (identical result, about 2× faster);
    ``False`` convolves the whole chirp with the whole response.
    """
    import pyroomacoustics as pra
    import scipy.signal
    from pyroomacoustics.directivities import CardioidFamily, DirectionVector

    chirp = Chirp() if chirp is None else chirp
    rx = Receiver() if receiver is None else receiver
    a = np.asarray(anchors, dtype=float)
    p = np.asarray(nodes, dtype=float)
    ratio = Fraction(rx.fs / fs_rir).limit_denominator(10000)
    if not math.isclose(float(ratio), rx.fs / fs_rir, rel_tol=1e-12):
        raise ValueError(f"fs_rir: receiver fs / fs_rir must be a simple ratio, got {fs_rir}")
    sig = chirp.samples(fs_rir)
    fdl2 = pra.constants.get("frac_delay_length") // 2
    aims = aim_vectors(a, room.centroid)
    start = int(round(rx.t_wake * rx.fs))
    N = rx.window
    keep = int(math.ceil((rx.t_wake + N / rx.fs) * fs_rir)) + 400 if truncate else None
    out = np.empty((len(p), len(a), N))
    old_hpf = pra.constants.get("rir_hpf_enable")
    pra.constants.set("rir_hpf_enable", False)
    try:
        for j in range(len(a)):
            materials = {
                name: pra.Material(energy_absorption=float(room.absorption[name]))
                for name in ("west", "east", "south", "north", "floor", "ceiling")
            }
            assert set(materials) == set(SURFACES)
            shoebox = pra.ShoeBox(
                list(room.size),
                fs=int(round(fs_rir)),
                materials=materials,
                max_order=room.max_order,
                air_absorption=False,
            )
            shoebox.set_sound_speed(room.speed_of_sound)
            if air_absorption and room.air_absorption > 0:
                # one band with our coefficient: exp(−½ a d) per image, as in ours
                shoebox.air_absorption = np.array([room.air_absorption])
            az = math.atan2(aims[j, 1], aims[j, 0])
            col = math.acos(max(-1.0, min(1.0, aims[j, 2])))
            cardioid = CardioidFamily(
                orientation=DirectionVector(azimuth=az, colatitude=col, degrees=False),
                p=0.5,
                gain=1.0,
            )
            shoebox.add_source(a[j].tolist(), directivity=cardioid)
            shoebox.add_microphone_array(p.T.copy())
            shoebox.compute_rir()
            for i in range(len(p)):
                h = np.asarray(shoebox.rir[i][0], dtype=float)[fdl2:]  # time zero at index 0
                # only the first t_wake + N/fs (plus the resampler's reach) is needed
                y = scipy.signal.fftconvolve(sig, h[:keep])[:keep]
                y192 = scipy.signal.resample_poly(y, ratio.numerator, ratio.denominator)
                seg = y192[start : start + N]
                out[i, j, : len(seg)] = seg
                out[i, j, len(seg) :] = 0.0
    finally:
        pra.constants.set("rir_hpf_enable", old_hpf)
    return out / (4 * np.pi) if scale_to_ours else out


def pra_walls(room: Room):
    """pyroomacoustics walls of a polygonal room or one with obstacles: the walls over the
    floor plan's edges, floor and ceiling (``extrude``'s construction: normals out of the
    room) and the obstacle faces not on the room's boundary (``wall_factory``, normals into
    the obstacle, away from the air), with our absorption."""
    import pyroomacoustics as pra

    h = room.size[2]
    c = room.floor_corners
    n = len(c)
    walls = []

    def add(corners, alpha, name):
        walls.append(
            pra.wall_factory(
                np.asarray(corners, float).T, np.array([alpha]), np.array([0.0]), name=name
            )  # fmt: skip
        )

    for i, w in enumerate(room.walls):
        a, b = c[i], c[(i + 1) % n]
        add([[*a, 0], [*b, 0], [*b, h], [*a, h]], room.absorption[w.name], w.name)
    add([[x, y, 0.0] for x, y in c[::-1]], room.absorption["floor"], "floor")
    add([[x, y, h] for x, y in c], room.absorption["ceiling"], "ceiling")
    from simulation.floorplan import face_rectangles

    faces = []  # every face, also those on the room's boundary: pyroomacoustics' inside test
    for k, ob in enumerate(room.obstacles):  # counts crossings and needs closed boxes
        for axis, side, flo, fhi in face_rectangles(ob):
            normal = np.zeros(3)
            normal[axis] = -1.0 if side == 0 else 1.0
            faces.append((flo, fhi, axis, normal, ob.absorption, f"{ob.name or k}:{axis}{side}"))
    for lo, hi, axis, out_normal, alpha, name in faces:
        u, v = (j for j in range(3) if j != axis)
        quad = []
        for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
            q = lo.copy()
            q[u] = (lo, hi)[du][u]
            q[v] = (lo, hi)[dv][v]
            quad.append(q)
        quad = np.array(quad)
        normal = np.cross(quad[1] - quad[0], quad[2] - quad[1])
        if normal @ out_normal > 0:  # pyroomacoustics' normal points away from the air
            quad = quad[::-1]
        add(quad, alpha, name)
    return walls


def pra_general_windows(
    room: Room,
    anchors,
    nodes,
    fs_rir: float = 1e6,
    air_absorption: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """(windows (P, M, N), line of sight (P, M)) of a polygonal room or one with obstacles,
    simulated with pyroomacoustics' general image-source model (``pra.Room`` from
    :func:`pra_walls`), omnidirectional speakers (its general rooms have no source
    directivity), the room's signal; windows scaled to ours (÷ 4π) as in
    :func:`pra_windows`."""
    import pyroomacoustics as pra
    import scipy.signal

    chirp, rx = Chirp(), Receiver()  # the paper's signal
    a = np.asarray(anchors, dtype=float)
    p = np.asarray(nodes, dtype=float)
    ratio = Fraction(rx.fs / fs_rir).limit_denominator(10000)
    sig = chirp.samples(fs_rir)
    fdl2 = pra.constants.get("frac_delay_length") // 2
    start = int(round(rx.t_wake * rx.fs))
    N = rx.window
    keep = int(math.ceil((rx.t_wake + N / rx.fs) * fs_rir)) + 400
    out = np.zeros((len(p), len(a), N))
    los = np.zeros((len(p), len(a)), dtype=bool)
    old_hpf = pra.constants.get("rir_hpf_enable")
    pra.constants.set("rir_hpf_enable", False)
    try:
        for j in range(len(a)):
            proom = pra.Room(pra_walls(room), fs=int(round(fs_rir)), max_order=room.max_order,
                             air_absorption=False)  # fmt: skip
            proom.set_sound_speed(room.speed_of_sound)
            air = float(room.air_coefficient(chirp.centre))
            if air_absorption and air > 0:
                proom.air_absorption = np.array([air])
            proom.add_source(a[j].tolist())
            proom.add_microphone_array(p.T.copy())
            proom.compute_rir()
            src = proom.sources[0]
            direct = np.flatnonzero(src.orders == 0)
            vis = proom.visibility[0]
            los[:, j] = vis[:, direct[0]] > 0 if direct.size else False
            for i in range(len(p)):
                h = np.asarray(proom.rir[i][0], dtype=float)[fdl2:]
                y = scipy.signal.fftconvolve(sig, h[:keep])[:keep]
                y192 = scipy.signal.resample_poly(y, ratio.numerator, ratio.denominator)
                seg = y192[start : start + N]
                out[i, j, : len(seg)] = seg
    finally:
        pra.constants.set("rir_hpf_enable", old_hpf)
    return out / (4 * np.pi), los

"""The signal design, its reach, detection and air absorption (rooms bigger than the
paper's): the reach formula against simulated windows, "no range" beyond it, the detection
threshold's false-alarm and miss rates on synthetic windows, ISO 9613-1 against the
standard's table, and the settings' round trip."""

import dataclasses
import math

import numpy as np
import pytest
from scipy.special import ndtr

import analysis
from placement.plan import LOCAL_SWARM
from simulation import Chirp, Receiver, Room, System, evaluate_layout, simulate_ranges
from simulation import air as air_model
from simulation.evaluation import RangingScene
from simulation.multipath import compute_paths
from simulation.received import received_windows
from simulation.receiver import HEARD, NOT_HEARD, OUT_OF_REACH, dsp_for
from simulation.synthesis import synthesize, synthesize_direct

TECHTILE = Room.techtile()
#: a long chirp whose 1 ms window opens at its last millisecond: reach c·89 ms
LONG = System(Chirp(duration=0.09), Receiver(t_wake=0.089))
PAPER = System()


def _overlap(signal: System, tau: np.ndarray) -> np.ndarray:
    """Seconds of a path's chirp the window holds, counted on the window's samples: the
    samples where the chirp of delay τ is on, over fs."""
    rx, ch = signal.receiver, signal.chirp
    t = rx.t_wake + np.arange(rx.window) / rx.fs
    u = t[None, :] - tau[:, None]
    return np.sum((u >= 0) & (u <= ch.duration), axis=1) / rx.fs


WIDE = System(receiver=Receiver(t_wake=0.01, window=3840))  # 20 ms of a 30 ms chirp
WHOLE = System(receiver=Receiver(t_wake=0.002, window=7680))  # 40 ms: holds whole chirps


@pytest.mark.parametrize(
    "signal", [System(), LONG, System(receiver=Receiver(t_wake=0.02)), WIDE, WHOLE]
)
def test_the_reach_is_where_the_window_stops_holding_enough_chirp(signal):
    """Derivation (simulation.system): an overlap of at least D = min(W, T, 1 ms) for τ in
    [τ_min, τ_max] and less just outside; the synthesized window of one path carries
    energy in proportion."""
    lo, hi = signal.delays
    W, T, D = signal.window_span, signal.chirp.duration, signal.min_overlap
    assert D == pytest.approx(min(W, T, 1e-3))
    assert hi == pytest.approx(signal.receiver.t_wake + max(0.0, W - D))
    step = 1 / signal.receiver.fs
    inside = np.linspace(max(lo, 0.0), hi, 7)
    outside = np.array([hi + 20 * step, hi + W / 2] + ([lo - 20 * step] if lo > 20 * step else []))
    assert np.all(_overlap(signal, inside) >= D - 1.5 * step)
    assert np.all(_overlap(signal, outside) < D - 10 * step)
    # the synthesizer agrees: the window energy of a unit path is its overlap's (½ per s)
    taus = np.concatenate([inside, outside])[:, None]
    w = synthesize(taus, np.ones_like(taus), signal.chirp, signal.receiver)
    energy = np.sum(w * w, axis=1) / signal.receiver.fs
    np.testing.assert_allclose(energy, 0.5 * _overlap(signal, taus[:, 0]), rtol=0.03, atol=2e-6)
    c = 343.0
    assert signal.reach(c) == pytest.approx(c * hi)
    assert signal.near_limit(c) == pytest.approx(c * lo)
    ranges = c * np.concatenate([inside, outside])[:, None] * [[1.0, 1.0]]  # any shape
    expected = np.concatenate([np.ones(len(inside)), np.zeros(len(outside))])[:, None] > 0
    np.testing.assert_array_equal(signal.within_reach(ranges, c), expected & [[True, True]])


def test_the_papers_design_keeps_its_reach_exactly():
    """D = W for the paper's 1 ms window: τ_max = t_wake and τ_min = 0 exactly, as
    before the overlap rule."""
    assert System().delays == (0.0, Receiver().t_wake)
    assert WIDE.reach(343.0) == pytest.approx(343.0 * (0.01 + WIDE.window_span - 1e-3))


def test_the_papers_design_reaches_ten_metres():
    """c·29 ms at 20 °C: the 10.30 m constant of the issue was an empty window."""
    c = TECHTILE.speed_of_sound
    assert PAPER.reach(c) == pytest.approx(c * 0.029)
    assert 9.9 < PAPER.reach(c) < 10.0 and PAPER.near_limit(c) == 0.0
    assert TECHTILE.diagonal < PAPER.reach(c)  # the paper's room fits


def test_noise_free_ranges_beyond_the_reach_are_no_range_and_within_it_as_before():
    """Along a 20 m hall, anechoic: ranges up to the reach are the distance (the paper's
    chain), beyond it NaN with the out-of-reach status, never a number."""
    hall = Room(size=(20.0, 12.0, 4.0), max_order=0)
    anchor = np.array([[0.03, 6.0, 2.0]])
    d = np.array([1.0, 4.0, 7.5, 9.5, 10.5, 12.0, 15.0, 19.0])
    nodes = np.stack([0.03 + d, np.full_like(d, 6.0), np.full_like(d, 2.0)], axis=1)
    r = simulate_ranges(hall, anchor, nodes, noise=False)[:, 0]
    within = d <= PAPER.reach(hall.speed_of_sound)
    assert within.sum() == 4
    np.testing.assert_allclose(r[within], d[within], atol=0.09)  # the receiver's own error
    assert np.all(np.isnan(r[~within]))
    scene = RangingScene(hall, anchor, nodes)
    _, status = scene.detect(scene.windows)
    assert np.all(status[within, 0] == HEARD) and np.all(status[~within, 0] == OUT_OF_REACH)
    # the longer chirp reaches them all
    r = simulate_ranges(hall, anchor, nodes, noise=False, system=LONG)[:, 0]
    np.testing.assert_allclose(r, d, atol=0.15)


def test_the_default_signal_leaves_every_techtile_range_as_the_receiver_chain_gives_it():
    """With the paper's design (no detection threshold, the room within the reach) the
    detection step changes no range of the techtile room, noisy or not: the default results
    stay those of the paper's chain."""
    a = TECHTILE.corners_layout()
    scene = RangingScene(TECHTILE, a)
    rng = np.random.default_rng(5)
    for windows in (scene.windows, scene.noisy_windows(rng), scene.noisy_windows(rng)):
        r, status = scene.detect(windows)
        raw = scene.dsp.ranges(windows, TECHTILE.speed_of_sound)
        assert np.all(status == HEARD)
        np.testing.assert_array_equal(r, raw)


def _noisy(dsp, clean: np.ndarray, sigma: float, n: int, rng) -> np.ndarray:
    return clean[None, :] + sigma * rng.standard_normal((n, clean.size))


def test_detection_false_alarm_rate_stays_below_its_bound():
    """Windows of noise alone: the share reported as heard is at most P_fa (the union
    bound; binomial margin of 3 standard deviations)."""
    rx = Receiver(false_alarm=0.05)
    dsp = dsp_for(Chirp(), rx)
    rng = np.random.default_rng(0)
    n = 4000
    sigma = 1.0
    windows = sigma * rng.standard_normal((n, rx.window))
    _, status = dsp.detect(windows, 343.0, sigma, System(receiver=rx).delays, 0.01)
    rate = np.mean(status == HEARD)
    assert rate <= 0.05 + 3 * math.sqrt(0.05 * 0.95 / n)
    assert rate > 0  # the threshold is not infinitely high


@pytest.mark.parametrize("margin", [-1.0, 0.0, 1.5])
def test_detection_miss_rate_follows_the_correlation_snr(margin):
    """A direct path whose correlation peak stands d noise standard deviations high is
    missed with probability between Φ(η − d − 1) and Φ(η − d) (docs/model.md,
    "Detection"): Φ(η − d) if the pick sat on the true lag; the pick is the highest of the
    neighbouring carrier peaks, which the noise lifts by a fraction of a σ."""
    rx = Receiver(false_alarm=1e-3)
    sig = System(receiver=rx)
    dsp = dsp_for(sig.chirp, rx)
    tau = 0.010
    clean = synthesize(np.array([[tau]]), np.ones((1, 1)), sig.chirp, rx)[0]
    k0, peak = dsp.picks(clean[None])
    gain = dsp.noise_gain[k0[0]]
    d = dsp.threshold + margin
    sigma = peak[0] / (d * gain)  # noise σ that puts the clean peak d standard deviations up
    rng = np.random.default_rng(1)
    n = 3000
    windows = _noisy(dsp, clean, sigma, n, rng)
    r, status = dsp.detect(windows, 343.0, sigma, sig.delays, tau)
    miss = np.mean(status == NOT_HEARD)
    upper, lower = ndtr(dsp.threshold - d), ndtr(dsp.threshold - d - 1.0)
    assert lower - 3 * math.sqrt(lower * (1 - lower) / n) <= miss
    assert miss <= upper + 3 * math.sqrt(upper * (1 - upper) / n)
    heard = status == HEARD
    assert np.all(np.isnan(r[~heard])) and np.all(np.isfinite(r[heard]))


def test_a_room_with_a_threshold_hears_fewer_anchors_far_away():
    """ISO air and a detection threshold in a long hall: the far anchor fades out; the
    simulated status and the bound's coverage agree on which nodes hear it."""
    hall = Room(size=(30.0, 6.0, 4.0), max_order=0, air_absorption="iso9613")
    system = LONG.with_signal(false_alarm=1e-3)
    anchor = np.array([[0.03, 3.0, 2.0]])
    d = np.array([2.0, 5.0, 10.0, 20.0, 29.0])
    nodes = np.stack([0.03 + d, np.full_like(d, 3.0), np.full_like(d, 2.0)], axis=1)
    scene = RangingScene(hall, anchor, nodes, system=system)
    _, status = scene.detect(scene.windows)
    heard = status[:, 0] == HEARD
    assert heard[0] and not heard[-1]  # near: heard; 29 m: faded below the threshold
    np.testing.assert_array_equal(analysis.heard(hall, anchor, nodes, system=system)[:, 0], heard)


def test_locate_from_the_heard_anchors_in_an_evaluation():
    """An evaluation of a layout in a hall: fixes where 4 anchors are heard, NaN and a
    counted no-fix elsewhere; the statistics are over the fixes and say the availability."""
    hall = Room(size=(20.0, 6.0, 3.0), max_order=1)
    a = np.array([[0.03, 0.03, 2.97], [5.0, 5.97, 2.97], [10.0, 0.03, 2.97], [15.0, 5.97, 2.0],
                  [19.97, 3.0, 2.97], [5.0, 0.03, 1.0]])  # fmt: skip
    nodes = hall.grid((10, 3, 2))
    ev = evaluate_layout(hall, a, realizations=2, rng=0, nodes=nodes)
    d = np.linalg.norm(nodes[:, None] - a[None], axis=-1)
    enough = np.sum(d <= PAPER.reach(hall.speed_of_sound), axis=1) >= 4
    assert 0 < enough.mean() < 1
    np.testing.assert_array_equal(np.isfinite(ev.errors), np.broadcast_to(enough, (2, 60)))
    assert ev.availability == pytest.approx(enough.mean())
    assert ev.stats["n"] == 2 * enough.sum() and math.isfinite(ev.std)
    assert np.all(ev.fix_status[:, ~enough] == -2)
    assert ev.to_dict()["stats"]["availability"] == ev.availability


# -- ISO 9613-1 ----------------------------------------------------------------------------
#: ISO 9613-1:1993, Table 1 (pure-tone attenuation, dB/km, 101.325 kPa) at the exact
#: one-third-octave midband frequencies 1000·10^(k/10) Hz: (°C, % RH, k, dB/km)
ISO_TABLE = [
    (20, 10, -13, 0.270),
    (20, 50, -10, 0.294),
    (20, 50, -9, 0.445),
    (20, 70, -9, 0.339),
    (20, 10, 0, 14.1),
    (20, 70, 0, 4.98),
    (20, 100, 0, 5.42),
    (20, 10, 6, 109.0),
    (20, 100, 6, 19.4),
    (0, 10, 0, 14.0),
    (0, 50, 0, 6.83),
    (10, 50, 0, 4.26),
    (30, 50, 0, 7.03),
    (-20, 100, 9, 41.1),
    (50, 70, 9, 80.3),
]


@pytest.mark.parametrize(("t", "rh", "k", "db_per_km"), ISO_TABLE)
def test_iso9613_coefficients_match_the_standards_table(t, rh, k, db_per_km):
    f = 1000.0 * 10.0 ** (k / 10.0)
    got = 1e3 * air_model.iso9613_db_per_m(f, temperature=t, humidity=rh)
    assert got == pytest.approx(db_per_km, rel=0.01)


def test_iso9613_in_the_chirps_band_is_about_three_times_the_papers_coefficient():
    db = air_model.iso9613_db_per_m(np.array([25e3, 35e3, 45e3]))
    np.testing.assert_allclose(db, [0.73, 1.13, 1.49], atol=0.01)
    paper = 0.0875 * air_model.DB_PER_NEPER
    assert paper == pytest.approx(0.38, abs=0.005)
    room = Room(air_absorption="iso9613")
    np.testing.assert_allclose(room.air_coefficient(35e3) * air_model.DB_PER_NEPER, 1.13,
                               atol=0.01)  # fmt: skip
    assert np.all(Room().air_coefficient([25e3, 45e3]) == 0.0875)


def test_iso_air_applies_across_the_band_as_the_exact_envelope():
    """The fast synthesizer's linearized air envelope against the sample-by-sample one, on
    paths over the whole band (a 20 m path, windows at the chirp's start and end)."""
    room = Room(size=(25.0, 5.0, 3.0), air_absorption="iso9613", max_order=1)
    a = np.array([[0.03, 2.5, 1.5]])
    nodes = np.array([[20.0, 2.5, 1.5], [3.0, 1.0, 1.0], [12.0, 4.0, 2.0]])
    sig = LONG
    paths = compute_paths(room, a, nodes, frequency=sig.chirp.centre)
    c = room.speed_of_sound
    air = room.air_excess(sig.chirp.centre)
    fast = received_windows(paths, c, sig.chirp, sig.receiver, air)
    exact = synthesize_direct(paths.delays(c), paths.amplitude, sig.chirp, sig.receiver,
                              lengths=paths.length, air=air)  # fmt: skip
    np.testing.assert_allclose(fast, exact, atol=1e-6 * np.abs(exact).max())
    # about 0.6 dB/m more absorbing than the paper's coefficient in the band the far
    # node's window holds (about 32 kHz): 20 m weaken it by some 12 dB in energy
    paper = dataclasses.replace(room, air_absorption=0.0875)
    plain = received_windows(compute_paths(paper, a, nodes), c, sig.chirp, sig.receiver)
    ratio_db = 10 * np.log10(np.sum(fast[0] ** 2) / np.sum(plain[0] ** 2))
    assert -16 < ratio_db < -9


# -- settings ------------------------------------------------------------------------------
def test_air_settings_round_trip_through_toml_and_the_system_beside_them(tmp_path):
    room = Room(size=(24.0, 16.0, 6.0), air_absorption="iso9613", humidity=35.0, pressure=98.0)
    system = System(Chirp(f0=30e3, f1=50e3, duration=0.06),
                    Receiver(t_wake=0.058, window=256, false_alarm=1e-4), name="long")  # fmt: skip
    path = tmp_path / "hall.toml"
    room.to_toml(path)
    text = path.read_text()
    assert 'air_absorption = "iso9613"' in text and "signal" not in text
    table = system.to_dict()
    text += '\n[system]\nname = "long"\n'
    for part in ("signal", "receiver"):
        text += f"\n[system.{part}]\n" + "".join(
            f"{k} = {v!r}\n" for k, v in table[part].items() if v is not None
        )
    path.write_text(text.replace("'", '"'))
    back = Room.from_toml(path)
    assert back.to_dict() == room.to_dict()
    assert System.from_toml(path) == system
    # the paper's room writes no signal: its dictionary is unchanged
    assert "signal" not in Room.techtile().to_dict()
    assert "humidity" not in Room.techtile().to_dict()


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: Room(humidity=120.0), "humidity"),
        (lambda: Room(humidity=-1.0), "humidity"),
        (lambda: Room(pressure=0.0), "pressure"),
        (lambda: Room(air_absorption="iso"), "air_absorption"),
        (lambda: System(Chirp(f0=45e3, f1=25e3)), "chirp"),  # inverted band
        (lambda: System(Chirp(f0=25e3, f1=120e3)), "chirp"),  # above fs/2
        (lambda: System(receiver=Receiver(t_wake=0.0, window=20000)).check_room(Room()), "window"),
        (lambda: Receiver(pick="last"), "pick"),
        (lambda: Receiver(first_path_ratio=0.0), "first_path_ratio"),
        (lambda: Receiver(first_path_noise=-1.0), "first_path_noise"),
        (lambda: Chirp(duration=0.0), "duration"),
        (lambda: Chirp(duration=-0.03), "duration"),
        (lambda: Chirp(duration=5.0), "duration"),  # seconds of chirp
        (
            lambda: System(Chirp(duration=1.0, f1=450e3), Receiver(fs=10e6)),
            "chirp duration x fs x window",
        ),  # a DSP of tens of GB: refused before any work
        (lambda: Receiver(false_alarm=0.0), "false_alarm"),
        (lambda: Receiver(false_alarm=0.7), "false_alarm"),
        (lambda: System.from_dict({"signal": {"duration": 0.05, "bogus": 1}}), "system.signal"),
        (
            lambda: Room.from_dict({"size": [8, 4, 2.4], "signal": {"duration": 0.05}}),
            "system.signal",
        ),
    ],  # fmt: skip
)
def test_bad_signal_and_air_settings_are_refused(make, name):
    with pytest.raises(ValueError, match=name):
        make()


# -- planning for availability -------------------------------------------------------------
def _long_room() -> Room:
    """A 22 × 4 × 3 m corridor: the paper's design (reach 9.95 m) leaves its ends without
    4 anchors unless they are spread along it."""
    return Room(size=(22.0, 4.0, 3.0), max_order=1,
                zones=[{"min": [0.5, 1.0, 1.0], "max": [21.5, 3.0, 1.0]}],
                zone_spacing=3.5)  # fmt: skip


def test_the_plan_scores_availability_first_and_says_so(caplog):
    import placement
    from placement.simselect import SearchOptions
    from placement.validation import ValidationOptions

    room = _long_room()
    search = SearchOptions(spacing=2.0, chains=2, evaluations=120, random_starts=6,
                           neighbours=12, batch=6, patience=4, fine_spacings=())  # fmt: skip
    quick = ValidationOptions(realizations=2, held_out_realizations=1, random_nodes=20,
                              mount_draws=1)  # fmt: skip
    with caplog.at_level("WARNING", logger="placement"):
        res = placement.seed_then_pso(room, 8, rng=0, search=search, validation=quick,
                                      swarm=dataclasses.replace(LOCAL_SWARM, particles=3),
                                      progress=False)  # fmt: skip
    assert "larger than the signal's reach" in caplog.text
    reach = res.settings.reach
    assert reach["exceeded"] and reach["reach_m"] == pytest.approx(PAPER.reach(room.speed_of_sound))
    v = res.validation
    for block in (v, v.held_out.grid, v.held_out.random, v.mounting):
        assert 0 <= block.availability <= 1
    # the planned layout hears 4 anchors at more nodes than a layout bunched at one end
    planned = analysis.covered_share(room, res.anchors, room.grid())
    bunched = np.array([[1.0, 0.03, 2.0], [3.0, 0.03, 2.97], [5.0, 3.97, 2.0], [2.0, 3.97, 1.0],
                        [4.0, 2.0, 2.97], [6.0, 0.03, 1.0], [7.0, 3.97, 2.5],
                        [8.0, 2.0, 2.97]])  # fmt: skip
    assert planned > analysis.covered_share(room, bunched, room.grid())
    assert v.availability == 1.0
    # the paper's room fits its signal: no warning, nothing exceeded
    from placement.plan import reach_check

    assert not reach_check(TECHTILE, PAPER)["exceeded"]


def test_the_sweep_recommends_the_smallest_m_with_the_availability():
    from placement.anchor_sweep import SweepRow, recommend

    def row(M, availability, p95):
        return SweepRow(M, 0.5, 0.6, p95, 0.5, 1.0, 0.5, 1.0, np.zeros((M, 3)), 1.0,
                        availability)  # fmt: skip

    rows = [row(4, 0.80, 1.0), row(5, 0.995, 2.5), row(6, 0.999, 1.5), row(7, 1.0, 1.2)]
    assert recommend(rows, None, 0.99) == 5
    assert recommend(rows, 2.0, 0.99) == 6
    assert recommend(rows, 1.3, 0.999) == 7
    assert recommend(rows, 1.0, 0.99) is None


def test_the_cli_prints_the_signal_and_the_availability(tmp_path, capsys):
    from placement.cli import main

    room = tmp_path / "corridor.toml"
    _long_room().to_toml(room)
    layout = tmp_path / "layout.json"
    layout.write_text('{"anchors": [[0.03, 1, 2.9], [0.03, 3, 1], [4, 0.03, 2.9], '
                      '[4, 3.97, 1], [8, 2, 2.97], [11, 0.03, 2]]}')  # fmt: skip
    out = tmp_path / "ev"
    argv = ["evaluate", "--layout", str(layout), "--room", str(room), "--out", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "reach 9.95 m" in text and "availability" in text and "without a fix" in text
    # a longer chirp on the command line reaches the whole corridor
    assert main([*argv, "--chirp-duration", "0.09", "--t-wake", "0.089"]) == 0
    text = capsys.readouterr().out
    assert "reach 30.55 m" in text and "availability 100 %" in text
    assert main([*argv, "--window", "20000"]) == 2
    assert "--window" in capsys.readouterr().err


def test_coverage_counts_the_anchors_heard_and_the_bound_ignores_the_rest():
    room = _long_room()
    a = np.array([[0.03, 1.0, 2.9], [0.03, 3.0, 1.0], [4.0, 0.03, 2.9], [4.0, 3.97, 1.0],
                  [21.97, 2.0, 2.0]])  # fmt: skip
    nodes = np.array([[2.0, 2.0, 1.0], [15.0, 2.0, 1.0]])
    d = np.linalg.norm(nodes[:, None] - a[None], axis=-1)
    reach = PAPER.reach(room.speed_of_sound)
    np.testing.assert_array_equal(analysis.coverage(room, a, nodes), np.sum(d <= reach, 1))
    s = analysis.heard_sigma(room, a, nodes, 0.04)
    assert np.all(np.isinf(s[d > reach])) and np.all(s[d <= reach] == 0.04)
    pebs = analysis.peb(a, nodes, sigma=s)
    assert np.isfinite(pebs[0]) and np.isinf(pebs[1])  # one anchor heard at 15 m: no bound
    # in the paper's room every anchor is heard everywhere: the PEB is the constant-σ one
    t = TECHTILE.corners_layout()
    g = TECHTILE.grid()
    np.testing.assert_array_equal(
        analysis.peb(t, g, sigma=analysis.heard_sigma(TECHTILE, t, g, 0.04)),
        analysis.peb(t, g, sigma=0.04),
    )

"""The receiver as a design setting: long windows (their FFT form and synthesis), the
first-path pick, and every valid setting giving a range or "no range"."""

import dataclasses

import numpy as np
import pytest

from simulation import Chirp, Receiver, Room, System
from simulation.evaluation import RangingScene, evaluate_layout
from simulation.multipath import compute_paths
from simulation.received import received_windows
from simulation.receiver import HEARD, OUT_OF_REACH, Dsp, dsp_for, reference_chain
from simulation.synthesis import synthesize, synthesize_direct

ALL = ("floor", "ceiling", "south", "north", "west", "east")
CH = Chirp()
C = 343.0
TECHTILE = Room.techtile()
ORDINARY = Room(absorption={k: 0.2 for k in ALL})  # the techtile box without absorbers
ANECHOIC = Room(absorption={k: 1.0 for k in ALL})
W20 = Receiver(window=3840, t_wake=0.01)  # 20 ms from 10 ms
EIGHT = np.array(
    [[0.03, 0.5, 2.0], [7.97, 3.5, 2.0], [4.0, 0.03, 0.6], [4.0, 3.97, 0.6],
     [1.5, 3.97, 2.37], [6.5, 0.03, 2.37], [0.03, 3.0, 0.4], [7.97, 1.0, 0.4]]
)  # fmt: skip


def _with(**rx) -> System:
    """The paper's system with the receiver's fields ``rx`` changed."""
    return System(receiver=Receiver(**rx))


def _random_windows(rx: Receiver, rng, n=24):
    """Windows of 1–6 paths anywhere in [0, 30] ms of delay, some with noise."""
    tau = rng.uniform(0.0, 0.03, (n, 6))
    amp = rng.uniform(0.05, 1.0, (n, 6)) * (rng.random((n, 6)) < 0.8)
    amp[:, 0] = 1.0
    w = synthesize_direct(tau, amp, CH, rx)
    return w + rng.choice([0.0, 0.02, 0.2], n)[:, None] * rng.standard_normal(w.shape)


@pytest.mark.parametrize("window", [1920, 3840])
def test_fft_form_gives_the_matrix_form_and_the_reference_index(window):
    """The long-window DSP (high-pass as a kernel plus end corrections, correlation and
    low-pass by FFT) computes the same map as the one-matrix form, and the literal
    chain's index."""
    rx = Receiver(window=window, t_wake=0.005)
    w = _random_windows(rx, np.random.default_rng(window))
    fft, matrix = Dsp(CH, rx, "float64", "fft"), Dsp(CH, rx, "float64", "matrix")
    assert fft.form == "fft" and dsp_for(CH, rx).form == "fft"
    cf, cm = fft.correlation(w), matrix.correlation(w)
    np.testing.assert_allclose(cf, cm, rtol=0, atol=1e-12 * cm.max())
    g = matrix.noise_gain
    np.testing.assert_allclose(fft.noise_gain, g, rtol=1e-10, atol=1e-12 * g.max())
    k = fft.indices(w)
    assert np.array_equal(k, matrix.indices(w))
    for i in range(0, len(w), 6):
        assert k[i] == reference_chain(w[i], CH, rx)["k"]
    assert np.array_equal(Dsp(CH, rx, "float32").indices(w), k)


@pytest.mark.parametrize("rx", [Receiver(), Receiver(window=1920, t_wake=0.005)])
def test_picks_the_same_with_the_kept_buffer(rx, monkeypatch):
    """Each thread keeps its correlation buffer from call to call (both forms): the picks
    are those of a fresh buffer whatever earlier calls left in it, its columns past the
    correlation stay zero, and another thread has its own."""
    import threading

    from simulation import receiver

    dsp = Dsp(CH, rx, "float32")
    w = _random_windows(rx, np.random.default_rng(11), n=40)
    other = _random_windows(rx, np.random.default_rng(12), n=60) * 3.0
    monkeypatch.setattr(receiver, "_BUFFERS", threading.local())
    fresh = dsp.picks(w[:25], sigma=0.01)
    dsp.picks(other, sigma=0.01)  # a longer part: the buffer grows and holds other rows
    kept = dsp.picks(w[:25], sigma=0.01)
    assert np.array_equal(kept[0], fresh[0]) and np.array_equal(kept[1], fresh[1])
    # a part of other rows: the same indices; the peaks to single precision's rounding (the
    # BLAS blocks a product by its rows)
    kept = dsp.picks(w, sigma=0.01)
    assert np.array_equal(kept[0][:25], fresh[0])
    np.testing.assert_allclose(kept[1][:25], fresh[1], rtol=1e-6)
    buf = receiver._BUFFERS.parts[np.dtype(np.float32).str]
    assert buf.shape[0] == 60 and not buf[:, dsp.n_corr :].any()
    assert buf[:, : dsp.n_corr].any()  # it holds the last part's correlation
    theirs = []
    t = threading.Thread(target=lambda: theirs.append(receiver._part_buffer(5, dsp.nfft, "<f4")))
    t.start()
    t.join()
    assert not np.shares_memory(theirs[0], buf)
    # another width replaces the kept buffer (one per thread and precision)
    assert receiver._part_buffer(5, dsp.nfft + 2, "<f4").shape == (5, dsp.nfft + 2)
    assert not np.shares_memory(receiver._BUFFERS.parts["<f4"], buf)


def test_the_papers_receiver_keeps_its_chain():
    """The default receiver runs the one-matrix DSP and the short-window synthesis: the
    paper's results do not move."""
    assert dsp_for().form == "matrix"
    assert System().delays == (0.0, Receiver().t_wake)
    assert Receiver().pick == "paper"


@pytest.mark.parametrize("rx", [W20, Receiver(window=7680, t_wake=0.002)])
def test_long_window_synthesis_equals_direct_evaluation(rx):
    room = ORDINARY
    paths = compute_paths(room, EIGHT[:4], room.grid()[::9])
    tau = paths.delays(room.speed_of_sound)
    fast = synthesize(tau, paths.amplitude, CH, rx)
    slow = synthesize_direct(tau, paths.amplitude, CH, rx)
    scale = np.abs(slow).max(axis=-1, keepdims=True)
    assert np.all(np.abs(fast - slow) <= 1e-10 * scale)
    # frequency-dependent air: the envelope linearized over each path's part of the chirp
    room = dataclasses.replace(room, air_absorption="iso9613")
    air = room.air_excess(CH.centre)
    fast = synthesize(tau, paths.amplitude, CH, rx, lengths=paths.length, air=air)
    slow = synthesize_direct(tau, paths.amplitude, CH, rx, lengths=paths.length, air=air)
    assert np.all(np.abs(fast - slow) <= 0.01 * scale)


@pytest.mark.parametrize("window,t_wake", [(192, 0.029), (3840, 0.01)])
def test_first_path_equals_the_papers_pick_without_echoes(window, t_wake):
    """Anechoic room: one arrival per window, so the earliest that stands out is the
    strongest: the same pick on every noise-free window. With noise, a sidelobe of a far
    (faint) anchor can rise above the first-path floor: still the same pick on 99.5 %."""
    room, system = ANECHOIC, _with(window=window, t_wake=t_wake)
    scene = RangingScene(room, EIGHT, room.grid()[::3], system=system)
    first = dataclasses.replace(system.receiver, pick="first-path")
    paper, fp = dsp_for(CH, system.receiver), dsp_for(CH, first)
    for w, share in ((scene.windows, 1.0), (scene.noisy_windows(np.random.default_rng(1)), 0.995)):
        sigma = np.broadcast_to(scene.noise_sigma, w.shape[:-1])
        assert np.mean(paper.indices(w) == fp.picks(w, sigma=sigma)[0]) >= share


def test_first_path_finds_the_direct_path_under_a_stronger_echo():
    """A direct path at 3 m and an echo 1 m later, 1.5× stronger (a speaker aimed away):
    the paper's pick takes the echo, the first-path pick the direct path, as the literal
    chain does."""
    tau = np.array([[3.0, 4.0]]) / C
    w = synthesize(tau, np.array([[1.0, 1.5]]), CH, W20)
    fp = dataclasses.replace(W20, pick="first-path")
    r_paper = dsp_for(CH, W20).ranges(w, C)[0]
    k_fp = dsp_for(CH, fp).indices(w)
    assert abs(r_paper - 4.0) < 0.02
    assert abs(fp.range_from_index(k_fp, C)[0] - 3.0) < 0.02
    assert k_fp[0] == reference_chain(w[0], CH, fp)["k"]


def test_first_path_noise_test_matches_the_reference_chain():
    """With a noise σ, a peak must also stand κ times above the noise-only mean of the
    low-passed curve: the DSP and the literal chain agree on noisy windows."""
    rx = Receiver(window=1920, t_wake=0.01, pick="first-path", first_path_ratio=0.2)
    rng = np.random.default_rng(4)
    w = _random_windows(rx, rng, 12)
    sigma = 0.2
    k = dsp_for(CH, rx, "float64").picks(w, sigma=np.full(len(w), sigma))[0]
    for i in range(0, len(w), 3):
        assert k[i] == reference_chain(w[i], CH, rx, sigma=sigma)["k"]


@pytest.mark.parametrize("pick", ["paper", "first-path"])
@pytest.mark.parametrize(
    "window,t_wake", [(5760, 0.0), (5761, 0.0), (192, 0.0), (960, 0.0), (3840, 0.02), (9600, 0.0)]
)
def test_no_valid_setting_raises_and_ranges_are_sensible(window, t_wake, pick):
    """The hard-walled room with the window opening with the chirp (the −2.69 m ranges
    that made ``locate`` raise) and other corners of the settings: every pair gets a
    range or "no range", never a negative one, and every node is located or not."""
    room, system = ORDINARY, _with(window=window, t_wake=t_wake, pick=pick)
    nodes = room.grid()[::9]
    ev = evaluate_layout(room, EIGHT, realizations=1, rng=0, nodes=nodes, system=system)
    r = np.asarray(ev.ranges)
    assert np.all(np.isnan(r) | (r >= 0))
    status = np.asarray(ev.range_status)
    assert np.all(np.isnan(r) == (status != HEARD))
    assert set(np.unique(status)) <= {HEARD, OUT_OF_REACH, 1}
    err = np.asarray(ev.errors)
    assert np.all(np.isnan(err) | (err >= 0))


def test_a_long_window_sees_ranges_the_papers_cannot():
    """Noise-free, anechoic, a 20 ms window: ranges to the reach (9.95 m) are the distance."""
    hall = Room(size=[12.0, 3.0, 3.0], absorption={k: 1.0 for k in ALL})
    system = _with(window=3840, t_wake=0.01)
    a = np.array([[0.03, 1.5, 1.5]])
    nodes = np.stack([np.linspace(1.0, 9.5, 9), np.full(9, 1.5), np.full(9, 1.5)], axis=1)
    paths = compute_paths(hall, a, nodes)
    w = received_windows(paths, hall.speed_of_sound, system.chirp, system.receiver)
    r = dsp_for(CH, system.receiver).ranges(w, hall.speed_of_sound)[:, 0]
    np.testing.assert_allclose(r, nodes[:, 0] - 0.03, atol=0.01)


def test_closing_windows_are_the_studys_designs():
    """A window of W closing with the chirp: 1 ms is the paper's receiver exactly, the
    whole chirp opens with it."""
    from simulation.system import closing_window

    assert closing_window(System(), 1e-3).receiver == System().receiver
    s = closing_window(System(), 20e-3, "first-path")
    assert (s.receiver.window, s.receiver.t_wake, s.receiver.pick) == (3840, 0.01, "first-path")
    assert closing_window(System(), 30e-3).receiver.t_wake == 0.0
    with pytest.raises(ValueError, match="window"):
        closing_window(System(), 0.05)


def test_the_sweep_command_takes_receiver_designs(capsys):
    """``anchorplan sweep --windows ... --picks ...`` builds one room per design; a bad
    window names the flag."""
    import argparse

    from placement.cli.sweep import designs

    args = argparse.Namespace(windows=[1.0, 20.0], picks=["paper", "first-path"])
    systems = designs(args, TECHTILE, System())
    assert list(systems) == ["1ms-paper", "1ms-first-path", "20ms-paper", "20ms-first-path"]
    assert systems["1ms-paper"].receiver == System().receiver
    assert systems["20ms-first-path"].receiver.window == 3840
    with pytest.raises(ValueError, match="--windows"):
        designs(argparse.Namespace(windows=[40.0], picks=None), TECHTILE, System())
    with pytest.raises(ValueError, match="--picks"):
        designs(argparse.Namespace(windows=None, picks=["paper"]), TECHTILE, System())

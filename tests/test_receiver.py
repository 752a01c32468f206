import numpy as np
import pytest
import scipy.fft
import scipy.linalg
import scipy.signal

from simulation import Chirp, Receiver, Room
from simulation.evaluation import RangingScene
from simulation.multipath import compute_paths
from simulation.noise import noise_sigma
from simulation.received import received_windows
from simulation.receiver import (
    NEAR_TOP,
    SINGLE_MARGIN_LOWPASSED,
    _Margins,
    _snap_rows,
    dsp_for,
    reference_chain,
    snap_to_peak,
)
from simulation.synthesis import synthesize, synthesize_direct

ALL = ("floor", "ceiling", "south", "north", "west", "east")
ANECHOIC = Room(absorption={k: 1.0 for k in ALL})
RX, CH = Receiver(), Chirp()
C = Room.techtile().speed_of_sound


def _single_path_windows(d, amp=1.0):
    d = np.atleast_1d(np.asarray(d, dtype=float))
    return synthesize((d / C)[:, None], np.full((len(d), 1), amp), CH, RX)


def _mixed_windows(rng, n_noisy=2):
    """Anechoic, reverberant and noisy windows from a few layouts (W, N)."""
    room = Room.techtile()
    nodes = room.grid()[rng.choice(270, 12, replace=False)]
    out = []
    for r in (ANECHOIC, room):
        w = received_windows(compute_paths(r, r.corners_layout(), nodes), C)
        out.append(w.reshape(-1, RX.window))
    s = noise_sigma(room, room.corners_layout())
    w = out[-1].reshape(12, 4, -1)
    for _ in range(n_noisy):
        out.append((w + s[:, None] * rng.standard_normal(w.shape)).reshape(-1, RX.window))
    return np.concatenate(out)


def test_fast_synthesis_equals_direct_evaluation():
    for room in (Room.techtile(), Room(absorption={k: 0.2 for k in ALL})):
        paths = compute_paths(room, room.corners_layout(), room.grid()[::5])
        tau = paths.delays(room.speed_of_sound)
        fast = synthesize(tau, paths.amplitude, CH, RX)
        slow = synthesize_direct(tau, paths.amplitude, CH, RX)
        scale = np.abs(slow).max(axis=-1, keepdims=True)
        assert np.all(np.abs(fast - slow) <= 1e-10 * scale)


def test_single_path_window_is_the_delayed_chirp():
    t = RX.window_times
    # fully inside, chirp starting inside the window (d > c·t_wake), after the window
    for d in (0.5, 4.321, 9.96, 10.1, 10.5):
        y = _single_path_windows(d, amp=0.7)[0]
        assert np.allclose(y, 0.7 * CH(t - d / C), rtol=0, atol=1e-12)
    assert np.all(_single_path_windows(10.5) == 0)  # arrives after the window closes


def test_fast_dsp_gives_the_reference_index():
    rng = np.random.default_rng(7)
    w = _mixed_windows(rng)[::3]  # ~64 windows, every kind
    dsp = dsp_for()
    k = dsp.indices(w)
    curve = dsp.correlation(w)
    lp = dsp.lowpass(curve)
    for i in range(len(w)):
        ref = reference_chain(w[i])
        assert k[i] == ref["k"]
        np.testing.assert_allclose(curve[i], ref["corr"], rtol=0, atol=1e-9 * ref["corr"].max())
        np.testing.assert_allclose(
            lp[i], ref["lowpassed"], rtol=0, atol=1e-9 * ref["lowpassed"].max()
        )
    # blocking does not change anything
    assert np.array_equal(dsp.indices(w, block=7), k)


def _matrix_form_indices(w):
    """Steps 1–2 as one (Nc, N) matrix built here from scratch, full-rate low-pass argmax:
    the chain in plain chunks, without the DSP's parts, blocks and threads."""
    ref = CH.samples(RX.fs)
    N = RX.window
    H = scipy.signal.sosfiltfilt(RX.highpass_sos(), np.eye(N), axis=0)
    T = scipy.linalg.toeplitz(np.r_[ref, np.zeros(N - 1)], np.zeros(N))  # T[k, m] = ref[k − m]
    G = (T @ H[::-1]).T
    dsp = dsp_for()
    out = []
    for part in np.array_split(w, -(-len(w) // 256)):
        curve = np.abs(part @ G)
        out.append(snap_to_peak(curve, np.argmax(dsp.lowpass(curve), axis=1), dsp.snap_width))
    return np.concatenate(out)


def _two_lobe_windows(rng, n):
    """Two paths of nearly equal amplitude (competing low-pass lobes), some with noise."""
    d1 = rng.uniform(0.5, 9.0, n)
    d2 = np.clip(d1 + rng.uniform(0.05, 4.0, n) * rng.choice([-1, 1], n), 0.1, 9.9)
    amp = np.stack([np.ones(n), 1 + 0.02 * rng.standard_normal(n)], axis=1)
    w = synthesize(np.stack([d1, d2], axis=1) / C, amp, CH, RX)
    level = rng.choice([0.0, 0.03, 0.3], n)[:, None] * np.abs(w).max(axis=1, keepdims=True)
    return w + level * rng.standard_normal(w.shape)


def test_dsp_gives_the_matrix_form_and_reference_index_on_simulated_scenes():
    """Several thousand reverberant windows, clean and noisy, from two layouts on the
    270-node grid: the parted, blocked, threaded DSP gives the index of the one-matrix form
    computed independently here, and of the literal chain on a sample."""
    rng = np.random.default_rng(2024)
    room = Room.techtile()
    parts = []
    inside = rng.uniform(0.03, np.array(room.size) - 0.03, (8, 3))  # 8 anchors anywhere
    for anchors, n_noisy in ((room.corners_layout(), 2), (inside, 1)):
        scene = RangingScene(room, anchors)
        parts.append(scene.windows.reshape(-1, RX.window)[::2])
        parts += [scene.noisy_windows(rng).reshape(-1, RX.window) for _ in range(n_noisy)]
    w = np.concatenate(parts)
    assert len(w) > 4000
    dsp = dsp_for()
    k = dsp.indices(w)
    assert np.array_equal(k, _matrix_form_indices(w))
    sub = rng.choice(len(w), 1500, replace=False)
    with scipy.fft.set_workers(2):  # blocks on two threads, another block size: same result
        assert np.array_equal(dsp.indices(w[sub], block=100), k[sub])
    for i in sub[:40]:
        assert k[i] == reference_chain(w[i])["k"]


def test_dsp_with_competing_lobes():
    """Two paths of nearly equal amplitude (two low-pass lobes of nearly equal height): the
    DSP still gives the one-matrix form's index."""
    w = _two_lobe_windows(np.random.default_rng(5), 1500)
    dsp = dsp_for()
    assert np.array_equal(dsp.indices(w), _matrix_form_indices(w))
    with pytest.raises(ValueError, match="block"):
        dsp.indices(w, block=0)


def test_float32_dsp_gives_the_float64_index():
    """Single precision redoes in double every window whose pick its rounding could
    change: the index is the double-precision chain's, window for window."""
    rng = np.random.default_rng(3)
    w = np.concatenate([_mixed_windows(rng, n_noisy=8) for _ in range(4)])
    k64 = dsp_for().indices(w)
    k32 = dsp_for(precision="float32").indices(w)
    assert len(w) > 1500
    assert np.array_equal(k64, k32)
    with pytest.raises(ValueError, match="precision"):
        dsp_for(precision="float16")


def _windows_at_ties(dsp, n=200, bisections=25):
    """Windows (W, N) of a path and an echo whose distance lies within 2e-7 m of a change
    of ``dsp``'s index: the chain's decisions there are as close as they come."""

    def windows(d):
        tau = np.stack([d, d + 0.05], axis=-1) / C
        return synthesize(tau, np.broadcast_to([1.0, 0.3], tau.shape), CH, dsp.receiver)

    d = 3.0 + np.linspace(0, 12 * C / RX.fs, n)
    k = dsp.indices(windows(d))
    at = np.flatnonzero(np.diff(k))
    lo, hi = d[at], d[at + 1]
    for _ in range(bisections):
        mid = 0.5 * (lo + hi)
        left = dsp.indices(windows(mid)) == k[at]
        lo, hi = np.where(left, mid, lo), np.where(left, hi, mid)
    return windows((lo[:, None] + np.linspace(-2e-7, 2e-7, 21)).ravel())


@pytest.mark.parametrize(
    "rx",
    [RX, Receiver(pick="first-path"), Receiver(window=3840, t_wake=0.01, pick="first-path")],
    ids=["paper", "first-path", "20-ms-fft-form"],
)
def test_another_cpus_rounding_cannot_move_a_pick(rx, monkeypatch):
    """Another CPU rounds the single-precision chain differently (another BLAS kernel,
    another FFT). At windows whose double-precision decisions are as close as they come,
    single precision rounded as this CPU rounds, and as a CPU whose matrix entries differ
    by 4 ulp would, gives the double-precision index; without its margins it would not."""
    from simulation import receiver
    from simulation.receiver import Dsp

    exact = Dsp(CH, rx, "float64")
    w = _windows_at_ties(exact)
    k64 = exact.indices(w)
    rng = np.random.default_rng(11)
    for trial in range(3 if exact.form == "matrix" else 1):
        single = Dsp(CH, rx, "float32")
        if trial:
            g, ulp = single._G.astype(float), np.spacing(np.abs(single._G)).astype(float)
            single._G = (g + 4 * ulp * rng.uniform(-1, 1, g.shape)).astype(np.float32)
        assert np.array_equal(single.indices(w), k64), trial
    monkeypatch.setattr(receiver, "SINGLE_MARGIN_LOWPASSED", 0.0)
    monkeypatch.setattr(receiver, "SINGLE_MARGIN_RAW", 0.0)
    assert not np.array_equal(Dsp(CH, rx, "float32").indices(w), k64)  # the test can fail


def test_single_precision_detection_is_the_double_precisions(monkeypatch):
    """The detection threshold's decision is checked against the margins too: with a
    threshold, single precision hears exactly the windows double precision hears, also
    for peaks within 2e-6 of the threshold (without the margins it would not)."""
    from simulation import receiver

    rx = Receiver(false_alarm=1e-3)
    rng = np.random.default_rng(4)
    w = np.concatenate([_mixed_windows(rng, n_noisy=4) for _ in range(2)])
    room = Room.techtile()
    sigma = np.resize(noise_sigma(room, room.corners_layout()), len(w))
    # scale the windows so that their peaks straddle the threshold
    from simulation.receiver import Dsp

    exact = Dsp(CH, rx, "float64")
    k, peak = exact.picks(w, sigma=sigma)
    level = exact.threshold * sigma * exact.noise_gain[k]
    w = w * (level / peak * rng.uniform(1 - 2e-6, 1 + 2e-6, len(w)))[:, None]
    k64, p64 = exact.picks(w, sigma=sigma)
    k32, p32 = Dsp(CH, rx, "float32").picks(w, sigma=sigma)
    level = exact.threshold * sigma * exact.noise_gain[k64]
    assert np.array_equal(k32, k64)
    assert np.array_equal(p32 > level, p64 > level)
    assert 0.2 < np.mean(p64 > level) < 0.8
    monkeypatch.setattr(receiver, "SINGLE_MARGIN_RAW", 0.0)
    p32 = Dsp(CH, rx, "float32").picks(w, sigma=sigma)[1]
    assert not np.array_equal(p32 > level, p64 > level)  # the test can fail


def test_range_formula_and_wake_time_with_an_oracle_seed():
    """Snapping the true correlation index to the nearest raw peak recovers the range to
    half a sample: checks synthesis, the correlation convention, t_wake and r = c·τ."""
    d = np.linspace(0.05, 9.9, 1500)
    w = _single_path_windows(d)
    dsp = dsp_for()
    k_true = RX.index_from_range(d, C)
    k = snap_to_peak(dsp.correlation(w), np.round(k_true).astype(int))
    err = RX.range_from_index(k, C) - d
    assert np.max(np.abs(err)) <= C / RX.fs / 2 + 1e-5
    assert RX.range_from_index(RX.index_from_range(3.3, C), C) == pytest.approx(3.3)


def test_anechoic_grid_ranges_reference_chain():
    """Noise-free, anechoic: the receiver chain's ranges are within centimetres of the truth.

    Not millimetres: the 1 ms window holds a ~667 Hz slice of the sweep, so the envelope
    of |c| is flat over ±100 samples, and sampling |c| at 192 kHz aliases its harmonics at
    2m·f_c onto the 5 kHz low-pass band (worst when f_c ≈ fs/6 = 32 kHz or fs/5). The
    low-pass argmax moves by a few samples and snaps onto a neighbouring carrier peak
    (≈ 2–7 samples apart).
    """
    nodes, anchors = ANECHOIC.grid(), ANECHOIC.corners_layout()
    w = received_windows(compute_paths(ANECHOIC, anchors, nodes), C)
    dsp = dsp_for()
    k = dsp.indices(w)
    r = RX.range_from_index(k, C)
    d = np.linalg.norm(nodes[:, None] - anchors[None], axis=-1)
    err = np.abs(r - d)
    assert np.max(err) <= 0.15
    assert np.median(err) <= 0.015
    # every estimate is a local maximum of the raw curve
    curve = dsp.correlation(w.reshape(-1, RX.window))
    kk = k.ravel()
    rows = np.arange(len(kk))
    assert np.all(curve[rows, kk] >= curve[rows, kk - 1])
    assert np.all(curve[rows, kk] >= curve[rows, kk + 1])


def test_anechoic_error_peaks_where_carrier_harmonics_alias():
    d = np.linspace(0.3, 9.5, 3000)
    fc = CH.f0 + CH.rate * (RX.t_wake + RX.window / RX.fs / 2 - d / C)
    err = np.abs(dsp_for().ranges(_single_path_windows(d), C) - d)
    near_fs6 = np.abs(fc - RX.fs / 6) < 500
    clean = (fc > 40e3) & (fc < 43e3)
    assert np.median(err[near_fs6]) > 2 * np.median(err[clean])


def test_snap_to_peak_nearest_and_ties():
    x = np.array([[0, 1, 0, 0, 2, 0, 0, 0, 0], [0, 3, 1, 0, 0, 0, 1, 3, 0]], dtype=float)
    assert snap_to_peak(x, np.array([3, 4])).tolist() == [4, 1]  # 2 vs 2 away: lower wins
    assert snap_to_peak(x, np.array([0, 8])).tolist() == [1, 7]
    flat = np.zeros((1, 9))
    assert snap_to_peak(flat, np.array([5])).tolist() == [5]  # no peak: unchanged


def _runner_up_vectorized(margin, values, k, curve, width, near_top=NEAR_TOP):
    """The single-precision margins' runner-up test as numpy array operations (the form
    :func:`simulation.receiver._runner_up_rows` compiles), with its batch-wide search span."""
    rows, n = np.arange(len(k))[:, None], values.shape[1]
    local = np.clip(k[:, None] + np.arange(-near_top, near_top + 1), 0, n - 1)
    near_values = values[rows, local]
    masked = values.copy()
    masked[rows, local] = -np.inf
    floor = (values[rows[:, 0], k].astype(float) - margin.lowpassed)[:, None]
    near = near_values >= floor
    first = np.argmax(near, axis=1)
    last = near.shape[1] - 1 - np.argmax(near[:, ::-1], axis=1)
    unsure = (masked.max(axis=1) >= floor[:, 0]) | (near.sum(axis=1) != last - first + 1)
    unsure |= (first == 0) | (last == near.shape[1] - 1)
    first, last = local[rows[:, 0], first], local[rows[:, 0], last]
    unsure |= snap_to_peak(curve, first, width) != snap_to_peak(curve, last, width)
    span = int(np.max(last - first)) if len(first) else 0
    idx = first[:, None] + np.arange(-width - 2, span + width + 3)
    inside = idx[:, 1:-2] <= (last + width + 1)[:, None]
    v = curve[rows, np.clip(idx, 0, n - 1)].astype(float)
    m, d = margin.curve[:, None], np.diff(v, axis=1)
    flat_top = (np.abs(d[:, 1:-1]) <= m) & (d[:, :-2] >= -m) & (d[:, 2:] <= m)
    return unsure | np.any(flat_top & inside, axis=1)


@pytest.mark.parametrize("seed", range(4))
def test_compiled_margins_equal_their_vectorized_form(seed):
    """The compiled runner-up test and snap decide as their numpy form, bit for bit: on
    smooth tops, quantized curves (level pairs and ties), −inf runs (the first-path pick's),
    NaN, either precision, strided rows, and indices at the ends."""
    rng = np.random.default_rng(seed)
    for _ in range(150):
        B, n = int(rng.integers(1, 24)), int(rng.integers(3, 400))
        dt = rng.choice([np.float32, np.float64])
        x = np.arange(n)[None]
        lp = np.exp(-(((x - rng.uniform(0, n, (B, 1))) / rng.uniform(1, 400, (B, 1))) ** 2))
        lp = np.round(lp / 10.0 ** rng.integers(-7, -1)) * 10.0 ** rng.integers(-7, -1)
        curve = np.abs(np.sin(np.pi * x / rng.uniform(2.2, 4, (B, 1)))) * (lp + 0.1)
        q = 10.0 ** rng.integers(-7, -2)
        lp, curve = lp.astype(dt), (np.round(curve / q) * q).astype(dt)
        if rng.random() < 0.2:
            lp[:, : int(rng.integers(0, n))] = -np.inf
        if rng.random() < 0.2:
            lp[rng.integers(0, B), rng.integers(0, n)] = np.nan
            curve[rng.integers(0, B), rng.integers(0, n)] = np.nan
        if rng.random() < 0.5:  # rows of a wider buffer, as the DSP's
            lp = np.pad(lp, ((0, 0), (0, 5)))[:, :n]
            curve = np.pad(curve, ((0, 0), (0, 7)))[:, :n]
        k = np.argmax(lp, axis=1) if rng.random() < 0.8 else rng.integers(0, n, B)
        width = int(rng.integers(1, 40))
        with np.errstate(invalid="ignore"):
            margin = _Margins(lp[np.arange(B), k], curve)
            want = _runner_up_vectorized(margin, lp, k, curve, width)
            before = lp.copy()
            assert np.array_equal(margin.runner_up(lp, k, curve, width), want)
        assert np.array_equal(lp, before, equal_nan=True)  # values put back
        assert np.array_equal(_snap_rows(curve, k, width), snap_to_peak(curve, k, width))


def test_compiled_margins_edge_cases():
    """A near run that reaches the end of the search, and a far lag exactly at the floor,
    are too close to call (each the only reason in its row)."""
    n, k = 400, 100
    lags = np.arange(n)
    plateau = np.where((lags >= k) & (lags <= k + NEAR_TOP), 1.0, 0.0)  # to the search's end
    far = np.where(lags == k, 1.0, 0.0)
    far[300] = 1.0 - SINGLE_MARGIN_LOWPASSED * 1.0  # exactly the floor
    lp = np.stack([plateau, far])
    top = np.array([k + NEAR_TOP // 2, k])  # one raw peak each, within the snap's reach
    curve = 200.0 - np.abs(lags[None] - top[:, None])
    margin = _Margins(lp[:, k], curve)
    want = _runner_up_vectorized(margin, lp, np.array([k, k]), curve, 40)
    assert want.tolist() == [True, True]
    assert margin.runner_up(lp, np.array([k, k]), curve, 40).tolist() == [True, True]


def test_receiver_validation():
    with pytest.raises(ValueError, match="lowpass_taps"):
        Receiver(lowpass_taps=0)
    with pytest.raises(ValueError, match="highpass_order"):
        Receiver(highpass_order=2.5)
    with pytest.raises(ValueError, match="window"):
        dsp_for().indices(np.zeros((3, 100)))
    with pytest.raises(ValueError, match="window"):
        reference_chain(np.zeros(100))

"""Receiver configuration and DSP chain (paper §II; docs/model.md, "The receiver chain").

The node samples at ``fs`` and is awake for ``window`` (N) samples from ``t_wake`` seconds
after the chirp starts. Each received window x (N,) goes through

1. a zero-phase Butterworth high-pass (order 10, 15 kHz): ``sosfiltfilt`` (its default odd
   padding);
2. pulse compression: a = |c| with c = ``scipy.signal.correlate(ref, x_hp, "full")``, ref
   the chirp sampled at fs (Nref samples), so c has Nc = Nref + N − 1 lags;
3. a zero-phase FIR low-pass (1000 taps, 5 kHz, ``firwin``): the filtfilt-equivalent
   convolution of a with h ⋆ h (the FIR's autocorrelation, frequency response |H|²),
   centred, with zero boundaries: ``scipy.signal.convolve(a, h ⋆ h, "same")``;
4. the pick (``Receiver.pick``):

   - ``"paper"``: k = argmax of the low-passed curve (the strongest arrival);
   - ``"first-path"``: k = the top of the earliest lobe that stands out. The lobes are the
     runs of lags where the low-passed curve is at least ρ' times its maximum, ρ' the
     larger of ρ (``first_path_ratio``) and twice the chain's own sidelobe level for the
     strongest arrival's delay (:func:`sidelobe_profile`: a lobe lower than that may be
     the strongest arrival's sidelobe, lifted by noise, not an earlier path); the
     earliest is the one with the largest lags (the shortest time of flight), and k is
     the argmax of the curve within it, kept when that top is at least κ times the
     curve's mean under noise alone, κ·σ·√(2/π)·‖g_k‖ (``first_path_noise``; σ and
     ‖g_k‖ as under *Detection* below; a pick without a known σ skips this test), else
     the global argmax. The direct path is the first to arrive, and a reflection can
     outshine it (a speaker aimed away, a grazing direct path), so the strongest peak is
     not always the direct one; where the direct path's lobe and an echo's merge, the
     pick is the paper's (docs/model.md, "The first-path pick");

   then k is snapped to the nearest local maximum of a (ties to the lower index);
5. the window starts at chirp sample s = k + 1 − N, so τ = (t_wake·fs − s)/fs, r = c·τ;
6. the range is kept only when the direct path's time of flight lies within the signal's
   reach (:mod:`simulation.signal`: the window can hold its chirp) and the chirp was heard:
   the window has a peak (|c[k]| > 0) and, with a detection threshold (``false_alarm``
   set), |c[k]| > η·σ·‖g_k‖ with the picked time of flight τ̂ within the reach too; a
   picked τ̂ < 0 (a chirp that arrived before it was sent: the pick caught a fragment,
   possible when the window opens early in the chirp) is no range, except that the
   paper's receiver (the paper's pick, no threshold) reports its picks down to
   c·τ̂ = :data:`RANGE_FLOOR`, as the paper's chain does (its window, 29 ms into the
   chirp, keeps them above −0.35 m); otherwise the receiver reports "no range" (NaN, with
   a status of :data:`RANGE_STATUS`).

Detection (docs/model.md, "Detection"). For white noise of σ per sample, c = G x is
Gaussian at every lag k with standard deviation σ·‖g_k‖, g_k the k-th row of the linear map
G of steps 1–2 (known exactly). A noise-only window is declared heard when its picked lag
exceeds η standard deviations; by the union bound over the Nc lags that happens with
probability at most Nc · 2Q(η), so η = Q⁻¹(P_fa / (2 Nc)) keeps the false-alarm rate per
window below ``Receiver.false_alarm`` = P_fa. σ is the noise level of the SNR rule
(:mod:`simulation.noise`): the receiver knows its own noise floor, as one measured while no
anchor transmits; the threshold stays when a simulation adds no noise, so a noise-free
window is heard when its peak clears it. The paper's receiver has no threshold
(``false_alarm=None``, the default): for an anchor within the reach it reports its pick
wherever it lands, as the paper's receiver does (a late echo picked beyond the reach is
its error, not a missing range).

:func:`reference_chain` is this chain written literally (one window at a time) and the
definition. :class:`Dsp` is the batched fast form used by the simulator, which gives the
same index (tested on thousands of clean, noisy and reverberant windows). Steps 1–2 are
linear in x (``sosfiltfilt`` with odd padding and scaled initial conditions is a linear map
of the window). Short windows (the paper's) fold them into one (Nc, N) matrix G applied to
a batch with one matrix product. Long windows (:data:`FFT_MIN_WINDOW` samples and more),
where G would be large and its product slow, use FFTs: the zero-phase high-pass is a
convolution with its two-sided impulse response k (2L + 1 taps, L where it has decayed
below double precision) plus exact corrections E_top, E_bot (L × L) for the padding and
initial conditions at the two ends of the window, then the correlation is a product with
the reference's spectrum. Step 3 is a product with |H|² in the frequency domain (one rfft
and one irfft of size ≥ Nc + taps − 1, no wrap-around), in blocks that can run on several
threads.

The float64 chain is bound by that product and the two FFTs (docs/implementation.md).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import threading
from dataclasses import dataclass

import numba
import numpy as np
import scipy.fft

from simulation import checks
from simulation.chirp import Chirp
from simulation.positioning import RANGE_FLOOR  # the lowest range positioning accepts

#: the shortest overlap (s) of a path's chirp with a window longer than it that the
#: receiver is taken to see: the paper's 1 ms slice (:mod:`simulation.system`, "Reach")
MIN_OVERLAP = 1e-3

#: accepted false-alarm probability per window of the detection (exclusive of 0)
FALSE_ALARM_RANGE = (0.0, 0.5)

#: what the receiver made of a window: a range, or why not (the range is NaN then)
RANGE_STATUS = {
    0: "heard: a range",
    1: "not heard: no correlation peak above the detection threshold",
    2: "out of reach: the time of flight lies outside the signal's reach (or the pick gives "
    "a negative one)",
}
#: the peak picks of the receiver (module docstring, step 4)
PICKS = ("paper", "first-path")
#: windows of this many samples and more run the DSP with FFTs instead of one matrix
FFT_MIN_WINDOW = 1024
HEARD, NOT_HEARD, OUT_OF_REACH = 0, 1, 2


@dataclass(frozen=True)
class Receiver:
    """Sampling, DSP and detection settings of the mobile node (defaults: docs/model.md).

    fs : sampling rate (Hz). t_wake : when the node wakes, seconds after the chirp starts.
    window : samples N it records from then. highpass_order, highpass_cutoff (Hz),
    lowpass_taps, lowpass_cutoff (Hz) : the DSP filters. false_alarm : the detection
    threshold's bound on the probability that a window of noise alone gives a range
    (module docstring), in (0, 0.5); None (the paper's receiver): no threshold.
    pick : ``"paper"`` (the strongest arrival) or ``"first-path"`` (the earliest arrival
    that stands out; module docstring, step 4). first_path_ratio : ρ in (0, 1], the share
    of the strongest peak a first path must reach. first_path_noise : κ ≥ 0, the multiple
    of the noise-only mean of the low-passed curve it must reach (0: no noise test).
    """

    fs: float = 192e3
    t_wake: float = 29e-3
    window: int = 192
    highpass_order: int = 10
    highpass_cutoff: float = 15e3
    lowpass_taps: int = 1000
    lowpass_cutoff: float = 5e3
    false_alarm: float | None = None
    pick: str = "paper"
    first_path_ratio: float = 0.3
    first_path_noise: float = 4.0

    def __post_init__(self) -> None:
        checks.real("fs", self.fs, low=0.0, high=10e6, low_open=True, unit="Hz")
        checks.real("t_wake", self.t_wake, low=0.0, high=1.0, unit="s")
        checks.count("window", self.window, low=2, high=65536)
        for name in ("highpass_cutoff", "lowpass_cutoff"):
            v = checks.real(name, getattr(self, name), low=0.0, low_open=True, unit="Hz")
            if not v < self.fs / 2:
                raise ValueError(
                    f"{name}: must be in (0, fs/2) = (0, {self.fs / 2:g}) Hz, got {v:g}"
                )
        order = checks.count("highpass_order", self.highpass_order, low=1, high=40)
        checks.count("lowpass_taps", self.lowpass_taps, low=1, high=100_000)
        if self.false_alarm is not None:
            lo, hi = FALSE_ALARM_RANGE
            checks.real("false_alarm", self.false_alarm, low=lo, high=hi, low_open=True)
        checks.choice("pick", self.pick, PICKS)
        checks.real("first_path_ratio", self.first_path_ratio, low=0.0, high=1.0, low_open=True)
        checks.real("first_path_noise", self.first_path_noise, low=0.0, high=1e3)
        # sosfiltfilt pads the window by 3 (2S + 1 − odd) samples, S = ⌈order/2⌉ sections
        pad = 3 * (2 * math.ceil(order / 2) + 1 - order % 2)
        if self.window <= pad:
            raise ValueError(
                f"window: must be more than {pad} samples (the zero-phase high-pass of order "
                f"{order} pads by that much), got {self.window}"
            )

    @property
    def window_times(self) -> np.ndarray:
        """(window,) sample times in seconds after the chirp start."""
        return self.t_wake + np.arange(self.window) / self.fs

    @property
    def wake_sample(self) -> float:
        """t_wake · fs: the chirp sample at which the window opens."""
        return self.t_wake * self.fs

    def highpass_sos(self) -> np.ndarray:
        """Second-order sections of the Butterworth high-pass."""
        import scipy.signal  # slow to import; only needed when a DSP is built

        return scipy.signal.butter(
            self.highpass_order, self.highpass_cutoff, "highpass", fs=self.fs, output="sos"
        )

    def lowpass_fir(self) -> np.ndarray:
        """(taps,) the FIR low-pass (Hamming-windowed sinc, ``firwin``)."""
        import scipy.signal

        return scipy.signal.firwin(self.lowpass_taps, self.lowpass_cutoff, fs=self.fs)

    def lowpass_kernel(self) -> np.ndarray:
        """(2·taps − 1,) the zero-phase kernel h ⋆ h (centre at index taps − 1)."""
        h = self.lowpass_fir()
        return np.convolve(h, h[::-1])

    def range_from_index(self, k, speed_of_sound: float) -> np.ndarray:
        """Range r = c·(t_wake·fs − s)/fs in metres for full-correlation index k, s = k + 1 − N."""
        s = np.asarray(k, dtype=float) + 1 - self.window
        return speed_of_sound * (self.wake_sample - s) / self.fs

    def index_from_range(self, r, speed_of_sound: float) -> np.ndarray:
        """The (fractional) correlation index at which a path of length r (m) peaks."""
        return (
            self.wake_sample
            - np.asarray(r, dtype=float) * self.fs / speed_of_sound
            + (self.window - 1)
        )


def delay_span(chirp: Chirp, receiver: Receiver) -> tuple[float, float]:
    """(τ_min, τ_max) s: the times of flight whose chirp the window holds at least
    D = min(W, T, :data:`MIN_OVERLAP`) of, W = (N − 1)/fs the window's span
    (:mod:`simulation.system`, "Reach"): τ_min = max(0, t_wake + min(0, D − T)),
    τ_max = t_wake + max(0, W − D)."""
    span = (receiver.window - 1) / receiver.fs
    t, D = receiver.t_wake, min(span, chirp.duration, MIN_OVERLAP)
    return max(0.0, t + min(0.0, D - chirp.duration)), t + max(0.0, span - D)


def snap_to_peak(curve: np.ndarray, index: np.ndarray, width: int = 32) -> np.ndarray:
    """Move each index to the nearest local maximum of ``curve`` (B, n), vectorized.

    A local maximum is an interior sample with curve[k−1] < curve[k] ≥ curve[k+1]. Ties in
    distance go to the lower index. Indices with no local maximum within ``width`` samples
    are returned unchanged.
    """
    a = np.asarray(curve)
    k = np.asarray(index)
    B, n = a.shape
    off = np.arange(-width, width + 1)
    idx = k[:, None] + off
    valid = (idx >= 1) & (idx <= n - 2)
    idc = np.clip(idx, 1, n - 2)
    rows = np.arange(B)[:, None]
    v = a[rows, idc]
    peak = valid & (v > a[rows, idc - 1]) & (v >= a[rows, idc + 1])
    dist = np.where(peak, np.abs(off), width + 1)
    j = np.argmin(dist, axis=1)  # first minimum: lower index on ties
    r = np.arange(B)
    return np.where(dist[r, j] <= width, idx[r, j], k)


def reference_chain(
    window, chirp: Chirp | None = None, receiver: Receiver | None = None, sigma=None
) -> dict:
    """The receiver DSP written literally for one window (N,); the definition of the chain.

    Returns a dict with the high-passed window ``x_hp``, the raw curve ``corr`` = |c| (Nc,),
    the low-passed curve ``lowpassed``, the low-pass pick ``k_lowpass`` (the argmax, or the
    first path: module docstring, step 4, with the window's noise σ ``sigma`` for its
    noise test) and the snapped index ``k``. Slow; used to check :class:`Dsp`.
    """
    import scipy.signal

    chirp, rx = signal_chain(chirp, receiver)
    x = np.asarray(window, dtype=float)
    if x.shape != (rx.window,):
        raise ValueError(f"window: expected shape ({rx.window},), got {x.shape}")
    x_hp = scipy.signal.sosfiltfilt(rx.highpass_sos(), x)
    ref = chirp.samples(rx.fs)
    corr = np.abs(scipy.signal.correlate(ref, x_hp, mode="full"))
    lp = scipy.signal.convolve(corr, rx.lowpass_kernel(), mode="same")
    k_lp = int(np.argmax(lp))
    if rx.pick == "first-path":
        tau_top = (rx.wake_sample - (k_lp + 1.0 - rx.window)) / rx.fs
        ok = lp >= first_path_floor(chirp, rx, tau_top) * lp[k_lp]
        end = int(np.flatnonzero(ok)[-1])  # the lobe with the largest lags: the earliest path
        start = end
        while start > 0 and ok[start - 1]:
            start -= 1
        top = start + int(np.argmax(lp[start : end + 1]))
        if sigma is not None and rx.first_path_noise > 0:
            gain = _literal_noise_gain(chirp, rx)[top]  # ‖g_top‖
            if lp[top] < rx.first_path_noise * sigma * np.sqrt(2 / np.pi) * gain:
                top = k_lp  # a lobe of noise: the strongest peak
        k_lp = top
    k = k_lp
    for d in range(len(corr)):  # nearest local maximum, lower index first on ties
        hit = [
            i
            for i in (k_lp - d, k_lp + d)
            if 1 <= i <= len(corr) - 2 and corr[i - 1] < corr[i] >= corr[i + 1]
        ]
        if hit:
            k = hit[0]
            break
    return {"x_hp": x_hp, "corr": corr, "lowpassed": lp, "k_lowpass": k_lp, "k": k}


#: how far above the chain's own sidelobe level an earlier lobe must reach to be a path
SIDELOBE_MARGIN = 2.0


def first_path_floor(chirp: Chirp, receiver: Receiver, tau) -> np.ndarray:
    """ρ' = max(ρ, :data:`SIDELOBE_MARGIN` · :func:`sidelobe_profile` at τ) (shape of
    ``tau``): the share of the strongest peak a lobe must reach to be taken for the first
    path, when the strongest arrival has the delay τ (s)."""
    taus, level = sidelobe_profile(chirp, receiver)
    side = np.interp(np.asarray(tau, dtype=float), taus, level)
    return np.maximum(receiver.first_path_ratio, SIDELOBE_MARGIN * side)


@functools.lru_cache(maxsize=8)
def sidelobe_profile(chirp: Chirp, receiver: Receiver) -> tuple[np.ndarray, np.ndarray]:
    """(delays (33,) s, levels (33,)): for one noise-free path of each delay from the near
    limit to the reach, the highest lobe of the low-passed curve besides the main one, as a
    share of the main one: what the strongest arrival alone puts on the curve around it. A
    path that overlaps the window by a 1 ms slice of the chirp has sidelobes of about a
    fifth of its peak (a rectangular slice's −13 dB); a path the window holds whole has
    lower ones."""
    from simulation.synthesis import synthesize

    rx = dataclasses.replace(receiver, pick="paper", false_alarm=None)
    lo, hi = delay_span(chirp, rx)
    taus = np.linspace(lo, hi, 33)
    windows = synthesize(taus[:, None], np.ones((len(taus), 1)), chirp, rx)
    levels = np.zeros(len(taus))
    for i, window in enumerate(windows):
        lp = reference_chain(window, chirp, rx)["lowpassed"]
        top = int(np.argmax(lp))
        low = lp < 0.05 * lp[top]  # the main lobe: the run around the top above 5 %
        left, right = np.flatnonzero(low[:top]), np.flatnonzero(low[top:])
        a = left[-1] + 1 if left.size else 0
        b = top + right[0] if right.size else len(lp)
        others = np.r_[lp[:a], lp[b:]]
        levels[i] = others.max() / lp[top] if others.size else 0.0
    return taus, levels


@functools.lru_cache(maxsize=2)
def _literal_noise_gain(chirp: Chirp, rx: Receiver) -> np.ndarray:
    """(Nc,) ‖g_k‖ from the linear map of steps 1–2 written literally: row n of G is the
    chain's correlation of the n-th unit window, one window at a time."""
    import scipy.signal

    ref, sos = chirp.samples(rx.fs), rx.highpass_sos()
    g2 = np.zeros(len(ref) + rx.window - 1)
    for e in np.eye(rx.window):
        g2 += scipy.signal.correlate(ref, scipy.signal.sosfiltfilt(sos, e)) ** 2
    return np.sqrt(g2)


PRECISIONS = ("float64", "float32")
#: the simulator's default DSP precision: float32 computes in single precision and redoes
#: in double the windows whose pick its rounding could change, so that it picks the float64
#: chain's index (docs/model.md, "The receiver chain"); "float64" stays selectable
DEFAULT_PRECISION = "float32"
#: a single-precision decision (a comparison of two values of a curve, or of one with a
#: threshold) is trusted when the values differ by more than this share of the curve's
#: largest value, for the low-passed curve and for the raw one: single precision moves the
#: low-passed curve by at most 4e-7 of its largest value and the raw one by at most 1.3e-6,
#: on clean, noisy, weak and noise-only windows of either form (docs/model.md, "The
#: receiver chain"), so another CPU's rounding (another BLAS kernel, another FFT) stays
#: well inside the margins
SINGLE_MARGIN_LOWPASSED, SINGLE_MARGIN_RAW = 4e-6, 1e-5
#: lags on each side of the low-passed curve's top searched for the lags within the margin
#: of it (a run reaching further is redone in double precision)
NEAR_TOP = 64

#: size of the correlation buffer of one part (bytes): a part's correlation is one matrix
#: product (see Dsp.indices)
PART_BYTES = 128 * 2**20

#: each thread's correlation buffers (:func:`_part_buffer`)
_BUFFERS = threading.local()


def _part_buffer(rows: int, nfft: int, dtype) -> np.ndarray:
    """(rows, nfft) zeros of ``dtype``: this thread's correlation buffer of that precision,
    kept from call to call of :meth:`Dsp.picks` (made again for another width or more
    rows). A part's rows hold its correlation at lags 0 … Nc − 1 and zeros after, which
    every step leaves zero, so a kept buffer keeps them. Memory fresh from the system costs a page
    fault and the kernel's zeroing on its first write, every call again for a buffer made
    per call: one buffer per thread and precision (at most :data:`PART_BYTES`) stays held
    instead."""
    kept = getattr(_BUFFERS, "parts", None)
    if kept is None:
        kept = _BUFFERS.parts = {}
    key = np.dtype(dtype).str
    buf = kept.get(key)
    if buf is None or buf.shape[1] != nfft or buf.shape[0] < rows:
        buf = kept[key] = np.zeros((rows, nfft), dtype=dtype)
    return buf[:rows]


class Dsp:
    """Batched, fast form of the receiver chain for one chirp and receiver.

    Build with :func:`dsp_for` (cached). ``indices(windows)`` maps windows (..., N) to the
    snapped full-correlation indices (...,) and ``ranges(windows, c)`` to metres.

    ``precision="float64"`` (this class's default) gives the index of
    :func:`reference_chain`. ``"float32"`` (the simulator's default,
    :data:`DEFAULT_PRECISION`) runs the correlation and low-pass in single precision and
    checks every decision of the pick (the argmax, the snap's comparisons, the first-path
    floor and noise test, the detection threshold) against :data:`SINGLE_MARGIN`; a window
    with a decision closer than that is redone in double precision. It gives the float64
    index, and the same index on any CPU (docs/model.md, "The receiver chain"). ``form`` is
    ``"matrix"`` or ``"fft"`` (module docstring; default: by the window's length,
    :data:`FFT_MIN_WINDOW`).
    """

    def __init__(
        self, chirp: Chirp, receiver: Receiver, precision: str = "float64", form: str | None = None
    ):
        if precision not in PRECISIONS:
            raise ValueError(f"precision: must be one of {PRECISIONS}, got {precision!r}")
        self.chirp = chirp
        self.receiver = receiver
        self.precision = precision
        self.dtype = np.dtype(precision)
        N = receiver.window
        ref = chirp.samples(receiver.fs)
        if len(ref) < 2:
            raise ValueError("chirp: shorter than two samples at the receiver's fs")
        self.n_corr = len(ref) + N - 1
        kernel = _highpass_kernel(receiver)
        self.form = dsp_form(receiver) if form is None else checks.choice("form", form, FORMS)
        if self.form == "fft" and kernel is not None and self.dtype == np.float32:
            kernel = _highpass_kernel(receiver, SINGLE_TAIL)  # decayed below float32's ulp
        # Step 3: |H|² in the frequency domain, kernel centred at lag 0. Outputs 0..Nc−1
        # see no wrap-around when nfft ≥ Nc + taps − 1.
        kern = receiver.lowpass_kernel()
        half = receiver.lowpass_taps - 1
        self.nfft = scipy.fft.next_fast_len(self.n_corr + half, real=True)
        hc = np.zeros(self.nfft)
        hc[: half + 1] = kern[half:]
        hc[self.nfft - half :] = kern[:half]
        self.lowpass_response = scipy.fft.rfft(hc).real  # |H(f)|², real: kernel symmetric
        self._H = self.lowpass_response.astype(self.dtype)
        if self.form == "matrix":
            self._build_matrix(ref)
        else:
            if kernel is None or N < 3 * (len(kernel) // 2):
                raise ValueError(
                    f"form: 'fft' needs a window of at least 3 high-pass decay lengths, got "
                    f"{N} samples"
                )
            self._build_fft(ref, kernel)
        # raw peaks of |c| are half a carrier period apart: search a few periods around
        self.snap_width = max(32, math.ceil(receiver.fs / min(chirp.f0, chirp.f1)) + 2)
        #: η: the detection threshold in noise standard deviations (module docstring); 0
        #: without one (the paper's receiver)
        self.threshold = (
            0.0
            if receiver.false_alarm is None
            else detection_threshold(receiver.false_alarm, self.n_corr)
        )
        self._noise_gain = None

    def _build_matrix(self, ref: np.ndarray) -> None:
        """Steps 1–2 as one matrix: c = T · reverse(H · x) = (T · H[::-1]) x, with H the
        sosfiltfilt map (applied to the identity) and T the (Nc, N) convolution matrix of
        ref, T[k, m] = ref[k − m]."""
        import scipy.signal

        rx, N = self.receiver, self.receiver.window
        checks.check_size(
            "chirp duration x fs x window",
            (len(ref) + N) * N * 8 * 4,
            value=(self.chirp.duration, rx.fs, N),
            hint="use a shorter chirp, a lower fs or a shorter window",
        )
        try:
            H = scipy.signal.sosfiltfilt(rx.highpass_sos(), np.eye(N), axis=0)
        except np.linalg.LinAlgError:  # poles at z = 1 to rounding: no initial conditions
            raise ValueError(
                f"highpass_cutoff: {rx.highpass_cutoff:g} Hz is too close to 0 for a "
                f"high-pass of order {rx.highpass_order} at fs = {rx.fs:g} Hz"
            ) from None
        kk = np.arange(self.n_corr)[:, None] - np.arange(N)[None, :]
        T = np.where((kk >= 0) & (kk < len(ref)), ref[np.clip(kk, 0, len(ref) - 1)], 0.0)
        self.G_T = np.ascontiguousarray((T @ H[::-1]).T)  # (N, Nc): windows @ G_T
        self._G = self.G_T.astype(self.dtype)

    def _build_fft(self, ref: np.ndarray, kernel: np.ndarray) -> None:
        """Steps 1–2 with FFTs (module docstring): the high-pass as the convolution with its
        two-sided impulse response ``kernel`` (2L + 1,) plus the exact end corrections, then
        the correlation as a product with the reference's spectrum."""
        import scipy.signal

        rx, N = self.receiver, self.receiver.window
        L = len(kernel) // 2
        self.edge = L
        self.n_hp = scipy.fft.next_fast_len(N + L, real=True)
        kc = np.zeros(self.n_hp)  # the kernel centred at lag 0 (circular)
        kc[: L + 1] = kernel[L:]
        kc[self.n_hp - L :] = kernel[:L]
        cdt = np.result_type(self.dtype, np.complex64)
        K_hat = scipy.fft.rfft(kc)
        # the end corrections: the exact map on the first and last L inputs minus the kernel
        cols = np.r_[0:L, N - L : N]
        unit = np.zeros((N, 2 * L))
        unit[cols, np.arange(2 * L)] = 1.0
        exact = scipy.signal.sosfiltfilt(rx.highpass_sos(), unit, axis=0)  # (N, 2L)
        lag = np.arange(N)[:, None] - cols[None, :]
        conv = np.where(np.abs(lag) <= L, kernel[np.clip(lag + L, 0, 2 * L)], 0.0)
        E = exact - conv
        E_top_T, E_bot_T = np.ascontiguousarray(E[:L, :L].T), np.ascontiguousarray(E[N - L :, L:].T)
        # c = correlate(ref, y, "full") = convolve(ref, y reversed), lags 0 … Nc − 1; the
        # reversal's phase e^{−2πif(N − 1)/nfft} is folded into the reference's spectrum
        self.n_xc = scipy.fft.next_fast_len(self.n_corr, real=True)  # no wrap-around
        f = np.arange(self.n_xc // 2 + 1)
        shift = np.exp(-2j * np.pi * ((f * (N - 1)) % self.n_xc) / self.n_xc)  # exact turns
        R_hat = scipy.fft.rfft(ref, n=self.n_xc) * shift
        #: the FFT form's maps (K̂, R̂, E_topᵀ, E_botᵀ) in double precision, and in this DSP's
        self._maps64 = (K_hat, R_hat, E_top_T, E_bot_T)
        self._maps = (K_hat.astype(cdt), R_hat.astype(cdt),
                      E_top_T.astype(self.dtype), E_bot_T.astype(self.dtype))  # fmt: skip

    def _fft_correlate(self, x: np.ndarray, out: np.ndarray, maps=None) -> None:
        """Steps 1–2 with FFTs for windows x (B, N) into ``out`` (B, nfft): c at lags
        0 … Nc − 1, zeros after; ``maps`` the FFT form's maps (default this DSP's
        precision's)."""
        N, L = self.receiver.window, self.edge
        K_hat, R_hat, E_top_T, E_bot_T = self._maps if maps is None else maps
        spec = scipy.fft.rfft(x, n=self.n_hp, axis=-1, workers=1)
        spec *= K_hat
        y = scipy.fft.irfft(spec, n=self.n_hp, axis=-1, workers=1)[:, :N]
        y[:, :L] += x[:, :L] @ E_top_T
        y[:, N - L :] += x[:, N - L :] @ E_bot_T
        # the spectrum of y reversed, y[N − 1 − n], is conj(Ŷ) times e^{−2πif(N − 1)/nfft}
        spec = scipy.fft.rfft(y, n=self.n_xc, axis=-1, workers=1)
        np.conjugate(spec, out=spec)
        spec *= R_hat
        out[:, : self.n_corr] = scipy.fft.irfft(spec, n=self.n_xc, axis=-1, workers=1)[
            :, : self.n_corr
        ]
        out[:, self.n_corr :] = 0.0

    @property
    def noise_gain(self) -> np.ndarray:
        """(Nc,) ‖g_k‖: the standard deviation of c[k] for white noise of unit σ."""
        if self._noise_gain is None:
            if self.form == "matrix":
                g2 = np.einsum("nk,nk->k", self.G_T, self.G_T)
            else:  # the rows of G, the chain on the unit windows, a block at a time
                N, g2 = self.receiver.window, np.zeros(self.n_corr)
                buf = np.empty((256, self.nfft))
                for s in range(0, N, 256):
                    unit = np.zeros((min(256, N - s), N))
                    unit[np.arange(len(unit)), s + np.arange(len(unit))] = 1.0
                    rows = buf[: len(unit)]
                    self._fft_correlate(unit, rows, self._maps64)
                    g2 += np.einsum("bk,bk->k", rows[:, : self.n_corr], rows[:, : self.n_corr])
            self._noise_gain = np.sqrt(g2)
        return self._noise_gain

    def correlation(self, windows: np.ndarray) -> np.ndarray:
        """(B, Nc) raw curve |c| of windows (B, N)."""
        w = np.asarray(windows, dtype=float)
        if self.form == "matrix":
            return np.abs(w @ self.G_T)
        out = np.empty((len(w), self.nfft))
        self._fft_correlate(w, out, self._maps64)
        return np.abs(out[:, : self.n_corr])

    def lowpass(self, curve: np.ndarray) -> np.ndarray:
        """(B, Nc) zero-phase low-pass of curves (B, Nc)."""
        spec = scipy.fft.rfft(curve, n=self.nfft, axis=-1)
        spec *= self.lowpass_response
        return scipy.fft.irfft(spec, n=self.nfft, axis=-1)[:, : self.n_corr]

    def _block_picks(self, buf: np.ndarray, sigma=None):
        """Snapped indices (B,), the raw peaks |c[k]| there (B,) and whether a decision was
        too close to call in this DSP's precision (B,) bool (always False in double) of rows
        (B, nfft) holding c at lags 0 … Nc − 1, zeros after (c is replaced by |c| in place);
        ``sigma`` (B,) the windows' noise σ for the first-path pick's noise test and the
        detection threshold."""
        curve = buf[:, : self.n_corr]
        np.abs(curve, out=curve)
        spec = scipy.fft.rfft(buf, axis=-1, workers=1)
        spec *= self._H
        lp = scipy.fft.irfft(spec, n=self.nfft, axis=-1, workers=1)
        lp[:, self.n_corr :] = -np.inf  # outside the correlation; argmax on whole rows is faster
        k = np.argmax(lp, axis=-1)
        lp = lp[:, : self.n_corr]
        verify = self.dtype == np.float32
        margin = _Margins(lp[np.arange(len(k)), k], curve) if verify else None
        w = self.snap_width
        unsure = margin.runner_up(lp, k, curve, w) if verify else np.zeros(len(k), dtype=bool)
        if self.receiver.pick == "first-path":
            k = self._first_path(lp, k, sigma, margin, unsure, curve)
        k = _snap_rows(curve, k, self.snap_width)  # snap_to_peak, compiled
        peak = curve[np.arange(len(k)), k].astype(float)
        if verify and self.threshold and sigma is not None:
            level = self.threshold * np.asarray(sigma) * self.noise_gain[k]
            unsure |= np.abs(peak - level) <= margin.curve
        return k, peak, unsure

    def _first_path(self, lp, k_max, sigma, margin=None, unsure=None, curve=None):
        """(B,) the first-path pick on low-passed curves lp (B, Nc) (module docstring, step
        4): the argmax within the qualifying run of lags with the largest lags, else
        ``k_max``. With ``margin`` (:class:`_Margins`), rows whose floor or noise test a
        rounding could decide otherwise are marked in ``unsure`` (B,) in place."""
        rx = self.receiver
        rows = np.arange(len(lp))
        tau_top = (rx.wake_sample - (k_max + 1.0 - rx.window)) / rx.fs
        floor = first_path_floor(self.chirp, rx, tau_top) * lp[rows, k_max]
        ok = lp >= floor[:, None]
        n = lp.shape[1]
        end = n - 1 - np.argmax(ok[:, ::-1], axis=1)  # the run's latest lag: earliest path
        lags = np.arange(n)
        gap = ~ok & (lags[None, :] < end[:, None])  # lags below the run that do not qualify
        start = np.where(gap.any(axis=1), n - np.argmax(gap[:, ::-1], axis=1), 0)
        run = (lags[None, :] >= start[:, None]) & (lags[None, :] <= end[:, None])
        in_run = np.where(run, lp, -np.inf)
        k = np.argmax(in_run, axis=1)
        if margin is not None:
            unsure |= margin.crosses(lp, floor)
            unsure |= margin.runner_up(in_run, k, curve, self.snap_width)
        if sigma is not None and rx.first_path_noise > 0:  # a lobe of noise: the strongest
            noise = rx.first_path_noise * np.asarray(sigma) * math.sqrt(2 / math.pi)
            level = noise * self.noise_gain[k]
            if margin is not None:
                unsure |= np.abs(lp[rows, k] - level) <= margin.lowpassed
            k = np.where(lp[rows, k] >= level, k, k_max)
        return k

    def indices(self, windows: np.ndarray, block: int = 128) -> np.ndarray:
        """Snapped full-correlation index k (...,) for windows (..., N) (:meth:`picks`)."""
        return self.picks(windows, block)[0]

    def picks(
        self, windows: np.ndarray, block: int = 128, sigma=None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Snapped full-correlation index k (...,) and raw peak |c[k]| (...,) for windows
        (..., N); ``sigma`` (broadcast to (...,)) the noise σ of each window, used by the
        first-path pick's noise test (None: no noise test).

        Windows go through in parts of up to :data:`PART_BYTES` of correlation: a part's
        correlation is one matrix product (or its FFT form) into a zero-padded buffer
        reused from part to part and from call to call (:func:`_part_buffer`; few large
        products: each wakes the BLAS threads), its
        FFTs run in blocks of ``block`` rows on ``scipy.fft``'s worker count of threads
        (``with scipy.fft.set_workers(n): ...``; numpy and scipy.fft release the GIL).
        Results depend neither on ``block`` nor on the threads. In single precision, the
        windows with a decision too close to call are redone in double (class docstring).
        """
        if int(block) != block or block < 1:
            raise ValueError(f"block: must be an integer >= 1, got {block}")
        w = np.asarray(windows)
        if w.dtype not in (np.float32, np.float64):
            w = w.astype(float)
        if w.shape[-1] != self.receiver.window:
            raise ValueError(f"windows: last axis must be {self.receiver.window}, got {w.shape}")
        lead = w.shape[:-1]
        flat = w.reshape(-1, w.shape[-1])
        n = flat.shape[0]
        sig = None
        if sigma is not None:
            sig = np.broadcast_to(np.asarray(sigma, dtype=float), lead).reshape(-1)
            if self.receiver.pick == "first-path" or self.threshold:
                self.noise_gain  # noqa: B018 - computed once here, not in every thread
        step = block * max(1, PART_BYTES // (self.nfft * self.dtype.itemsize * block))
        out = np.empty(n, dtype=np.int64)
        peak = np.empty(n)
        unsure = np.zeros(n, dtype=bool)
        buf = _part_buffer(min(step, n), self.nfft, self.dtype)
        threads = min(scipy.fft.get_workers(), -(-min(step, n) // block))
        pool = None
        if threads > 1:
            from concurrent.futures import ThreadPoolExecutor

            pool = ThreadPoolExecutor(threads)
        try:
            for s in range(0, n, step):
                part = flat[s : s + step].astype(self.dtype, copy=False)
                rows = buf[: part.shape[0]]
                starts = range(0, part.shape[0], block)
                if self.form == "matrix":
                    np.matmul(part, self._G, out=rows[:, : self.n_corr])
                    task = self._picks_of
                else:  # the FFT form runs its correlation in the blocks too
                    task = self._fft_picks_of(part)
                args = [(rows, b, block, None if sig is None else sig[s + b : s + b + block])
                        for b in starts]  # fmt: skip
                results = list(map(task, args) if pool is None else pool.map(task, args))
                out[s : s + part.shape[0]] = np.concatenate([r[0] for r in results])
                peak[s : s + part.shape[0]] = np.concatenate([r[1] for r in results])
                unsure[s : s + part.shape[0]] = np.concatenate([r[2] for r in results])
        finally:
            if pool is not None:
                pool.shutdown()
        redo = np.flatnonzero(unsure)
        if redo.size:
            exact = dsp_for(self.chirp, self.receiver, "float64", self.form)
            out[redo], peak[redo] = exact.picks(
                flat[redo], block, None if sig is None else sig[redo]
            )
        return out.reshape(lead), peak.reshape(lead)

    def _picks_of(self, arg):
        rows, b, block, sig = arg
        return self._block_picks(rows[b : b + block], sig)

    def _fft_picks_of(self, part: np.ndarray):
        def task(arg):
            rows, b, block, sig = arg
            self._fft_correlate(part[b : b + block], rows[b : b + block])
            return self._block_picks(rows[b : b + block], sig)

        return task

    def ranges(self, windows: np.ndarray, speed_of_sound: float) -> np.ndarray:
        """Range estimates in metres (...,) for windows (..., N), without detection."""
        return self.receiver.range_from_index(self.indices(windows), speed_of_sound)

    def detect(
        self,
        windows: np.ndarray,
        speed_of_sound: float,
        noise_sigma,
        delays: tuple[float, float],
        direct_delays,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Ranges (...,) in metres and their status (...,) (:data:`RANGE_STATUS`) for
        windows (..., N) (step 6 of the module docstring): NaN unless the direct path's
        delay ``direct_delays`` (s, broadcast to the windows' leading shape) lies within
        ``delays`` = (τ_min, τ_max) seconds (:attr:`simulation.signal.Signal.delays`), the
        picked delay is not negative (the paper's receiver: not below
        :data:`RANGE_FLOOR` in range) and the picked peak exceeds η·σ·‖g_k‖
        (``noise_sigma`` σ broadcast likewise; η = 0 without a threshold, and then any
        peak > 0 is heard) with, under a threshold, the picked delay within ``delays``
        too."""
        lead = np.shape(windows)[:-1]
        sigma = np.broadcast_to(np.asarray(noise_sigma, dtype=float), lead)
        k, peak = self.picks(windows, sigma=sigma)
        r = self.receiver.range_from_index(k, speed_of_sound)
        heard = peak > self.threshold * sigma * self.noise_gain[k] if self.threshold else peak > 0
        lo, hi = delays
        direct = np.broadcast_to(np.asarray(direct_delays, dtype=float), k.shape)
        tau = (self.receiver.wake_sample - (k + 1.0 - self.receiver.window)) / self.receiver.fs
        rx = self.receiver
        paper = rx.pick == "paper" and rx.false_alarm is None
        seen = (direct >= lo) & (direct <= hi)
        seen &= tau >= (RANGE_FLOOR / speed_of_sound if paper else 0.0)
        if self.receiver.false_alarm is not None:  # a detecting receiver checks its pick too
            seen &= (tau >= lo) & (tau <= hi)
        status = np.where(seen, np.where(heard, HEARD, NOT_HEARD), OUT_OF_REACH)
        status = status.astype(np.int8)
        return np.where(status == HEARD, r, np.nan), status


class _Margins:
    """The margins (B,) within which a single-precision decision on a row of the low-passed
    curve ``lowpassed`` or of the raw curve ``curve`` (B, Nc) is too close to call:
    :data:`SINGLE_MARGIN_LOWPASSED` and :data:`SINGLE_MARGIN_RAW` times the row's largest
    value (``top`` (B,) of the low-passed curve)."""

    def __init__(self, top: np.ndarray, curve: np.ndarray):
        self.lowpassed = SINGLE_MARGIN_LOWPASSED * top.astype(float)
        self.curve = SINGLE_MARGIN_RAW * curve.max(axis=1).astype(float)

    def runner_up(self, values: np.ndarray, k: np.ndarray, curve: np.ndarray, width: int):
        """(B,) the argmax k (B,) of each row of ``values`` (B, Nc, low-passed) could snap
        elsewhere: the lags within the margin of its value are not one run within
        :data:`NEAR_TOP` of k, or the run's ends snap to different raw peaks of ``curve``
        (B, Nc) (between them every lag snaps to the same peak), or a local maximum of the
        raw curve within ``width`` samples of the run could move (:func:`_runner_up_rows`,
        compiled)."""
        near = np.full((len(k), 2 * NEAR_TOP + 1), -np.inf, dtype=values.dtype)
        _swap_near(values, k, NEAR_TOP, near)  # the lags within NEAR_TOP of k now −inf
        far = values.max(axis=1)  # the largest value beyond them (NaN: one is NaN)
        _swap_near(values, k, NEAR_TOP, near)  # and back
        return _runner_up_rows(values, k, far, curve, self.lowpassed, self.curve, width, NEAR_TOP)

    def crosses(self, values: np.ndarray, level: np.ndarray) -> np.ndarray:
        """(B,) a lag of ``values`` (B, Nc) lies within the margin of the row's ``level``."""
        near = np.abs(values - level[:, None].astype(values.dtype))
        return np.any(near <= self.lowpassed[:, None], axis=1)


@numba.njit(cache=True)
def _nearest_peak(a, k, width):  # pragma: no cover - compiled
    """The local maximum (a[i − 1] < a[i] ≥ a[i + 1]) of the row a (n,) nearest to the index
    k, the lower index on ties; k itself when there is none within ``width`` samples (one
    row of :func:`snap_to_peak`)."""
    n = a.shape[0]
    for d in range(width + 1):
        for i in (k - d, k + d):
            if 1 <= i <= n - 2 and a[i] > a[i - 1] and a[i] >= a[i + 1]:
                return i
    return k


@numba.njit(cache=True)
def _snap_rows(curve, k, width):  # pragma: no cover - compiled
    """(B,) :func:`snap_to_peak` of the indices k (B,) on the rows of ``curve`` (B, n)."""
    out = np.empty(k.shape[0], dtype=np.int64)
    for b in range(k.shape[0]):
        out[b] = _nearest_peak(curve[b], k[b], width)
    return out


@numba.njit(cache=True)
def _swap_near(values, k, near_top, saved):  # pragma: no cover - compiled
    """In place: the values (B, Nc) at the lags k − ``near_top`` … k + ``near_top`` (clipped
    to the row) of each row, k (B,), exchanged with the first of ``saved`` (B, 2·near_top
    + 1); a second call undoes the first."""
    n = values.shape[1]
    for b in range(values.shape[0]):
        lo, hi = max(k[b] - near_top, 0), min(k[b] + near_top, n - 1)
        for i in range(lo, hi + 1):
            values[b, i], saved[b, i - lo] = saved[b, i - lo], values[b, i]


@numba.njit(cache=True)
def _near_run(row, k, floor, near_top):  # pragma: no cover - compiled
    """Over the 2·``near_top`` + 1 lags j of k − near_top … k + near_top (each clipped to
    the row (n,)): (the number of lags whose value is at least ``floor`` (float64), the
    first and the last such j); (0, 0, 2·near_top) when there is none."""
    n, count, first, last = row.shape[0], 0, -1, 2 * near_top
    for j in range(2 * near_top + 1):
        if row[min(max(k - near_top + j, 0), n - 1)] >= floor:
            count += 1
            first = j if first < 0 else first
            last = j
    return count, max(first, 0), last if first >= 0 else 2 * near_top


@numba.njit(cache=True)
def _flat_top(row, start, stop, m):  # pragma: no cover - compiled
    """Whether a pair of samples (p, p + 1) of the raw row (n,), p = start … stop (samples
    clipped to the row), is level to within the margin m, the sample before it rises into
    it and the one after it falls from it (each to within m): a top a snap may take."""
    n = row.shape[0]
    for p in range(start, stop + 1):
        v0 = np.float64(row[min(max(p - 1, 0), n - 1)])
        v1 = np.float64(row[min(max(p, 0), n - 1)])
        v2 = np.float64(row[min(max(p + 1, 0), n - 1)])
        v3 = np.float64(row[min(max(p + 2, 0), n - 1)])
        if abs(v2 - v1) <= m and v1 - v0 >= -m and v3 - v2 <= m:
            return True
    return False


@numba.njit(cache=True)
def _runner_up_rows(values, k, far, curve, lowpassed, raw, width, near_top):  # pragma: no cover
    """(B,) bool :meth:`_Margins.runner_up` for the argmax k (B,) of the low-passed rows
    ``values`` (B, Nc), ``far`` (B,) their largest values beyond ``near_top`` lags of k,
    the raw rows ``curve`` (B, Nc) and the margins ``lowpassed`` and ``raw`` (B,) (float64).
    The near run is the lags within ``lowpassed`` of the top (:func:`_near_run`). A row is
    unsure when ``far`` reaches the run, when the run has a gap or touches the end of the
    search, when its ends snap (``width``) to different raw peaks, or when the raw curve
    has a flat top (:func:`_flat_top`) from the run's first lag − ``width`` − 1 to its last
    + ``width`` + 1 (the batch's widest run, S = max(last − first): to first + S +
    ``width``, as the vectorized form searched)."""
    B, n = values.shape
    first, last = np.empty(B, dtype=np.int64), np.empty(B, dtype=np.int64)
    unsure = np.zeros(B, dtype=np.bool_)
    for b in range(B):
        row, kb = values[b], k[b]
        floor = np.float64(row[kb]) - lowpassed[b]
        count, f, l = _near_run(row, kb, floor, near_top)
        unsure[b] = far[b] >= floor or count != l - f + 1 or f == 0 or l == 2 * near_top
        first[b] = min(max(kb - near_top + f, 0), n - 1)
        last[b] = min(max(kb - near_top + l, 0), n - 1)
        if not unsure[b]:
            a = curve[b]
            unsure[b] = _nearest_peak(a, first[b], width) != _nearest_peak(a, last[b], width)
    span = np.max(last - first) if B else 0
    for b in range(B):
        if not unsure[b]:
            stop = min(last[b] + width + 1, first[b] + span + width)
            unsure[b] = _flat_top(curve[b], first[b] - width - 1, stop, raw[b])
    return unsure


FORMS = ("matrix", "fft")


def dsp_form(receiver: Receiver) -> str:
    """The :class:`Dsp` form for a receiver: ``"fft"`` for windows of
    :data:`FFT_MIN_WINDOW` samples and more that span three decay lengths of the
    high-pass's response, else ``"matrix"``."""
    kernel = _highpass_kernel(receiver)
    fits = kernel is not None and receiver.window >= 3 * (len(kernel) // 2)
    return "fft" if receiver.window >= FFT_MIN_WINDOW and fits else "matrix"


#: where the high-pass's response is cut: below this share of its peak (double
#: precision's rounding) and, for a single-precision DSP, :data:`SINGLE_TAIL`
DOUBLE_TAIL, SINGLE_TAIL = 1e-17, 1e-9


def _highpass_kernel(receiver: Receiver, tail: float = DOUBLE_TAIL) -> np.ndarray | None:
    """(2L + 1,) the zero-phase high-pass's two-sided impulse response (centre L), cut
    where it has decayed below ``tail`` of its peak; None when that takes more than
    :data:`KERNEL_PROBE` samples a side (the FFT form then does not apply)."""
    return _kernel_cached(receiver.highpass_order, receiver.highpass_cutoff, receiver.fs, tail)


#: samples a side of the impulse used to find the high-pass's two-sided response
KERNEL_PROBE = 4096


@functools.lru_cache(maxsize=8)
def _kernel_cached(order: int, cutoff: float, fs: float, tail: float) -> np.ndarray | None:
    import scipy.signal

    sos = scipy.signal.butter(order, cutoff, "highpass", fs=fs, output="sos")
    unit = np.zeros(2 * KERNEL_PROBE + 1)
    unit[KERNEL_PROBE] = 1.0
    try:
        h = scipy.signal.sosfiltfilt(sos, unit)
    except np.linalg.LinAlgError:
        return None
    beyond = np.maximum.accumulate(np.abs(h[KERNEL_PROBE:])[::-1])[::-1]  # max beyond each lag
    small = np.flatnonzero(beyond < tail * np.abs(h).max())
    if not small.size or small[0] > KERNEL_PROBE // 2:
        return None
    L = int(small[0])
    return h[KERNEL_PROBE - L : KERNEL_PROBE + L + 1]


def detection_threshold(false_alarm: float, lags: int) -> float:
    """η = Q⁻¹(P_fa / (2·lags)): with it, noise alone exceeds η standard deviations at any
    of ``lags`` Gaussian lags with probability at most P_fa (union bound)."""
    from scipy.special import ndtri

    return float(-ndtri(false_alarm / (2.0 * lags)))


def signal_chain(chirp: Chirp | None, receiver: Receiver | None) -> tuple[Chirp, Receiver]:
    """The chirp and receiver (the defaults when None), checked to work together: the
    chirp's band below the receiver's Nyquist frequency fs/2."""
    chirp = Chirp() if chirp is None else chirp
    receiver = Receiver() if receiver is None else receiver
    if not isinstance(chirp, Chirp):
        raise ValueError(f"chirp: must be a simulation.Chirp or None, got {checks.describe(chirp)}")
    if not isinstance(receiver, Receiver):
        raise ValueError(
            f"receiver: must be a simulation.Receiver or None, got {checks.describe(receiver)}"
        )
    top = max(chirp.f0, chirp.f1)
    if not top < receiver.fs / 2:
        raise ValueError(
            f"chirp: its band reaches {top:g} Hz, at or above the receiver's Nyquist frequency "
            f"fs/2 = {receiver.fs / 2:g} Hz (it would alias)"
        )
    return chirp, receiver


def dsp_for(
    chirp: Chirp | None = None,
    receiver: Receiver | None = None,
    precision: str = "float64",
    form: str | None = None,
) -> Dsp:
    """The (cached) :class:`Dsp` of a chirp and receiver (the defaults when None)."""
    chirp, receiver = signal_chain(chirp, receiver)
    return _dsp_cached(chirp, receiver, precision, form)


@functools.lru_cache(maxsize=8)
def _dsp_cached(chirp: Chirp, receiver: Receiver, precision: str, form) -> Dsp:
    return Dsp(chirp, receiver, precision, form)

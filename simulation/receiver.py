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
4. k = argmax of the low-passed curve, snapped to the nearest local maximum of a (ties to
   the lower index);
5. the window starts at chirp sample s = k + 1 − N, so τ = (t_wake·fs − s)/fs, r = c·τ;
6. the range is kept only when the direct path's time of flight lies within the signal's
   reach (:mod:`simulation.signal`: the window can hold its chirp) and the chirp was heard:
   the window has a peak (|c[k]| > 0) and, with a detection threshold (``false_alarm``
   set), |c[k]| > η·σ·‖g_k‖ with the picked time of flight τ̂ within the reach too;
   otherwise the receiver reports "no range" (NaN, with a status of :data:`RANGE_STATUS`).

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
same index (tested on thousands of clean, noisy and reverberant windows): steps 1–2 are
linear in x (``sosfiltfilt`` with odd padding and scaled initial conditions is a linear map
of the window), so they are folded into one (Nc, N) matrix G applied to a batch with one
matrix product; step 3 is a product with |H|² in the frequency domain (one rfft and one
irfft of size ≥ Nc + taps − 1, no wrap-around), in blocks that can run on several threads.

The float64 chain is bound by that product and the two FFTs (docs/implementation.md).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import scipy.fft

from simulation import checks
from simulation.chirp import Chirp

#: accepted false-alarm probability per window of the detection (exclusive of 0)
FALSE_ALARM_RANGE = (0.0, 0.5)

#: what the receiver made of a window: a range, or why not (the range is NaN then)
RANGE_STATUS = {
    0: "heard: a range",
    1: "not heard: no correlation peak above the detection threshold",
    2: "out of reach: the time of flight lies outside the signal's reach",
}
HEARD, NOT_HEARD, OUT_OF_REACH = 0, 1, 2


@dataclass(frozen=True)
class Receiver:
    """Sampling, DSP and detection settings of the mobile node (defaults: docs/model.md).

    fs : sampling rate (Hz). t_wake : when the node wakes, seconds after the chirp starts.
    window : samples N it records from then. highpass_order, highpass_cutoff (Hz),
    lowpass_taps, lowpass_cutoff (Hz) : the DSP filters. false_alarm : the detection
    threshold's bound on the probability that a window of noise alone gives a range
    (module docstring), in (0, 0.5); None (the paper's receiver): no threshold.
    """

    fs: float = 192e3
    t_wake: float = 29e-3
    window: int = 192
    highpass_order: int = 10
    highpass_cutoff: float = 15e3
    lowpass_taps: int = 1000
    lowpass_cutoff: float = 5e3
    false_alarm: float | None = None

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


def reference_chain(window, chirp: Chirp | None = None, receiver: Receiver | None = None) -> dict:
    """The receiver DSP written literally for one window (N,); the definition of the chain.

    Returns a dict with the high-passed window ``x_hp``, the raw curve ``corr`` = |c| (Nc,),
    the low-passed curve ``lowpassed``, the low-pass argmax ``k_lowpass`` and the snapped
    index ``k``. Slow; used to check :class:`Dsp`.
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


PRECISIONS = ("float64", "float32")
#: the simulator's default DSP precision: float32 picks the float64 correlation index for
#: all but a few windows in 10⁴ (docs/model.md, "The receiver chain"); "float64" stays
#: selectable
DEFAULT_PRECISION = "float32"

#: size of the correlation buffer of one part (bytes): a part's correlation is one matrix
#: product (see Dsp.indices)
PART_BYTES = 128 * 2**20


class Dsp:
    """Batched, fast form of the receiver chain for one chirp and receiver.

    Build with :func:`dsp_for` (cached). ``indices(windows)`` maps windows (..., N) to the
    snapped full-correlation indices (...,) and ``ranges(windows, c)`` to metres.

    ``precision="float64"`` (this class's default) gives the index of
    :func:`reference_chain`. ``"float32"`` (the simulator's default,
    :data:`DEFAULT_PRECISION`) runs the correlation and low-pass in single precision;
    rounding then moves the low-pass argmax of a few windows in 10⁴ onto a neighbouring
    raw peak (docs/model.md, "The receiver chain").
    """

    def __init__(self, chirp: Chirp, receiver: Receiver, precision: str = "float64"):
        import scipy.signal

        if precision not in PRECISIONS:
            raise ValueError(f"precision: must be one of {PRECISIONS}, got {precision!r}")
        self.chirp = chirp
        self.receiver = receiver
        self.precision = precision
        self.dtype = np.dtype(precision)
        N = receiver.window
        n_ref = int(round(chirp.duration * receiver.fs))
        checks.check_size(
            "chirp duration x fs x window",
            (n_ref + N) * N * 8 * 4,
            value=(chirp.duration, receiver.fs, N),
            hint="use a shorter chirp, a lower fs or a shorter window",
        )
        ref = chirp.samples(receiver.fs)
        if len(ref) < 2:
            raise ValueError("chirp: shorter than two samples at the receiver's fs")
        self.n_corr = len(ref) + N - 1
        # Steps 1-2 as one matrix: c = T · reverse(H · x) = (T · H[::-1]) x, with H the
        # sosfiltfilt map (applied to the identity) and T the (Nc, N) convolution matrix
        # of ref, T[k, m] = ref[k − m].
        try:
            H = scipy.signal.sosfiltfilt(receiver.highpass_sos(), np.eye(N), axis=0)
        except np.linalg.LinAlgError:  # poles at z = 1 to rounding: no initial conditions
            raise ValueError(
                f"highpass_cutoff: {receiver.highpass_cutoff:g} Hz is too close to 0 for a "
                f"high-pass of order {receiver.highpass_order} at fs = {receiver.fs:g} Hz"
            ) from None
        kk = np.arange(self.n_corr)[:, None] - np.arange(N)[None, :]
        T = np.where((kk >= 0) & (kk < len(ref)), ref[np.clip(kk, 0, len(ref) - 1)], 0.0)
        self.G_T = np.ascontiguousarray((T @ H[::-1]).T)  # (N, Nc): windows @ G_T
        # Step 3: |H|² in the frequency domain, kernel centred at lag 0. Outputs 0..Nc−1
        # see no wrap-around when nfft ≥ Nc + taps − 1.
        kern = receiver.lowpass_kernel()
        half = receiver.lowpass_taps - 1
        self.nfft = scipy.fft.next_fast_len(self.n_corr + half, real=True)
        hc = np.zeros(self.nfft)
        hc[: half + 1] = kern[half:]
        hc[self.nfft - half :] = kern[:half]
        self.lowpass_response = scipy.fft.rfft(hc).real  # |H(f)|², real: kernel symmetric
        self._G = self.G_T.astype(self.dtype)
        self._H = self.lowpass_response.astype(self.dtype)
        # raw peaks of |c| are half a carrier period apart: search a few periods around
        self.snap_width = max(32, math.ceil(receiver.fs / min(chirp.f0, chirp.f1)) + 2)
        #: (Nc,) ‖g_k‖: the standard deviation of c[k] for white noise of unit σ
        self.noise_gain = np.sqrt(np.einsum("nk,nk->k", self.G_T, self.G_T))
        #: η: the detection threshold in noise standard deviations (module docstring); 0
        #: without one (the paper's receiver)
        self.threshold = (
            0.0
            if receiver.false_alarm is None
            else detection_threshold(receiver.false_alarm, self.n_corr)
        )

    def correlation(self, windows: np.ndarray) -> np.ndarray:
        """(B, Nc) raw curve |c| of windows (B, N)."""
        return np.abs(np.asarray(windows, dtype=float) @ self.G_T)

    def lowpass(self, curve: np.ndarray) -> np.ndarray:
        """(B, Nc) zero-phase low-pass of curves (B, Nc)."""
        spec = scipy.fft.rfft(curve, n=self.nfft, axis=-1)
        spec *= self.lowpass_response
        return scipy.fft.irfft(spec, n=self.nfft, axis=-1)[:, : self.n_corr]

    def _block_picks(self, buf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Snapped indices (B,) and the raw peaks |c[k]| there (B,) of rows (B, nfft)
        holding c at lags 0 … Nc − 1, zeros after (c is replaced by |c| in place)."""
        curve = buf[:, : self.n_corr]
        np.abs(curve, out=curve)
        spec = scipy.fft.rfft(buf, axis=-1, workers=1)
        spec *= self._H
        lp = scipy.fft.irfft(spec, n=self.nfft, axis=-1, workers=1)
        lp[:, self.n_corr :] = -np.inf  # outside the correlation; argmax on whole rows is faster
        k = snap_to_peak(curve, np.argmax(lp, axis=-1), self.snap_width)
        return k, curve[np.arange(len(k)), k].astype(float)

    def indices(self, windows: np.ndarray, block: int = 128) -> np.ndarray:
        """Snapped full-correlation index k (...,) for windows (..., N) (:meth:`picks`)."""
        return self.picks(windows, block)[0]

    def picks(self, windows: np.ndarray, block: int = 128) -> tuple[np.ndarray, np.ndarray]:
        """Snapped full-correlation index k (...,) and raw peak |c[k]| (...,) for windows
        (..., N).

        Windows go through in parts of up to :data:`PART_BYTES` of correlation: a part's
        correlation is one matrix product into a zero-padded buffer reused from part to part
        (few large products: each wakes the BLAS threads), its FFTs run in blocks of
        ``block`` rows on ``scipy.fft``'s worker count of threads (``with
        scipy.fft.set_workers(n): ...``; numpy and scipy.fft release the GIL). Results
        depend neither on ``block`` nor on the threads.
        """
        if int(block) != block or block < 1:
            raise ValueError(f"block: must be an integer >= 1, got {block}")
        w = np.asarray(windows, dtype=float)
        if w.shape[-1] != self.receiver.window:
            raise ValueError(f"windows: last axis must be {self.receiver.window}, got {w.shape}")
        lead = w.shape[:-1]
        flat = w.reshape(-1, w.shape[-1])
        n = flat.shape[0]
        step = block * max(1, PART_BYTES // (self.nfft * self.dtype.itemsize * block))
        out = np.empty(n, dtype=np.int64)
        peak = np.empty(n)
        buf = np.zeros((min(step, n), self.nfft), dtype=self.dtype)
        threads = min(scipy.fft.get_workers(), -(-min(step, n) // block))
        pool = None
        if threads > 1:
            from concurrent.futures import ThreadPoolExecutor

            pool = ThreadPoolExecutor(threads)
        try:
            for s in range(0, n, step):
                part = flat[s : s + step]
                rows = buf[: part.shape[0]]
                np.matmul(part.astype(self.dtype, copy=False), self._G, out=rows[:, : self.n_corr])
                starts = range(0, part.shape[0], block)
                blocks = (rows[b : b + block] for b in starts)
                results = list(
                    map(self._block_picks, blocks)
                    if pool is None
                    else pool.map(self._block_picks, blocks)
                )
                out[s : s + part.shape[0]] = np.concatenate([r[0] for r in results])
                peak[s : s + part.shape[0]] = np.concatenate([r[1] for r in results])
        finally:
            if pool is not None:
                pool.shutdown()
        return out.reshape(lead), peak.reshape(lead)

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
        ``delays`` = (τ_min, τ_max) seconds (:attr:`simulation.signal.Signal.delays`) and
        the picked peak exceeds η·σ·‖g_k‖ (``noise_sigma`` σ broadcast likewise; η = 0
        without a threshold, and then any peak > 0 is heard) with, under a threshold,
        the picked delay within ``delays`` too."""
        k, peak = self.picks(windows)
        r = self.receiver.range_from_index(k, speed_of_sound)
        sigma = np.broadcast_to(np.asarray(noise_sigma, dtype=float), k.shape)
        heard = peak > self.threshold * sigma * self.noise_gain[k]
        lo, hi = delays
        direct = np.broadcast_to(np.asarray(direct_delays, dtype=float), k.shape)
        seen = (direct >= lo) & (direct <= hi)
        if self.receiver.false_alarm is not None:  # a detecting receiver checks its pick too
            tau = (self.receiver.wake_sample - (k + 1.0 - self.receiver.window)) / self.receiver.fs
            seen &= (tau >= lo) & (tau <= hi)
        status = np.where(seen, np.where(heard, HEARD, NOT_HEARD), OUT_OF_REACH)
        status = status.astype(np.int8)
        return np.where(status == HEARD, r, np.nan), status


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
    chirp: Chirp | None = None, receiver: Receiver | None = None, precision: str = "float64"
) -> Dsp:
    """The (cached) :class:`Dsp` of a chirp and receiver (the defaults when None)."""
    chirp, receiver = signal_chain(chirp, receiver)
    return _dsp_cached(chirp, receiver, precision)


@functools.lru_cache(maxsize=8)
def _dsp_cached(chirp: Chirp, receiver: Receiver, precision: str) -> Dsp:
    return Dsp(chirp, receiver, precision)

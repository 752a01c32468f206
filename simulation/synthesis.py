"""Windows synthesized from the analytic chirp for given path delays and amplitudes (paper
§II); ``receiver`` arguments are :class:`simulation.receiver.Receiver` (its fs, t_wake and
window).

The node samples at fs for N samples from t_wake after the chirp starts. The noise-free
window of anchor j at node p is the superposition of the delayed, scaled chirps of its
paths,

    y[n] = Σ_i A_i · s(t_wake + n/fs − τ_i),   τ_i = d_i / c,  n = 0 … N−1,

with s the analytic chirp (zero outside [0, T]), so no impulse responses are needed and
fractional delays are exact. Paths whose chirp does not overlap the window (they arrive
after it closes, or the chirp has ended before it opens) and zero-amplitude paths are not
evaluated.

Frequency-dependent air absorption (``Room(air_absorption="iso9613")``): the amplitudes
A_i hold the attenuation at the chirp's centre frequency; the rest of the band is applied
as an envelope along the chirp, A_i · exp(−½ d_i Δm(f(u))), with f(u) = f0 + k·u the
instantaneous frequency at chirp time u = t_n − τ_i and Δm(f) = m(f) − m(f_centre). This is
the chirp filtered by the path's attenuation |H_i(f)| = exp(−½ d_i m(f)) in the
stationary-phase approximation, which holds because the attenuation varies little over the
chirp's instantaneous bandwidth (docs/model.md, "Air absorption").
"""

from __future__ import annotations

import numba
import numpy as np

from simulation.chirp import Chirp


def active_paths(delays: np.ndarray, amplitude: np.ndarray, chirp: Chirp, receiver):
    """Boolean mask, shape of ``delays``: the path has A ≠ 0 and its chirp overlaps the window."""
    t0 = receiver.t_wake
    t1 = receiver.t_wake + (receiver.window - 1) / receiver.fs
    return (amplitude != 0) & (delays <= t1) & (delays >= t0 - chirp.duration)


def synthesize(
    delays: np.ndarray,
    amplitude: np.ndarray,
    chirp: Chirp,
    receiver,
    *,
    lengths: np.ndarray | None = None,
    air=None,
    grouped: bool = False,
) -> np.ndarray:
    """Noise-free windows (..., N) for path delays and amplitudes (..., I) (s, unit chirp).

    ``grouped`` sums the windows in groups of similar path counts (a polygonal room's
    windows hold from a few paths to a hundred; the result equals the ungrouped one to
    rounding).

    ``air`` (a function f ↦ Δm(f) in 1/m, e.g. ``Room.air_excess()``) with the path
    ``lengths`` (..., I) in m applies the air's attenuation across the band (module
    docstring): exactly sample by sample for paths evaluated directly, and for the fast
    form below with ln of the envelope linear across the window, its value and slope
    taken at the window's centre frequency.

    Fast form of :func:`synthesize_direct` (equal to ~1e-13 relative). For a path whose
    chirp covers the whole window, with u0 = t_wake − τ the chirp's time at sample 0, the
    phase is quadratic in n:

        2π(f0 u + ½ k u²), u = u0 + n/fs  →  α + β n + γ n²,
        α = 2π(f0 u0 + ½ k u0²), β = 2π(f0 + k u0)/fs, γ = π k/fs²,

    so Σ_i A_i sin(·) = Im(e^{iγn²} Σ_i A_i e^{iα_i} e^{iβ_i n}); γ is common to all paths.
    Writing n = Q·q + r, e^{iβn} = e^{iβQq}·e^{iβr}, and the path sum becomes one small
    complex matrix product per window, with the powers from cumulative products (three
    complex exponentials per path instead of N sines). Paths that see the chirp start or
    end inside the window are evaluated directly.
    """
    delays = np.asarray(delays, dtype=float)
    amplitude = np.asarray(amplitude, dtype=float)
    if delays.shape != amplitude.shape:
        raise ValueError(f"delays {delays.shape} and amplitude {amplitude.shape} must match")
    lead = delays.shape[:-1]
    n_win = int(np.prod(lead, dtype=np.int64))
    N, fs = receiver.window, receiver.fs
    tau = delays.reshape(n_win, -1)
    amp = amplitude.reshape(n_win, -1)
    dist = None
    if air is not None:
        if lengths is None or np.shape(lengths) != delays.shape:
            raise ValueError(f"lengths: expected the shape of delays {delays.shape} with air")
        dist = np.asarray(lengths, dtype=float).reshape(n_win, -1)
    act = active_paths(tau, amp, chirp, receiver)
    u0 = receiver.t_wake - tau
    if N >= LONG_WINDOW:
        return _long_windows(u0, amp, act, dist, air, chirp, receiver).reshape(*lead, N)
    whole = act & (u0 >= 0) & (u0 + (N - 1) / fs <= chirp.duration)
    out = _synthesize_direct_rows(tau, amp, act & ~whole, chirp, receiver, dist, air)
    if not np.any(whole):
        return out.reshape(*lead, N)
    groups = _groups(np.sum(whole, axis=1)) if grouped else [slice(None)]
    for rows in groups:
        out[rows] += _whole_windows(
            u0[rows], amp[rows], whole[rows], None if dist is None else dist[rows], air,
            chirp, receiver,
        )  # fmt: skip
    return out.reshape(*lead, N)


#: windows per group of similar path counts (:func:`_groups`)
GROUP = 2048
#: windows of this many samples and more (longer than the paper's 192) are synthesized by
#: :func:`_long_windows`
LONG_WINDOW = 256


def _long_windows(u0, amp, act, dist, air, chirp: Chirp, receiver) -> np.ndarray:
    """(W, N) the sum of the active paths (``act`` (W, I)) of long windows, whose chirp
    may start and end inside the window: :func:`synthesize`'s fast form with each path
    restricted to the samples its chirp covers, n ∈ [a, b] with 0 ≤ u0 + n/fs ≤ T.

    Compiled (:func:`_long_kernel`): per path, the powers e^{βr}, r < Q, once, then block
    by block n = Q·q + r the block's power times them, over the blocks its support holds
    (the first and last ones in part)."""
    n_win, N, fs = len(u0), receiver.window, receiver.fs
    a = np.clip(np.ceil(-u0 * fs), 0, N).astype(np.int64)
    b = np.clip(np.floor((chirp.duration - u0) * fs), -1, N - 1).astype(np.int64)
    w_amp = np.where(act & (b >= a), amp, 0.0)
    k = chirp.rate
    alpha = 2 * np.pi * (chirp.f0 * u0 + 0.5 * k * u0 * u0)
    step = 1j * (2 * np.pi * (chirp.f0 + k * u0) / fs)  # per sample: e^{iβ}
    weights = w_amp * np.exp(1j * alpha)
    if air is not None:  # the air's envelope linearized at the centre of each support
        log0, slope = _air_envelope(air, dist, u0, chirp, receiver, 0.5 * (a + b))
        weights = weights * np.exp(np.where(w_amp != 0, log0, 0.0))
        step = step + np.where(w_amp != 0, slope, 0.0)
    n = np.arange(N)
    quad = np.exp(1j * (np.pi * k / fs**2) * (n * n))
    out = np.empty((n_win, N))
    _long_kernel(weights.real.copy(), weights.imag.copy(), step.real.copy(), step.imag.copy(),
                 a, b, quad.real.copy(), quad.imag.copy(), out)  # fmt: skip
    return out


@numba.njit(cache=True)
def _long_kernel(w_re, w_im, s_re, s_im, a, b, q_re, q_im, out):  # pragma: no cover - compiled
    """out[w, n] = Im(quad[n] · Σ_i w_i e^{s_i n} [a_i ≤ n ≤ b_i]) for windows w, paths i:
    weights w = w_re + i w_im, per-sample log-steps s (W, I), supports [a, b] (W, I)."""
    n_win, n_path = w_re.shape
    N = out.shape[1]
    Q = 64
    z_re = np.empty(N)
    z_im = np.empty(N)
    e_re = np.empty(Q)
    e_im = np.empty(Q)
    for w in range(n_win):
        z_re[:] = 0.0
        z_im[:] = 0.0
        for i in range(n_path):
            lo, hi = a[w, i], b[w, i]
            if hi < lo or (w_re[w, i] == 0.0 and w_im[w, i] == 0.0):
                continue
            step = complex(s_re[w, i], s_im[w, i])
            one = np.exp(step)
            e = 1.0 + 0.0j
            for r in range(Q):  # e^{s r}
                e_re[r] = e.real
                e_im[r] = e.imag
                e = e * one
            big = np.exp(Q * step)
            q0, q1 = lo // Q, hi // Q
            p = complex(w_re[w, i], w_im[w, i]) * np.exp(Q * q0 * step)
            for q in range(q0, q1 + 1):
                base = q * Q
                r0 = max(lo - base, 0)
                r1 = min(hi - base, Q - 1)
                pr, pi = p.real, p.imag
                for r in range(r0, r1 + 1):
                    z_re[base + r] += pr * e_re[r] - pi * e_im[r]
                    z_im[base + r] += pr * e_im[r] + pi * e_re[r]
                p = p * big
        for n in range(N):
            out[w, n] = q_re[n] * z_im[n] + q_im[n] * z_re[n]


def _groups(counts: np.ndarray) -> list:
    """Windows by their number of whole-window paths (W,): one group (every window) when
    the counts are even, as in a shoebox; else groups of similar counts, so that a window
    with few paths is not padded to the most any window has."""
    if counts.size <= GROUP or counts.max() <= 1.25 * max(np.median(counts), 1):
        return [slice(None)]
    order = np.argsort(counts, kind="stable")
    return [order[i : i + GROUP] for i in range(0, len(order), GROUP)]


def _whole_windows(u0, amp, whole, dist, air, chirp: Chirp, receiver) -> np.ndarray:
    """(W, N) the sum of the whole-window paths (``whole`` (W, I)) of windows whose chirp
    times at sample 0 are ``u0`` (W, I) (:func:`synthesize`'s fast form)."""
    n_win, N, fs = len(u0), receiver.window, receiver.fs
    # gather the whole-window paths of each window to the front, drop empty columns
    order = np.argsort(~whole, axis=1, kind="stable")
    width = int(np.max(np.sum(whole, axis=1)))
    order = order[:, :width]
    sel = np.take_along_axis(whole, order, axis=1)
    u = np.take_along_axis(u0, order, axis=1)
    w_amp = np.where(sel, np.take_along_axis(amp, order, axis=1), 0.0)
    k = chirp.rate
    alpha = 2 * np.pi * (chirp.f0 * u + 0.5 * k * u * u)
    beta = 2 * np.pi * (chirp.f0 + k * u) / fs
    Q = 16
    nq = -(-N // Q)
    weights = w_amp * np.exp(1j * alpha)
    step = 1j * beta  # per sample: e^{iβ}, times the envelope's e^{b} with air
    if air is not None:
        d = np.take_along_axis(dist, order, axis=1)
        log0, b = _air_envelope(air, d, u, chirp, receiver)
        weights = weights * np.exp(log0)
        step = step + b
    er = np.empty((n_win, width, Q), dtype=complex)  # e^{iβr}, r = 0…Q−1
    er[..., 0] = 1.0
    er[..., 1:] = np.exp(step)[..., None]
    _cumprod(er)
    eq = np.empty((n_win, width, nq), dtype=complex)  # A e^{iα} e^{iβQq}, q = 0…nq−1
    eq[..., 0] = weights
    eq[..., 1:] = np.exp(Q * step)[..., None]
    _cumprod(eq)
    z = np.matmul(eq.transpose(0, 2, 1), er).reshape(n_win, nq * Q)[:, :N]
    n = np.arange(N)
    quad = np.exp(1j * (np.pi * k / fs**2) * (n * n))
    return quad.real * z.imag + quad.imag * z.real


def _cumprod(z: np.ndarray) -> None:
    """In place: z (W, I, K) complex replaced by its cumulative products along the last
    axis, bit for bit ``np.cumprod(z, axis=-1)``: compiled for K ≥ 3 (numpy's accumulate
    over a short last axis goes row by row, slowly, with the plain complex product the
    compiled loop uses), numpy's own for K ≤ 2 (one product a row, which numpy takes
    through its vectorized loop, rounded otherwise)."""
    if z.shape[-1] >= 3:
        _cumprod_rows(z)
    else:
        np.cumprod(z, axis=-1, out=z)


@numba.njit(cache=True)
def _cumprod_rows(z):  # pragma: no cover - compiled
    """In place: z[w, i, k] = z[w, i, k − 1] · z[w, i, k] for k = 1 … K − 1, z (W, I, K)."""
    W, I, K = z.shape
    for w in range(W):
        for i in range(I):
            for k in range(1, K):
                z[w, i, k] = z[w, i, k - 1] * z[w, i, k]


def _air_envelope(air, d: np.ndarray, u0: np.ndarray, chirp: Chirp, receiver, n_mid=None):
    """ln of the air envelope exp(−½ d Δm(f)) linear in the sample n across the window:
    (value at n = 0, slope per sample), from Δm and its derivative at the frequency of
    sample ``n_mid`` (default the window's centre), for paths of lengths d whose chirp time
    at sample 0 is u0 (same shapes)."""
    if n_mid is None:
        n_mid = 0.5 * (receiver.window - 1)
    f_mid = chirp.f0 + chirp.rate * (u0 + n_mid / receiver.fs)
    h = 1.0  # Hz: a central difference of a function smooth on the scale of kHz
    dm = air(f_mid)
    slope_f = (air(f_mid + h) - air(f_mid - h)) / (2 * h)  # 1/m per Hz
    b = -0.5 * d * slope_f * chirp.rate / receiver.fs  # per sample
    return -0.5 * d * dm - b * n_mid, b


def _synthesize_direct_rows(
    tau, amp, mask, chirp: Chirp, receiver, dist=None, air=None
) -> np.ndarray:
    """(W, N) Σ over masked paths of A·s(t_n − τ), evaluated sample by sample (with the
    air's envelope exp(−½ d Δm(f(u))) when ``air`` is given, ``dist`` the path lengths)."""
    n_win, N = tau.shape[0], receiver.window
    out = np.zeros((n_win, N))
    rows, _ = np.nonzero(mask)  # row-major: sorted by window
    if rows.size:
        u = (receiver.t_wake - tau[mask])[:, None] + np.arange(N) / receiver.fs
        contrib = amp[mask][:, None] * chirp(u)
        if air is not None:
            f = chirp.f0 + chirp.rate * np.clip(u, 0.0, chirp.duration)
            contrib *= np.exp(-0.5 * dist[mask][:, None] * air(f))
        starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]])
        out[rows[starts]] = np.add.reduceat(contrib, starts, axis=0)
    return out


def synthesize_direct(
    delays: np.ndarray,
    amplitude: np.ndarray,
    chirp: Chirp,
    receiver,
    *,
    lengths: np.ndarray | None = None,
    air=None,
) -> np.ndarray:
    """Reference form of :func:`synthesize`: every active path's chirp, sample by sample
    (the air's envelope exactly at every sample)."""
    delays = np.asarray(delays, dtype=float)
    amplitude = np.asarray(amplitude, dtype=float)
    lead = delays.shape[:-1]
    tau = delays.reshape(-1, delays.shape[-1])
    amp = amplitude.reshape(tau.shape)
    dist = None if air is None else np.asarray(lengths, dtype=float).reshape(tau.shape)
    act = active_paths(tau, amp, chirp, receiver)
    out = _synthesize_direct_rows(tau, amp, act, chirp, receiver, dist, air)
    return out.reshape(*lead, receiver.window)

"""Range-noise models: the σ_j(p) that enters the Fisher information (paper eq. 6).

- :class:`ConstantRangeNoise`: one σ for every anchor and node (default 0.04 m, the
  paper's 0.03–0.045 m).
- :class:`PhysicalRangeNoise`: σ_j(p) from the SNR that node p sees from anchor j, through
  the Cramér–Rao bound for time-delay estimation of the received 1 ms window.
- :class:`CalibratedRangeNoise` / :func:`calibrated_sigma`: robust per-anchor σ from
  simulated range errors (``simulation.evaluate_layout(...).range_errors``).

Every model has ``sigma(anchors, positions)`` returning σ in metres, broadcastable to
(..., P, M) for anchors (..., M, 3) and positions (P, 3).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from analysis.fim import DEFAULT_SIGMA, check_sigma
from simulation import checks
from simulation.directivity import aim_vectors, cardioid
from simulation.multipath import REFERENCE_FREQUENCY
from simulation.noise import check_snr
from simulation.room import Room, as_room
from simulation.system import System, as_system

#: accepted constant range σ (m)


@dataclass(frozen=True)
class ConstantRangeNoise:
    """σ_j(p) = ``value`` metres for every pair."""

    value: float = DEFAULT_SIGMA

    def __post_init__(self) -> None:
        v = check_sigma(self.value, "value")
        object.__setattr__(self, "value", v)

    def sigma(self, anchors, positions) -> np.ndarray:
        """σ as a 0-d array (broadcasts to any (..., P, M))."""
        return np.asarray(self.value)


def direct_amplitude(
    room: Room, anchors, positions, frequency: float = REFERENCE_FREQUENCY
) -> np.ndarray:
    """Direct-path amplitude A_j(p), (..., P, M), for a unit-amplitude chirp at the speaker.

    A = g(θ)·exp(−a·d/2)/(4π d): cardioid gain toward p (anchor aimed at the centroid),
    air absorption at ``frequency`` (Hz, the chirp's centre) and spherical spreading
    (docs/model.md). A node on an anchor gets +inf.
    """
    room = as_room(room)
    a = checks.reals("anchors", anchors)
    p = checks.points("positions", positions)
    if a.ndim < 2 or a.shape[-1] != 3:
        raise ValueError(f"anchors: expected shape (..., M, 3), got {a.shape}")
    diff = p[:, None, :] - a[..., None, :, :]  # (..., P, M, 3)
    d = np.linalg.norm(diff, axis=-1)
    aim = aim_vectors(a, room.centroid)[..., None, :, :]  # (..., 1, M, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.where(d > 0, np.sum(diff * aim, axis=-1) / np.where(d > 0, d, 1.0), 1.0)
        air = float(room.air_coefficient(frequency))
        amp = cardioid(cos) * np.exp(-0.5 * air * d) / (4 * np.pi * d)
    return np.where(d > 0, amp, np.inf)


@dataclass(frozen=True)
class PhysicalRangeNoise:
    """Range σ from the SNR at each node and the CRLB of time-delay estimation.

    Per anchor j the white-noise variance is set as in paper §V-A: SNR = ``snr_db`` at the
    grid node closest to the anchor, σ_w,j² = (A_j(p_ref)²/2)/10^(SNR/10) (A²/2 is the mean
    power of the direct-path sinusoid; multipath is not modelled here). At node p the
    received window is A_j(p)·s(t_n − τ), t_n = t_wake + n/fs, n = 0…N−1, τ = d/c. The CRLB
    for the delay of a known waveform in white Gaussian noise is

        var(τ̂) ≥ σ_w² / Σ_n (A ṡ(t_n − τ))²  ≈  σ_w² / (A² · 2π² · Σ_n f(t_n − τ)²),

    using ṡ = 2π f(t) cos(·) with instantaneous frequency f(t) = f0 + k t and ⟨cos²⟩ = ½,
    the sum running over the samples where the chirp is on. Then σ_r = c·√var(τ̂):

        σ_j(p) = c / (2π) · (A_j(p_ref)/A_j(p)) / √(10^(SNR/10) · Σ_n f(t_n − τ)²).

    This is the coherent (carrier-phase) bound: it assumes the right carrier peak is
    found, so it is far below what the envelope-and-snap receiver achieves in a
    reverberant room (millimetres, against centimetres to metres); use it to see the
    geometry of the SNR, and a calibrated σ to compare with simulation.

    σ = inf (no information from that anchor: the receiver gets no direct-path range) where
    the anchor is not heard (:meth:`heard`): a wall or an obstacle blocks the line of sight,
    the direct path lies beyond the signal's reach or within its near limit, or, for a
    receiver with a detection threshold η, its expected correlation peak A_j(p)·‖g_k‖²
    stays below η·σ_w,j·‖g_k‖ (:mod:`simulation.receiver`).
    """

    room: Room = field(default_factory=Room.techtile)
    snr_db: float = 30.0
    grid_shape: tuple[int, int, int] = (9, 6, 5)
    system: System = field(default_factory=System)

    def __post_init__(self) -> None:
        if not isinstance(self.room, Room):
            raise ValueError(f"room: must be a simulation.Room, got {checks.describe(self.room)}")
        object.__setattr__(self, "snr_db", check_snr("snr_db", self.snr_db))
        object.__setattr__(self, "grid_shape", checks.grid_shape("grid_shape", self.grid_shape))
        object.__setattr__(self, "system", as_system(self.system))

    @property
    def chirp(self):
        """The system's chirp."""
        return self.system.chirp

    @property
    def receiver(self):
        """The system's receiver."""
        return self.system.receiver

    def reference_amplitude(self, anchors) -> np.ndarray:
        """A_j at the grid node closest to each anchor, (..., M)."""
        a = np.asarray(anchors, dtype=float)
        grid = self.room.grid(self.grid_shape)  # the room grid, not the tag zones (SNR rule)
        d = np.linalg.norm(grid[:, None, :] - a[..., None, :, :], axis=-1)  # (..., G, M)
        closest = np.argmin(d, axis=-2)  # (..., M)
        amp = direct_amplitude(self.room, a, grid, self.chirp.centre)  # (..., G, M)
        return np.take_along_axis(amp, closest[..., None, :], axis=-2)[..., 0, :]

    def _sum_f2(self, tau: np.ndarray) -> np.ndarray:
        """Σ_n f(t_n − τ)² over window samples inside the chirp, closed form, shape of τ."""
        rx, ch = self.receiver, self.chirp
        fs, N = rx.fs, rx.window
        lo = np.clip(np.ceil((tau - rx.t_wake) * fs), 0, N)
        hi = np.clip(np.floor((tau + ch.duration - rx.t_wake) * fs), -1, N - 1)
        cnt = np.maximum(hi - lo + 1, 0)
        # f_n = α + β n with α = f0 + k(t_wake − τ), β = k/fs
        alpha = ch.f0 + ch.rate * (rx.t_wake - tau)
        beta = ch.rate / fs

        def s1(n):  # Σ_{i=0}^{n} i
            return n * (n + 1) / 2

        def s2(n):  # Σ_{i=0}^{n} i²
            return n * (n + 1) * (2 * n + 1) / 6

        S1 = np.where(cnt > 0, s1(hi) - s1(lo - 1), 0.0)
        S2 = np.where(cnt > 0, s2(hi) - s2(lo - 1), 0.0)
        return cnt * alpha**2 + 2 * alpha * beta * S1 + beta**2 * S2

    def heard(self, anchors, positions) -> np.ndarray:
        """(..., P, M) bool: the receiver reports a range of anchor j at node p from its
        direct path (class docstring): a line of sight (no wall or obstacle between them,
        :func:`simulation.polyhedral.line_of_sight`), the direct path within the signal's
        reach and, with a detection threshold, its expected correlation peak above it."""
        from simulation.polyhedral import line_of_sight

        a = np.asarray(anchors, dtype=float)
        p = np.asarray(positions, dtype=float)
        d = np.linalg.norm(p[:, None, :] - a[..., None, :, :], axis=-1)
        c = self.room.speed_of_sound
        lo, hi = self.system.delays
        out = (d / c >= lo) & (d / c <= hi) & line_of_sight(self.room, a, p)
        rx = self.receiver
        if rx.false_alarm is not None:
            from simulation.receiver import dsp_for

            dsp = dsp_for(self.chirp, rx)
            k = np.clip(np.rint(rx.index_from_range(d, c)), 0, dsp.n_corr - 1).astype(int)
            gain = dsp.noise_gain[k]
            noise = self.reference_amplitude(a)[..., None, :] / np.sqrt(2.0)
            noise = noise / np.sqrt(10.0 ** (self.snr_db / 10.0))  # σ_w of the SNR rule
            amp = direct_amplitude(self.room, a, p, self.chirp.centre)
            out &= amp * gain > dsp.threshold * noise
        return out

    def sigma(self, anchors, positions) -> np.ndarray:
        """σ_j(p) in metres, (..., P, M); inf where the anchor is not :meth:`heard`.
        Anchors (..., M, 3) and positions (P, 3) must lie in the room (a speaker outside it
        has no SNR here): ``ValueError`` otherwise."""
        a = checks.reals("anchors", anchors)
        p = checks.reals("positions", positions)
        if a.ndim < 2 or a.shape[-1] != 3:
            raise ValueError(f"anchors: expected shape (..., M, 3), got {a.shape}")
        self.room.check_anchors(a.reshape(-1, 3), min_anchors=1)
        self.room.check_nodes(p)
        c = self.room.speed_of_sound
        d = np.linalg.norm(p[:, None, :] - a[..., None, :, :], axis=-1)
        amp = direct_amplitude(self.room, a, p, self.chirp.centre)
        ref = self.reference_amplitude(a)[..., None, :]
        f2 = self._sum_f2(d / c)
        snr = 10.0 ** (self.snr_db / 10.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = c / (2 * np.pi) * (ref / amp) / np.sqrt(snr * f2)
        return np.where(np.isfinite(s) & (f2 > 0) & self.heard(a, p), s, np.inf)


# -- calibrated from simulated range errors (paper §V-A) ----------------------------------

#: 1/Φ⁻¹(¾): makes the median absolute deviation a consistent σ estimate for a Gaussian
MAD_TO_SIGMA = 1.482602218505602


def calibrated_sigma(
    range_errors, method: str = "inlier", per_node: bool = False, k: float = 3.0
) -> np.ndarray:
    """Robust range σ in metres from simulated range errors (R, P, M) (or (N, M)).

    The simulated errors mix a near-Gaussian core (the right correlation peak, a few
    centimetres) with reflection outliers (metres), so the plain standard deviation is
    dominated by the outliers. ``method``:

    - ``"inlier"`` (default): the standard deviation of the errors within ``k`` MAD-σ of
      the median (unbiased for a Gaussian core with ~10 % gross outliers to ~1 %);
    - ``"mad"``: σ = 1.4826 · median |e − median e| (the Gaussian-consistent MAD; the
      outliers inflate it by about 1.2× their fraction).

    Pools realizations and nodes per anchor, returning (M,); with ``per_node=True`` pools
    realizations only and returns (P, M) (input must be (R, P, M), R ≥ 2). Errors with no
    spread (every error of an anchor the same, e.g. noise-free) have no σ to calibrate:
    ``ValueError`` naming the anchors; a σ of 0 from a spread whose MAD is 0 (over half
    the errors equal) is returned as the smallest positive float, usable as ``sigma``.
    """
    e = checks.reals("range_errors", range_errors)
    checks.choice("method", method, ("mad", "inlier"))
    k = checks.real("k", k, low=0.0, low_open=True)
    per_node = checks.flag("per_node", per_node)
    if per_node:
        if e.ndim != 3 or e.shape[0] < 2:
            raise ValueError(f"range_errors: per_node needs shape (R >= 2, P, M), got {e.shape}")
        x = e
    else:
        if e.ndim < 2:
            raise ValueError(f"range_errors: expected shape (..., M), got {e.shape}")
        x = e.reshape(-1, e.shape[-1])
    if not np.all(np.isfinite(x)):
        raise ValueError("range_errors: must be finite")
    if x.size == 0:
        raise ValueError(f"range_errors: no errors to calibrate from (shape {e.shape})")
    flat = np.ptp(x, axis=0) == 0
    if np.any(flat):
        which = np.flatnonzero(flat if flat.ndim == 1 else flat.any(axis=0))
        raise ValueError(
            f"range_errors: anchor(s) {[int(j) for j in which]} have no spread (every error the "
            "same), so there is no σ to calibrate; simulate with noise"
        )
    med = np.median(x, axis=0)
    sigma = MAD_TO_SIGMA * np.median(np.abs(x - med), axis=0)
    if method == "inlier":
        inl = np.abs(x - med) <= k * sigma
        n = np.sum(inl, axis=0)
        mean = np.sum(np.where(inl, x, 0.0), axis=0) / np.maximum(n, 1)
        var = np.sum(np.where(inl, (x - mean) ** 2, 0.0), axis=0) / np.maximum(n, 1)
        sigma = np.sqrt(var)
    return np.maximum(sigma, np.finfo(float).tiny)


@dataclass(frozen=True)
class CalibratedRangeNoise:
    """σ_j calibrated from simulated range errors: one value per anchor (M,) or (P, M).

    Build with :meth:`from_range_errors` (e.g. ``Evaluation.range_errors`` of
    :func:`simulation.evaluate_layout`) so that the PEB and the simulation are compared on
    the same footing; :meth:`sigma` returns the stored values for the layout they were
    calibrated on.
    """

    values: np.ndarray

    def __post_init__(self) -> None:
        v = checks.reals("values", self.values, low=0.0, low_open=True, unit="m")
        if v.ndim not in (1, 2) or v.size == 0:
            raise ValueError(f"values: expected shape (M,) or (P, M), got {v.shape}")
        if not np.all(np.isfinite(v) & (v > 0)):
            raise ValueError("values: every σ must be finite and > 0 m")
        object.__setattr__(self, "values", v)

    @classmethod
    def from_range_errors(
        cls, range_errors, method: str = "inlier", per_node: bool = False, k: float = 3.0
    ) -> CalibratedRangeNoise:
        """Calibrate with :func:`calibrated_sigma`."""
        return cls(calibrated_sigma(range_errors, method=method, per_node=per_node, k=k))

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        """The values as an array, so the model itself can be passed as ``sigma``."""
        return np.array(self.values, dtype=dtype, copy=True if copy is None else copy)

    def sigma(self, anchors, positions) -> np.ndarray:
        """The calibrated σ, (M,) or (P, M); checks M (and P) against the arguments."""
        a = np.asarray(anchors, dtype=float)
        p = np.asarray(positions, dtype=float)
        M = a.shape[-2]
        if self.values.shape[-1] != M:
            raise ValueError(f"anchors: calibrated for {self.values.shape[-1]} anchors, got {M}")
        if self.values.ndim == 2 and self.values.shape[0] != p.shape[0]:
            raise ValueError(
                f"positions: calibrated per node for {self.values.shape[0]} nodes, got {p.shape[0]}"
            )
        return self.values


@dataclass(frozen=True)
class MultipathRangeNoise:
    """σ_j(p) = √(σ0² + b_j(p)²) with b_j(p) the noise-free simulated range error.

    The bias b comes from the full chirp simulation without noise (image sources, cardioid
    speakers, the receiver chain): it is the error that reverberation and the receiver
    make deterministically at that anchor–node pair, which the Gaussian range model of the
    CRLB ignores. Treating it as extra variance gives a multipath-aware FIM: pairs whose
    range the receiver gets wrong carry little information. ``floor`` σ0 (m) stands for the
    noise. Costs one noise-free simulation of every anchor–node pair.
    """

    room: Room = field(default_factory=Room.techtile)
    floor: float = 0.04
    snr_db: float = 30.0
    system: System = field(default_factory=System)

    def __post_init__(self) -> None:
        if not isinstance(self.room, Room):
            raise ValueError(f"room: must be a simulation.Room, got {checks.describe(self.room)}")
        floor = check_sigma(self.floor, "floor")
        object.__setattr__(self, "floor", floor)
        object.__setattr__(self, "snr_db", check_snr("snr_db", self.snr_db))
        object.__setattr__(self, "system", as_system(self.system))

    def bias(self, anchors, positions) -> np.ndarray:
        """(P, M) noise-free simulated range minus true distance, metres."""
        from simulation.evaluation import simulate_ranges

        a = np.asarray(anchors, dtype=float)
        p = np.asarray(positions, dtype=float)
        r = simulate_ranges(self.room, a, p, noise=False, snr_db=self.snr_db, system=self.system)
        return r - np.linalg.norm(p[:, None, :] - a[None, :, :], axis=-1)

    def sigma(self, anchors, positions) -> np.ndarray:
        """(P, M) σ in metres for anchors (M, 3) and positions (P, 3)."""
        b = self.bias(anchors, positions)
        return np.sqrt(self.floor**2 + b * b)

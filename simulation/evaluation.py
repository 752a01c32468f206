"""Monte Carlo evaluation of an anchor layout with the full chirp simulator (docs/model.md).

One realization: for every node and anchor, the received window (image-source multipath,
:mod:`simulation.received`) plus AWGN (:mod:`simulation.noise`) goes through the receiver
DSP (:mod:`simulation.receiver`) to a range; the node is then located by least squares
(:mod:`simulation.positioning`). The noise-free windows do not depend on the realization
and are computed once per layout (:class:`RangingScene`).

Randomness (the ``rng`` convention of the whole API: an int seed, a numpy ``Generator`` or
None): :func:`evaluate_layout` turns ``rng`` into one integer seed s (the int itself, or one
draw of the Generator, :func:`simulation.checks.entropy`) and realization r draws its noise
from its own stream ``np.random.default_rng(SeedSequence(s).spawn(R)[r])``, so results do
not depend on how realizations are chunked, and ``rng=s`` reproduces the former ``seed=s``.
"""

from __future__ import annotations

import contextlib
import functools
from dataclasses import dataclass, field

import numpy as np
import scipy.fft

from simulation import checks, degeneracy, statistics, streams
from simulation.multipath import ImageSet, compute_paths
from simulation.noise import DEFAULT_SNR_DB, check_snr, noise_sigma
from simulation.received import received_windows
from simulation.receiver import DEFAULT_PRECISION, HEARD, PRECISIONS, dsp_for
from simulation.robust import NO_FIX, UNVERIFIED, VERIFIED
from simulation.room import Room, as_room
from simulation.system import System, as_system

#: noise samples held in memory at once when chunking realizations (bytes)
NOISE_BUDGET_BYTES = 64 * 2**20
#: bytes held per (realization, node, anchor) by evaluate_layout and locate, an estimate
BYTES_PER_RANGE = 8 * 16


class RangingScene:
    """A layout in a room, prepared for drawing range realizations quickly.

    Holds the noise-free windows (P, M, N) of the ``system``'s chirp and receiver (default
    the paper's, :class:`simulation.System`), the true distances (P, M), the per-anchor
    noise σ (M,) of the SNR rule and the receiver DSP (``precision``: see
    :class:`~simulation.receiver.Dsp`). ``ranges(rng)`` draws one realization: a range, or
    NaN where the receiver reports none (``detect`` gives the status too).
    """

    def __init__(
        self,
        room: Room,
        anchors,
        nodes=None,
        *,
        system=None,
        snr_db: float = DEFAULT_SNR_DB,
        precision: str = DEFAULT_PRECISION,
    ):
        self.room = room = as_room(room)
        self.system = system = as_system(system)
        system.check_room(room)
        self.anchors = room.check_anchors(checks.reals("anchors", anchors), min_anchors=1)
        self.nodes = room.grid() if nodes is None else room.check_nodes(nodes)
        self.chirp, self.receiver = system.chirp, system.receiver
        self.snr_db = check_snr("snr_db", snr_db)
        checks.choice("precision", precision, PRECISIONS)
        n = len(self.nodes) * len(self.anchors) * self.receiver.window
        checks.check_size("nodes x anchors", n * 8 * 4, value=(len(self.nodes), len(self.anchors)))
        c = room.speed_of_sound
        # the shoebox's image set, computed once for the paths and the noise rule
        images = ImageSet.for_room(room) if room.is_shoebox and not room.obstacles else None
        centre = self.chirp.centre
        paths = compute_paths(room, self.anchors, self.nodes, images=images, frequency=centre)
        self.distances = paths.length[:, :, 0]  # image 0 is the direct path
        #: (P, M) bool: no wall or obstacle blocks the direct path
        self.line_of_sight = paths.los
        air = room.air_excess(centre)
        self.dsp = dsp_for(self.chirp, self.receiver, precision)
        #: the windows' and their noise's dtype: single precision for a long window's
        #: single-precision DSP (FFT form), which reads no more; double otherwise
        self.dtype = np.dtype(np.float32 if self.dsp.form == "fft" and precision == "float32"
                              else np.float64)  # fmt: skip
        windows = received_windows(paths, c, self.chirp, self.receiver, air)
        self.windows = windows.astype(self.dtype, copy=False)
        self.noise_sigma = noise_sigma(room, self.anchors, snr_db, images=images, system=system)

    @property
    def shape(self) -> tuple[int, int]:
        """(P, M)."""
        return self.windows.shape[:2]

    def detect(self, windows: np.ndarray, sigma=None) -> tuple[np.ndarray, np.ndarray]:
        """Ranges (..., P, M) in metres (NaN: no range) and their status (...,
        P, M) (:data:`simulation.receiver.RANGE_STATUS`) of windows (..., P, M, N), the
        detection threshold set from ``sigma`` (M,) (default the scene's noise σ)."""
        sigma = self.noise_sigma if sigma is None else sigma
        c = self.room.speed_of_sound
        return self.dsp.detect(windows, c, sigma, self.system.delays, self.distances / c)

    def _to_ranges(self, windows: np.ndarray) -> np.ndarray:
        return self.detect(windows)[0]

    def noise(self, rng: np.random.Generator, shape=None) -> np.ndarray:
        """σ_j · N(0, 1) noise of shape ``shape`` (default the windows', (P, M, N); any
        shape ending in (M, N)) from ``rng``, in the windows' dtype."""
        shape = self.windows.shape if shape is None else shape
        sigma = self.noise_sigma.astype(self.dtype, copy=False)
        return sigma[:, None] * rng.standard_normal(shape, dtype=self.dtype)

    def noisy_windows(self, rng: np.random.Generator) -> np.ndarray:
        """(P, M, N) received windows of one realization: clean + σ_j · N(0, 1) from ``rng``."""
        return self.windows + self.noise(rng)

    def ranges(self, rng: np.random.Generator | None = None, noise: bool = True) -> np.ndarray:
        """(P, M) estimated ranges in metres (NaN: no range) for one realization drawn
        from ``rng``."""
        if not checks.flag("noise", noise):
            return self._to_ranges(self.windows)
        return self._to_ranges(self.noisy_windows(streams.rng("rng", rng)))

    def ranges_batch(self, rngs, noise: bool = True) -> np.ndarray:
        """(len(rngs), P, M) ranges (NaN: no range), realization r drawn from ``rngs[r]``."""
        return self.draw_batch(rngs, noise)[0]

    def draw_batch(self, rngs, noise: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(len(rngs), P, M) ranges and their statuses, realization r from ``rngs[r]``."""
        rngs = list(rngs)
        if not noise:
            r0, s0 = self.detect(self.windows)
            shape = (len(rngs), *r0.shape)
            return np.broadcast_to(r0, shape).copy(), np.broadcast_to(s0, shape).copy()
        if not rngs:
            return np.empty((0, *self.shape)), np.empty((0, *self.shape), dtype=np.int8)
        return self.detect(np.stack([self.noisy_windows(g) for g in rngs]))


def simulate_ranges(
    room: Room,
    anchors,
    nodes,
    noise: bool = True,
    rng: np.random.Generator | None = None,
    snr_db: float = DEFAULT_SNR_DB,
    precision: str = DEFAULT_PRECISION,
    system=None,
) -> np.ndarray:
    """(P, M) range estimates in metres from the full simulation, one realization, with the
    ``system``'s chirp and receiver (default the paper's); NaN where the receiver hears no
    chirp or the time of flight lies beyond the signal's reach (:mod:`simulation.receiver`).

    ``rng`` (numpy Generator, or a seed) draws the noise (a fresh unseeded one when None).
    Anchors may be anywhere in the room (on the mounting surfaces or not) but at least
    1 mm apart; nodes must be inside the room.
    """
    rng = streams.rng("rng", rng)
    room = as_room(room)
    checks.distinct("anchors", room.check_anchors(checks.reals("anchors", anchors), 1))
    scene = RangingScene(room, anchors, nodes, system=system, snr_db=snr_db, precision=precision)
    return scene.ranges(rng, noise=noise)


def _stat(key: str, doc: str) -> property:
    """A read-only property giving ``self.stats[key]``."""
    return property(lambda self: self.stats[key], doc=doc)


def _computed(fn, doc: str, *fields: str) -> functools.cached_property:
    """A cached property: ``fn`` of the named fields (a function of
    :mod:`simulation.statistics`)."""

    def get(self):
        return fn(*(getattr(self, f) for f in fields))

    get.__doc__ = doc
    return functools.cached_property(get)


@dataclass(frozen=True)
class Evaluation:
    """Monte Carlo result of :func:`evaluate_layout` (metres throughout).

    anchors (M, 3), nodes (P, 3); estimates (R, P, 3); ranges (R, P, M) estimated ranges
    (NaN where the receiver reported none); range_status (R, P, M) why not
    (:data:`simulation.receiver.RANGE_STATUS`); range_errors (R, P, M) = ranges − true
    distances; errors (R, P) Euclidean position errors (NaN where fewer than 4 anchors
    were heard: no fix); converged (R, P) solver flags; fix_status (R, P) the solver's
    status (:data:`simulation.positioning.STATUS_MESSAGES`); noise_sigma (M,) the AWGN σ
    per anchor; line_of_sight (P, M) whether nothing blocks each direct path; seed the
    integer seed of the noise streams (``evaluate_layout(...,
    rng=seed)`` reproduces it). Statistics (``std`` population σ, ``mean``, ``p95``,
    ``rms``) are over the fixes among all R·P, and ``availability`` is the share of the
    R·P with a fix; per node, :attr:`dop` is the paper's DOP (standard deviation of the
    error / σ_r) and :attr:`dop_rms` the RMS-based one (RMSE / σ_r); formulas in
    :mod:`simulation.statistics`.
    """

    anchors: np.ndarray
    nodes: np.ndarray
    estimates: np.ndarray
    ranges: np.ndarray
    range_errors: np.ndarray
    errors: np.ndarray
    converged: np.ndarray
    noise_sigma: np.ndarray
    seed: int
    snr_db: float
    room: Room = field(repr=False)
    range_status: np.ndarray = field(default=None, repr=False)
    fix_status: np.ndarray = field(default=None, repr=False)
    line_of_sight: np.ndarray = field(default=None, repr=False)
    system: System = field(default_factory=System, repr=False)
    fix_quality: np.ndarray = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.range_status is None:  # built by hand: every range a range
            heard = np.where(np.isfinite(self.ranges), HEARD, 1).astype(np.int8)
            object.__setattr__(self, "range_status", heard)
        if self.fix_status is None:
            object.__setattr__(self, "fix_status", np.where(self.converged, 1, 0))
        if self.line_of_sight is None:  # built by hand: nothing blocks
            object.__setattr__(self, "line_of_sight", np.ones(self.ranges.shape[1:], bool))
        if self.fix_quality is None:  # built by hand: every fix unverified
            q = np.where(np.isfinite(self.errors), UNVERIFIED, NO_FIX).astype(np.int8)
            object.__setattr__(self, "fix_quality", q)

    @property
    def realizations(self) -> int:
        return self.errors.shape[0]

    @property
    def geometry(self) -> str:
        """The anchors' geometry: "3d", or "coplanar" (positions are mirror-ambiguous
        through the anchors' plane; the room box resolves it), "collinear" (the position
        is not determined: every fix is flagged unconverged)."""
        return degeneracy.geometry(self.anchors)

    @functools.cached_property
    def stats(self) -> dict:
        """std, mean, p95, rms, median, max over the fixes among the R·P Euclidean errors,
        with ``n``, ``n_invalid`` and ``availability``
        (:func:`simulation.statistics.error_stats`)."""
        return statistics.error_stats(self.errors)

    @property
    def availability(self) -> float:
        """The share of the R·P node realizations with a position fix (4 or more anchors
        heard)."""
        return self.stats["availability"]

    @property
    def verified(self) -> float:
        """The share of the R·P node realizations with a verified fix (5 or more anchors
        consistent: :mod:`simulation.robust`; 0 for least squares, which verifies nothing)."""
        return float(np.mean(self.fix_quality == VERIFIED)) if self.fix_quality.size else 0.0

    @property
    def heard(self) -> np.ndarray:
        """(R, P, M) bool: the receiver reported a range."""
        return self.range_status == HEARD

    @property
    def node_availability(self) -> np.ndarray:
        """(P,) the share of realizations with a fix at each node."""
        return np.mean(np.isfinite(self.errors), axis=0)

    @property
    def anchors_heard(self) -> np.ndarray:
        """(P,) the mean number of anchors heard at each node over the realizations."""
        return np.mean(np.sum(self.heard, axis=-1), axis=0)

    std = _stat("std", "population standard deviation σ of all R·P errors (m), the paper's σ")
    mean = _stat("mean", "mean of all R·P errors (m)")
    p95 = _stat("p95", "95th percentile of all R·P errors (m)")
    rms = _stat("rms", "RMS of all R·P errors (m)")

    @property
    def axis_errors(self) -> np.ndarray:
        """(R, P, 3) absolute per-axis errors |p̂ − p|."""
        return statistics.axis_errors(self.estimates, self.nodes)

    rmse = _computed(
        statistics.node_rmse,
        "(P,) RMS over realizations of the Euclidean error (the numerator of dop_rms)",
        "errors",
    )
    node_std = _computed(
        statistics.node_std,
        "(P,) standard deviation over realizations of the Euclidean error (σ^p of dop)",
        "errors",
    )
    node_mean = _computed(statistics.node_mean, "(P,) mean Euclidean error per node", "errors")
    range_std = _computed(
        statistics.range_std,
        "(P,) σ_r: mean over anchors of the std over realizations of the range error",
        "range_errors",
    )
    dop = _computed(
        statistics.dop,
        "(P,) the paper's DOP (§V-A) = node_std / range_std; +inf where σ_r = 0",
        "errors",
        "range_errors",
    )
    dop_rms = _computed(
        statistics.dop_rms,
        "(P,) the RMS-based DOP = rmse / range_std (≥ dop); +inf where σ_r = 0",
        "errors",
        "range_errors",
    )

    @property
    def n_unconverged(self) -> int:
        return int(np.sum(~self.converged))

    def to_dict(self, include_errors: bool = True) -> dict:
        """Plain JSON-ready dictionary (non-finite floats stay floats; the CLI maps them)."""
        ax = self.axis_errors
        fixed = bool(np.any(np.isfinite(self.errors)))
        d = {
            "room": self.room.to_dict(),
            "system": self.system.to_dict(),
            "anchors": self.anchors.tolist(),
            "nodes": self.nodes.tolist(),
            "realizations": self.realizations,
            "seed": self.seed,
            "snr_db": self.snr_db,
            "noise_sigma": self.noise_sigma.tolist(),
            "stats": {
                **self.stats,
                "verified": self.verified,
                "n_unconverged": self.n_unconverged,
                "anchor_geometry": self.geometry,
                "axis_mean": np.nanmean(ax, axis=(0, 1)).tolist() if fixed else None,
                "axis_p95": np.nanpercentile(ax, 95, axis=(0, 1)).tolist() if fixed else None,
                "range_error_median_abs": _nanmedian_abs(self.range_errors).tolist(),
                "heard_share": np.mean(self.heard, axis=(0, 1)).tolist(),
            },
            "per_node": {
                "availability": self.node_availability.tolist(),
                "anchors_heard": self.anchors_heard.tolist(),
                "anchors_in_sight": np.sum(self.line_of_sight, axis=-1).tolist(),
                "rmse": self.rmse.tolist(),
                "std": self.node_std.tolist(),
                "dop": self.dop.tolist(),
                "dop_rms": self.dop_rms.tolist(),
                "mean": self.node_mean.tolist(),
                "range_std": self.range_std.tolist(),
            },
        }
        if include_errors:
            d["errors"] = self.errors.tolist()
            d["converged"] = self.converged.tolist()
        return d


def _nanmedian_abs(range_errors: np.ndarray) -> np.ndarray:
    """(M,) median |range error| per anchor over its heard ranges (NaN if none)."""
    e = np.abs(range_errors.reshape(-1, range_errors.shape[-1]))
    out = np.full(e.shape[1], np.nan)
    for j in range(e.shape[1]):  # M columns: no loop over nodes
        v = e[:, j][np.isfinite(e[:, j])]
        if v.size:
            out[j] = np.median(v)
    return out


def _check_workers(workers) -> None:
    if workers is not None and (
        isinstance(workers, bool)
        or not isinstance(workers, int | np.integer)
        or workers not in range(-1, 1025)
        or workers == 0
    ):
        raise ValueError(
            "workers: must be None, -1 (all cores) or an integer in [1, 1024], "
            f"got {checks.describe(workers)}"
        )


def _draw_ranges(scene: RangingScene, seed: int, realizations: int, chunk, workers, noise,
                 progress=None):  # fmt: skip
    """(R, P, M) ranges and statuses; realization r from ``SeedSequence(seed).spawn(R)[r]``,
    ``chunk`` realizations at a time (default: :data:`NOISE_BUDGET_BYTES` of noise), each
    chunk reported to ``progress(done, total)`` (realizations) when it is given."""
    P, M = scene.shape
    if chunk is None:
        chunk = max(1, NOISE_BUDGET_BYTES // (P * M * scene.receiver.window * 8))
    children = np.random.SeedSequence(seed).spawn(realizations)
    ranges = np.empty((realizations, P, M))
    status = np.empty((realizations, P, M), dtype=np.int8)
    threads = contextlib.nullcontext() if workers is None else scipy.fft.set_workers(workers)
    with threads:
        for i in range(0, realizations, chunk):
            rngs = [np.random.default_rng(s) for s in children[i : i + chunk]]
            part = slice(i, i + len(rngs))
            ranges[part], status[part] = scene.draw_batch(rngs, noise=noise)
            if progress is not None:
                progress(part.stop, realizations)
    return ranges, status


def evaluate_layout(
    room: Room,
    anchors,
    realizations: int = 1,
    rng: int | np.random.Generator | None = 0,
    nodes=None,
    *,
    noise: bool = True,
    snr_db: float = DEFAULT_SNR_DB,
    system=None,
    chunk: int | None = None,
    precision: str = DEFAULT_PRECISION,
    workers: int | None = None,
    progress=None,
) -> Evaluation:
    """Simulate ``realizations`` noisy range sets for every node and locate the nodes.

    anchors (M, 3) must lie in the room (M ≥ 4; anywhere in the room, not only on the
    mounting surfaces, so existing installations can be evaluated) and be at least 1 mm
    apart; nodes (P, 3), inside the room, default to ``room.grid()``. Collinear anchors
    give fixes flagged unconverged; ``Evaluation.geometry`` names the geometry.
    ``chunk`` realizations are processed at a time (default: as many as fit in
    :data:`NOISE_BUDGET_BYTES` of noise); the result does not depend on it. ``system``
    (:class:`simulation.System`, a preset's name or None: the paper's) is the chirp, the
    receiver and the positioning simulated. ``precision`` is the receiver DSP's
    (default float32, :data:`~simulation.receiver.DEFAULT_PRECISION`; "float64" gives
    the reference chain's index exactly, see :class:`~simulation.receiver.Dsp`). ``workers``
    threads run the FFTs (results do not depend on it; ``-1``: all cores; None: the
    ``scipy.fft`` default, 1 unless set with ``scipy.fft.set_workers``). ``progress``, a
    callable ``progress(done, total)``, is told the realizations simulated so far after
    each chunk (the long phase: a realization of a thousand nodes takes seconds); None:
    nothing is reported.

    ``rng`` (an int seed, default 0; a numpy ``Generator``, drawn once; or None, fresh
    entropy) gives the integer seed s of the noise streams (see the module docstring),
    kept as ``Evaluation.seed``: ``rng=ev.seed`` reproduces ``ev``.
    """
    room = as_room(room)
    anchors = room.check_anchors(checks.reals("anchors", anchors))
    checks.distinct("anchors", anchors)
    realizations = checks.count("realizations", realizations, low=1)
    seed = streams.entropy("rng", rng)
    noise = checks.flag("noise", noise)
    system = as_system(system)
    if chunk is not None:
        chunk = checks.count("chunk", chunk, low=1)
    _check_workers(workers)
    if progress is not None and not callable(progress):
        raise ValueError(
            f"progress: expected a callable progress(done, total) or None, got {progress!r}"
        )
    n_nodes = len(room.grid()) if nodes is None else len(room.check_nodes(nodes))
    checks.check_size(
        "realizations",
        realizations * n_nodes * len(anchors) * BYTES_PER_RANGE,
        value=realizations,
        hint=f"{n_nodes} nodes x {len(anchors)} anchors per realization; use fewer",
    )
    scene = RangingScene(room, anchors, nodes, system=system, snr_db=snr_db, precision=precision)
    ranges, status = _draw_ranges(scene, seed, realizations, chunk, workers, noise, progress)
    fix = system.positioning.locate(room, anchors, ranges, full_output=True)
    errors = statistics.euclidean_errors(fix.x, scene.nodes)
    return Evaluation(
        anchors=anchors,
        nodes=scene.nodes,
        estimates=fix.x,
        ranges=ranges,
        range_errors=ranges - scene.distances,
        errors=errors,
        converged=fix.converged,
        noise_sigma=scene.noise_sigma,
        seed=seed,
        snr_db=scene.snr_db,
        room=room,
        range_status=status,
        fix_status=fix.status,
        line_of_sight=scene.line_of_sight,
        system=system,
        fix_quality=fix.quality,
    )

"""Least-squares positioning from ranges, batched over nodes and realizations (paper §II).

For each node, minimize F(x) = ½ Σ_j (‖x − a_j‖ − ρ_j)² over x ∈ ℝ³ with a damped
Gauss–Newton method (Levenberg–Marquardt with Nielsen's damping update, per-node damping,
a fixed maximum number of iterations, explicit 3 × 3 solves). The loop over nodes is
compiled (numba): every node is solved on its own, in one pass over the batch.
An undamped Gauss–Newton diverges on the outlier ranges of a reverberant room.

Start: the linear least-squares solution of the squared-range differences (subtracting
the mean equation, ‖x‖² cancels: 2(a_j − ā)ᵀx = (‖a_j‖² − mean‖a‖²) − (ρ_j² − mean ρ²))
when the anchors are not coplanar and that point lies inside ``region``, else the centre
of ``region``. Unbounded by default; ``bounded=True`` keeps every iterate in ``region``:
a coordinate at a bound whose gradient points out of the box is held there while the
others take the damped step of their own 3 × 3 block (an active set), and every step is
projected onto the box.

Every node gets a status (modelled on scipy ``least_squares``): 1 gradient small, 2 cost
change small, 3 step small, 4 zero residual, 0 iteration limit (not converged: the best
iterate is returned and flagged, never silently).

Missing ranges (NaN: the receiver heard no chirp from that anchor) leave their anchor
out of that node's sums: a node with 4 or more heard anchors, not collinear, is solved
from those alone (start, bounds and iterations as if only they had been given); a node
with fewer has no fix: status −2, position NaN (docs/model.md, "Positioning with the
anchors that hear the tag").
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numba
import numpy as np

from simulation import checks, degeneracy
from simulation.least_squares import linear_fix, lm_rows
from simulation.polyhedral import NO_MAP, blocking_map, facing
from simulation.robust import (
    NO_FIX,
    UNVERIFIED,
    VERIFIED,
    bias_scales,
    proved_echoes,
    robust_rows,
    thresholds,
)

logger = logging.getLogger(__name__)

STATUS_MESSAGES = {
    0: "iteration limit reached",
    1: "gradient norm below gtol",
    2: "relative cost change below ftol",
    3: "step below xtol",
    4: "zero residual",
    -1: "anchors collinear or coincident: the position is not determined",
    -2: "no fix: fewer than 4 anchors heard (or the heard ones collinear)",
}
#: ranges below this (m) are not measurements; the receiver's noisy ranges reach -0.34 m
RANGE_FLOOR = -1.0
#: ranges above this (m) are not indoor measurements
RANGE_CEILING = 1e5
#: the fewest heard anchors that fix a node with missing ranges
MIN_HEARD = 4
#: the positioning methods (:class:`simulation.Positioning`): least squares on every heard
#: range (the paper's), and least squares on the anchors consistent with each other
#: (:mod:`simulation.robust`)
METHODS = ("ls", "robust")
#: the robust method's defaults: the receiver's range σ (m) and the false-alarm
#: probability of its consistency test
RANGE_SIGMA, FALSE_ALARM, ALERT_LIMIT = 0.01, 1e-3, 0.5


@dataclass(frozen=True)
class PositionFix:
    """Positions from :func:`locate` with per-node solver diagnostics.

    x : (..., P, 3) estimates in metres. converged : (..., P) bool. status : (..., P) int
    (see :data:`STATUS_MESSAGES`). nit : (..., P) iterations used. cost : (..., P)
    F(x) = ½ Σ residual² in m² over the anchors used. start : (..., P, 3) starting points
    (the robust method's: of its first fit, without the ranges proved echoes).
    used : (..., P, M) bool, the anchors each fix rests on (the heard ones; the robust
    method's consistent ones). quality : (..., P) int, :data:`simulation.robust.QUALITY`
    (least squares verifies nothing: its fixes are unverified).
    """

    x: np.ndarray
    converged: np.ndarray
    status: np.ndarray
    nit: np.ndarray
    cost: np.ndarray
    start: np.ndarray
    used: np.ndarray | None = None
    quality: np.ndarray | None = None

    @property
    def verified(self) -> np.ndarray:
        """(..., P) bool: the fix is verified (5 or more consistent anchors)."""
        return np.asarray(self.quality) == VERIFIED

    @property
    def success(self) -> bool:
        """True when every node converged."""
        return bool(np.all(self.converged))

    def to_dict(self) -> dict:
        return {
            "x": self.x.tolist(),
            "converged": self.converged.tolist(),
            "status": self.status.tolist(),
            "nit": self.nit.tolist(),
            "cost": self.cost.tolist(),
            "quality": None if self.quality is None else self.quality.tolist(),
        }


def _region(region) -> tuple[np.ndarray, np.ndarray]:
    """The box (lo (3,), hi (3,)) of a given ``region``, checked."""
    try:
        lo, hi = (checks.reals("region", v, shape=(3,)) for v in region)
    except (TypeError, ValueError):
        raise ValueError(
            f"region: expected (lo (3,), hi (3,)) in metres, got {checks.describe(region)}"
        ) from None
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi >= lo)):
        raise ValueError(
            f"region: expected finite (lo (3,), hi (3,)) with hi >= lo, "
            f"got lo {lo.tolist()}, hi {hi.tolist()}"
        )
    return lo, hi


def _centred_svd(a: np.ndarray):
    """The SVD (U, s, Vᵀ) of A = 2 (a − ā), the matrix of the squared-range differences,
    for layouts a (L, M, 3): one decomposition serves the linear solution and the
    layouts' affine rank."""
    A = 2.0 * (a - a.mean(axis=1, keepdims=True))  # (L, M, 3)
    return np.linalg.svd(A, full_matrices=False)


def _linear_solution(a: np.ndarray, ranges: np.ndarray, svd=None):
    """Linear LS solutions (B, 3) of the squared-range differences for ranges (B, M) of
    the layouts a (L, M, 3), B/L consecutive rows per layout, and whether each row's
    anchors are not coplanar (B,). ``svd``: :func:`_centred_svd` of a, if already known."""
    L, M, _ = a.shape
    u, sv, vt = _centred_svd(a) if svd is None else svd
    # the pseudo-inverse by numpy.linalg.pinv's rule (rcond 1e-15), from the same SVD
    large = sv > 1e-15 * sv.max(axis=1, keepdims=True)
    inv = np.divide(1.0, sv, where=large, out=np.zeros_like(sv))
    pinv = np.swapaxes(vt, 1, 2) @ (inv[..., None] * np.swapaxes(u, 1, 2))  # (L, 3, M)
    a2 = np.sum(a * a, axis=2)  # (L, M)
    r2 = ranges.reshape(L, -1, M) ** 2
    b = (a2 - a2.mean(axis=1, keepdims=True))[:, None] - (r2 - r2.mean(axis=2, keepdims=True))
    lin = b @ np.swapaxes(pinv, 1, 2)  # (L, B/L, 3)
    ok = sv[:, -1] > 1e-9 * np.maximum(sv[:, 0], 1e-300)
    return lin.reshape(-1, 3), np.repeat(ok, r2.shape[1])


def linear_start(anchors: np.ndarray, ranges: np.ndarray) -> np.ndarray | None:
    """Linear LS solution (B, 3) of the squared-range differences, None if anchors coplanar."""
    a = np.asarray(anchors, dtype=float)
    R = np.asarray(ranges, dtype=float).reshape(-1, a.shape[0])
    lin, ok = _linear_solution(a[None], R)
    return lin if np.all(ok) else None


def locate(
    anchors,
    ranges,
    *,
    method: str = "ls",
    region=None,
    bounded: bool = False,
    floor_plan=None,
    x0=None,
    max_iter: int = 100,
    xtol: float = 1e-10,
    ftol: float = 1e-12,
    gtol: float = 1e-12,
    range_sigma: float = RANGE_SIGMA,
    false_alarm: float = FALSE_ALARM,
    alert_limit: float = ALERT_LIMIT,
    room=None,
    full_output: bool = False,
):
    """Positions from ranges: anchors (M, 3), ranges (..., P, M) in metres.

    Several layouts at once: anchors (L, M, 3) and ranges (L, ..., P, M), layout l's
    ranges in ``ranges[l]``; each node is solved as it would be alone (up to rounding).

    Parameters
    ----------
    method : ``"ls"``, least squares on every heard range (the paper's), or ``"robust"``,
        least squares on the anchors consistent to ``range_sigma`` (m) at the
        false-alarm probability ``false_alarm`` of the χ² test (:mod:`simulation.robust`);
        a robust fix is verified only if one echo the test misses cannot move it by more
        than ``alert_limit`` (m; its protection level, :mod:`simulation.robust`).
    region : (lo (3,), hi (3,)) box the nodes are known to be in (e.g. ``(0, room.size)``);
        sets the start (box centre, or the linear solution when inside) and the bounds.
        Default: the anchors' bounding box.
    bounded : keep the iterates inside ``region``, and inside ``floor_plan`` when given.
    floor_plan : (K, 2) the floor plan's corners (m, counter-clockwise) a bounded iterate
        is kept in (a position in a cut-out corner of the plan is not in the room).
    room : the :class:`simulation.Room` whose walls and obstacles can hide an anchor from a
        position: the robust method counts a range as direct only where nothing of the
        room blocks the segment from the position to its anchor. Default: nothing hides an
        anchor.
    x0 : optional (..., P, 3) or (3,) starting points (overrides the start rule).
    max_iter, xtol, ftol, gtol : iteration limit and tolerances (see module docstring).
    full_output : return a :class:`PositionFix` instead of the (..., P, 3) array.

    Returns (..., P, 3) estimates, or a :class:`PositionFix`. Nodes that hit ``max_iter``
    return their best iterate and ``converged = False`` (logged at DEBUG). With collinear
    or coincident anchors (closer than 1 mm to a line) the position is not determined:
    every node of that layout gets status −1 and ``converged = False``. A NaN range is a
    missing one (module docstring): a node needs 4 heard anchors, else it gets status −2
    and NaN. Ranges below −1 m (a noisy range may be slightly negative), above 1e5 m or
    infinite raise ``ValueError``.
    """
    tols = (xtol, ftol, gtol)
    flags = {"bounded": bounded, "full_output": full_output}
    a, rho, max_iter = _check_input(anchors, ranges, max_iter, tols, flags)
    test = (range_sigma, false_alarm, alert_limit)
    poly, room_map = _check_method(method, floor_plan, test, room)
    M = a.shape[-2]
    lead = rho.shape[:-1]
    R = rho.reshape(-1, M)
    layouts = a.reshape(-1, M, 3)
    echo_sigma = range_sigma if method == "robust" else None
    fix, start, (owner, lo, hi), heard, F = _least_squares(
        layouts, R, region, x0, lead, bounded, int(max_iter), tols, poly, echo_sigma
    )
    x, cost, status, nit = fix
    used, quality = heard, np.where(status < 0, NO_FIX, UNVERIFIED).astype(np.int8)
    if method == "robust":
        used, quality = _robust(layouts, owner, R, F, fix, lo, hi, bounded, poly, int(max_iter),
                                tols, test, room_map, _front(room, layouts))  # fmt: skip
    converged = _converged(status, max_iter)
    if not full_output:
        return x.reshape(*lead, 3)
    return _position_fix(lead, x, converged, status, nit, cost, start, used, quality)


def _least_squares(layouts, R, region, x0, lead, bounded, max_iter, tols, poly, echo_sigma):
    """The least-squares fixes of the rows R (N, M) of ``layouts`` (L, M, 3) (module
    docstring; the arguments as :func:`locate` checked them), solved on the ranges F: R,
    or for the robust method (``echo_sigma``, its range σ, not None) R without its proved
    echoes (:func:`simulation.robust.proved_echoes`; the search boxes and whether a node
    can be fixed still follow every heard range). Returns ((x (N, 3), cost, status, nit),
    the starting points (N, 3), (owner, lo, hi) the rows' layouts and search boxes, heard
    (N, M), F (N, M))."""
    owner, lo, hi = _rows(layouts, len(R), region)
    svd = _centred_svd(layouts)
    heard = ~np.isnan(R)
    partial = ~np.all(heard, axis=1)
    F = R
    if echo_sigma is not None and len(R):
        F = proved_echoes(_c(layouts), _c(owner, np.int64), _c(R), float(echo_sigma))
    x, lo, hi = _starting_points(layouts, F, heard, partial, owner, lo, hi, region, x0, lead,
                                 svd, bounded)  # fmt: skip
    start = x.copy()
    x, cost, status, nit = _levenberg_marquardt(
        layouts, owner, F, x, lo, hi, bounded, max_iter, tols, poly
    )
    _mark_undetermined(layouts, owner, svd, heard, partial, x, cost, status)
    return (x, cost, status, nit), start, (owner, lo, hi), heard, F


def _converged(status: np.ndarray, max_iter: int) -> np.ndarray:
    """(N,) whether each node converged (status > 0); the others logged at DEBUG."""
    converged = status > 0
    if not np.all(converged):
        n = int(np.sum(~converged))
        logger.debug("locate: %d of %d nodes not converged (max_iter=%d)", n, len(status),
                     max_iter)  # fmt: skip
    return converged


def _check_method(method, floor_plan, test, room):
    """The checked ``method`` and its settings (:func:`locate`; ``test`` the robust
    method's (range_sigma, false_alarm, alert_limit)); returns the floor plan
    (K, 2) or None, and the map of ``room`` (:func:`_room_map`; empty for least squares,
    which does not use it)."""
    checks.choice("method", method, METHODS)
    poly = _floor_plan(floor_plan)
    _check_room(room)
    if method == "robust":
        check_test(*test)
        return poly, _room_map(room)
    return poly, NO_MAP


def _position_fix(lead, x, converged, status, nit, cost, start, used, quality) -> PositionFix:
    """The :class:`PositionFix` of the flat per-node arrays (N, ...) shaped to ``lead``."""
    return PositionFix(
        x=x.reshape(*lead, 3),
        converged=converged.reshape(lead),
        status=status.astype(int).reshape(lead),
        nit=nit.reshape(lead),
        cost=cost.reshape(lead),
        start=start.reshape(*lead, 3),
        used=used.reshape(*lead, used.shape[-1]),
        quality=quality.reshape(lead),
    )


def _starting_points(layouts, F, heard, partial, owner, lo, hi, region, x0, lead, svd, bounded):
    """(starts (N, 3), lo, hi): the start of every node from its ranges F (module
    docstring), its search box narrowed to the anchors it heard (``heard`` (N, M), the
    nodes ``partial`` (N,) that missed some) when some are missing, clipped to it when
    ``bounded``."""
    if np.any(partial):
        lo, hi = _heard_bounds(layouts, owner, heard, partial, lo, hi, region)
    x = _start(layouts, F, owner, lo, hi, x0, lead, svd)
    gaps = np.any(np.isnan(F), axis=1)  # partial, or the proved echoes left out
    if np.any(gaps) and x0 is None:
        _masked_starts(layouts, _c(owner, np.int64), _c(F), _c(lo), _c(hi), _c(gaps), x)
    if bounded:
        x = np.clip(x, lo, hi)
    return x, lo, hi


def _mark_undetermined(layouts, owner, svd, heard, partial, x, cost, status) -> None:
    """In place: status −1 for every node of a collinear layout (rotation about the anchor
    line leaves the ranges unchanged); status −2 and NaN for a node whose heard anchors
    cannot fix it."""
    M = layouts.shape[-2]
    rank = np.atleast_1d(degeneracy.rank_of_spread(svd[1] / 2, M))  # svd of 2 (a − ā)
    status[(rank < 2)[owner]] = -1
    if np.any(partial):
        lost = partial.copy()
        lost[partial] = ~_fixable(layouts, owner[partial], heard[partial])
        status[lost] = -2
        x[lost] = np.nan
        cost[lost] = np.nan


def _check_input(anchors, ranges, max_iter, tols, flags) -> tuple[np.ndarray, np.ndarray, int]:
    a = checks.reals("anchors", anchors)
    if a.ndim not in (2, 3) or a.shape[-1] != 3 or a.shape[-2] < 3:
        raise ValueError(f"anchors: expected shape (M, 3) or (L, M, 3) with M >= 3, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("anchors: must be finite")
    rho = checks.reals("ranges", ranges, finite=False)  # NaN: not heard (checked below)
    M = a.shape[-2]
    if rho.ndim < 1 or rho.shape[-1] != M:
        raise ValueError(f"ranges: expected shape (..., P, {M}), got {rho.shape}")
    if a.ndim == 3 and (rho.ndim < 2 or rho.shape[0] != a.shape[0]):
        raise ValueError(
            f"ranges: with {a.shape[0]} layouts expected shape ({a.shape[0]}, ..., P, {M}), "
            f"got {rho.shape}"
        )
    if np.any(np.isinf(rho)):
        raise ValueError("ranges: must be finite distances or NaN (not heard), got inf")
    given = rho[~np.isnan(rho)]
    if given.size and (given.min() < RANGE_FLOOR or given.max() > RANGE_CEILING):
        bad = given.min() if given.min() < RANGE_FLOOR else given.max()
        raise ValueError(
            f"ranges: must be distances in [{RANGE_FLOOR:g}, {RANGE_CEILING:g}] m (noisy ranges "
            f"may be slightly negative) or NaN (not heard), got {bad:g} m"
        )
    max_iter = checks.count("max_iter", max_iter, low=1)
    for name, tol in zip(("xtol", "ftol", "gtol"), tols, strict=True):
        checks.real(name, tol, low=0.0)
    for name, flag in flags.items():
        checks.flag(name, flag)
    return a, rho, max_iter


def _rows(a: np.ndarray, B: int, region):
    """The layout (B,) of each row of ranges for layouts a (L, M, 3), and the bounds of
    the region (B, 3) each row lies in (each layout's bounding box when ``region`` is
    None)."""
    owner = np.repeat(np.arange(len(a)), B // max(len(a), 1))  # no layouts: no rows
    if region is None:
        lo, hi = a.min(axis=1)[owner], a.max(axis=1)[owner]
    else:
        lo, hi = _region(region)
        lo, hi = np.broadcast_to(lo, (B, 3)), np.broadcast_to(hi, (B, 3))
    return owner, lo, hi


def _start(a, R, owner, lo, hi, x0, lead, svd) -> np.ndarray:
    """(B, 3) starting points: ``x0``, else the linear solution when inside the region,
    else the region's centre (``svd``: :func:`_centred_svd` of the layouts a)."""
    B = len(R)
    if x0 is not None:
        x0 = checks.reals("x0", x0)
        try:
            x = np.broadcast_to(x0, (*lead, 3)).reshape(B, 3).copy()
        except ValueError:
            raise ValueError(f"x0: expected shape (3,) or (..., P, 3), got {x0.shape}") from None
        if not np.all(np.isfinite(x)):
            raise ValueError("x0: must be finite")
        return x
    x = (lo + hi) / 2
    if B == 0:
        return x
    lin, ok = _linear_solution(a, R, svd)
    inside = ok & np.all((lin >= lo) & (lin <= hi), axis=1)
    x[inside] = lin[inside]
    return x


def _heard_bounds(a, owner, heard, partial, lo, hi, region):
    """The bounds (B, 3) of every row: without ``region``, a row with missing ranges gets
    the bounding box of its heard anchors (as if only they had been given)."""
    if region is not None:
        return lo, hi
    lo, hi = lo.copy(), hi.copy()
    pts = a[owner[partial]]  # (Bp, M, 3)
    mask = heard[partial][..., None]
    any_heard = np.any(heard[partial], axis=1)
    lo_p = np.min(np.where(mask, pts, np.inf), axis=1)
    hi_p = np.max(np.where(mask, pts, -np.inf), axis=1)
    rows = np.flatnonzero(partial)[any_heard]
    lo[rows], hi[rows] = lo_p[any_heard], hi_p[any_heard]
    return lo, hi


def _fixable(a: np.ndarray, owner: np.ndarray, heard: np.ndarray) -> np.ndarray:
    """(B,) bool: at least :data:`MIN_HEARD` heard anchors, not collinear (the rank rule
    of :func:`simulation.checks.rank_of_spread` on the heard subset)."""
    n = heard.sum(axis=1)
    pts = a[owner]  # (B, M, 3)
    w = heard[..., None]
    mean = np.sum(np.where(w, pts, 0.0), axis=1) / np.maximum(n, 1)[:, None]
    dev = np.where(w, pts - mean[:, None], 0.0)
    scatter = np.einsum("bmi,bmj->bij", dev, dev)
    sv = np.sqrt(np.maximum(np.linalg.eigvalsh(scatter), 0.0))[:, ::-1]
    rank = np.sum(sv / np.sqrt(np.maximum(n, 1))[:, None] > checks.MIN_ANCHOR_DISTANCE, axis=1)
    return (n >= MIN_HEARD) & (rank >= 2)


@numba.njit(cache=True)
def _masked_starts(a, owner, R, lo, hi, rows, x):  # pragma: no cover - compiled
    """For the ``rows`` with missing ranges, the linear solution of the heard anchors'
    squared-range differences (module docstring) written into x (B, 3) when it lies in
    [lo, hi] and the heard anchors are not coplanar (:func:`linear_fix`)."""
    p = np.empty(3)
    for b in range(R.shape[0]):
        if not rows[b] or not linear_fix(a[owner[b]], R[b], p, 1e-18):
            continue  # coplanar heard anchors: the start stays at the centre
        inside = True
        for k in range(3):
            inside = inside and lo[b, k] <= p[k] <= hi[b, k]
        if inside:
            x[b, 0], x[b, 1], x[b, 2] = p[0], p[1], p[2]


def _levenberg_marquardt(a, owner, R, x, lo, hi, bounded, max_iter, tols, poly=None):
    """Damped Gauss–Newton (Levenberg–Marquardt, Nielsen's damping update) on every row:
    ranges R (B, M), anchors a (L, M, 3) with row b's layout ``owner[b]``, starts x (B, 3)
    and bounds lo, hi (B, 3). Returns the positions (B, 3), costs ½Σr² (B,), statuses (B,)
    and iterations (B,)."""
    B = len(R)
    out = (np.empty((B, 3)), np.empty(B), np.zeros(B, dtype=np.int8), np.zeros(B, dtype=np.int32))
    if B:
        lm_rows(
            _c(a),
            _c(owner, np.int64),
            _c(R),
            _c(x),
            _c(np.broadcast_to(lo, (B, 3))),
            _c(np.broadcast_to(hi, (B, 3))),
            bool(bounded),
            _c(np.empty((0, 2)) if poly is None else poly),
            int(max_iter),
            *(float(t) for t in tols),
            *out,
        )
    return out


def check_test(range_sigma, false_alarm, alert_limit) -> None:
    """The robust method's test settings (:func:`locate`), refused by name (ValueError)."""
    checks.real("range_sigma", range_sigma, low=0.0, high=10.0, low_open=True, unit="m")
    checks.real("false_alarm", false_alarm, low=0.0, high=0.5, low_open=True)
    checks.real("alert_limit", alert_limit, low=0.0, high=100.0, low_open=True, unit="m")


def _robust(a, owner, R, F, fix, lo, hi, bounded, poly, max_iter, tols, test, room_map, front):
    """In place on the least-squares ``fix`` (x, cost, status, nit) of the ranges F
    (:func:`_least_squares`) of the rows R: the robust method's
    fixes (:mod:`simulation.robust`) with the test ``test`` (range_sigma, false_alarm,
    alert_limit) on the map ``room_map`` (:func:`simulation.polyhedral.blocking_map`;
    ``front`` (L, M, F) the faces each anchor faces); returns the anchors used (B, M) and
    the qualities."""
    B, M = R.shape
    sigma, false_alarm, alert_limit = (float(v) for v in test)
    used, quality = np.zeros((B, M), dtype=bool), np.zeros(B, dtype=np.int8)
    if B:
        x, cost, status, nit = fix
        robust_rows(_c(a), _c(owner, np.int64), _c(R), _c(F), x, cost, status, nit,
                    _c(np.broadcast_to(lo, (B, 3))), _c(np.broadcast_to(hi, (B, 3))),
                    bool(bounded), poly, max_iter, *(float(t) for t in tols), float(sigma),
                    thresholds(false_alarm, M), bias_scales(false_alarm, M), alert_limit, used,
                    quality, room_map, front)  # fmt: skip
    return used, quality


def _check_room(room) -> None:
    """A room (or None) is what ``room=`` takes: refused by name before any solve."""
    if room is not None and not all(
        hasattr(room, k) for k in ("obstacles", "is_convex", "floor_corners")
    ):
        raise ValueError(f"room: expected a simulation.Room or None, got {checks.describe(room)}")


def _room_map(room):
    """The map of ``room`` for the robust search (an empty map without a room)."""
    return NO_MAP if room is None else blocking_map(room)


def _front(room, layouts) -> np.ndarray:
    """(L, M, F) the faces of the map of ``room`` that each anchor of ``layouts`` (L, M, 3)
    faces (:func:`simulation.polyhedral.facing`; F = 0 without a room)."""
    return np.zeros((*layouts.shape[:2], 0), dtype=bool) if room is None else facing(room, layouts)


def _floor_plan(floor_plan) -> np.ndarray:
    """(K, 2) the floor plan's corners as a C array (empty (0, 2) without one)."""
    if floor_plan is None:
        return np.empty((0, 2))
    poly = checks.reals("floor_plan", floor_plan)
    if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3:
        raise ValueError(
            f"floor_plan: expected the corners (K, 2) of a polygon, K >= 3, got {poly.shape}"
        )
    return _c(poly)


def _c(x, dtype=float) -> np.ndarray:
    """``x`` as a writable C-contiguous array (a copy only when it is not one already): the
    compiled loop then has one signature, whatever views the caller passed."""
    return np.require(x, dtype, ("C", "W"))

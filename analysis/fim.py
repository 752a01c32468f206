"""Fisher information, CRLB, PEB and GDOP for range (time-of-flight) positioning (paper §IV).

Range model (paper §IV, eq. 3): r_j = ‖p − a_j‖ + n_j, n_j ~ N(0, σ_j²) independent. Then

    J(p) = Σ_j u_j u_jᵀ / σ_j²,      u_j = (p − a_j)/‖p − a_j‖,

CRLB = J⁻¹ and PEB(p) = √tr J(p)⁻¹ in metres. The paper (§IV, eq. 7) calls tr J⁻¹ itself
the PEB (m²); :func:`crlb_trace` returns that quantity.

Shapes: ``anchors`` is (M, 3) or a batch of layouts (..., M, 3); ``positions`` is (P, 3).
Results carry the batch axes first: (..., P) or (..., P, 3, 3). ``sigma`` (metres) is a
scalar, a per-anchor (M,) array, a per-pair (P, M) array, or anything broadcasting to
(..., P, M); σ = inf means "no information from that anchor".

A singular J (fewer than three independent directions, e.g. the node in the plane of
coplanar anchors) gives PEB = +inf, never an exception, NaN or warning. J is declared
singular when its smallest eigenvalue (estimated as det J / Σ principal 2×2 minors) is
below ``SINGULAR_RTOL`` · tr J: :func:`nonsingular` is that rule, used here and by the
selection criteria of :mod:`placement.selection`.
"""

from __future__ import annotations

import numpy as np

from simulation import checks

#: relative eigenvalue threshold below which J counts as singular (PEB ≥ 1e5× typical)
SINGULAR_RTOL = 1e-10

#: pairs (positions × anchors × layouts) processed per chunk, to bound memory
_CHUNK_ELEMENTS = 1 << 21


def _as_inputs(anchors, positions):
    a = checks.reals("anchors", anchors)
    p = checks.reals("positions", positions)
    if a.ndim < 2 or a.shape[-1] != 3:
        raise ValueError(f"anchors: expected shape (M, 3) or (..., M, 3), got {a.shape}")
    if p.ndim == 1 and p.shape[0] == 3:
        p = p[None, :]
    if p.ndim != 2 or p.shape[-1] != 3:
        raise ValueError(f"positions: expected shape (P, 3), got {p.shape}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(p))):
        raise ValueError("anchors/positions: must be finite (no NaN or inf)")
    if a.shape[-2] == 0 or p.shape[0] == 0:
        raise ValueError(
            f"anchors/positions: need at least one of each, got {a.shape} and {p.shape}"
        )
    return a, p


#: the default range standard deviation σ (m) of the bounds, the PEB cost and the plan's
#: reported PEB: the paper's constant σ (§IV)
DEFAULT_SIGMA = 0.04
#: the scalar range σ (m) the noise models, costs and commands accept: (low, high]
SIGMA_RANGE = (0.0, 10.0)


def check_sigma(value, name: str = "sigma") -> float:
    """A scalar range σ (m), checked: in :data:`SIGMA_RANGE`, (0, 10] m."""
    lo, hi = SIGMA_RANGE
    return checks.real(name, value, low=lo, high=hi, low_open=True, unit="m")


def _inverse_variance(sigma, batch: tuple[int, ...], P: int, M: int) -> tuple[np.ndarray, float]:
    """(w, s0): w = (s0/σ)² broadcast to (..., P, M), so 1/σ² = w / s0², with s0 the
    smallest σ. σ must be > 0 (inf allowed: weight 0). The FIM is linear in 1/σ², and the
    scaled weights (≤ 1) keep 1/σ² and the determinant from overflowing for σ far below
    1 m (or underflowing far above)."""
    s = checks.reals("sigma", sigma, allow_inf=True, low=0.0, low_open=True, unit="m")
    try:
        s = np.broadcast_to(s, (*batch, P, M))
    except ValueError:
        raise ValueError(
            f"sigma: shape {s.shape} does not broadcast to (..., P, M) = {(*batch, P, M)}; "
            "use a scalar, (M,), (P, M) or (..., P, M)"
        ) from None
    s0 = float(np.min(s)) if s.size else 1.0
    if not np.isfinite(s0):  # every σ infinite: no information at all
        return np.zeros(s.shape), 1.0
    r = s0 / s
    return r * r, s0


def _components(a: np.ndarray, p: np.ndarray, w: np.ndarray):
    """Six unique FIM entries (xx, yy, zz, xy, xz, yz), each (..., P).

    u u_jᵀ/σ² = diff diffᵀ · w/d², which avoids the square root and three divisions.
    """
    diff = p[:, None, :] - a[..., None, :, :]  # (..., P, M, 3)
    d2 = np.einsum("...k,...k->...", diff, diff)
    # A node exactly on an anchor has no defined direction: it carries no information.
    s = np.divide(w, d2, out=np.zeros_like(d2), where=d2 > 0)
    dx, dy, dz = diff[..., 0], diff[..., 1], diff[..., 2]
    sx, sy = s * dx, s * dy
    return (
        np.einsum("...m,...m->...", sx, dx),
        np.einsum("...m,...m->...", sy, dy),
        np.einsum("...m,...m->...", s * dz, dz),
        np.einsum("...m,...m->...", sx, dy),
        np.einsum("...m,...m->...", sx, dz),
        np.einsum("...m,...m->...", sy, dz),
    )


def _cross(a, b, c, d):
    """a·b − c·d, with one temporary."""
    out = a * b
    out -= c * d
    return out


def minors_det(xx, yy, zz, xy, xz, yz):
    """(Σ of the principal 2×2 minors = tr adj J, det J) of symmetric 3×3 matrices J given
    by their six unique entries (arrays of one shape); the inputs are not modified."""
    mx, my, mz = _cross(yy, zz, yz, yz), _cross(xx, zz, xz, xz), _cross(xx, yy, xy, xy)
    det = xx * mx
    det -= xy * _cross(xy, zz, yz, xz)
    det += xz * _cross(xy, yz, yy, xz)
    minors = mx + my
    minors += mz
    return minors, det


def nonsingular(xx, yy, zz, minors, det):
    """The FIM-singularity rule, the one place it is written: J is singular when its
    smallest eigenvalue, estimated as det J / Σ minors, is at most ``SINGULAR_RTOL`` · tr J
    (or the minors are not positive). Returns a bool array, True where J is usable.

    ``xx, yy, zz`` are J's diagonal entries, ``minors, det`` from :func:`minors_det`; every
    bound-driven number (PEB, tr J⁻¹, the selection criteria) is +inf where this is False.
    """
    bar = xx + yy
    bar += zz
    bar *= minors
    bar *= SINGULAR_RTOL
    return (minors > 0) & (det > bar)


def _trace_inverse(xx, yy, zz, xy, xz, yz) -> np.ndarray:
    """tr J⁻¹ by the adjugate formula, +inf where J is singular (:func:`nonsingular`)."""
    minors, det = minors_det(xx, yy, zz, xy, xz, yz)
    ok = nonsingular(xx, yy, zz, minors, det)
    out = np.full(np.shape(det), np.inf)
    np.divide(minors, det, out=out, where=ok)
    return out


def _chunked(a, p, sigma, fn) -> tuple[np.ndarray, float]:
    """``fn(a, p_chunk, w_chunk)`` over chunks of positions, concatenated on axis -1, on
    the scaled weights w of :func:`_inverse_variance`; returns it and their scale s0."""
    batch, M, P = a.shape[:-2], a.shape[-2], p.shape[0]
    w, s0 = _inverse_variance(sigma, batch, P, M)
    step = max(1, _CHUNK_ELEMENTS // max(1, M * int(np.prod(batch, dtype=np.int64))))
    if step >= P:
        return fn(a, p, w), s0
    parts = [fn(a, p[i : i + step], w[..., i : i + step, :]) for i in range(0, P, step)]
    return np.concatenate(parts, axis=len(batch)), s0


def _rescaled(x: np.ndarray, s0: float, power: int) -> np.ndarray:
    """x · s0^power, where 0 and +inf entries stay as they are (no 0 · inf); beyond the
    float range the product is +inf or 0."""
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        return np.where((x == 0) | np.isinf(x), x, x * np.float64(s0) ** power)


def fim(anchors, positions, sigma=DEFAULT_SIGMA) -> np.ndarray:
    """Fisher information matrix J(p) for range measurements, (..., P, 3, 3) in 1/m².

    J(p) = Σ_j u_j u_jᵀ / σ_j² (paper eq. 6).
    """
    a, p = _as_inputs(anchors, positions)

    def one(a, p, w):
        xx, yy, zz, xy, xz, yz = _components(a, p, w)
        return np.stack(
            [np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1), np.stack([xz, yz, zz], -1)],
            -2,
        )

    J, s0 = _chunked(a, p, sigma, one)
    return _rescaled(J, s0, -2)


def crlb(anchors, positions, sigma=DEFAULT_SIGMA) -> np.ndarray:
    """Position CRLB J(p)⁻¹, (..., P, 3, 3) in m²; all entries +inf where J is singular."""
    a, p = _as_inputs(anchors, positions)

    def one(a, p, w):
        xx, yy, zz, xy, xz, yz = _components(a, p, w)
        adj = np.stack(
            [
                np.stack([yy * zz - yz * yz, xz * yz - xy * zz, xy * yz - xz * yy], -1),
                np.stack([xz * yz - xy * zz, xx * zz - xz * xz, xy * xz - xx * yz], -1),
                np.stack([xy * yz - xz * yy, xy * xz - xx * yz, xx * yy - xy * xy], -1),
            ],
            -2,
        )
        det = xx * adj[..., 0, 0] + xy * adj[..., 1, 0] + xz * adj[..., 2, 0]
        singular = ~np.isfinite(_trace_inverse(xx, yy, zz, xy, xz, yz))
        det = np.where(singular, 1.0, det)
        out = adj / det[..., None, None]
        out[singular] = np.inf
        return out

    C, s0 = _chunked(a, p, sigma, one)
    return _rescaled(C, s0, 2)


def crlb_trace(anchors, positions, sigma=DEFAULT_SIGMA) -> np.ndarray:
    """tr J(p)⁻¹, (..., P) in m² — the paper's "PEB" (§IV, eq. 7); +inf where singular."""
    t, s0 = _scaled_trace(anchors, positions, sigma)
    return _rescaled(t, s0, 2)


def _scaled_trace(anchors, positions, sigma) -> tuple[np.ndarray, float]:
    """(tr J⁻¹ / s0², s0): the trace on the scaled weights, and their scale."""
    a, p = _as_inputs(anchors, positions)
    return _chunked(a, p, sigma, lambda a, p, w: _trace_inverse(*_components(a, p, w)))


def peb(anchors, positions, sigma=DEFAULT_SIGMA) -> np.ndarray:
    """Position error bound √tr J(p)⁻¹, (..., P) in metres; +inf where J is singular."""
    t, s0 = _scaled_trace(anchors, positions, sigma)
    return np.sqrt(t) * s0  # in range for any σ the float type holds


def gdop(anchors, positions) -> np.ndarray:
    """Geometric dilution of precision √tr (HᵀH)⁻¹, (..., P), dimensionless (PEB at σ = 1)."""
    return peb(anchors, positions, sigma=1.0)

"""The selection problem shared by the exhaustive search and the convex relaxation.

Choosing M anchors out of N candidate mounting points (paper §III-A) is judged by the
Fisher information at the P evaluation nodes (paper eq. 6). The FIM is linear in the
selection, J_p(S) = Σ_{n∈S} G_pn with G_pn = u uᵀ/σ_pn², so the six unique entries of every
G_pn are tabulated once, (6, N, P) (:func:`fim_table`), and both
:func:`placement.exhaustive_search` and :func:`placement.relax_select` work on that table.

Criteria (σ the range standard deviation, J_p the FIM at node p), all minimized:

* ``"A"``: mean over the nodes of tr J_p⁻¹ (m², the paper's "PEB" without the root);
* ``"minimax"``: max over the nodes of tr J_p⁻¹ (m²);
* ``"D"``: the geometric mean over the nodes of det(J_p)^(−1/3) (m²), i.e.
  exp(−Σ_p log det J_p / (3P)). Minimizing it is maximizing Σ_p log det J_p; it is the
  per-axis variance of a sphere with the volume of the mean CRLB ellipsoid.

Each is +inf for a subset whose J_p is singular at any node, by the one singularity rule
of :func:`analysis.fim.nonsingular`; tr J⁻¹ and det J come from the closed-form 3×3
adjugate (:func:`analysis.fim.minors_det`), as in :func:`analysis.crlb_trace`. The solvers
work with σ normalized to its geometric mean σ_ref (:class:`DesignInputs`) and rescale
the results to m² (:func:`to_value`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.fim import DEFAULT_SIGMA, minors_det, nonsingular
from placement.surfaces import allowed, candidate_grid
from simulation import checks
from simulation.room import Room, as_room

CRITERIA = ("A", "D", "minimax")

#: (row, col) of the six unique entries (xx, yy, zz, xy, xz, yz) of a symmetric 3×3, the
#: order of the first axis of :func:`fim_table`
ENTRIES = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))

#: weights of the six unique entries (xx, yy, zz, xy, xz, yz) in a Frobenius inner product
ENTRY_WEIGHTS = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])

#: default candidate spacing (m) when ``candidates`` is None: ~200 points in techtile
DEFAULT_SPACING = 0.75


# -- design inputs ----------------------------------------------------------------------------
@dataclass(frozen=True)
class DesignInputs:
    """Validated inputs of a selection problem.

    ``candidates`` (N, 3) m, ``nodes`` (P, 3) m, ``sigma`` (N,) m per candidate or (N, P)
    per candidate and node, and
    ``sigma_ref`` (m, their geometric mean): the solvers work with σ_n/σ_ref (σ
    normalized to 1) and rescale the results.
    """

    candidates: np.ndarray
    nodes: np.ndarray
    sigma: np.ndarray
    sigma_ref: float
    M: int
    criterion: str

    def table(self) -> np.ndarray:
        """(6, N, P) normalized FIM entries of every candidate at every node."""
        return fim_table(self.candidates, self.nodes, self.sigma / self.sigma_ref)

    def scale(self, objective):
        """Normalized objective (see :func:`criterion_values`) → criterion value in m²."""
        return to_value(objective, self.criterion, self.sigma_ref)


def design_inputs(
    room: Room,
    M,
    candidates=None,
    criterion: str = "A",
    sigma=DEFAULT_SIGMA,
    nodes=None,
    spacing: float = DEFAULT_SPACING,
) -> DesignInputs:
    """Check the arguments of a selection problem; raise ``ValueError`` naming the problem."""
    room = as_room(room)
    checks.choice("criterion", criterion, CRITERIA)
    if candidates is None:
        cand = candidate_grid(room, spacing)
    else:
        cand = checks.reals("candidates", candidates)
        if cand.ndim != 2 or cand.shape[1] != 3 or cand.shape[0] == 0:
            raise ValueError(f"candidates: expected shape (N, 3) with N >= 1, got {cand.shape}")
        if not np.all(np.isfinite(cand)):
            raise ValueError("candidates: must be finite (no NaN or inf)")
        off = np.flatnonzero(~allowed(room, cand, tol=1e-6))
        if off.size:
            raise ValueError(
                f"candidates: {off.size} point(s) are not on an allowed mounting surface "
                f"{list(room.mounting)} or lie in a keep-out "
                f"(first: index {off[0]}, {cand[off[0]].tolist()}); "
                "use placement.project or placement.candidate_grid"
            )
        checks.distinct("candidates", cand)  # a repeated point would give coincident anchors
    N = cand.shape[0]
    if isinstance(M, bool) or not isinstance(M, int | np.integer) or not 4 <= M <= N:
        raise ValueError(
            f"M: number of anchors must be an integer in [4, {N}] (4 for 3D positioning, "
            f"at most the {N} candidates), got {M!r}"
        )
    if nodes is None:
        p = room.grid()
    else:
        p = room.check_nodes(nodes)
    s = checks.reals("sigma", sigma)
    if s.ndim == 0:
        s = np.full(N, float(s))
    if s.shape == (p.shape[0], N):
        s = s.T  # per (node, candidate) pair, stored (N, P) like the FIM table
    elif s.shape != (N,):
        raise ValueError(
            f"sigma: expected a scalar, shape ({N},) (one per candidate) or "
            f"({p.shape[0]}, {N}) (one per node and candidate), got {s.shape}"
        )
    if not (np.all(np.isfinite(s)) and np.all(s > 0)):
        raise ValueError("sigma: range standard deviations must be finite and > 0 m")
    checks.check_size(
        "candidates x nodes", 6 * N * p.shape[0] * 8 * 4, value=(N, p.shape[0]),
        hint="use fewer candidates (a larger spacing) or nodes",
    )  # fmt: skip
    return DesignInputs(cand, p, s, float(np.exp(np.mean(np.log(s)))), int(M), criterion)


# -- the FIM table and the criteria -----------------------------------------------------------
def fim_table(candidates, nodes, sigma=1.0) -> np.ndarray:
    """(6, N, P) entries (xx, yy, zz, xy, xz, yz) of G_pn = u uᵀ/σ_pn² (paper eq. 6).

    ``sigma`` is a scalar, per candidate (N,), or per candidate and node (N, P).

    u is the unit vector from candidate n to node p; a node on a candidate carries no
    information (G = 0), as in :func:`analysis.fim`.
    """
    a = np.asarray(candidates, dtype=float)
    p = np.asarray(nodes, dtype=float)
    d = p[None, :, :] - a[:, None, :]  # (N, P, 3)
    d2 = np.einsum("npk,npk->np", d, d)
    w = 1.0 / np.asarray(sigma, dtype=float) ** 2
    w = w[:, None] if w.ndim == 1 else np.broadcast_to(w, d2.shape)  # (N,) or (N, P)
    s = np.divide(w, d2, out=np.zeros_like(d2), where=d2 > 0)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack([s * x * x, s * y * y, s * z * z, s * x * y, s * x * z, s * y * z])


def node_values(J, criterion: str) -> np.ndarray:
    """Per-node objective from FIM entries J (6, ..., P): tr J⁻¹ ("A", "minimax") or
    −log det J ("D"); +inf where J is singular."""
    minors, det = minors_det(*J)
    ok = nonsingular(J[0], J[1], J[2], minors, det)
    out = np.full(det.shape, np.inf)
    if criterion == "D":
        np.log(det, out=out, where=ok)
        np.negative(out, out=out, where=ok)
    else:
        np.divide(minors, det, out=out, where=ok)
    return out


def criterion_values(J, criterion: str) -> np.ndarray:
    """Normalized objective of FIM entries J (6, ..., P) → (...): mean tr J⁻¹ ("A"),
    max tr J⁻¹ ("minimax") or −mean log det J ("D"); +inf if any node is singular."""
    v = node_values(J, criterion)
    return v.max(axis=-1) if criterion == "minimax" else v.mean(axis=-1)


def to_value(objective, criterion: str, sigma_ref: float):
    """Rescale a normalized objective (σ_ref = 1) to the criterion's value in m²."""
    objective = np.asarray(objective, dtype=float)
    if criterion == "D":
        # −mean log det J_norm = g  →  det J = det J_norm · σ_ref⁻⁶
        with np.errstate(over="ignore"):
            out = np.exp(objective / 3.0) * sigma_ref**2
    else:
        out = objective * sigma_ref**2
    return out.item() if out.ndim == 0 else out


def subset_values(G: np.ndarray, S: np.ndarray, criterion: str, block: int = 64) -> np.ndarray:
    """Normalized criterion of the subsets S (K, M) of the table G (6, N, P) → (K,)."""
    out = np.empty(S.shape[0])
    for lo in range(0, S.shape[0], block):
        out[lo : lo + block] = criterion_values(G[:, S[lo : lo + block]].sum(axis=2), criterion)
    return out

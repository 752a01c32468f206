"""Image-source multipath in a shoebox room with a cardioid speaker (paper §V-A).

Every anchor j has image sources indexed by n = (nx, ny, nz) ∈ ℤ³ with |nx|+|ny|+|nz| ≤
``room.max_order`` (Allen & Berkley). Along an axis of length L, the image of a coordinate
a is n·L + a for even n and (n+1)·L − a for odd n. A path reaching the node p from the image
at q has length d = ‖p − q‖ and amplitude

    A = Π_walls β · g(cos θ) · exp(−a·d/2) / (4π d),

with β = √(1 − α) the reflection amplitude of each wall hit (for n > 0 the path hits the
plane at L ⌈n/2⌉ times and the plane at 0 ⌊n/2⌋ times, mirrored for n < 0), a the air
attenuation coefficient (the constant one, or ISO 9613-1 at the chirp's centre frequency,
whose variation across the band :mod:`simulation.synthesis` applies) and
g(θ) = ½(1 + cos θ) the cardioid of the real speaker aimed at the room centroid. θ is
measured for the ray as it leaves the real speaker: the direction
image → node, mirrored back through the reflections, i.e. with the sign of each component
flipped for every axis that is reflected an odd number of times. The node is
omnidirectional. This is the convention of pyroomacoustics' shoebox ISM
(``libroom`` ``image_source_shoebox``), the peer simulator of the tests.

Images whose wall product is zero (e.g. the techtile room's fully absorbing west and east
walls) are dropped once per room, so the path axis only holds paths that can carry energy.

A room that is not a plain shoebox (a polygonal floor plan, or obstacles) has images that
are not visible from every node: :func:`compute_paths` then traces each path
(:mod:`simulation.polyhedral`), with the same amplitude rule.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simulation import checks
from simulation.directivity import aim_vectors, cardioid
from simulation.room import MAX_ORDER, Room, as_room


def image_indices(max_order: int) -> np.ndarray:
    """(I, 3) integer image indices n with |nx|+|ny|+|nz| ≤ ``max_order``; n = 0 first.

    I = (2N+1)(2N²+2N+3)/3 for order N (63 for N = 3); N is at most 12.
    """
    max_order = checks.count("max_order", max_order, low=0, high=MAX_ORDER)
    r = np.arange(-int(max_order), int(max_order) + 1)
    n = np.stack(np.meshgrid(r, r, r, indexing="ij"), axis=-1).reshape(-1, 3)
    order = np.abs(n).sum(axis=1)
    n = n[order <= max_order]
    # direct path first, then by order (stable), so path 0 is always the line of sight
    return n[np.argsort(np.abs(n).sum(axis=1), kind="stable")]


def wall_hits(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reflection counts on the planes at 0 and at L for image indices n (any int array).

    Returns (hits_low, hits_high) of the shape of n: for n > 0, ⌊n/2⌋ and ⌈n/2⌉; for n < 0,
    ⌈|n|/2⌉ and ⌊|n|/2⌋.
    """
    n = np.asarray(n)
    a = np.abs(n)
    low = np.where(n >= 0, a // 2, (a + 1) // 2)
    high = np.where(n >= 0, (a + 1) // 2, a // 2)
    return low, high


@dataclass(frozen=True)
class ImageSet:
    """Image indices of a room that can carry energy, and their wall-reflection products.

    indices : (I, 3) int image indices (path 0 is the direct path).
    reflection : (I,) amplitude product Π β over the walls each image's path hits (> 0).
    mirror : (I, 3) ±1, −1 on axes reflected an odd number of times.
    """

    indices: np.ndarray
    reflection: np.ndarray
    mirror: np.ndarray

    @classmethod
    def for_room(cls, room: Room) -> ImageSet:
        """Images up to ``room.max_order`` with a nonzero wall product."""
        n = image_indices(as_room(room).max_order)
        beta = room.reflections  # (3, 2) by [axis, side]
        low, high = wall_hits(n)
        with np.errstate(divide="ignore"):
            # 0**0 = 1: a wall that is never hit does not matter even when β = 0
            refl = np.prod(beta[:, 0] ** low * beta[:, 1] ** high, axis=1)
        keep = refl > 0
        n = n[keep]
        return cls(
            indices=n, reflection=refl[keep], mirror=np.where(n % 2 == 0, 1.0, -1.0).astype(float)
        )

    def __len__(self) -> int:
        return len(self.indices)

    def positions(self, room: Room, anchors: np.ndarray) -> np.ndarray:
        """(M, I, 3) image positions of anchors (M, 3)."""
        a = np.asarray(anchors, dtype=float)[:, None, :]
        L = np.asarray(room.size)
        n = self.indices[None]
        odd = (n % 2) != 0
        return np.where(odd, (n + 1) * L - a, n * L + a)


@dataclass(frozen=True)
class Paths:
    """Propagation paths from every anchor to every node.

    length : (P, M, I) path lengths d in metres; path 0 is the direct path.
    amplitude : (P, M, I) amplitudes A (unit-amplitude chirp at the speaker); paths that
        carry no energy (cardioid null, a blocked direct path, padding) have A = 0.
    line_of_sight : (P, M) bool, whether the direct path is unobstructed (None: all are,
        as in a shoebox without obstacles).
    """

    length: np.ndarray
    amplitude: np.ndarray
    line_of_sight: np.ndarray | None = None

    @property
    def los(self) -> np.ndarray:
        """(P, M) bool: the direct path is unobstructed."""
        if self.line_of_sight is None:
            return np.ones(self.length.shape[:2], dtype=bool)
        return self.line_of_sight

    def delays(self, speed_of_sound: float) -> np.ndarray:
        """(P, M, I) propagation delays d/c in seconds."""
        return self.length / speed_of_sound


#: the paper's chirp's centre frequency (Hz): where the air's attenuation is taken by default
REFERENCE_FREQUENCY = 35e3


def compute_paths(
    room: Room,
    anchors,
    nodes,
    images: ImageSet | None = None,
    aim_at=None,
    directivity: str = "cardioid",
    frequency: float = REFERENCE_FREQUENCY,
) -> Paths:
    """Image-source paths from anchors (M, 3) to nodes (P, 3), vectorized over P × M × I.

    ``aim_at`` (3,) is where the cardioids point (default the room centroid, paper §V-A);
    ``directivity`` "omni" makes the speakers omnidirectional (the peer simulator's
    general rooms have no speaker directivity). A node exactly on an image (d = 0) is not
    physical; such paths get A = 0. A polygonal room or one with obstacles goes through
    :mod:`simulation.polyhedral` (``images`` is then not used). ``frequency`` (Hz) is where
    the air's attenuation is taken (the chirp's centre; default the paper's 35 kHz).
    """
    room = as_room(room)
    a = checks.reals("anchors", anchors)
    p = checks.reals("nodes", nodes)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"anchors: expected shape (M, 3), got {a.shape}")
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"nodes: expected shape (P, 3), got {p.shape}")
    checks.choice("directivity", directivity, ("cardioid", "omni"))
    aim = aim_vectors(a, room.centroid if aim_at is None else np.asarray(aim_at, float))  # (M,3)
    air = float(room.air_coefficient(checks.real("frequency", frequency, low=0.0, unit="Hz")))
    if not room.is_shoebox or room.obstacles:
        return _traced_paths(room, a, p, aim, directivity, air)
    images = ImageSet.for_room(room) if images is None else images
    if not isinstance(images, ImageSet):
        raise ValueError(f"images: must be an ImageSet or None, got {checks.describe(images)}")
    n = p.shape[0] * a.shape[0] * len(images)
    checks.check_size(
        "nodes x anchors x image sources",
        n * 8 * 10,
        value=(p.shape[0], a.shape[0], len(images)),
        hint="use fewer nodes or anchors, or a lower max_order",
    )
    q = images.positions(room, a)  # (M, I, 3)
    u = p[:, None, None, :] - q[None]  # (P, M, I, 3) image -> node
    d = np.sqrt(np.einsum("pmik,pmik->pmi", u, u))
    # emission direction of the real speaker: mirror back through the reflections
    proj = np.einsum("pmik,ik,mk->pmi", u, images.mirror, aim)
    ok = d > 0
    safe = np.where(ok, d, 1.0)
    gain = cardioid(np.clip(proj / safe, -1.0, 1.0)) if directivity == "cardioid" else 1.0
    amp = images.reflection * gain * np.exp(-0.5 * air * d) / (4 * np.pi * safe)
    return Paths(length=d, amplitude=np.where(ok, amp, 0.0))


def _traced_paths(room: Room, a, p, aim, directivity, air: float) -> Paths:
    """:func:`compute_paths` of a room that is not a plain shoebox (module docstring)."""
    from simulation.polyhedral import paths

    n = p.shape[0] * a.shape[0]
    checks.check_size(
        "nodes x anchors", n * 8 * 200, value=(p.shape[0], a.shape[0]), hint="use fewer nodes"
    )
    d, first, beta, valid, los = paths(room, a, p)
    cos = np.einsum("pmik,mk->pmi", first, aim)
    gain = cardioid(np.clip(cos, -1.0, 1.0)) if directivity == "cardioid" else 1.0
    ok = valid & (d > 0)
    safe = np.where(ok, d, 1.0)
    amp = beta * gain * np.exp(-0.5 * air * safe) / (4 * np.pi * safe)
    return Paths(length=d, amplitude=np.where(ok, amp, 0.0), line_of_sight=los)

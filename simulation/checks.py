"""Argument checks shared by every layer: one message style, ``ValueError`` only.

The lowest layer (imports only numpy), so :mod:`simulation`, :mod:`analysis`,
:mod:`placement` and the CLI all use the same rules. Every check raises ``ValueError``
with one line naming the argument, the value given and what is allowed, e.g.

    max_order: must be an integer in [0, 12], got True (a bool)

Integer counts reject bools, strings and non-integral floats (3.0 is 3, 3.7 is an
error); reals reject bools, strings, NaN and ±inf; sizes that would not fit in memory are
refused from an estimate before anything is allocated (:func:`check_size`). The ``rng``
arguments and random streams are :mod:`simulation.streams`'; the names of degenerate
layouts :mod:`simulation.degeneracy`'s.
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "check_size",
    "choice",
    "count",
    "describe",
    "distinct",
    "flag",
    "input_dir",
    "input_file",
    "inside",
    "known_keys",
    "mapping",
    "memory_limit",
    "output_path",
    "points",
    "real",
    "reals",
]

#: default share of the physical memory one array may take before it is refused
MEMORY_FRACTION = 0.5
#: the distance (m) under which two anchors count as the same point
MIN_ANCHOR_DISTANCE = 1e-3
#: names of the affine ranks of a point set (:func:`geometry`)


# -- formatting -------------------------------------------------------------------------------
def describe(value: Any, limit: int = 60) -> str:
    """A short description of a value for an error message: its repr, and its type when
    the repr alone would mislead (bools, strings, containers, arrays)."""
    if isinstance(value, bool | np.bool_):
        return f"{value!r} (a bool)"
    if isinstance(value, str):
        text = repr(value) if len(value) <= limit else repr(value[:limit]) + "..."
        return f"{text} (a string)"
    if isinstance(value, np.ndarray):
        if value.size <= 6:
            return f"{value.tolist()!r} (array of shape {value.shape})"
        return f"an array of shape {value.shape} and dtype {value.dtype}"
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001 - a broken __repr__ must not hide the real error
        text = f"<{type(value).__name__}>"
    if len(text) > limit:
        text = text[:limit] + "..."
    if isinstance(value, numbers.Number | np.generic):
        return text
    return f"{text} (a {type(value).__name__})"


def _num(x: float) -> str:
    return f"{x:g}"


def _interval(low, high, low_open, high_open, unit: str) -> str:
    u = f" {unit}" if unit else ""
    if low is not None and high is not None and math.isfinite(low) and math.isfinite(high):
        return (
            f"in {'(' if low_open else '['}{_num(low)}, {_num(high)}{')' if high_open else ']'}{u}"
        )
    if low is not None and math.isfinite(low):
        return f"{'>' if low_open else '>='} {_num(low)}{u}"
    if high is not None and math.isfinite(high):
        return f"{'<' if high_open else '<='} {_num(high)}{u}"
    return "finite"


def _bytes(n: float) -> str:
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} bytes"


# -- scalars ----------------------------------------------------------------------------------
def count(name: str, value: Any, *, low: int = 0, high: int | None = None) -> int:
    """An integer in [low, high] (``high`` None: no upper limit), returned as ``int``.

    Accepts Python and numpy integers and integral floats (3.0); rejects bools,
    non-integral or non-finite floats, strings and everything else.
    """
    allowed = f"an integer in [{low}, {high}]" if high is not None else f"an integer >= {low}"
    v = None
    if isinstance(value, bool | np.bool_):
        v = None
    elif isinstance(value, int | np.integer):
        v = int(value)
    elif isinstance(value, float | np.floating) and math.isfinite(value) and value == int(value):
        v = int(value)
    if v is None:
        raise ValueError(f"{name}: must be {allowed}, got {describe(value)}")
    if v < low or (high is not None and v > high):
        raise ValueError(f"{name}: must be {allowed}, got {v}")
    return v


def grid_shape(name: str, value: Any) -> tuple[int, int, int]:
    """Nodes per axis of a regular grid: 3 integers ≥ 1, returned as a tuple."""
    if not isinstance(value, Sequence | np.ndarray) or len(value) != 3:
        raise ValueError(f"{name}: expected 3 integers >= 1, got {describe(value)}")
    nx, ny, nz = (count(name, n, low=1) for n in value)
    return nx, ny, nz


def real(
    name: str,
    value: Any,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
) -> float:
    """A finite real number within the bounds, returned as ``float``.

    Accepts ints, floats, numpy scalars and 0-d arrays; rejects bools, strings, None,
    complex numbers, NaN and ±inf.
    """
    allowed = _interval(low, high, low_open, high_open, unit)
    allowed = "a finite number" if allowed == "finite" else f"a finite number {allowed}"
    v = None
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if not isinstance(value, bool | np.bool_) and isinstance(
        value, numbers.Real | np.integer | np.floating
    ):
        v = float(value)
    if v is None or not math.isfinite(v):
        raise ValueError(f"{name}: must be {allowed}, got {describe(value)}")
    bad = (low is not None and (v <= low if low_open else v < low)) or (
        high is not None and (v >= high if high_open else v > high)
    )
    if bad:
        raise ValueError(f"{name}: must be {allowed}, got {_num(v)}")
    return v


def flag(name: str, value: Any) -> bool:
    """A bool (Python or numpy); 0, 1, strings and None are errors."""
    if isinstance(value, bool | np.bool_):
        return bool(value)
    raise ValueError(f"{name}: must be True or False, got {describe(value)}")


def choice(name: str, value: Any, allowed: Iterable[Any]) -> Any:
    """``value`` if it is one of ``allowed`` (compared with ==, same type family)."""
    options = list(allowed)
    for a in options:
        if type(value) is type(a) or (isinstance(value, str) and isinstance(a, str)):
            try:
                if value == a:
                    return value
            except Exception:  # noqa: BLE001 - e.g. arrays: not equal
                continue
    raise ValueError(f"{name}: must be one of {options}, got {describe(value)}")


# -- collections ------------------------------------------------------------------------------
def mapping(name: str, value: Any, what: str = "a mapping") -> Mapping:
    """``value`` if it is a mapping (dict, TOML table)."""
    if not isinstance(value, Mapping):
        raise ValueError(f"{name}: must be {what}, got {describe(value)}")
    return value


def known_keys(name: str, keys: Iterable[Any], allowed: Iterable[str]) -> None:
    """Every key is a string among ``allowed``; unknown keys (typos) are errors."""
    allowed = list(allowed)
    unknown = [k for k in keys if not (isinstance(k, str) and k in allowed)]
    if unknown:
        raise ValueError(f"{name}: unknown key(s) {unknown}; allowed: {allowed}")


def _has_bool(value: Any, budget: int = 10_000) -> bool:
    """Whether a (nested) list or tuple holds a bool (numpy would make it 0 or 1)."""
    stack = [value]
    while stack and budget > 0:
        v = stack.pop()
        budget -= 1
        if isinstance(v, bool | np.bool_):
            return True
        if isinstance(v, list | tuple):
            stack.extend(v)
    return False


def reals(
    name: str,
    value: Any,
    *,
    shape: tuple[int | None, ...] | None = None,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
    allow_inf: bool = False,
    finite: bool = True,
) -> np.ndarray:
    """A float array of real numbers with the given ``shape`` (None entries: any length),
    every entry finite (or +inf when ``allow_inf``; anything when not ``finite``) and
    within the bounds."""
    if isinstance(value, str | bytes | Mapping) or value is None or _has_bool(value):
        raise ValueError(f"{name}: must be an array of numbers, got {describe(value)}")
    try:
        raw = np.asarray(value)
        if raw.dtype.kind in "bUSVcmM":
            raise TypeError
        if raw.dtype.kind == "O" and any(isinstance(x, bool | str | bytes) for x in raw.flat):
            raise TypeError
        a = np.asarray(raw, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name}: must be an array of numbers, got {describe(value)}") from None
    if shape is not None:
        ok = a.ndim == len(shape) and all(
            s is None or s == n for s, n in zip(shape, a.shape, strict=False)
        )
        if not ok:
            want = tuple("n" if s is None else s for s in shape)
            want = str(want).replace("'", "")
            raise ValueError(f"{name}: expected shape {want}, got {describe(value)}")
    ok = np.isfinite(a) | (allow_inf & (a == np.inf))
    if finite and not np.all(ok):
        raise ValueError(f"{name}: every entry must be a finite number (no NaN or inf)")
    allowed = _interval(low, high, low_open, high_open, unit)
    bad = np.zeros(a.shape, dtype=bool)
    if low is not None:
        bad |= (a <= low) if low_open else (a < low)
    if high is not None:
        bad |= ((a >= high) if high_open else (a > high)) & np.isfinite(a)
    if np.any(bad):
        first = a[bad].ravel()[0]
        raise ValueError(
            f"{name}: every entry must be {allowed}, got {_num(first)}"
            + (f" in {describe(value)}" if 1 < a.size <= 6 else "")
        )
    return a


def points(name: str, value: Any, *, min_rows: int = 1, max_rows: int | None = None) -> np.ndarray:
    """(N, 3) finite coordinates in metres, min_rows ≤ N ≤ max_rows."""
    a = reals(name, value)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name}: expected shape (N, 3) of x, y, z in metres, got {a.shape}")
    n = a.shape[0]
    if n < min_rows or (max_rows is not None and n > max_rows):
        rows = f"[{min_rows}, {max_rows}]" if max_rows is not None else f">= {min_rows}"
        raise ValueError(f"{name}: expected a number of points {rows}, got {n}")
    return a


def inside(name: str, pts: np.ndarray, size, what: str = "the room") -> None:
    """Every point (N, 3) lies in the box [0, size] (m); else name the first one outside."""
    p = np.asarray(pts, dtype=float).reshape(-1, 3)
    L = np.asarray(size, dtype=float)
    tol = 1e-9 * max(1.0, float(np.max(L)))
    out = ~np.all((p >= -tol) & (p <= L + tol), axis=-1)
    if np.any(out):
        i = int(np.flatnonzero(out)[0])
        box = " x ".join(f"[0, {x:g}]" for x in L)
        raise ValueError(
            f"{name}: {int(out.sum())} point(s) lie outside {what} {box} m "
            f"(first: index {i}, {np.round(p[i], 6).tolist()})"
        )


def distinct(name: str, pts: np.ndarray, min_distance: float = MIN_ANCHOR_DISTANCE) -> None:
    """No two points (N, 3) closer than ``min_distance`` metres (duplicated anchors)."""
    p = np.asarray(pts, dtype=float).reshape(-1, 3)
    if len(p) < 2:
        return
    if len(p) <= 512:
        d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=-1)
        d[np.tril_indices(len(p))] = np.inf
        i, j = np.unravel_index(int(np.argmin(d)), d.shape)
        close = d[i, j] < min_distance
    else:
        from scipy.spatial import cKDTree

        pairs = cKDTree(p).query_pairs(min_distance)
        close = bool(pairs)
        if close:
            i, j = min(pairs)
    if close:
        raise ValueError(
            f"{name}: points {i} and {j} are {float(np.linalg.norm(p[i] - p[j])):.3g} m apart "
            f"({np.round(p[i], 6).tolist()}); distinct anchors must be at least "
            f"{min_distance * 1000:g} mm apart"
        )


# -- memory -----------------------------------------------------------------------------------
def memory_limit() -> int:
    """Bytes a single computation may allocate: ``ANCHORPLAN_MEMORY_LIMIT`` (bytes) if set,
    else half the physical memory (4 GB if unknown)."""
    env = os.environ.get("ANCHORPLAN_MEMORY_LIMIT")
    if env:
        try:
            return int(float(env))
        except ValueError:
            pass
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        total = 8e9
    return int(MEMORY_FRACTION * total)


def check_size(
    name: str, n_bytes: float, limit: float | None = None, *, value: Any = None, hint: str = ""
) -> None:
    """Refuse a computation estimated to need more than ``limit`` bytes (default
    :func:`memory_limit`) before anything is allocated."""
    limit = memory_limit() if limit is None else limit
    if n_bytes > limit:
        shown = "" if value is None else f"{describe(value)} "
        raise ValueError(
            f"{name}: {shown}would need about {_bytes(n_bytes)} of memory, more than the "
            f"{_bytes(limit)} allowed" + (f"; {hint}" if hint else "")
        )


# -- files ------------------------------------------------------------------------------------
def _path(name: str, path: Any) -> Path:
    if not isinstance(path, str | os.PathLike) or str(path) == "":
        raise ValueError(f"{name}: must be a file path, got {describe(path)}")
    return Path(path)


def input_file(name: str, path: Any) -> Path:
    """An existing, readable regular file."""
    p = _path(name, path)
    if not p.exists():
        raise ValueError(f"{name} {p}: no such file")
    if p.is_dir():
        raise ValueError(f"{name} {p}: is a directory, expected a file")
    if not os.access(p, os.R_OK):
        raise ValueError(f"{name} {p}: not readable (permission denied)")
    return p


def input_dir(name: str, path: Any) -> Path:
    """An existing, readable directory."""
    p = _path(name, path)
    if not p.exists():
        raise ValueError(f"{name} {p}: not a folder (no such directory)")
    if not p.is_dir():
        raise ValueError(f"{name} {p}: not a folder (it is a file)")
    if not os.access(p, os.R_OK | os.X_OK):
        raise ValueError(f"{name} {p}: not readable (permission denied)")
    return p


def output_path(
    name: str, path: Any, *, kind: str = "file", suffixes: Iterable[str] | None = None
) -> Path:
    """Check before any work that ``path`` can be written: a file (``kind="file"``, not an
    existing directory, suffix among ``suffixes``) or a directory (``kind="dir"``, not an
    existing file); missing parent folders must be creatable."""
    p = _path(name, path)
    if kind not in ("file", "dir"):
        raise ValueError(f"kind: must be 'file' or 'dir', got {kind!r}")
    if kind == "file":
        if p.is_dir():
            raise ValueError(f"{name} {p}: is a directory, expected a file name")
        if suffixes is not None:
            allowed = [s.lower() for s in suffixes]
            if p.suffix.lower() not in allowed:
                raise ValueError(f"{name} {p}: the file name must end in one of {allowed}")
        if p.exists() and not os.access(p, os.W_OK):
            raise ValueError(f"{name} {p}: not writable (permission denied)")
    elif p.exists():
        if not p.is_dir():
            raise ValueError(f"{name} {p}: exists and is not a directory")
        if not os.access(p, os.W_OK | os.X_OK):
            raise ValueError(f"{name} {p}: directory not writable (permission denied)")
        return p
    parent = p.absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise ValueError(f"{name} {p}: {parent} is a file, not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"{name} {p}: cannot write in {parent} (permission denied)")
    return p

"""Plain-JSON conversion of results: numpy arrays and scalars to lists and floats."""

from __future__ import annotations

import hashlib
import json
import math
import os
from typing import Any

import numpy as np

from simulation.output import write_file


def to_jsonable(obj: Any, strict: bool = True) -> Any:
    """Numpy arrays and scalars to lists and Python numbers, containers recursively;
    ``strict``: non-finite floats to None (strict JSON), else kept."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v, strict) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v, strict) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist(), strict)
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item(), strict)
    if strict and isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def fingerprint(parts: dict) -> str:
    """SHA-256 of the canonical JSON of ``parts`` (sorted keys): identifies the arguments
    a checkpoint was written with."""
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()


def write_json_atomic(path: str | os.PathLike, obj, strict: bool = True) -> None:
    """Write ``obj`` as JSON to ``path`` atomically (missing parent folders created; a
    temporary file, flushed to disk, then renamed over ``path``), so a crash never leaves
    a half-written file. ``strict``: non-finite numbers become null (:func:`to_jsonable`);
    otherwise they are written as Python's ``Infinity``/``NaN`` and read back unchanged
    (checkpoints)."""
    write_file(path, json.dumps(to_jsonable(obj) if strict else obj))

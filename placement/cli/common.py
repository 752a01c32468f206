"""Shared CLI helpers: reading rooms and layout files, writing JSON."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from simulation.room import Room


def add_room_argument(parser) -> None:
    parser.add_argument(
        "--room",
        metavar="R.toml",
        default=None,
        help="room description in TOML (default: the embedded techtile room)",
    )


def load_room(path: str | None) -> Room:
    """The room from a TOML file, or the techtile room when ``path`` is None."""
    return Room.techtile() if path is None else Room.from_toml(path)


def load_layout(path: str, room: Room, min_anchors: int = 4) -> np.ndarray:
    """(M, 3) anchors from a JSON file ``{"anchors": [[x, y, z], ...]}``, validated."""
    try:
        data = json.loads(Path(path).read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"--layout {path}: not valid JSON ({exc})") from None
    if not isinstance(data, dict) or "anchors" not in data:
        raise ValueError(f'--layout {path}: expected an object {{"anchors": [[x, y, z], ...]}}')
    try:
        anchors = np.array(data["anchors"], dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"--layout {path}: anchors must be a list of [x, y, z] numbers") from None
    return room.check_anchors(anchors, min_anchors=min_anchors)


def to_jsonable(obj: Any) -> Any:
    """Numpy arrays and scalars to lists and floats; non-finite floats to None (strict JSON)."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_json(path: str | Path, obj: Any) -> Path:
    """Write ``obj`` as indented strict JSON, creating parent folders."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(to_jsonable(obj), indent=2) + "\n")
    return path

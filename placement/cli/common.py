"""Shared CLI helpers: reading rooms and layout files, writing JSON."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from placement.serialization import to_jsonable
from simulation import checks
from simulation.room import Room

__all__ = [
    "add_room_argument",
    "load_layout",
    "load_room",
    "output_dir",
    "output_file",
    "to_jsonable",
    "write_json",
]


def add_room_argument(parser) -> None:
    """Add ``--room`` (a room TOML file; default: the embedded techtile room)."""
    parser.add_argument(
        "--room",
        metavar="R.toml",
        default=None,
        help="room description in TOML (default: the embedded techtile room)",
    )


def load_room(path: str | None) -> Room:
    """The room from a TOML file, or the techtile room when ``path`` is None."""
    if path is None:
        return Room.techtile()
    checks.input_file("--room", path)
    return Room.from_toml(path)


def load_layout(path: str, room: Room, min_anchors: int = 4) -> np.ndarray:
    """(M, 3) anchors from a JSON file ``{"anchors": [[x, y, z], ...]}``, validated."""
    p = checks.input_file("--layout", path)
    try:
        data = json.loads(p.read_text())
    except UnicodeDecodeError:
        raise ValueError(f"--layout {path}: not a text (JSON) file") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"--layout {path}: not valid JSON ({exc})") from None
    if not isinstance(data, dict) or "anchors" not in data:
        raise ValueError(f'--layout {path}: expected an object {{"anchors": [[x, y, z], ...]}}')
    try:
        anchors = checks.points("anchors", data["anchors"])
        anchors = room.check_anchors(anchors, min_anchors=min_anchors)
        checks.distinct("anchors", anchors)
    except ValueError as exc:
        raise ValueError(f"--layout {path}: {exc}") from None
    return anchors


def output_dir(name: str, path) -> Path:
    """An output folder that can be created or written, checked before any work."""
    return checks.output_path(name, path, kind="dir")


def output_file(name: str, path, suffixes=None) -> Path:
    """An output file that can be written, checked before any work."""
    return checks.output_path(name, path, kind="file", suffixes=suffixes)


def write_json(path: str | Path, obj: Any) -> Path:
    """Write ``obj`` as indented strict JSON, creating parent folders."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(to_jsonable(obj), indent=2) + "\n")
    return path

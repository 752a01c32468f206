"""Shared CLI helpers: reading rooms and layout files, writing JSON."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from analysis.percent import percent
from placement.serialization import to_jsonable
from simulation import checks
from simulation.dxf import UNITS, room_from_dxf
from simulation.output import write_file
from simulation.room import Room
from simulation.statistics import penalty_text

__all__ = [
    "add_room_argument",
    "add_system_arguments",
    "describe_room",
    "describe_system",
    "json_text",
    "load_layout",
    "load_room",
    "load_system",
    "output_dir",
    "output_file",
    "to_jsonable",
    "write_json",
]


def obstacle_heights(text: str) -> float | dict[str, float]:
    """``--obstacle-height``: one height in m ("2.5"), or heights by DXF layer
    ("A-COLS=2.8,A-FURN=0.75")."""
    try:
        if "=" not in text:
            return float(text)
        pairs = [p.split("=", 1) for p in text.split(",") if p.strip()]
        return {k.strip(): float(v) for k, v in pairs}
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a height in m or LAYER=M pairs separated by commas, got {text!r}"
        ) from None


def obstacle_height_text(value) -> str:
    """``--obstacle-height``'s text for a value :func:`obstacle_heights` gave."""
    if isinstance(value, dict):
        return ",".join(f"{k}={v!r}" for k, v in value.items())
    return repr(value)


def add_room_argument(parser) -> None:
    """Add ``--room`` (a room TOML file or a DXF floor plan; default: the embedded
    techtile room) and the options of a DXF floor plan."""
    parser.add_argument(
        "--room",
        metavar="R.toml|R.dxf",
        default=None,
        help="room description in TOML, or a DXF floor plan (with --room-height) (default: "
        "the embedded techtile room)",
    )
    g = parser.add_argument_group("a DXF floor plan (--room R.dxf)")
    g.add_argument("--room-height", type=float, metavar="M", help="the room's height, m")
    g.add_argument(
        "--dxf-unit",
        choices=tuple(UNITS),
        default=None,
        help="the drawing's unit (default: the one its header declares, $INSUNITS, else m)",
    )
    g.add_argument(
        "--dxf-layer", default="room", help="layer of the outline's closed polyline (room)"
    )
    g.add_argument(
        "--dxf-obstacle-layer",
        default="obstacles",
        metavar="LAYERS",
        help="layer(s) of the obstacles' rectangles and circles, separated by commas (obstacles)",
    )
    g.add_argument(
        "--obstacle-height",
        type=obstacle_heights,
        metavar="M",
        help="height of the obstacles the drawing does not label, m; or per layer, "
        "LAYER=M,LAYER=M (A-COLS=2.8,A-FURN=0.75)",
    )


def load_room(path: str | None, args=None) -> Room:
    """The room from a TOML file or a DXF floor plan (the DXF options from ``args``), or
    the techtile room when ``path`` is None."""
    if path is None:
        return Room.techtile()
    checks.input_file("--room", path)
    if str(path).lower().endswith(".dxf"):
        height = getattr(args, "room_height", None)
        if height is None:
            raise ValueError(f"--room-height: a DXF floor plan ({path}) needs the room's height, m")
        try:
            return room_from_dxf(
                path,
                height,
                unit=getattr(args, "dxf_unit", None),
                layer=getattr(args, "dxf_layer", "room"),
                obstacle_layer=getattr(args, "dxf_obstacle_layer", "obstacles"),
                obstacle_height=getattr(args, "obstacle_height", None),
            )
        except ValueError as exc:
            key, _, text = str(exc).partition(":")
            flag = {"height": "--room-height", "layer": "--dxf-layer", "unit": "--dxf-unit",
                    "obstacle_height": "--obstacle-height",
                    "obstacle_layer": "--dxf-obstacle-layer"}.get(key)  # fmt: skip
            raise ValueError(f"{flag}: {text.strip()}" if flag else str(exc)) from None
    return Room.from_toml(path)


#: the signal flags and the fields of the system's chirp or receiver they set (None: the
#: two band edges)
SIGNAL_FLAGS = {
    "--chirp-duration": "duration",
    "--band": None,
    "--fs": "fs",
    "--t-wake": "t_wake",
    "--window": "window",
    "--false-alarm": "false_alarm",
    "--pick": "pick",
}


def add_system_arguments(parser) -> None:
    """Add ``--system NAME|FILE`` and the signal flags that change one field of it."""
    from simulation.system import PRESETS

    g = parser.add_argument_group(
        "the positioning system (default: the room file's [system] table, else the paper's)"
    )
    g.add_argument(
        "--system",
        metavar="NAME|FILE",
        help=f"a preset ({', '.join(PRESETS)}) or a TOML file with a [system] table "
        "(its [system.signal], [system.receiver] and [system.positioning] parts)",
    )
    g.add_argument("--chirp-duration", type=float, metavar="S", help="chirp length, s (0.03)")
    g.add_argument(
        "--band", type=float, nargs=2, metavar=("F0", "F1"), help="chirp band, Hz (25000 45000)"
    )
    g.add_argument("--fs", type=float, metavar="HZ", help="receiver sampling rate, Hz (192000)")
    g.add_argument(
        "--t-wake", type=float, metavar="S", help="when the tag wakes after the chirp starts, s"
    )
    g.add_argument("--window", type=int, metavar="N", help="samples the tag records (192)")
    g.add_argument(
        "--false-alarm",
        type=float,
        metavar="P",
        help="detection threshold's false-alarm bound per window, e.g. 1e-3 (default: none, "
        "the paper's receiver)",
    )
    g.add_argument(
        "--pick",
        choices=("paper", "first-path"),
        help="the receiver's peak pick: the strongest arrival (paper, the default) or the "
        "earliest that stands out (first-path)",
    )


def system_choice(value: str | None, room_file: str | None = None):
    """The system named by ``--system`` (a preset or a TOML file), else the ``[system]``
    table of the room file, else the paper's; an unknown name lists the presets."""
    from simulation.system import PRESETS, System

    if value is None:
        if room_file is not None and str(room_file).lower().endswith(".toml"):
            return System.from_toml(room_file)
        return System()
    if value in PRESETS:
        return System.preset(value)
    if Path(value).exists() or value.lower().endswith(".toml"):
        checks.input_file("--system", value)
        return System.from_toml(value)
    raise ValueError(
        f"--system: {value!r} is neither a preset nor a file; the presets: {list(PRESETS)}"
    )


def load_system(args, room: Room | None = None):
    """The run's system (:func:`system_choice` of ``--system`` and ``--room``) with the
    signal flags given in ``args`` applied; checked against ``room``; an error names the
    flag."""
    system = system_choice(getattr(args, "system", None), getattr(args, "room", None))
    given = {}
    for flag, key in SIGNAL_FLAGS.items():
        value = getattr(args, flag[2:].replace("-", "_"), None)
        if value is None:
            continue
        if key is None:
            given["f0"], given["f1"] = value
        else:
            given[key] = value
    try:
        system = system.with_signal(**given)
        if room is not None:
            system.check_room(room)
    except ValueError as exc:
        key, _, text = str(exc).partition(":")
        if key == "chirp" and "fs" in given and "f0" not in given:
            key = "fs"  # the band lies above the Nyquist limit of the --fs the user typed
        flags = [
            f
            for f, k in SIGNAL_FLAGS.items()
            if k == key or (k is None and key in ("f0", "f1", "chirp"))
        ]
        if not flags and not given:
            raise
        raise ValueError(f"{flags[0] if flags else 'signal'}: {text.strip()}") from None
    return system


def describe_room(room: Room) -> str:
    """The room in a few words: its size, or its floor plan, and its obstacles."""
    L = room.size
    if room.is_shoebox:
        text = f"{L[0]:g} x {L[1]:g} x {L[2]:g} m"
    else:
        text = f"{len(room.corners)}-corner floor plan in {L[0]:g} x {L[1]:g} m, {L[2]:g} m high"
    if room.obstacles:
        n = len(room.obstacles)
        text += f", {n} obstacle{'s' if n > 1 else ''}"
    return text


def describe_system(room: Room, system) -> str:
    """One line: the system's name, the chirp, the window, the detection, the reach and the
    positioning."""
    ch, rx = system.chirp, system.receiver
    detect = (
        "no detection threshold"
        if rx.false_alarm is None
        else f"detection at false alarm <= {rx.false_alarm:g}"
    )
    c = room.speed_of_sound
    near = system.near_limit(c)
    near = f", nothing nearer than {near:.2f} m" if near > 0 else ""
    return (
        f"system {system.name}: chirp {ch.duration * 1e3:g} ms {ch.f0 / 1e3:g}-{ch.f1 / 1e3:g} "
        f"kHz, window {rx.window} samples ({system.window_span * 1e3:.3g} ms) from "
        f"{rx.t_wake * 1e3:g} ms at {rx.fs / 1e3:g} kHz, {rx.pick} pick, {detect}: reach "
        f"{system.reach(c):.2f} m{near}; {system.positioning.describe()}"
    )


def add_effort_argument(p) -> None:
    """``--effort``: the preset of the planner's options (:mod:`placement.effort`)."""
    from placement.effort import EFFORT_NAMES

    p.add_argument(
        "--effort",
        choices=EFFORT_NAMES,
        default="default",
        help="preset of the search, finalists and validation options: quick (a first answer: "
        "seconds in the paper's room, minutes in a room with obstacles), default, thorough "
        "(minutes); the other flags change single values of it (default)",
    )


def number(x, spec: str = ".4g") -> str:
    """``x`` formatted by ``spec``, or "–" in the spec's width and alignment when there is
    none (NaN: a check that did not run, a finalist without a swarm cost)."""
    if x == x:
        return format(x, spec)
    width = "".join(c for c in spec.split(".")[0] if c.isdigit())
    return format("–", ("<" if spec.startswith("<") else ">") + (width or ""))


def cost_text(x) -> str:
    """A planner's cost for the reader: :func:`number`, or what a penalty says instead of
    its value (:func:`simulation.statistics.penalty_text`)."""
    return penalty_text(x) or number(x)


def availability_note(summary: dict) -> str:
    """ ", availability 99.2 % (0.8 % without a fix)" for a summary with an availability."""
    a = summary.get("availability")
    if a is None or a != a:
        return ""
    if a >= 1:
        return ", availability 100 %"
    return f", availability {percent(a, 2)} % ({percent(1 - a, 2)} % without a fix)"


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
        return checked_layout(room, data["anchors"], min_anchors)
    except ValueError as exc:
        raise ValueError(f"--layout {path}: {exc}") from None


def checked_layout(room: Room, anchors, min_anchors: int = 4) -> np.ndarray:
    """(M, 3) ``anchors`` checked as a layout file's: points, at least ``min_anchors``, in
    the room and out of its keep-outs (:meth:`simulation.Room.check_anchors`), distinct."""
    a = room.check_anchors(checks.points("anchors", anchors), min_anchors=min_anchors)
    checks.distinct("anchors", a)
    return a


def output_dir(name: str, path) -> Path:
    """An output folder that can be created or written, checked before any work."""
    return checks.output_path(name, path, kind="dir")


def output_file(name: str, path, suffixes=None) -> Path:
    """An output file that can be written, checked before any work."""
    return checks.output_path(name, path, kind="file", suffixes=suffixes)


def json_text(obj: Any) -> str:
    """``obj`` as indented strict JSON text."""
    return json.dumps(to_jsonable(obj), indent=2) + "\n"


def write_json(path: str | Path, obj: Any) -> Path:
    """Write ``obj`` as indented strict JSON, creating parent folders; never half-written
    (:mod:`simulation.output`)."""
    return write_file(path, json_text(obj))


def load_plan(result_dir):
    """(room, anchors (M, 3)) of a result folder (``result.json``, else
    ``evaluation.json``); ValueError naming RESULT_DIR when it has neither or they are bad."""
    from analysis.report_data import load_results, main_anchors, room_of

    try:
        data = load_results(result_dir)
        return room_of(data), main_anchors(data)
    except (ValueError, FileNotFoundError) as exc:
        msg = str(exc)  # name the folder once
        raise ValueError(
            msg if msg.startswith("RESULT_DIR") else f"RESULT_DIR {result_dir}: {msg}"
        ) from None


def plan_system(result_dir, value: str | None = None):
    """The system of a result folder (its ``system``), or the one ``--system`` names."""
    from analysis.report_data import load_results, system_of

    if value is not None:
        return system_choice(value)
    try:
        return system_of(load_results(result_dir))
    except (ValueError, FileNotFoundError) as exc:
        raise ValueError(f"RESULT_DIR {result_dir}: {exc}") from None

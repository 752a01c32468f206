"""What a plan keeps beside its checkpoint, so that a rerun resumes where it was killed.

``seed_then_pso(..., checkpoint=PATH)`` (``anchorplan plan --checkpoint PATH``) keeps:

- ``PATH.search.json``: the search's starting layouts, once the search has finished
  (:func:`placement.initial.search_initial`);
- ``PATH``: the swarm's state after every iteration (:func:`placement.pso.pso`);
- ``PATH.phases.json``: the refined layouts once the refinement has finished, then the
  finalists and the chosen layout (:class:`PhaseStore`).

A rerun with the same arguments reads what is there and runs the rest: a plan killed in
the search redoes the search; in the swarm, the iteration it was in; in the refinement,
the range table and the refinement; in the finalists, the finalists; in the validation,
the validation. Every phase is reproducible from the run's seed, so the resumed plan ends
with the uninterrupted plan's layout and figures (BENCHMARKS.md, "Resuming a killed plan").
Every file is written atomically (:mod:`simulation.output`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from placement.serialization import fingerprint, to_jsonable, write_json_atomic

#: the phases whose outcome :class:`PhaseStore` keeps, in the plan's order
PHASES = ("refinement", "finalists")


class PhaseStore:
    """The finished phases of one plan, kept in ``<checkpoint>.phases.json``.

    ``parts``: what identifies the plan (its room, settings, seed and nodes); a file
    written by another plan is ignored and replaced.
    """

    def __init__(self, checkpoint: Path, parts: dict[str, Any]):
        self.path = checkpoint.with_name(checkpoint.name + ".phases.json")
        self.fingerprint = fingerprint(to_jsonable(parts))
        self._saved = self._read()

    def _read(self) -> dict[str, Any]:
        try:
            data = json.loads(self.path.read_text())
        except FileNotFoundError:
            return {}
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise ValueError(
                f"checkpoint {self.path}: cannot read it ({exc}); delete it to start afresh"
            ) from None
        if not isinstance(data, dict) or data.get("fingerprint") != self.fingerprint:
            return {}  # another plan's: this plan's phases replace it
        return data.get("phases", {})

    def load(self, phase: str) -> Any | None:
        """What ``phase`` saved (None when it has not finished)."""
        return self._saved.get(phase)

    def save(self, phase: str, value: Any) -> None:
        """Keep ``value`` (plain JSON with arrays; NaN and inf kept) as ``phase``'s outcome."""
        self._saved[phase] = to_jsonable(value, strict=False)
        blob = {"fingerprint": self.fingerprint, "phases": self._saved}
        write_json_atomic(self.path, blob, strict=False)


def refined_to_json(refined: list[tuple[str, np.ndarray]]) -> list[dict[str, Any]]:
    """The refined layouts (name, anchors) as JSON rows."""
    return [{"name": name, "anchors": a} for name, a in refined]


def refined_from_json(rows) -> list[tuple[str, np.ndarray]]:
    """:func:`refined_to_json` read back."""
    return [(r["name"], np.asarray(r["anchors"], dtype=float)) for r in rows]


def finalists_from_json(rows) -> list[dict[str, Any]]:
    """Finalist rows (``source``, ``anchors``, ``pso_cost``, ``cost``) read back."""
    return [
        {"source": r["source"], "anchors": np.asarray(r["anchors"], dtype=float),
         "pso_cost": _float(r["pso_cost"]), "cost": _float(r["cost"])}
        for r in rows
    ]  # fmt: skip


def _float(x) -> float:
    return math.nan if x is None else float(x)

"""A share printed as a percentage: to a fixed number of decimals, with more where that
would read 100 (or 0) for a share that is not all (or none)."""

from __future__ import annotations

from typing import Any


def percent(share: float, digits: int = 1) -> str:
    """``share`` (0–1) in per cent to ``digits`` decimals (no sign), with up to 4 decimals
    more where ``digits`` would read 100 for a share short of all, or 0 for one above none:
    1 point of 2 000 left out reads "99.95", not "100.0"."""
    for d in range(digits, digits + 5):
        text = f"{100 * share:.{d}f}"
        if (share >= 1 or float(text) < 100) and (share <= 0 or float(text) > 0):
            return text
    return text


def percent_cell(share: Any, whole: str | None = None) -> str:
    """A report's cell for ``share`` (0–1): "–" when unknown (None, NaN, not a number),
    ``whole`` (when given) for a share of 1 or more, else :func:`percent` to 2 decimals
    and " %"."""
    if share is None or not isinstance(share, int | float) or share != share:
        return "–"
    if whole is not None and share >= 1:
        return whole
    return f"{percent(share, 2)} %"

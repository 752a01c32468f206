"""Progress of the long phases (a plan's, a report's simulations, the what-if tables):
tqdm bars on stderr, a caller's function, or nothing.

``progress`` is True (tqdm bars), False (silent) or a callable
``progress(phase, done, total)`` called from the working process (``phase`` a str such as
"range table", "search", "swarm", "refinement", "finalists", "validation", "report
simulations"; ``done`` and ``total`` ints): what a page or a log shows instead of bars.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from simulation import checks


def check_progress(value: Any) -> bool | Callable[[str, int, int], Any]:
    """``value`` if it is a bool or a callable; a ValueError naming ``progress`` otherwise."""
    if callable(value):
        return value
    return checks.flag("progress", value)


class ProgressBar:
    """A progress bar fed with (done, total) reports: a tqdm bar when ``progress`` is True
    (stderr; library code never prints otherwise), the caller's ``progress(desc, done,
    total)`` when it is callable, nothing when it is False."""

    def __init__(self, progress, desc: str):
        self.desc, self.bar = desc, None
        self.report = progress if callable(progress) else None
        self.enabled = bool(progress)

    def update(self, done: int, total: int, stage: str | None = None) -> None:
        """Report ``done`` of ``total`` (``stage`` names a sub-step of a tqdm bar)."""
        if self.report is not None:
            self.report(self.desc, int(done), int(total))
            return
        if not self.enabled:
            return
        if self.bar is None:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=total, desc=self.desc, leave=False)
        if stage is not None:
            self.bar.set_description(f"{self.desc} ({stage})")
        self.bar.total = total
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        """Close the bar (a later update opens a new one)."""
        if self.bar is not None:
            self.bar.close()
            self.bar = None


class CountingBar:
    """The swarm's iterations reported to a caller's ``progress("swarm", done, total)``:
    the part of tqdm's interface the swarm uses (``update``, ``set_postfix``, ``close``)."""

    def __init__(self, report, total: int, initial: int):
        self.report, self.total, self.n = report, int(total), int(initial)
        self.report("swarm", self.n, self.total)

    def update(self, n: int = 1) -> None:
        self.n += int(n)
        self.report("swarm", self.n, self.total)

    def set_postfix(self, **_) -> None:
        """Nothing: the caller reads the swarm's best cost from the result."""

    def close(self) -> None:
        """Nothing to close."""

"""Progress bars for the planner's long phases (tqdm), silent when switched off."""

from __future__ import annotations


class ProgressBar:
    """A tqdm progress bar fed with (done, total) reports; silent when ``enabled`` is
    False. Library code never prints: tqdm writes to stderr only while enabled."""

    def __init__(self, enabled: bool, desc: str):
        self.desc, self.bar = desc, None
        self.enabled = enabled

    def update(self, done: int, total: int, stage: str | None = None) -> None:
        """Report ``done`` of ``total`` (``stage`` names a sub-step)."""
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

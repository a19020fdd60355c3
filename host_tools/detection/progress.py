"""Training's progress bar: the share of the work done, the phase, elapsed time and an estimate of what is left.

Training announces its phases and how many steps each has (frames, rounds, epochs) with a rough cost per step
(`plan`), then reports each step (`tick`). The bar is drawn on stderr, in place on a terminal and as a line
every PRINT_EVERY_S seconds otherwise (a log file), and once at the end.
"""
import sys
import time
from collections.abc import Sequence
from typing import TextIO

BAR_WIDTH = 30
PRINT_EVERY_S = 10.0


class Progress:
    """Weighted steps of named phases -> a bar with the current phase, elapsed time and ETA."""

    def __init__(self, stream: TextIO | None = None, clock=time.monotonic):
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.clock = clock
        self.start = clock()
        self.last = -PRINT_EVERY_S
        self.weights: dict[str, float] = {}
        self.total = 0.0
        self.done = 0.0
        self.phase = ""

    def plan(self, phases: Sequence[tuple[str, int, float]]) -> None:
        """phases: (name, steps, cost of one step); replaces any earlier plan, keeps the work done."""
        self.weights = {name: cost for name, _steps, cost in phases}
        self.total = self.done + sum(steps * cost for _name, steps, cost in phases)

    def tick(self, phase: str, steps: int = 1) -> None:
        self.phase = phase
        self.done = min(self.total, self.done + steps * self.weights.get(phase, 0.0))
        now = self.clock()
        if self.tty or now - self.last >= PRINT_EVERY_S:
            self.draw(now)

    def finish(self) -> None:
        self.done = self.total
        self.phase = "done"
        self.draw(self.clock(), end=True)

    def draw(self, now: float, end: bool = False) -> None:
        self.last = now
        share = self.done / self.total if self.total > 0 else 1.0
        elapsed = now - self.start
        eta = elapsed * (1.0 - share) / share if share > 0 else float("nan")
        filled = int(round(BAR_WIDTH * share))
        text = "train [%s%s] %3d %%  %s  elapsed %s  left ~%s" % (
            "#" * filled, "." * (BAR_WIDTH - filled), int(100 * share), self.phase, duration(elapsed), duration(eta))
        if self.tty:
            self.stream.write("\r" + text + ("\n" if end else ""))
        else:
            self.stream.write(text + "\n")
        self.stream.flush()


def duration(seconds: float) -> str:
    if seconds != seconds:
        return "?"
    seconds = int(round(seconds))
    return "%dm%02ds" % (seconds // 60, seconds % 60)

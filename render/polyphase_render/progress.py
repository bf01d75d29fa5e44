"""A frames-done progress bar with elapsed time and ETA on stderr (one line per frame when
stderr is not a terminal, so logs stay readable)."""

import sys
import time


def _clock(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


class Progress:
    """Counts frames done out of `total`."""

    def __init__(self, total: int, stream=None):
        self.total = total
        self.done = 0
        self.start = time.monotonic()
        self.stream = stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()

    def line(self, label: str = "") -> str:
        """The bar's current text."""
        elapsed = time.monotonic() - self.start
        width = 30
        filled = int(width * self.done / self.total) if self.total else width
        eta = elapsed / self.done * (self.total - self.done) if self.done else 0.0
        eta_text = _clock(eta) if self.done else "?"
        return (
            f"[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} frames  "
            f"{_clock(elapsed)} elapsed, ETA {eta_text}  {label}"
        ).rstrip()

    def step(self, label: str = "") -> None:
        """One frame finished (rendered or skipped)."""
        self.done += 1
        if self.tty:
            self.stream.write("\r\033[K" + self.line(label))
            if self.done == self.total:
                self.stream.write("\n")
        else:
            self.stream.write(self.line(label) + "\n")
        self.stream.flush()

    def elapsed(self) -> float:
        """Seconds since the bar started."""
        return time.monotonic() - self.start

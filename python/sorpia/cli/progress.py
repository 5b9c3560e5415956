"""The progress line of a command on stderr."""

from __future__ import annotations

import sys
import threading
import time

# In a pipe or a file: the seconds between two plain lines, and after which a phase still under way gets its line.
PIPE_INTERVAL = 2.0
# A terminal's live line is cut to this many characters (an 80-column terminal keeps it on one line).
LIVE_WIDTH = 79


class Progress:
    """Progress of a command: the phase it is in (`status`), its iterations
    (`note`, and the solve's callback(k, error)).

    On a terminal: one live line on stderr (the phase, then iteration and
    E_k/E_0 redrawn at most 10 times a second), at most LIVE_WIDTH
    characters, erased at the end. In a pipe or a file: plain lines at most
    every PIPE_INTERVAL seconds of iterating (short runs print none), and a
    phase that is still under way after PIPE_INTERVAL seconds gets a line
    of its own ("label: phase ...", from a timer thread), so that a long
    phase without iterations is not silent. Disabled: nothing at all. A
    context manager: the live line is erased and the timer stopped however
    the block ends (before an error message).
    """

    def __init__(self, label: str = "", enabled: bool = True, stream=None):
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.tty = enabled and _isatty(self.stream)
        self.interval = 0.1 if self.tty else PIPE_INTERVAL
        self.width = 0
        self._timer: threading.Timer | None = None
        self._lock = threading.Lock()
        self.restart(label)

    def restart(self, label: str) -> None:
        """A new solve: its label, its clock."""
        self.label = label
        self.start = self.last = time.perf_counter()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _draw(self, text: str) -> None:
        global _live_line
        if len(text) > LIVE_WIDTH:
            text = text[:LIVE_WIDTH - 3] + "..."
        self.stream.write("\r" + text.ljust(self.width))
        self.width = len(text)
        self.stream.flush()
        _live_line = self

    def _line(self, text: str) -> None:
        """A plain line (pipe or file)."""
        with self._lock:
            self.stream.write(text + "\n")
            self.stream.flush()

    def status(self, text: str) -> None:
        """The phase the command is in: drawn on a terminal; in a pipe,
        printed once it has lasted PIPE_INTERVAL seconds; current_phase()
        returns it."""
        global _phase
        _phase = text
        if self.tty:
            self._draw(f"{text} ...")
        elif self.enabled:
            self._cancel_timer()
            line = f"{self.label}: {text} ..." if self.label and not text.startswith(self.label) else f"{text} ..."
            if PIPE_INTERVAL <= 0:
                self._line(line)
            else:
                self._timer = threading.Timer(PIPE_INTERVAL, self._line, (line,))
                self._timer.daemon = True
                self._timer.start()

    def note(self, text: str) -> None:
        """An iteration's line (approximate's records): drawn on a terminal,
        a plain line in a pipe, each at most once per interval."""
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self.last < self.interval:
            return
        self.last = now
        if self.tty:
            self._draw(text)
        else:
            self._line(text)

    def _cancel_timer(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def __call__(self, k: int, error: float) -> bool:
        if self.enabled:
            now = time.perf_counter()
            if now - self.last >= self.interval:
                self.last = now
                text = f"{self.label}: iteration {k}, E_k/E_0 = {error:.3e}, {now - self.start:.1f} s"
                if self.tty:
                    self._draw(text)
                else:
                    self._line(text)
        return False  # never ask the solver to stop

    def close(self) -> None:
        """Erase the live line (it is drawn again by the next update)."""
        global _live_line
        self._cancel_timer()
        if self.tty and self.width:
            self.stream.write("\r" + " " * self.width + "\r")
            self.stream.flush()
            self.width = 0
        if _live_line is self:
            _live_line = None


_live_line: Progress | None = None  # the Progress whose line is on the terminal now
_phase = ""  # the last phase a Progress was told of (status), shown or not


def current_phase() -> str:
    """The phase the command is in, for an error that has no place of its own (out of memory)."""
    return _phase


def reset_phase() -> None:
    global _phase
    _phase = ""


def erase_live_line() -> None:
    """Erase the live line, if one is drawn, so that a message gets a line of its own."""
    if _live_line is not None:
        _live_line.close()


def _isatty(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False

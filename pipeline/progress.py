"""Progress on long work, through one reporter.

The engine, the block writer, ``roughcontact accuracy`` and the kernels of long stages all
report through a :class:`Reporter`:

* one line per stage (``[2/6] contact: computed in 0.04 s (...) -> outputs/default/contact.nc``)
  on its stream (stderr by default; nothing at all with ``stream=None``);
* on a terminal, live progress bars (tqdm) for the work inside a stage: adhesion marches,
  each BEM solve, accuracy rungs, blocks written;
* elsewhere (a log file, a pipe, CI) no bars: one line per stage, and for work that lasts longer
  than a few seconds (:data:`LINE_INTERVAL`) a progress line at most every few seconds, one per
  finished task when tasks are slower (``    writing: 12/108 blocks (11%), 4 min 02 s so far,
  about 32 min left``), preceded by the stage's start line; work that ends sooner prints nothing
  more than its stage line;
* with ``--quiet`` (``bars=False``): one line per stage, nothing else.

A kernel never sees the reporter: a stage passes it a plain callable ``tick(n=1)`` from
:meth:`roughcontact.stage.StageInput.progress`. A tick is picklable and does nothing in another
process (the process and distributed schedulers), so kernels stay pure.
"""

from __future__ import annotations

import sys
import threading
import time
from typing import TextIO

#: off a terminal, seconds between two progress lines of one piece of work (and before the first)
LINE_INTERVAL = 5.0


class Tick:
    """Advance one progress bar by ``n``: a callable a kernel is handed (``progress=tick``)."""

    def __init__(self, bar=None):
        self._bar = bar
        self._lock = threading.Lock()

    def __call__(self, n: int = 1) -> None:
        if self._bar is not None:
            with self._lock:
                self._bar.update(n)

    @property
    def count(self) -> int:
        """How far the bar has advanced (0 without a bar)."""
        return self._bar.n if self._bar is not None else 0

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> "Tick":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __reduce__(self):  # in a worker process: a tick that does nothing
        return (Tick, ())


class LineBar:
    """Progress as plain lines (a log file, a pipe): a line when the work has lasted
    ``interval`` seconds since the last one (or since it began) and has advanced, so that short
    work prints nothing and long work a line per finished task, or every few seconds."""

    def __init__(self, reporter: "Reporter", what: str, total: int | None, unit: str, initial: int = 0,
                 interval: float = LINE_INTERVAL):
        self.reporter, self.what, self.total, self.unit = reporter, what, total, unit
        self.n = self.initial = self.shown = int(initial)
        self.interval = interval
        self.start = self.last = time.monotonic()

    def update(self, n: int = 1) -> None:
        self.n += n
        now = time.monotonic()
        if now - self.last >= self.interval and self.n != self.shown:
            self.last, self.shown = now, self.n
            self.reporter.progress_line(self.line(now - self.start))

    def line(self, elapsed: float) -> str:
        many = (self.total or self.n) != 1  # "3/40 blocks", "1/40 blocks", "1 block"
        units = self.unit.strip() + ("s" if self.unit.strip() and many else "")
        if not self.total:
            return f"    {self.what}: {self.n} {units}, {duration(elapsed)} so far"
        share = 100 * self.n // self.total
        text = f"    {self.what}: {self.n}/{self.total} {units} ({share}%), {duration(elapsed)} so far"
        done = self.n - self.initial  # what this run computed (kept blocks of an earlier run cost nothing)
        if 0 < done and self.n < self.total:
            text += f", about {duration(elapsed / done * (self.total - self.n))} left"
        return text

    def close(self) -> None:
        pass


def duration(seconds: float) -> str:
    """A duration for a person: '42 s', '3 min 05 s', '2 h 07 min'."""
    s = int(round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class Reporter:
    """Where progress goes.

    Parameters
    ----------
    stream
        Text stream for the lines and bars (default stderr); None: silent.
    bars
        Live progress bars: None (default) draws them only when ``stream`` is a terminal, and
        writes progress lines elsewhere (:class:`LineBar`); False never shows progress
        (``--quiet``: one line per stage).
    interval
        Off a terminal, the seconds between progress lines (:data:`LINE_INTERVAL`).
    """

    def __init__(self, stream: TextIO | None = sys.stderr, *, bars: bool | None = None,
                 interval: float = LINE_INTERVAL):
        self.stream = stream
        self.bars = stream is not None and (_is_terminal(stream) if bars is None else bool(bars))
        self.lines = stream is not None and bars is None and not self.bars
        self.interval = interval
        self._open: list[Tick] = []
        self._pending: str | None = None  # off a terminal: the start line, shown with the first progress line

    def __call__(self, message: str) -> None:
        """A line that is always shown (unless silent): one per stage."""
        self._pending = None
        if self.stream is not None:
            print(message, file=self.stream, flush=True)

    def live(self, message: str) -> None:
        """A line shown with live progress (a terminal), e.g. that a stage starts; off a terminal
        it is shown only before the first progress line that follows it (long work)."""
        if self.bars:
            self(message)
        elif self.lines:
            self._pending = message

    def progress_line(self, message: str) -> None:
        """A progress line off a terminal (after the pending start line, if any)."""
        if self._pending is not None:
            self(self._pending)
        self(message)

    def note(self, message: str) -> None:
        """A line about the work of a stage (e.g. that it resumes), shown on a terminal and in a
        log (after the stage's start line), not with ``--quiet``."""
        if self.bars or self.lines:
            self.progress_line(message)

    def bar(self, what: str, total: int | None = None, unit: str = "step", initial: int = 0) -> Tick:
        """A progress bar (tqdm) on a terminal, progress lines in a log (:class:`LineBar`), else
        a tick that does nothing; ``initial``: already done (kept from an earlier run). It is
        closed by :meth:`finish` (or as a context manager)."""
        if self.lines:
            tick = Tick(LineBar(self, what, total, unit, initial, self.interval))
            self._open.append(tick)
            return tick
        if not self.bars:
            return Tick()
        from tqdm import tqdm

        tick = Tick(tqdm(total=total, desc=f"    {what}", unit=f" {unit}", file=self.stream, leave=False,
                         dynamic_ncols=True, mininterval=0.2, initial=initial))
        self._open.append(tick)
        return tick

    def finish(self) -> None:
        """Close every bar still open (the work of a stage is done)."""
        while self._open:
            self._open.pop().close()
        self._pending = None


#: a reporter that shows nothing
SILENT = Reporter(None)

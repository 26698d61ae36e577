"""Progress on long work, through one reporter.

The engine, the block writer, ``roughcontact accuracy`` and the kernels of long stages all
report through a :class:`Reporter`:

* one line per stage (``[2/6] contact: computed in 0.04 s (...) -> outputs/default/contact.nc``)
  on its stream (stderr by default; nothing at all with ``stream=None``);
* on a terminal only, live progress bars (tqdm) for the work inside a stage: adhesion marches,
  each BEM solve, accuracy rungs, blocks written. Elsewhere (a log file, a pipe, CI, ``--quiet``)
  there are no bars and no start lines: one line per stage.

A kernel never sees the reporter: a stage passes it a plain callable ``tick(n=1)`` from
:meth:`roughcontact.stage.StageInput.progress`. A tick is picklable and does nothing in another
process (the process and distributed schedulers), so kernels stay pure.
"""

from __future__ import annotations

import sys
import threading
from typing import TextIO


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
        Live progress bars: None (default) draws them only when ``stream`` is a terminal;
        False never (``--quiet``: one line per stage).
    """

    def __init__(self, stream: TextIO | None = sys.stderr, *, bars: bool | None = None):
        self.stream = stream
        self.bars = stream is not None and (_is_terminal(stream) if bars is None else bool(bars))
        self._open: list[Tick] = []

    def __call__(self, message: str) -> None:
        """A line that is always shown (unless silent): one per stage."""
        if self.stream is not None:
            print(message, file=self.stream, flush=True)

    def live(self, message: str) -> None:
        """A line shown only with live progress (a terminal), e.g. that a stage starts."""
        if self.bars:
            self(message)

    def bar(self, what: str, total: int | None = None, unit: str = "step") -> Tick:
        """A progress bar (tqdm) on a terminal, else a tick that does nothing. It is closed by
        :meth:`finish` (or as a context manager)."""
        if not self.bars:
            return Tick()
        from tqdm import tqdm

        tick = Tick(tqdm(total=total, desc=f"    {what}", unit=f" {unit}", file=self.stream, leave=False,
                         dynamic_ncols=True, mininterval=0.2))
        self._open.append(tick)
        return tick

    def finish(self) -> None:
        """Close every bar still open (the work of a stage is done)."""
        while self._open:
            self._open.pop().close()


#: a reporter that shows nothing
SILENT = Reporter(None)

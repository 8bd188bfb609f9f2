"""Progress of the long calls (``fatigue``, ``mpc``, ``optimize``, ``sweep``): ``progress=True``
draws a bar (tqdm when it is installed, else plain lines on standard error), a callable is
called as ``progress(done, total)``.

The Rust library never prints: it counts what it has done (runs of a fatigue study, decisions of
a closed loop, iterations of an optimiser) and the bindings hand the count to the callback on the
calling thread about every 50 ms while the computation runs with the GIL released. What a unit is
depends on the call: ``fatigue`` counts (cell, controller) runs, ``mpc`` control decisions of
every closed loop it runs, ``optimize`` iterations out of ``max_iters`` (a single start; with
``starts`` > 1, starts), ``sweep`` cases, ``design`` iterations out of ``[design]
max_iterations`` (its bar also shows each iterate's damage, life, gradient norm and design).
"""

from __future__ import annotations

import importlib
import sys
import time
from collections.abc import Callable
from typing import Any, Optional, Union

ProgressCallback = Callable[[int, int], Any]
ProgressArg = Union[bool, ProgressCallback, None]


class _Plain:
    """The fallback bar: a line ``desc: done/total unit (pct %)`` on standard error at most once
    a second, and one at the end."""

    def __init__(self, desc: str, unit: str) -> None:
        self.desc, self.unit = desc, unit
        self.last = 0.0
        self.shown: tuple[int, int] | None = None
        self.state: tuple[int, int] = (0, 0)

    def __call__(self, done: int, total: int) -> None:
        self.state = (done, total)
        now = time.monotonic()
        if now - self.last >= 1.0:
            self.last = now
            self._line()

    def _line(self) -> None:
        done, total = self.state
        pct = f" ({100.0 * done / total:.0f} %)" if total else ""
        print(f"{self.desc}: {done}/{total} {self.unit}{pct}", file=sys.stderr, flush=True)
        self.shown = self.state

    def note(self, text: str) -> None:
        print(f"{self.desc}: {text}", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.shown != self.state:
            self._line()


class _Tqdm:
    """A tqdm bar (``tqdm.auto``: a widget in a notebook) fed with (done, total)."""

    def __init__(self, tqdm: Any, desc: str, unit: str) -> None:
        self.bar = tqdm(total=None, desc=desc, unit=unit, leave=True)

    def __call__(self, done: int, total: int) -> None:
        if total and self.bar.total != total:
            self.bar.total = total
        self.bar.n = done
        self.bar.refresh()

    def note(self, text: str) -> None:
        self.bar.set_postfix_str(text, refresh=True)

    def close(self) -> None:
        self.bar.close()


def _tqdm() -> Any:
    """tqdm's bar class (``tqdm.auto``), or None without tqdm."""
    try:
        module = importlib.import_module("tqdm.auto")
    except ImportError:
        return None
    return module.tqdm


class Reporter:
    """What a call does with its ``progress`` argument: ``callback`` (None: nothing) to hand to
    the extension module, and ``close()`` when the call ends."""

    def __init__(self, progress: ProgressArg, desc: str, unit: str) -> None:
        self._bar: Optional[Union[_Plain, _Tqdm]] = None
        self.callback: Optional[ProgressCallback] = None
        if progress is None or progress is False:
            return
        if progress is True:
            tqdm = _tqdm()
            self._bar = _Tqdm(tqdm, desc, unit) if tqdm is not None else _Plain(desc, unit)
            self.callback = self._bar
        elif callable(progress):
            self.callback = progress
        else:
            from ._errors import InvalidArgumentError

            raise InvalidArgumentError(
                f"progress: expected True, False, None or a callable progress(done, total), "
                f"got {type(progress).__name__}",
                "InvalidArgument",
                "progress",
            )

    def note(self, text: str) -> None:
        """Shows ``text`` (a design iterate's numbers) on the bar: tqdm's postfix, or a line on
        standard error; nothing for a callable."""
        if self._bar is not None:
            self._bar.note(text)

    def __enter__(self) -> "Reporter":
        return self

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.close()


__all__ = ["Reporter", "ProgressArg", "ProgressCallback"]

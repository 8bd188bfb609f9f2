"""Parameter studies on any ``concurrent.futures.Executor``-like engine.

``sweep(fn, cases, executor=None)`` applies ``fn(case) -> dict`` to every case and returns a pandas
DataFrame, one row per case in the order given: the case's inputs (a dict case's keys; any other
case as the column ``case``), the fields ``fn`` returned, and ``error``: ``None``, or for a case that
raised, ``"ExceptionType: message"`` (the other fields of that row are missing). A failing case
never loses the batch.

``executor`` is anything with ``submit(fn, *args)`` returning a future with ``result()``:
``concurrent.futures.ProcessPoolExecutor`` / ``ThreadPoolExecutor``, a ``dask.distributed.Client``
or its ``get_executor()``, Ray's ``ray.util.multiprocessing``-style pools wrapped as executors.
``fn`` and the cases must be picklable for process and cluster executors (define ``fn`` at module
level; scenes and results pickle). Every case is computed by the same deterministic code whatever
runs it, so the DataFrame does not depend on the executor or the number of workers, bit for bit.

On a SLURM cluster, the same script runs through dask-jobqueue::

    from dask_jobqueue import SLURMCluster
    from dask.distributed import Client
    cluster = SLURMCluster(cores=1, processes=1, memory="2GB", walltime="02:00:00")
    cluster.scale(jobs=50)            # 50 SLURM jobs, one worker each
    with Client(cluster) as client:
        df = chainbeam.sweep(fn, cases, executor=client)
    chainbeam.to_parquet(df, "study.parquet")

(one core per worker: chainbeam's multistart and MPC use threads of their own inside a call).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, Protocol

import pandas as pd

from ._progress import ProgressArg, Reporter


class _Future(Protocol):
    def result(self, timeout: float | None = None) -> Any: ...


class ExecutorLike(Protocol):
    """What ``sweep`` needs of an executor: ``submit(fn, *args) -> future``."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any: ...


def _error_text(e: BaseException) -> str:
    return f"{type(e).__name__}: {e}"


def _run_case(fn: Callable[[Any], Mapping[str, Any]], case: Any) -> tuple[bool, Any]:
    """(True, fields) or (False, "Type: message") for one case; runs on the worker."""
    try:
        out = fn(case)
        if not isinstance(out, Mapping):
            raise TypeError(
                f"sweep: fn must return a dict of fields, returned a {type(out).__name__}"
            )
        return True, dict(out)
    except Exception as e:  # a failing case is a row with its error
        return False, _error_text(e)


def _cancel_all(futures: Sequence[Any]) -> None:
    """Cancels the futures not yet started (a running task cannot be stopped from here; a Ctrl-C
    reaches the worker processes of a terminal's process group by itself)."""
    for f in futures:
        cancel = getattr(f, "cancel", None)
        if cancel is not None:
            try:
                cancel()
            except Exception:  # an executor whose cancel fails: nothing more to do
                pass


def _gather(
    futures: Sequence[Any],
    progress: Callable[[int, int], Any] | None = None,
    errors_as_rows: bool = False,
) -> list[Any]:
    """The futures' results in order, ``progress(done, total)`` after each; on an exception
    (a Ctrl-C's ``KeyboardInterrupt`` included) the futures not yet started are cancelled and it
    is raised. ``errors_as_rows``: a future that raises (the worker died) gives
    ``(False, "Type: message")`` instead."""
    out: list[Any] = []
    total = len(futures)
    try:
        if progress is not None:
            progress(0, total)
        for f in futures:
            try:
                out.append(f.result())
            except Exception as e:
                if not errors_as_rows:
                    raise
                out.append((False, _error_text(e)))
            if progress is not None:
                progress(len(out), total)
    except BaseException as e:
        _cancel_all(futures)
        if isinstance(e, KeyboardInterrupt):
            # Tasks running on this process's threads (a ThreadPoolExecutor) get no signal.
            from . import _chainbeam

            _chainbeam._cancel_running()
        raise
    return out


def sweep(
    fn: Callable[[Any], Mapping[str, Any]],
    cases: Iterable[Any],
    executor: ExecutorLike | None = None,
    *,
    progress: ProgressArg = False,
) -> pd.DataFrame:
    """Applies ``fn`` to every case (serially, or on ``executor``) and returns one row per case,
    in order: the case's inputs, ``fn``'s fields and ``error`` (module docs). ``progress``:
    ``True`` for a bar (tqdm, else lines on standard error) or a callable
    ``progress(done, total)`` over the cases. A Ctrl-C while waiting cancels the cases not yet
    started on the executor."""
    cases = list(cases)
    with Reporter(progress, "sweep", "case") as r:
        if executor is None:
            outcomes = []
            if r.callback is not None:
                r.callback(0, len(cases))
            for c in cases:
                outcomes.append(_run_case(fn, c))
                if r.callback is not None:
                    r.callback(len(outcomes), len(cases))
        else:
            futures = [executor.submit(_run_case, fn, c) for c in cases]
            # A worker that died (e.g. BrokenProcessPool) is that case's error.
            outcomes = _gather(futures, r.callback, errors_as_rows=True)
    rows = []
    for case, (ok, value) in zip(cases, outcomes):
        row: dict[str, Any] = dict(case) if isinstance(case, Mapping) else {"case": case}
        if ok:
            clash = sorted(set(row) & set(value))
            if clash:
                ok, value = False, f"ValueError: sweep: fn returned the case's own keys {clash}"
            else:
                row.update(value)
        row["error"] = None if ok else value
        rows.append(row)
    columns: list[str] = []
    for row in rows:
        columns.extend(k for k in row if k not in columns and k != "error")
    return pd.DataFrame(rows, columns=[*columns, "error"])


def to_parquet(df: pd.DataFrame, path: str) -> None:
    """Writes a sweep's DataFrame to Parquet (needs pyarrow; array fields become list columns)."""
    df.to_parquet(path, index=False)


__all__ = ["sweep", "to_parquet", "ExecutorLike"]

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

from collections.abc import Callable, Iterable, Mapping
from typing import Any, Protocol

import pandas as pd


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


def sweep(
    fn: Callable[[Any], Mapping[str, Any]],
    cases: Iterable[Any],
    executor: ExecutorLike | None = None,
) -> pd.DataFrame:
    """Applies ``fn`` to every case (serially, or on ``executor``) and returns one row per case,
    in order: the case's inputs, ``fn``'s fields and ``error`` (module docs)."""
    cases = list(cases)
    if executor is None:
        outcomes = [_run_case(fn, c) for c in cases]
    else:
        futures = [executor.submit(_run_case, fn, c) for c in cases]
        outcomes = []
        for f in futures:
            try:
                outcomes.append(f.result())
            except Exception as e:  # the worker itself died (e.g. BrokenProcessPool)
                outcomes.append((False, _error_text(e)))
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

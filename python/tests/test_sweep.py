"""sweep: one row per case in order, failing cases as rows with their error, and the same
DataFrame bit for bit serially, on a ProcessPoolExecutor and on a dask.distributed LocalCluster
of worker processes (reference: the serial sweep, itself the library's deterministic code)."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

import chainbeam as cb

RISER = Path(__file__).resolve().parents[2] / "examples" / "scenes" / "riser_5.toml"


def study(case: dict[str, Any]) -> dict[str, Any]:
    """One case: the riser with another drag and load; M₀ at the end, its peak, and the gradient."""
    scene = cb.Scene.from_file(RISER).replace(
        {"loads.drag": case["drag"], "loads.point[0].force": case["force"], "time.steps": 200}
    )
    traj = cb.simulate(scene)
    c, g = cb.gradient(scene)
    return {
        "m0_final": traj.moment[-1],
        "m0_peak": float(np.abs(traj.moment).max()),
        "objective": c,
        "grad": g,
    }


CASES = [{"drag": d, "force": f} for d in (0.0, 5.0, 12.0) for f in (1.0, 2.0, 4.0)] + [
    {"drag": -1.0, "force": 2.0}  # invalid: a SceneError row
]


def assert_same(a: pd.DataFrame, b: pd.DataFrame) -> None:
    assert list(a.columns) == list(b.columns) and len(a) == len(b)
    for col in a.columns:
        for x, y in zip(a[col], b[col]):
            if isinstance(x, np.ndarray):
                assert np.array_equal(x.view(np.int64), y.view(np.int64)), col
            elif isinstance(x, float) and np.isnan(x):
                assert isinstance(y, float) and np.isnan(y), col
            else:
                assert x == y and type(x) is type(y), (col, x, y)


@pytest.fixture(scope="module")
def serial() -> pd.DataFrame:
    return cb.sweep(study, CASES)


def test_rows_in_order_with_errors(serial: pd.DataFrame) -> None:
    assert list(serial.columns) == ["drag", "force", "m0_final", "m0_peak", "objective", "grad", "error"]
    assert serial["drag"].tolist() == [c["drag"] for c in CASES]
    assert serial["error"].iloc[:-1].isna().all()
    last = serial.iloc[-1]
    assert last["error"].startswith("SceneError: ") and "loads.drag" in last["error"]
    assert np.isnan(last["m0_final"])
    # Each row is the case's own computation (reference: the call made directly).
    direct = study(CASES[4])
    assert serial["m0_final"].iloc[4] == direct["m0_final"]


def test_process_pool_equals_serial(serial: pd.DataFrame) -> None:
    with ProcessPoolExecutor(max_workers=2) as ex:
        assert_same(cb.sweep(study, CASES, executor=ex), serial)


def test_dask_local_cluster_equals_serial(serial: pd.DataFrame) -> None:
    from dask import distributed
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        assert_same(cb.sweep(study, CASES, executor=client), serial)
        assert_same(cb.sweep(study, CASES, executor=client.get_executor()), serial)

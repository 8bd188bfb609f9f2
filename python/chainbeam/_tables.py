"""Short reprs and notebook HTML of the results (``_repr_html_``), and the units of their
columns: what ``to_pandas()`` / ``to_xarray()`` put in ``attrs["units"]``."""

from __future__ import annotations

import html
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

#: The unit of every column the results export (SI; the thesis's M₀ = 2k₁z₁/l₁² has the unit
#: N: k₁ in N·m/rad over l₁² in m², times z₁ in m; docs/conventions.md "The wellhead moment").
UNITS: dict[str, str] = {
    "t": "s",
    "energy": "J",
    "moment": "N (M0 = 2 k1 z1 / l1^2, thesis eq. 3.1.3)",
    "moment_x": "N (M0 x component)",
    "wellhead_moment": "N m (M_w = M0 l1 / 2)",
    "wellhead_moment_x": "N m (M_w x component)",
    "control": "N",
    "control_x": "N",
    "eta": "m",
    "tip": "m",
    "positions": "m",
    "hs": "m",
    "tp": "s",
    "direction": "deg",
    "probability": "1",
    "damage": "1 (Miner sum over the record)",
    "damage_per_year": "1/year",
    "duration_s": "s",
    "life_years": "year",
    "force": "N",
    "stress_range_MPa": "MPa",
    "mean_MPa": "MPa",
    "count": "cycles (0.5: a half cycle)",
}


def fmt(x: Any) -> str:
    """A number in 4 significant digits (other values as ``str``)."""
    if isinstance(x, (float, np.floating)):
        return f"{float(x):.4g}"
    return str(x)


def span(a: np.ndarray) -> str:
    """``min…max`` of an array (or ``empty``)."""
    if a.size == 0:
        return "empty"
    return f"{fmt(np.min(a))}…{fmt(np.max(a))}"


def html_table(title: str, rows: Iterable[tuple[str, Any]]) -> str:
    """A two-column HTML table (name, value) under a bold title."""
    body = "".join(
        f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
        f"<td style='text-align:left'>{html.escape(fmt(v))}</td></tr>"
        for k, v in rows
    )
    return f"<b>{html.escape(title)}</b><table>{body}</table>"


def units_of(columns: Iterable[str]) -> dict[str, str]:
    """The units of the columns that have one."""
    return {c: UNITS[c] for c in columns if c in UNITS}


def short_mapping(m: Mapping[str, Any], limit: int = 6) -> str:
    """``{k: v, ...}`` with at most ``limit`` entries and numbers in 4 digits."""
    items = [f"{k}={fmt(v)}" for k, v in list(m.items())[:limit]]
    more = ", …" if len(m) > limit else ""
    return ", ".join(items) + more

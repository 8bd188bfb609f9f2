"""The result of :func:`chainbeam.fatigue`: the command line's JSON as a dict (it compares equal
to ``json.load`` of ``chainbeam fatigue``'s output), with tables for pandas and a notebook.

``pd.DataFrame(result)`` cannot make a table of a nested dict; use the methods:

- :meth:`FatigueResult.to_pandas`: with controllers, the cells × controllers table of
  ``damage_per_year`` (or another per-cell field); with a scatter alone, one row per cell; a
  plain run, one row;
- :meth:`FatigueResult.cells_frame`: every (controller, cell) run in long form;
- :meth:`FatigueResult.summary_frame`: one row per controller (damage per year, life, life
  extension);
- :meth:`FatigueResult.cycles_frame`: a plain run's rainflow cycles with named columns
  ``stress_range_MPa``, ``mean_MPa``, ``count``.
"""

from __future__ import annotations

from typing import Any

import pandas as pd

from . import _tables

#: The columns of a rainflow cycle ``[range, mean, count]`` in ``result["cycles"]``.
CYCLE_COLUMNS = ["stress_range_MPa", "mean_MPa", "count"]


class FatigueResult(dict[str, Any]):
    """``chainbeam fatigue``'s JSON as a dict (module docs), with tables."""

    @property
    def kind(self) -> str:
        """``"controllers"``, ``"scatter"`` or ``"plain"``: which JSON this is."""
        if "controllers" in self:
            return "controllers"
        return "scatter" if "cells" in self else "plain"

    def cycles_frame(self) -> pd.DataFrame:
        """A plain run's rainflow cycles: columns ``stress_range_MPa``, ``mean_MPa``, ``count``
        (0.5 for a half cycle), one row per cycle; units in ``attrs["units"]``."""
        if "cycles" not in self:
            raise KeyError(
                "cycles: only a plain fatigue run (no scatter, no controllers) lists its cycles"
            )
        df = pd.DataFrame(self["cycles"], columns=CYCLE_COLUMNS)
        df.attrs["units"] = _tables.units_of(CYCLE_COLUMNS)
        return df

    def cells_frame(self) -> pd.DataFrame:
        """Every run in long form: one row per (controller, cell) with ``controller``,
        ``cell`` (its index in the diagram), ``hs``, ``tp`` (``direction``), ``probability``,
        ``damage``, ``damage_per_year``, ``duration_s`` (``force``, ``gains`` where the
        controller has them). A scatter run without controllers has the controller
        ``"scene"`` (the scene's own control)."""
        if self.kind == "plain":
            raise KeyError("cells: a plain fatigue run has no cells (give scatter= or controllers=)")
        runs = self["controllers"] if self.kind == "controllers" else {"scene": self}
        rows = [
            {"controller": name, "cell": i, **cell}
            for name, c in runs.items()
            for i, cell in enumerate(c["cells"])
        ]
        df = pd.DataFrame(rows)
        df.attrs["units"] = _tables.units_of(df.columns)
        return df

    def to_pandas(self, value: str = "damage_per_year") -> pd.DataFrame:
        """The result as a table. With controllers: rows the cells (index ``hs``, ``tp``
        [, ``direction``]), columns the controllers, entries the cells' ``value``
        (``damage_per_year``: the cell's probability-weighted contribution [1/year];
        ``damage``, ``duration_s``, ``force``). With a scatter alone: one row per cell, every
        field. A plain run: one row (``damage``, ``duration_s``, ``damage_per_year``,
        ``life_years``)."""
        if self.kind == "plain":
            keys = ["damage", "duration_s", "damage_per_year", "life_years"]
            df = pd.DataFrame([{k: self[k] for k in keys}])
        elif self.kind == "scatter":
            df = pd.DataFrame(self["cells"])
        else:
            runs = self["controllers"]
            cells = next(iter(runs.values()))["cells"]
            fields = sorted({k for c in runs.values() for cell in c["cells"] for k in cell})
            if value not in fields:
                raise KeyError(f"value: the cells have no {value!r} (they have {', '.join(fields)})")
            names = [c for c in ("hs", "tp", "direction") if c in fields]
            index = pd.MultiIndex.from_tuples(
                [tuple(cell.get(c) for c in names) for cell in cells], names=names
            )
            df = pd.DataFrame(
                {name: [cell.get(value) for cell in c["cells"]] for name, c in runs.items()},
                index=index,
            )
            df.columns.name = "controller"
            df.attrs["value"] = value
        df.attrs["units"] = _tables.units_of([*df.columns, value])
        return df

    def summary_frame(self) -> pd.DataFrame:
        """One row per controller (index ``controller``): ``damage_per_year``, ``life_years``
        and ``life_extension`` (a plain or scatter run: one row, ``scene``)."""
        if self.kind != "controllers":
            row = {k: self[k] for k in ("damage_per_year", "life_years")}
            return pd.DataFrame([row], index=pd.Index(["scene"], name="controller"))
        rows = {
            name: {
                "damage_per_year": c["damage_per_year"],
                "life_years": c["life_years"],
                "life_extension": self["life_extension"][name],
            }
            for name, c in self["controllers"].items()
        }
        df = pd.DataFrame.from_dict(rows, orient="index")
        df.index.name = "controller"
        return df

    def __repr__(self) -> str:
        if self.kind == "controllers":
            body = ", ".join(
                f"{name}: {_tables.fmt(c['damage_per_year'])}/yr" for name, c in self["controllers"].items()
            )
            cells = len(next(iter(self["controllers"].values()))["cells"])
            return f"chainbeam.FatigueResult({cells} cell(s); {body})"
        if self.kind == "scatter":
            return (
                f"chainbeam.FatigueResult({len(self['cells'])} cells, damage_per_year="
                f"{_tables.fmt(self['damage_per_year'])}, life_years={_tables.fmt(self['life_years'])})"
            )
        return (
            f"chainbeam.FatigueResult({len(self['cycles'])} cycles over "
            f"{_tables.fmt(self['duration_s'])} s, damage_per_year="
            f"{_tables.fmt(self['damage_per_year'])}, life_years={_tables.fmt(self['life_years'])})"
        )

    def _repr_html_(self) -> str:
        title = "<b>chainbeam.FatigueResult</b>"
        table = self.summary_frame()
        return title + str(table.to_html(float_format="{:.4g}".format))

    def __reduce__(self) -> tuple[Any, ...]:
        return (FatigueResult, (dict(self),))


__all__ = ["FatigueResult", "CYCLE_COLUMNS"]

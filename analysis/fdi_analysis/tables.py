"""Labelled tables for notebooks: the HTML that Jupyter shows for a result (``_repr_html_``), pandas DataFrames
with names as row and column labels (pandas is optional: the ``notebook`` extra), and short name lists for reprs.

Names are any identifiers (`fdi_analysis.names`): every label is escaped, none is assumed to look like ``f<number>``.
A label with a space (``NO_FAULT``) can therefore never clash with a fault's name.
"""

from __future__ import annotations

import html
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

NO_FAULT = "(no fault)"  # the fault matrix's row and column of the fault-free case
MARK = "●"  # a true cell of a Boolean matrix in HTML


def require_pandas() -> Any:
    """The pandas module, or an ImportError that says how to install it (it is an optional dependency)."""
    try:
        import pandas
    except ImportError as exc:
        raise ImportError("this table needs pandas, an optional dependency: pip install 'romo-fdi[notebook]' "
                          "(or pip install pandas)") from exc
    return pandas


def name_list(names: Iterable[str], limit: int = 6, empty: str = "none") -> str:
    """``a, b, c, ... (+12 more)``: at most `limit` names, for a repr of bounded length."""
    listed = list(names)
    if not listed:
        return empty
    text = ", ".join(listed[:limit])
    return text + (f", ... (+{len(listed) - limit} more)" if len(listed) > limit else "")


def _cell(value: object) -> str:
    if isinstance(value, bool | np.bool_):
        return MARK if value else ""
    if isinstance(value, float | np.floating):
        return f"{float(value):.4g}"
    return html.escape(str(value))


def html_table(rows: Sequence[Sequence[object]], columns: Sequence[str], index: Sequence[str] | None = None,
               caption: str = "", index_name: str = "") -> str:
    """An HTML table: `columns` as header, one row per entry of `rows` (labelled by `index` when given); Boolean
    cells as a dot or empty, floats to 4 significant digits, everything else as escaped text."""
    out = ['<table class="fdi-table" style="border-collapse: collapse">']
    if caption:
        out.append(f'<caption style="caption-side: top; text-align: left">{html.escape(caption)}</caption>')
    head = ([f"<th>{html.escape(index_name)}</th>"] if index is not None else []) + [
        f"<th>{html.escape(c)}</th>" for c in columns]
    out.append("<thead><tr>" + "".join(head) + "</tr></thead><tbody>")
    for k, row in enumerate(rows):
        label = f'<th style="text-align: left">{html.escape(index[k])}</th>' if index is not None else ""
        out.append("<tr>" + label + "".join(f"<td>{_cell(v)}</td>" for v in row) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def matrix_html(matrix: npt.ArrayLike, rows: Sequence[str], columns: Sequence[str], caption: str = "",
                corner: str = "", diagonal: str | None = None) -> str:
    """A Boolean matrix as an HTML table with labelled rows and columns (a dot where true); `diagonal`, when given,
    is written on the diagonal of a square matrix instead of its values."""
    m = np.asarray(matrix, dtype=bool)
    cells: list[list[object]] = [[bool(v) for v in row] for row in m]
    if diagonal is not None:
        for i in range(min(m.shape[0], m.shape[1] if m.ndim == 2 else 0)):
            cells[i][i] = diagonal
    return html_table(cells, columns, rows, caption, corner)


def matrix_frame(matrix: npt.ArrayLike, rows: Sequence[str], columns: Sequence[str], rows_name: str,
                 columns_name: str) -> Any:
    """A matrix as a pandas DataFrame with names as row and column labels (and the axes named)."""
    pd = require_pandas()
    return pd.DataFrame(np.asarray(matrix), index=pd.Index(list(rows), name=rows_name),
                        columns=pd.Index(list(columns), name=columns_name))

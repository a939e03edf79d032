"""Tables of bodies and states: CSV, Parquet, pandas DataFrames and xarray Datasets.

A debris catalogue is a table with one row per body; :func:`ensemble_columns` reads the
columns that :meth:`attitude.Ensemble.from_table` documents (principal moments or a
tensor, the attitude, the rates, a name), with units in the column headers
(``wx [deg/s]``) converted to SI.
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path

import numpy as np
import xarray as xr

from ..foundations.errors import InvalidInertiaError, InvalidStateError
from ..foundations.quantities import to_si
from ..foundations.spec import Key, Table
from .body import diagonal_inertia

__all__ = ["ensemble_columns", "read_table", "COLUMNS"]

_MOMENT = "kg m2"
#: The columns of a table of bodies and the SI unit of each.  A header may give another
#: unit of the same dimension in brackets (``wx [deg/s]``); other columns are ignored.
COLUMNS = Table("columns", (
    *(Key(k, "quantity", unit=_MOMENT, shape=None, doc=f"principal moment {k}")
      for k in "ABC"),
    *(Key(k, "quantity", unit=_MOMENT, shape=None,
          doc="inertia tensor, body frame" + ("" if k[1] == k[2] else "; default 0"))
      for k in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")),
    *(Key(k, "quantity", unit="", shape=None,
          doc="attitude quaternion, body -> inertial, scalar last; default identity")
      for k in ("qx", "qy", "qz", "qw")),
    *(Key(k, "quantity", unit="rad/s", shape=None, required=True,
          doc="body-frame angular velocity") for k in ("wx", "wy", "wz")),
    Key("name", "string", doc="label of the body"),
), open=True, title="Columns of an `[ensemble] table`",
    doc="One row per body: A, B, C or Ixx, Iyy, Izz (with Ixy, Ixz, Iyz); rows that are "
        "not physical (or hold NaN) are reported by index and propagated as NaN.")


def ensemble_columns(table):
    """Inertia tensors (N, 3, 3), quaternions (N, 4) body -> inertial, body rates (N, 3)
    in rad/s and names (or None) from a table (see :meth:`attitude.Ensemble.from_table`).

    Examples
    --------
    >>> import io
    >>> inertia, q, w, names = ensemble_columns(io.StringIO("A,B,C,wx,wy,wz\\n1,2,3,0,0,1\\n"))
    >>> inertia[0].diagonal(), q[0], w[0], names
    (array([1., 2., 3.]), array([0., 0., 0., 1.]), array([0., 0., 1.]), None)
    """
    columns = read_table(table)
    get = _column_getter(columns)
    if all(k in columns for k in ("A", "B", "C")):
        inertia = diagonal_inertia(np.column_stack([get(k) for k in ("A", "B", "C")]))
        n = inertia.shape[0]
    elif all(k in columns for k in ("Ixx", "Iyy", "Izz")):
        xx, yy, zz = (get(k) for k in ("Ixx", "Iyy", "Izz"))
        n = xx.size
        xy, xz, yz = (get(k) if k in columns else np.zeros(n)
                      for k in ("Ixy", "Ixz", "Iyz"))
        inertia = np.stack([np.column_stack(r) for r in
                            ((xx, xy, xz), (xy, yy, yz), (xz, yz, zz))], axis=1)
    else:
        raise InvalidInertiaError(
            f"table: no body columns; give A, B, C (principal moments) or Ixx, Iyy, "
            f"Izz[, Ixy, Ixz, Iyz] (found {', '.join(columns) or 'no columns'})")
    missing = [k for k in ("wx", "wy", "wz") if k not in columns]
    if missing:
        raise InvalidStateError(f"table: missing rate column(s) {', '.join(missing)} "
                                "(body-frame angular velocity, rad/s)")
    omega = np.column_stack([get(k) for k in ("wx", "wy", "wz")])
    if all(k in columns for k in ("qx", "qy", "qz", "qw")):
        q = np.column_stack([get(k) for k in ("qx", "qy", "qz", "qw")])
    else:
        q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    names = [str(x) for x in columns["name"][1]] if "name" in columns else None
    return inertia, q, omega, names


def read_table(table) -> dict[str, tuple[str, np.ndarray]]:
    """``{column: (unit, values)}`` from a path, DataFrame or Dataset.

    Examples
    --------
    >>> import io
    >>> read_table(io.StringIO("wz [deg/s]\\n1.5\\n"))["wz"]
    ('deg/s', array([1.5]))
    """
    import pandas as pd  # costly to import (xarray's dependency): only tables need it

    if isinstance(table, (str, PathLike)):
        path = Path(table)
        if not path.is_file():
            raise InvalidStateError(f"{path}: no such table file")
        try:
            if path.suffix.lower() in (".parquet", ".pq"):
                table = pd.read_parquet(path)
            elif path.suffix.lower() in (".nc", ".cdf"):
                table = xr.load_dataset(path)
            else:
                table = pd.read_csv(path, skipinitialspace=True, comment="#")
        except ImportError as exc:
            raise InvalidStateError(f"{path}: reading it needs an optional package "
                                    f"({exc})") from None
        except (ValueError, OSError, RuntimeError) as exc:  # RuntimeError: netCDF4 on a
            # damaged HDF5 block
            raise InvalidStateError(f"{path}: not a readable table ({exc})") from None
    elif hasattr(table, "read"):
        table = pd.read_csv(table, skipinitialspace=True, comment="#")
    if isinstance(table, xr.Dataset):
        items = {k: (v.attrs.get("units", ""), v.values) for k, v in table.data_vars.items()}
    elif isinstance(table, pd.DataFrame):
        items = {}
        for col in table.columns:
            name, unit = str(col).strip(), ""
            if name.endswith("]") and "[" in name:
                name, unit = name[:-1].split("[", 1)
                name, unit = name.strip(), unit.strip()
            items[name] = (unit, table[col].to_numpy())
    else:
        raise InvalidStateError(f"table: expected a path, a pandas DataFrame or an xarray "
                                f"Dataset, got {type(table).__name__}")
    return items


def _column_getter(columns):
    """``get(name, si_unit)``: a column as SI floats (its header unit converted)."""
    def get(name):
        si = COLUMNS[name].unit
        unit, values = columns[name]
        try:
            values = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            raise InvalidStateError(f"expected numbers, got {list(values)[:3]!r}...",
                                    key=f"column {name}") from None
        if values.size == 0:
            raise InvalidStateError("the table has no rows", key=f"column {name}")
        # NaN rows are kept: they become invalid bodies, reported by index; so do infinite
        # values (1e999), as NaN, before inf * 0 makes one in the inertia tensors
        values = np.where(np.isinf(values), np.nan, values)
        return to_si({"value": values, "unit": unit or si}, si, key=f"column {name}",
                     finite=False, error=InvalidStateError)

    return get



"""Columns of a Parquet file as numpy arrays, with one-line errors naming the file.

Generic (no poker, no Gymnasium): the poker decision tables (:mod:`pokerirl.datasets.decisions`),
the environments' rollouts (:meth:`pokerirl.irl.Transitions.from_parquet`) and the reward
card's states (:mod:`pokerirl.poker.reward_card`) all read their files through it. It sits in
the lowest layer so that each of those layers may use it.

>>> import pyarrow as pa
>>> table = pa.table({"x": pa.array([[1, 2], [3, 4]], pa.list_(pa.int8(), 2))})
>>> fixed_width(table, "x", 2, "t").tolist()
[[1, 2], [3, 4]]
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from pokerirl.errors import InputError


def read_parquet(
    path: str | os.PathLike[str],
    required: Sequence[str],
    optional: Sequence[str] = (),
    *,
    what: str,
) -> pa.Table:
    """The ``required`` columns (and the ``optional`` ones present) of the Parquet file at
    ``path``: ``FileNotFoundError`` if it is missing, else a one-line ``ValueError`` naming it.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{what} not found: {path}")
    # Through a file object: pyarrow cannot open a path whose name is not UTF-8.
    with open(path, "rb") as file:
        try:
            parquet = pq.ParquetFile(file)
            schema = parquet.schema_arrow
        except (pa.ArrowException, OSError) as error:
            raise InputError(f"cannot read {path} as Parquet: {first_line(error)}") from None
        missing = [name for name in required if name not in schema.names]
        if missing:
            raise InputError(f"{path} lacks required column(s): {', '.join(missing)}")
        check_footer(parquet.metadata, os.fstat(file.fileno()).st_size, str(path))
        columns = [*required, *(c for c in optional if c in schema.names)]
        try:
            return parquet.read(columns=columns)
        except (pa.ArrowException, OSError) as error:
            raise InputError(f"cannot read {path}: {first_line(error)}") from None


# Our tables inflate about 20 times (zstd over small integers); a footer that declares far
# more than this many bytes per byte of file is not a table, and reading it would allocate
# what it declares before failing (issue 36).
MAX_INFLATION = 1000
# Our tables take about 16 bytes of file per row (0.06 rows per byte); encoded with
# dictionaries and run lengths, a few bytes of true footer can declare a million identical rows,
# and each row takes a hundred bytes or more in memory once decoded.
MAX_ROWS_PER_BYTE = 1


def check_footer(metadata: pq.FileMetaData, file_bytes: int, source: str) -> None:
    """Refuse, in one line naming ``source``, a Parquet footer whose declared sizes the file
    cannot hold: a column chunk larger than the file, more rows than
    :data:`MAX_ROWS_PER_BYTE` per byte, or rows that would inflate more than
    :data:`MAX_INFLATION` times its size. Checked before a row is read."""
    declared = 0
    for group in range(metadata.num_row_groups):
        row_group = metadata.row_group(group)
        declared += row_group.total_byte_size
        for column in range(row_group.num_columns):
            if row_group.column(column).total_compressed_size > file_bytes:
                raise InputError(
                    f"{source}: its footer declares a column chunk larger than the file "
                    f"({file_bytes:,} bytes): not a readable table"
                )
    if declared > MAX_INFLATION * max(file_bytes, 1):
        raise InputError(
            f"{source}: its footer declares {metadata.num_rows:,} rows and {declared:,} bytes, "
            f"more than {MAX_INFLATION:,} times the file's {file_bytes:,}: not a readable table"
        )
    if metadata.num_rows > MAX_ROWS_PER_BYTE * max(file_bytes, 1):
        raise InputError(
            f"{source}: its footer declares {metadata.num_rows:,} rows in a file of "
            f"{file_bytes:,} bytes, more than {MAX_ROWS_PER_BYTE} per byte: not a table of "
            "decisions (runs of identical rows?)"
        )


def fixed_width(
    table: pa.Table, name: str, width: int | None, source: str, *, floating: bool = False
) -> np.ndarray:
    """A fixed_size_list column as an (N, width) numpy array, via its flat child values.

    ``width`` None accepts any list size; ``floating`` accepts float values too.
    """
    column = table.column(name)
    kind = column.type
    if not pa.types.is_fixed_size_list(kind) or (width is not None and kind.list_size != width):
        size = "" if width is None else f"[{width}]"
        raise InputError(f"{source}: column {name!r} must be fixed_size_list{size}, got {kind}")
    value_type = kind.value_type
    numeric = pa.types.is_integer(value_type) or pa.types.is_boolean(value_type)
    if not (numeric or (floating and pa.types.is_floating(value_type))):
        raise InputError(f"{source}: column {name!r} holds {value_type}, not numbers")
    array = column.combine_chunks()
    # flatten() honours slicing offsets, unlike .values; null children would be corrupt data.
    values = array.flatten()
    if values.null_count:
        raise InputError(f"{source}: column {name!r} has null entries inside its lists")
    return values.to_numpy(zero_copy_only=False).reshape(len(array), kind.list_size)


def first_line(error: BaseException) -> str:
    """The first line of an error's message (its type's name when it has none)."""
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__

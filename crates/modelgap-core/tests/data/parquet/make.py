"""Makes the Parquet fixtures of crates/modelgap-core/tests/parquet_exports.rs (issue 16, item 3).

Each file is what pandas or Polars writes from the first ROWS samples of the bundled motor
recording (examples/data/motor_hidden_effect.csv), as they export it, or a file that must be
refused. The tests read only the committed files (CI has no pandas); to make them again:

    python3 -m venv /tmp/pqenv && /tmp/pqenv/bin/pip install pandas pyarrow polars
    /tmp/pqenv/bin/python crates/modelgap-core/tests/data/parquet/make.py

Made with pandas 3.1.1, pyarrow 26.0.1, polars 2.1.0.
"""

import csv
import pathlib

import numpy as np
import pandas as pd
import polars as pl
import pyarrow as pa
import pyarrow.parquet as pq

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[4]
ROWS = 250


def motor() -> dict[str, np.ndarray]:
    """The first ROWS samples, each number parsed by Python's float (correctly rounded)."""
    path = ROOT / "examples/data/motor_hidden_effect.csv"
    with open(path, newline="") as f:
        lines = (line for line in f if not line.startswith("#"))
        reader = csv.reader(lines)
        header = next(reader)
        rows = [[float(x) for x in row] for _, row in zip(range(ROWS), reader)]
    data = np.array(rows)
    return {name: data[:, k].copy() for k, name in enumerate(header)}


def main() -> None:
    m = motor()
    df = pd.DataFrame(m)

    # (a) pandas' default: pyarrow, Snappy; the RangeIndex kept only in the pandas metadata.
    df.to_parquet(HERE / "pandas_default.parquet")
    # The index stored as a column, `__index_level_0__` (rows 1000, 1001, ...).
    df.set_axis(pd.RangeIndex(1000, 1000 + ROWS)).to_parquet(
        HERE / "pandas_index.parquet", index=True
    )
    # (b) Time not first, units in the names, no index.
    df[["V", "omega", "t", "i"]].rename(
        columns={"V": "V [V]", "omega": "omega [rad/s]", "i": "i [A]"}
    ).to_parquet(HERE / "pandas_reordered.parquet", index=False)
    # Time as a DatetimeIndex named `time` (timestamp[ns] from 2024-05-01 12:00), no `t`.
    start = pd.Timestamp("2024-05-01 12:00:00")
    stamped = df.drop(columns="t").set_axis(
        pd.DatetimeIndex(start + pd.to_timedelta(np.round(m["t"] * 1e9), unit="ns"), name="time")
    )
    stamped.to_parquet(HERE / "pandas_datetime_index.parquet")
    # Time as a timedelta column `t` (duration[ns]; Parquet stores int64, pandas' metadata
    # says timedelta64[ns]).
    df.assign(t=pd.to_timedelta(np.round(m["t"] * 1e9), unit="ns")).to_parquet(
        HERE / "pandas_timedelta.parquet", index=False
    )

    # Time in milliseconds under another name (`--time stamp`), a pandas frame read back from
    # `to_csv()` output: its index column `Unnamed: 0` first.
    pd.DataFrame(
        {
            "Unnamed: 0": np.arange(ROWS),
            "stamp [ms]": np.round(m["t"] * 1e3, 9),
            "V": m["V"],
            "i": m["i"],
            "omega": m["omega"],
        }
    ).to_parquet(HERE / "stamp_ms.parquet", index=False)

    # (c) Polars' default: zstd.
    pl.DataFrame(m).write_parquet(HERE / "polars_default.parquet")
    # Polars with time as a Datetime("us") column `time` (TIMESTAMP(MICROS)).
    pl.DataFrame(m).with_columns(
        time=pl.lit(pd.Timestamp("2024-05-01 12:00:00"))
        + pl.duration(microseconds=(pl.col("t") * 1e6).round().cast(pl.Int64))
    ).drop("t").write_parquet(HERE / "polars_datetime.parquet")

    # (d) Several row groups (50 rows each) of small pages, dictionary encoded where it pays.
    table = pa.Table.from_pandas(df, preserve_index=False)
    pq.write_table(
        table, HERE / "row_groups.parquet", row_group_size=50, data_page_size=256
    )

    # (e) int32 volts, float32 current, int64 and uint16 counters.
    pd.DataFrame(
        {
            "t": m["t"],
            "V": m["V"].astype(np.int32),
            "i": m["i"].astype(np.float32),
            "omega": m["omega"],
            "count": np.arange(ROWS, dtype=np.int64) * 3 - 7,
            "code": (np.arange(ROWS) % 7 + 60000).astype(np.uint16),
        }
    ).to_parquet(HERE / "types.parquet", index=False)

    # (f) Files to refuse.
    # A null in `i` at row 7 (pandas writes NaN as null).
    bad = df.copy()
    bad.loc[7, "i"] = np.nan
    bad.to_parquet(HERE / "null_value.parquet", index=False)
    # A NaN in `omega` at row 9 (Polars keeps NaN).
    pl.DataFrame(m).with_columns(
        omega=pl.when(pl.int_range(pl.len()) == 9).then(float("nan")).otherwise(pl.col("omega"))
    ).write_parquet(HERE / "nan_value.parquet")
    # A text column `mode`.
    df.assign(mode=np.where(m["V"] > 0, "drive", "idle")).to_parquet(
        HERE / "string_column.parquet", index=False
    )
    # Time that goes back at row 12 (rows 11 and 12 swapped).
    order = list(range(ROWS))
    order[11], order[12] = order[12], order[11]
    df.iloc[order].to_parquet(HERE / "time_not_increasing.parquet", index=False)
    # Gzip, a codec modelgap does not read.
    df.to_parquet(HERE / "gzip.parquet", index=False, compression="gzip")
    # The first 60 % of the default file: the footer is gone.
    whole = (HERE / "pandas_default.parquet").read_bytes()
    (HERE / "truncated.parquet").write_bytes(whole[: len(whole) * 6 // 10])


if __name__ == "__main__":
    main()

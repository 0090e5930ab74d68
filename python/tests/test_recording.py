"""Recordings from Python: numpy in and out, CSV and MCAP files (and Parquet, read), errors."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

import modelgap
from modelgap import DataError, ModelgapError, Recording


def test_from_numpy_round_trips(signals):
    t, values, names = signals
    rec = Recording.from_numpy(t, values, names)
    assert len(rec) == 101
    assert rec.names == names
    t2, v2, n2 = rec.to_numpy()
    assert t2.dtype == np.float64 and v2.shape == (101, 3)
    np.testing.assert_array_equal(t2, t)
    np.testing.assert_array_equal(v2, values)
    assert n2 == names
    np.testing.assert_array_equal(rec.signal("b"), values[:, 1])
    assert "a" in rec and "t" not in rec
    assert rec.duration == pytest.approx(1.0)
    assert "n_samples=101" in repr(rec)


def test_arrays_out_are_fresh_copies(signals):
    rec = Recording(*signals)
    a = rec.t
    a[:] = 0.0
    assert rec.t[-1] == 1.0
    s = rec.signal("a")
    s[:] = 7.0
    assert rec.signal("a")[0] == 0.0


def test_strided_and_non_float_input(signals):
    t, values, names = signals
    wide = np.zeros((101, 6))
    wide[:, ::2] = values
    rec = Recording.from_numpy(t, wide[:, ::2], names)
    np.testing.assert_array_equal(rec.to_numpy()[1], values)
    backwards = values[::-1][::-1]
    rec = Recording.from_numpy(t[::1], backwards, names)
    np.testing.assert_array_equal(rec.signal("c"), values[:, 2])
    ints = Recording.from_numpy([0, 1, 2], [[1], [2], [3]], ["x"])
    assert ints.signal("x").dtype == np.float64
    one = Recording.from_numpy([0.0, 1.0], np.array([5.0, 6.0]), ["y"])
    np.testing.assert_array_equal(one.signal("y"), [5.0, 6.0])


@pytest.mark.parametrize("ext", ["csv", "mcap"])
def test_file_round_trip(tmp_path: Path, signals, ext):
    rec = Recording(*signals)
    path = tmp_path / f"rec.{ext}"
    rec.save(path)
    back = Recording.load(str(path))
    assert back.names == rec.names
    np.testing.assert_allclose(back.t, rec.t, rtol=0, atol=1e-9)  # MCAP stores ns
    np.testing.assert_array_equal(back.to_numpy()[1], rec.to_numpy()[1])


def test_bad_shape_is_a_data_error_and_a_value_error(signals):
    t, values, names = signals
    with pytest.raises(DataError, match=r"values must be \(n_samples, n_signals\) = \(101, 2\)"):
        Recording.from_numpy(t, values, names[:2])
    with pytest.raises(ValueError):
        Recording.from_numpy(t, values[:-1], names)


def test_rust_messages_come_through():
    with pytest.raises(DataError) as e:
        Recording.from_numpy([0.0, 0.2, 0.1], [[1.0], [2.0], [3.0]], ["i"])
    assert str(e.value) == "time is not strictly increasing at sample 2: 0.1 s after 0.2 s"
    assert isinstance(e.value, ModelgapError) and isinstance(e.value, ValueError)
    with pytest.raises(DataError, match="not finite"):
        Recording.from_numpy([0.0, 1.0], [[1.0], [np.nan]], ["i"])
    with pytest.raises(DataError, match=r"unknown signal `x`; available: i"):
        Recording.from_numpy([0.0], [[1.0]], ["i"]).signal("x")


def test_file_errors_name_the_file(tmp_path: Path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,i\n0,1\n0.1,abc\n")
    with pytest.raises(DataError, match=r"cannot read `abc` as a number at line 3.*bad\.csv"):
        Recording.load(bad)
    with pytest.raises(DataError, match="unknown file extension `txt`"):
        Recording.load(tmp_path / "x.txt")
    with pytest.raises(DataError, match="i/o error"):
        Recording.load(tmp_path / "missing.csv")


def test_exports_of_other_tools_load_and_time_names_the_column(tmp_path: Path):
    # Issue 16: pandas' `to_csv()` (an unnamed index column) and a spreadsheet's `;` with
    # decimal commas read as they are; `time=` names a time column that is not `t`.
    pandas = tmp_path / "pandas.csv"
    pandas.write_text(",t,u [V],y\n0,0.0,1.0,0.5\n1,0.001,1.0,0.25\n")
    rec = Recording.load(pandas)
    assert rec.names == ["u", "y"]
    np.testing.assert_array_equal(rec.t, [0.0, 0.001])
    sheet = tmp_path / "sheet.csv"
    sheet.write_text("Zeit [s];u [V]\n0;1,5\n0,001;2,25\n")
    with pytest.raises(DataError, match=r"its columns are `Zeit \[s\]`, `u \[V\]`.*--time COL"):
        Recording.load(sheet)
    rec = Recording.load(sheet, time="Zeit")
    np.testing.assert_array_equal(rec.signal("u"), [1.5, 2.25])
    rec = Recording.load(sheet, time="Zeit", delimiter=";", decimal_comma=True)
    np.testing.assert_array_equal(rec.t, [0.0, 0.001])
    with pytest.raises(DataError, match="delimiter must be one character"):
        Recording.load(sheet, delimiter=";;")


PARQUET = Path(__file__).resolve().parents[2] / "crates/modelgap-core/tests/data/parquet"
MOTOR_CSV = Path(__file__).resolve().parents[2] / "examples/data/motor_hidden_effect.csv"


def test_parquet_exports_load_as_the_csv_rows(tmp_path: Path):
    # Issue 16: the committed files pandas (`to_parquet()`) and Polars (`write_parquet()`)
    # wrote from the first 250 samples of the motor recording read as the CSV's samples.
    t, values, names = Recording.load(MOTOR_CSV).to_numpy()
    for name in ["pandas_default.parquet", "polars_default.parquet", "row_groups.parquet"]:
        rec = Recording.load(PARQUET / name)
        assert rec.names == names, name
        t2, v2, _ = rec.to_numpy()
        np.testing.assert_array_equal(t2, t[:250])
        np.testing.assert_array_equal(v2, values[:250])
    rec = Recording.load(PARQUET / "stamp_ms.parquet", time="stamp")
    np.testing.assert_allclose(rec.t, t[:250], rtol=0.0, atol=1e-12)
    with pytest.raises(
        DataError, match=r"missing value \(null\) at row 7, column `i`.*null_value\.parquet"
    ):
        Recording.load(PARQUET / "null_value.parquet")
    with pytest.raises(DataError, match=r"column `mode` holds text.*string_column\.parquet"):
        Recording.load(PARQUET / "string_column.parquet")
    with pytest.raises(DataError, match=r"truncated or corrupt.*truncated\.parquet"):
        Recording.load(PARQUET / "truncated.parquet")
    with pytest.raises(DataError, match="applies to CSV files"):
        Recording.load(PARQUET / "polars_default.parquet", delimiter=";")
    out = tmp_path / "out.parquet"
    with pytest.raises(DataError, match="cannot write a recording as parquet"):
        rec.save(out)
    assert not out.exists()


def test_pickle_round_trip(signals):
    rec = Recording(*signals)
    back = pickle.loads(pickle.dumps(rec))
    assert back == rec
    assert type(back) is modelgap.Recording

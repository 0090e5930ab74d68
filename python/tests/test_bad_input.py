"""Bad input from Python (issue 11): each class raises its typed exception with the Rust
message — what is wrong and where — and the loop answers honestly when a recording cannot
be judged, instead of saying "nothing is missing"."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np
import pytest

import modelgap
from modelgap import DataError, ModelError, ModelgapError
from modelgap import cloth
from modelgap.bond import BondModel

MOTOR = Path(__file__).resolve().parents[2] / "crates/modelgap-bond/models/dc-motor.toml"


def good_csv() -> str:
    rows = ["t,V,i,omega"] + [f"{k * 1e-3},12,{2 - k * 1e-3},{10 * k * 1e-3}" for k in range(40)]
    return "\n".join(rows) + "\n"


def csv_with_line(line: int, text: str) -> str:
    lines = good_csv().splitlines()
    lines[line - 1] = text
    return "\n".join(lines) + "\n"


def motor_with(old: str, new: str) -> str:
    src = MOTOR.read_text()
    assert old in src
    return src.replace(old, new, 1)


def scene_with(old: str, new: str) -> str:
    src = cloth.scene("drape").resized(6, 6).to_toml()
    assert old in src, src
    return src.replace(old, new, 1)


def obj(extra: str) -> str:
    lines = ["# sheet"]
    for j in range(3):
        for i in range(3):
            lines.append(f"v {i * 0.1} 0 {j * 0.1}")
    lines += ["f 1 2 5 4", "f 2 3 6 5", "f 4 5 8 7", "f 5 6 9 8"]
    return "\n".join(lines) + "\n" + extra


def markers(edit: Callable[[str], str] = lambda s: s) -> str:
    rows = ["t,id,x,y,z"]
    for k in range(5):
        for vid in (0, 7, 35):
            rows.append(f"{k * 0.01},{vid},0.1,0.2,0.3")
    return edit("\n".join(rows) + "\n")


def load_text(tmp: Path, name: str, text: str | bytes, loader: Callable[[Path], object]) -> object:
    path = tmp / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    return loader(path)


# (class, what to do given a temporary folder, exception type, message pattern)
CASES: list[tuple[str, Callable[[Path], object], type[Exception], str]] = [
    ("csv: empty", lambda d: load_text(d, "r.csv", "", modelgap.Recording.load), DataError, r"no header line .*r\.csv"),
    ("csv: no t column", lambda d: load_text(d, "r.csv", csv_with_line(1, "when,V,i,omega"), modelgap.Recording.load),
     DataError, r"missing column `t`.*line 1"),
    ("csv: duplicate column", lambda d: load_text(d, "r.csv", csv_with_line(1, "t,V,i,i"), modelgap.Recording.load),
     DataError, r"duplicate signal `i`"),
    ("csv: not a number", lambda d: load_text(d, "r.csv", csv_with_line(5, "0.003,12,abc,1"), modelgap.Recording.load),
     DataError, r"`abc`.*line 5.*column `i`"),
    ("csv: NaN", lambda d: load_text(d, "r.csv", csv_with_line(6, "0.004,12,NaN,1"), modelgap.Recording.load),
     DataError, r"not finite at line 6"),
    ("csv: time goes back", lambda d: load_text(d, "r.csv", csv_with_line(7, "0.001,12,1,1"), modelgap.Recording.load),
     DataError, r"not strictly increasing at line 7"),
    ("csv: short row", lambda d: load_text(d, "r.csv", csv_with_line(8, "0.006,12,1"), modelgap.Recording.load),
     DataError, r"line 8 has 3 cells, expected 4"),
    ("csv: header only", lambda d: load_text(d, "r.csv", "t,V,i,omega\n", modelgap.Recording.load),
     DataError, r"no samples"),
    ("csv: beyond the magnitude limit", lambda d: load_text(d, "r.csv", csv_with_line(9, "0.007,12,1.7e308,1"), modelgap.Recording.load),
     DataError, r"1\.7e308 at line 9.*`i`.*1e100"),
    ("csv: not utf-8", lambda d: load_text(d, "r.csv", good_csv().encode() + b"0.5,12,\xff,1\n", modelgap.Recording.load),
     DataError, r"not valid utf-8"),
    ("mcap: not an mcap", lambda d: load_text(d, "r.mcap", "text", modelgap.Recording.load), DataError, r"mcap"),
    ("file: unknown extension", lambda d: load_text(d, "r.txt", good_csv(), modelgap.Recording.load),
     DataError, r"extension `txt`"),
    ("model: toml syntax", lambda d: BondModel.from_toml(motor_with('name = "dc-motor"', 'name = dc-motor"')),
     DataError, r"line 6"),
    ("model: unknown element in a bond", lambda d: BondModel.from_toml(motor_with('to = "R"', 'to = "Rx"')),
     ModelgapError, r"unknown element 'Rx'"),
    ("model: negative inductance", lambda d: BondModel.from_toml(motor_with("value = 5e-3,", "value = -5e-3,")),
     DataError, r"L.*positive.*-0\.005"),
    ("model: --set L=0", lambda d: BondModel.dc_motor().set("L", 0.0), DataError, r"parameter L of element L .*positive, found 0"),
    ("model: --set J=-1", lambda d: BondModel.dc_motor().set("J", -1.0), DataError, r"J.*positive.*-1"),
    ("model: a law NaN at the start", lambda d: BondModel.from_toml(motor_with('parameter = "R"', 'effort = "f / 0"')).simulate(np.linspace(0, 0.01, 11)),
     ModelgapError, r"element R, `f/0`, is NaN at the start"),
    ("scene: a 1-wide grid", lambda d: cloth.Scene.from_toml(scene_with("nx = 6", "nx = 1")), DataError, r"2 x 2"),
    ("scene: a grid past the limit", lambda d: cloth.Scene.from_toml(scene_with("nx = 6", "nx = 99999999999")).world(),
     DataError, r"particles"),
    ("scene: zero time step", lambda d: cloth.Scene.from_toml(scene_with("dt = 0.01", "dt = 0.0")), DataError, r"dt"),
    ("scene: gravity past physics", lambda d: cloth.Scene.from_toml(scene_with("gravity = [0.0, -9.81, 0.0]", "gravity = [0.0, -1e200, 0.0]")),
     DataError, r"gravity"),
    ("scene: a vertex pinned twice", lambda d: cloth.Scene.from_toml(scene_with("pins = [", "pins = [0, 0, ")), DataError, r"vertex 0"),
    ("obj: a face index past the vertices", lambda d: cloth.ClothMesh.from_obj(obj("f 1 2 12\n")), DataError, r"OBJ line 15.*12"),
    ("obj: a negative index past the start", lambda d: cloth.ClothMesh.from_obj(obj("f 1 2 -20\n")), DataError, r"OBJ line 15.*-20"),
    ("obj: two coordinates", lambda d: cloth.ClothMesh.from_obj(obj("v 1 2\n")), DataError, r"OBJ line 15"),
    ("obj: no faces", lambda d: cloth.ClothMesh.from_obj("v 0 0 0\nv 1 0 0\n"), DataError, r"empty"),
    ("markers: a bad header", lambda d: load_text(d, "m.csv", markers(lambda s: s.replace("t,id,x,y,z", "t,x,y,z", 1)), cloth.MarkerRecording.load),
     DataError, r"header `t,id,x,y,z`"),
    ("markers: a frame without a marker", lambda d: load_text(d, "m.csv", markers(lambda s: "\n".join(l for i, l in enumerate(s.splitlines()) if i != 6) + "\n"), cloth.MarkerRecording.load),
     DataError, r"missing"),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_each_class_of_bad_input_raises_its_typed_error(tmp_path: Path, case: tuple) -> None:
    _, action, error, pattern = case
    with pytest.raises(error, match=pattern):
        action(tmp_path)


def test_data_errors_are_value_errors_too() -> None:
    with pytest.raises(ValueError):
        BondModel.dc_motor().set("L", 0.0)


def test_a_recording_that_cannot_be_judged_says_so(motor: BondModel) -> None:
    # A dead sensor: both outputs read 0 throughout.
    t = np.linspace(0.0, 0.5, 501)
    values = np.column_stack([np.full_like(t, 12.0), np.zeros_like(t), np.zeros_like(t)])
    rec = modelgap.Recording.from_numpy(t, values, ["V", "i", "omega"])
    ex = modelgap.explain(motor, rec)
    assert ex.verdict == "cannot-judge"
    assert "reads 0 throughout" in ex.reasons[0]
    assert ex.chosen == []
    # Too few samples to tell a model error from noise.
    tt, v, names = motor.simulate(t[:12]).to_numpy()
    ex = modelgap.explain(motor, modelgap.Recording.from_numpy(tt, v, names), noise={"i": 0.01, "omega": 0.1})
    assert ex.verdict == "cannot-judge"
    assert "12 samples" in ex.reasons[0]


def test_a_comparison_names_what_it_cannot_judge(motor: BondModel) -> None:
    t = np.linspace(0.0, 0.5, 501)
    run = motor.simulate(t)
    tt, values, names = run.to_numpy()
    values = values.copy()
    values[:, names.index("omega")] = 0.0
    c = modelgap.compare(motor, modelgap.Recording.from_numpy(tt, values, names))
    omega = c.output("omega")
    assert omega.finding is not None and "omega reads 0 throughout" in omega.finding
    assert any("omega" in w for w in c.warnings)


PUSHED_MASS = """
name = "pushed-mass"
[parameters]
m = { value = 2.0, unit = "kg" }
[inputs]
F = { default = 1.0, unit = "N" }
[[elements]]
name = "F"
kind = "Se"
effort = "F"
[[elements]]
name = "m"
kind = "I"
parameter = "m"
[[elements]]
name = "1"
kind = "1"
[[bonds]]
number = 1
from = "F"
to = "1"
[[bonds]]
number = 2
from = "1"
to = "m"
[[outputs]]
name = "v"
flow = "1"
unit = "m/s"
"""


def test_errors_through_the_loop_keep_their_class(tmp_path: Path) -> None:
    """A model's own error crosses compare and explain with its documented class (issue 12)."""
    t = np.linspace(0.0, 0.1, 101)
    # A law that is NaN at the start: the model cannot be simulated.
    nan_law = BondModel.from_toml(motor_with('parameter = "R"', 'effort = "f / 0"'))
    rec = modelgap.Recording.from_numpy(t, np.column_stack([np.full_like(t, 12.0), t, t]), ["V", "i", "omega"])
    with pytest.raises(ModelError, match="element R"):
        modelgap.compare(nan_law, rec)
    # No steady state to start from: a convergence failure.
    mass = BondModel.from_toml(PUSHED_MASS).with_start("steady")
    pushed = modelgap.Recording.from_numpy(t, np.column_stack([np.ones_like(t), t]), ["F", "v"])
    with pytest.raises(modelgap.ConvergenceError, match="no steady state"):
        modelgap.compare(mass, pushed)
    # A cloth that diverges: the model cannot be simulated.
    scene = cloth.scene("corner").resized(3, 3)
    text = scene.to_toml().replace("dt = 0.01", "dt = 1e99", 1)
    diverging = cloth.ClothModel(cloth.Scene.from_toml(text))
    markers = modelgap.Recording.from_numpy(
        np.array([0.0, 1e99, 2e99]), np.zeros((3, 3)), ["m8.x", "m8.y", "m8.z"]
    )
    with pytest.raises(ModelError, match="diverged"):
        modelgap.compare(diverging, markers)
    # A marker file with an id past the grid: bad data.
    path = tmp_path / "m.csv"
    path.write_text("t,id,x,y,z\n0,4000,0,0,0\n")
    with pytest.raises(DataError, match="4000"):
        modelgap.load_recording(path, cloth.ClothModel(scene))

"""Calibration from Python: ``modelgap.fit`` on the real cascaded-tanks record, and
``BondModel.free`` on a built-in."""

from pathlib import Path

import pytest

import modelgap

ROOT = Path(__file__).resolve().parents[2]
TANKS = ROOT / "examples/models/cascaded-tanks.toml"
ESTIMATION = ROOT / "examples/data/realdata/cascaded_tanks/tanks_estimation.csv"


def test_fit_calibrates_the_tanks_and_the_effect_builds_it_in() -> None:
    model = modelgap.load_model(str(TANKS))
    rec = modelgap.load_recording(str(ESTIMATION), model)
    cal = modelgap.fit(model, rec)
    names = [v["name"] for v in cal.values]
    assert names == ["k1", "k2", "k3", "offset", "Tank1(0)", "Tank2(0)"]
    assert cal.termination == "converged"
    assert cal.rms_after["y"] < 0.603 < cal.rms_before["y"]
    for v in cal.values:
        assert v["at_bound"] is None and v["std_error"] is not None, v
    fitted = model.with_effects([cal.effect])
    after = modelgap.compare(fitted, rec)
    assert after.outputs[0].rms == pytest.approx(cal.rms_after["y"], rel=1e-6)
    text = cal.to_file_text()
    assert text is not None and "[initial]" in text


def test_free_marks_a_parameter_and_errors_are_typed() -> None:
    model = modelgap.load_model("dc-motor")
    rec = modelgap.load_recording(str(ROOT / "examples/data/dc_motor_r_fault.csv"), model)
    with pytest.raises(modelgap.ModelgapError, match="nothing to calibrate"):
        modelgap.fit(model, rec)
    model.free("R", (0.5, 5.0))
    cal = modelgap.fit(model, rec)
    assert cal.values[0]["name"] == "R" and cal.values[0]["bounds"] == (0.5, 5.0)
    assert cal.rms_after["i"] <= cal.rms_before["i"]
    with pytest.raises(modelgap.DataError, match="outside its bounds"):
        model.free("L", (1.0, 2.0))
    with pytest.raises(modelgap.DataError):
        model.free("nope")

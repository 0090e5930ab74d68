"""The measurement loop on cloth from Python: a ClothModel held against marker recordings,
the hidden effect found, the error falls, nothing invented for a right model."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import modelgap
from modelgap import cloth
from modelgap.cloth import ClothModel, MarkerRecording, Scene

T = np.arange(101) * 0.01  # s: one second at the scene's 100 Hz step
MARKERS = [5, 21, 30, 35]
NOISE = 1e-3  # m


@pytest.fixture(scope="module")
def model() -> ClothModel:
    return ClothModel.from_scene("corner", nx=6, nz=6)


def measured(model: ClothModel, extra: str, seed: int) -> MarkerRecording:
    """The model's scene with `extra` TOML added, at the markers, with 1 mm noise."""
    truth = ClothModel(Scene.from_toml(model.scene.to_toml() + extra, "truth"))
    clean = truth.simulate(T, ids=MARKERS)
    noisy = clean.positions + np.random.default_rng(seed).normal(0.0, NOISE, clean.positions.shape)
    return MarkerRecording(T, clean.ids, noisy)


@pytest.fixture(scope="module")
def in_air(model: ClothModel) -> MarkerRecording:
    return measured(model, "\n[air]\ndrag_coefficient = 0.5\n", seed=1)


def test_markers_become_recordings_and_back(in_air: MarkerRecording):
    rec = in_air.to_recording()
    assert rec.names[:3] == ["m5.x", "m5.y", "m5.z"] and len(rec.names) == 12
    np.testing.assert_array_equal(rec.signal("m35.y"), in_air.track(35)[:, 1])
    assert MarkerRecording.from_recording(rec) == in_air


def test_cloth_model_basics(model: ClothModel):
    assert model.name == "corner" and model.scene.grid == (6, 6)
    assert len(model.outputs) == 3 * 36 and model.outputs[:2] == ["m0.x", "m0.y"]
    menu = {c["id"]: c for c in model.candidates()}
    assert menu["air-drag"]["params"] == ["drag_coefficient"]
    assert {"wind", "damping", "bending"} <= set(menu)
    assert model.settings["method"] == "newton"
    run = model.simulate(T[:11], ids=[35])
    assert run.n_frames == 11 and run.positions[-1, 0, 1] < 0.0
    # The model predicts what the scene's world does, step by step (Newton at the scene's
    # tolerance, 1e-4 relative stretch: far below a millimetre).
    world = model.scene.with_params(model.scene.params.replace(method="newton")).world()
    world.step(10, dt=0.01)
    np.testing.assert_allclose(run.positions[-1, 0], world.positions()[35], atol=1e-6)
    assert "ClothModel corner grid=6x6 effects=0" in repr(model)


def test_explain_finds_the_drag_and_the_error_falls(model: ClothModel, in_air: MarkerRecording):
    rec = in_air.to_recording()
    before = modelgap.compare(model, rec)
    ex = modelgap.explain(model, rec)
    assert ex.verdict == "effect-found"
    (best,) = ex.chosen
    assert best.id == "air-drag"
    (cd,) = best.params
    assert cd.value == pytest.approx(0.5, rel=0.01)
    assert 0 < cd.std_error < 0.01
    fixed = model.with_effects(ex.effects)
    after = modelgap.compare(fixed, rec)
    _, err_before = cloth.vertex_errors(before)
    ids, err_after = cloth.vertex_errors(after)
    assert list(ids) == MARKERS
    assert err_before.min() > 0.1  # tens of centimetres off without drag
    assert err_after.max() < 3 * NOISE * np.sqrt(3)  # about the noise with it
    assert "added by explain" in fixed.to_toml() and "drag_coefficient" in fixed.to_toml()
    assert modelgap.fix(model, rec).scene.to_toml() == fixed.scene.to_toml()
    # The fixed model pickles with its effect, so a process pool can use it.
    back = pickle.loads(pickle.dumps(fixed))
    assert back.effects == fixed.effects and type(back) is ClothModel
    np.testing.assert_array_equal(
        back.simulate(T, ids=[35]).positions, fixed.simulate(T, ids=[35]).positions
    )


def test_nothing_missing_for_a_right_cloth_model(model: ClothModel):
    rec = measured(model, "", seed=2).to_recording()
    ex = modelgap.explain(model, rec, only=["air-drag", "damping", "bending"])
    assert ex.verdict == "nothing-missing" and ex.chosen == []


def test_cloth_model_errors(model: ClothModel, tmp_path):
    with pytest.raises(modelgap.DataError, match='method must be "newton", "gauss-seidel" or "strips"'):
        ClothModel(model.scene, method="cg")
    with pytest.raises(modelgap.DataError, match="step_divisor must be at least 1"):
        ClothModel(model.scene, step_divisor=0)
    motor_like = modelgap.Recording.from_numpy(T, np.zeros((101, 1)), ["omega"])
    # A recording without markers is bad data for a cloth model: its own error crosses the
    # loop typed (issue 12), a DataError naming the scene.
    with pytest.raises(modelgap.DataError, match="scene 'corner': the recording holds no marker"):
        modelgap.compare(model, motor_like)
    path = tmp_path / "scene.toml"
    path.write_text(model.scene.to_toml())
    assert ClothModel.load(path).scene.grid == (6, 6)

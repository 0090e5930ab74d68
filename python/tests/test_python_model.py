"""Models written in Python (issue 12): an RC circuit in numpy with a candidate leakage
resistor plugs into compare, explain and fix like the built-in kinds; the leakage hidden in
a recording is found and the error falls; the model's own bugs come back as themselves."""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
import numpy.typing as npt
import pytest

import modelgap
from modelgap import Candidate, Effect, EffectParam, ModelError, Recording


class RC:
    """A resistor R charging a capacitor C from the source voltage ``u``; the output is the
    capacitor's voltage ``v``. Exact under a zero-order hold of ``u``."""

    name = "rc-circuit"
    outputs = ["v"]
    inputs = ["u"]

    def __init__(self, R: float = 1e4, C: float = 1e-4) -> None:
        self.R = R
        self.C = C

    def unit(self, output: str) -> str:
        return "V"

    def candidates(self) -> Sequence[Candidate]:
        return [
            Candidate(
                "leakage",
                "a leakage conductance across the capacitor",
                [EffectParam("G_leak", lower=0.0, upper=1e-3, initial=0.0, scale=1e-5, unit="S")],
            ),
            Candidate(
                "capacitance",
                "the capacitance C is off",
                [EffectParam("C", lower=1e-5, upper=1e-3, initial=self.C, scale=1e-5, unit="F")],
                kind="parameter-deviation",
            ),
            Candidate(
                "offset",
                "an offset of the voltmeter",
                [EffectParam("v0", lower=-1.0, upper=1.0, initial=0.0, scale=0.01, unit="V")],
            ),
        ]

    def predict(self, recording: Recording, effects: Sequence[Effect]) -> Mapping[str, npt.ArrayLike]:
        G, C, v0 = 0.0, self.C, 0.0
        for e in effects:
            if e.id == "leakage":
                G = e.values["G_leak"]
            elif e.id == "capacitance":
                C = e.values["C"]
            elif e.id == "offset":
                v0 = e.values["v0"]
        if C <= 0:
            raise ModelError(f"capacitance {C} F cannot be simulated")
        t = recording.t
        u = recording.signal("u")
        # dv/dt = (u - v)/(R C) - G v / C: a first-order lag to u/(1 + G R) with
        # time constant R C / (1 + G R), integrated exactly between samples.
        k = 1.0 + G * self.R
        tau = self.R * C / k
        v = np.empty_like(t)
        v[0] = 0.0
        for i in range(1, len(t)):
            a = np.exp(-(t[i] - t[i - 1]) / tau)
            v[i] = u[i - 1] / k + (v[i - 1] - u[i - 1] / k) * a
        return {"v": v + v0}


def recording_with_leak(G: float, noise: float = 0.005, seed: int = 3) -> Recording:
    t = np.arange(0.0, 10.0, 0.01)
    u = np.where(t < 1.0, 0.0, np.where(t < 5.0, 5.0, 2.0))
    dummy = Recording.from_numpy(t, np.column_stack([u, np.zeros_like(t)]), ["u", "v"])
    truth = RC()
    leak = [e for e in truth.candidates() if e.id == "leakage"][0]
    # The truth: the same circuit with the leakage the model lacks.
    effect = leak.effect({"G_leak": G})
    v = np.asarray(truth.predict(dummy, [effect])["v"])
    v = v + np.random.default_rng(seed).normal(0.0, noise, v.size)
    return Recording.from_numpy(t, np.column_stack([u, v]), ["u", "v"])


def test_a_python_model_runs_the_loop_and_the_hidden_leak_is_found() -> None:
    model = RC()
    assert isinstance(model, modelgap.ModelLike)
    rec = recording_with_leak(2e-5)
    before = modelgap.compare(model, rec)
    assert before.output("v").rms > 10 * before.output("v").noise_floor
    ex = modelgap.explain(model, rec)
    assert ex.verdict == "effect-found", ex.text()
    chosen = ex.chosen[0]
    assert chosen.id == "leakage", ex.text()
    G = chosen.params[0].value
    assert abs(G - 2e-5) < 0.05 * 2e-5, ex.text()
    fixed = modelgap.fix(model, rec)
    assert isinstance(fixed, modelgap.WithEffects)
    after = modelgap.compare(fixed, rec)
    assert after.output("v").rms < 1.3 * after.output("v").noise_floor
    assert after.output("v").rms < 0.2 * before.output("v").rms
    # The right model gets "nothing is missing".
    again = modelgap.explain(fixed, rec)
    assert again.verdict == "nothing-missing", again.text()


def test_a_bug_in_a_python_model_comes_back_as_itself() -> None:
    class Broken(RC):
        def predict(self, recording: Recording, effects: Sequence[Effect]) -> Mapping[str, npt.ArrayLike]:
            if effects:
                return {"v": 1 / 0}  # a bug: ZeroDivisionError
            return super().predict(recording, effects)

    rec = recording_with_leak(2e-5)
    modelgap.compare(Broken(), rec)  # the model as given works
    with pytest.raises(ZeroDivisionError) as info:
        modelgap.explain(Broken(), rec)
    # The traceback runs into the model's own code.
    assert info.traceback[-1].name == "predict"


def test_a_model_error_is_a_value_the_fit_steps_away_from() -> None:
    # C <= 0 raises ModelError inside predict: the capacitance fit must not blow up.
    rec = recording_with_leak(0.0)
    ex = modelgap.explain(RC(), rec)
    assert ex.verdict == "nothing-missing", ex.text()


def test_what_is_not_a_model_is_refused_naming_what_it_lacks() -> None:
    class NoPredict:
        outputs = ["v"]

        def candidates(self) -> list[Candidate]:
            return []

    with pytest.raises(TypeError, match="NoPredict has no `predict`"):
        modelgap.compare(NoPredict(), recording_with_leak(0.0))  # type: ignore[arg-type]


def test_load_model_gives_the_kind_of_class_the_file_or_name_holds(tmp_path) -> None:
    motor = modelgap.load_model("dc-motor", set={"R": 1.2})
    assert isinstance(motor, modelgap.bond.BondModel) and motor.params["R"] == 1.2
    corner = modelgap.load_model("corner")
    assert isinstance(corner, modelgap.cloth.ClothModel)
    with pytest.raises(modelgap.DataError, match="--set changes bond-graph models"):
        modelgap.load_model("corner", set={"x": 1.0})
    with pytest.raises(modelgap.DataError, match="neither a model file nor a built-in"):
        modelgap.load_model("nothing-like-it")
    path = tmp_path / "run.csv"
    motor.simulate(np.linspace(0, 0.1, 101)).save(path)
    rec = modelgap.load_recording(path, motor)
    assert "omega" in rec.names


class RCFree(RC):
    """The RC circuit with its resistance unknown: ``free_parameters()`` lists it (with a
    datasheet's prior when given), and ``predict`` reads it from the ``calibration`` effect."""

    name = "rc-free"

    def __init__(self, prior: tuple[float, float] | None = None) -> None:
        super().__init__(R=5e3)
        self.prior = prior

    def free_parameters(self) -> Sequence[EffectParam]:
        return [EffectParam("R", lower=1e3, upper=1e5, initial=5e3, scale=1e3, unit="Ohm", prior=self.prior)]

    def predict(self, recording: Recording, effects: Sequence[Effect]) -> Mapping[str, npt.ArrayLike]:
        R = self.R
        for e in effects:
            if e.id == "calibration":
                R = e.values["R"]
        inner = RC(R=R, C=self.C)
        return inner.predict(recording, [e for e in effects if e.id != "calibration"])


def test_a_python_model_marks_its_own_unknowns_and_fit_calibrates_them() -> None:
    rec = recording_with_leak(0.0)  # the truth: R = 1e4, C = 1e-4, no leak
    cal = modelgap.fit(RCFree(), rec)
    (R,) = cal.values
    assert R["name"] == "R" and R["unit"] == "Ohm" and R["prior"] is None
    assert abs(R["value"] - 1e4) < 0.02 * 1e4, R
    assert R["std_error"] is not None and R["std_error"] < 0.02 * 1e4, R
    assert cal.rms_after["v"] < 0.2 * cal.rms_before["v"]
    # Explain calibrates first and fits candidates jointly with R: the hidden leak is found,
    # not absorbed into R.
    leaky = recording_with_leak(2e-5)
    ex = modelgap.explain(RCFree(), leaky)
    assert ex.chosen and ex.chosen[0].id == "leakage", ex.text()
    # A prior is reported and weighed: a tight wrong one pulls R towards it.
    cal_prior = modelgap.fit(RCFree(prior=(8e3, 1.0)), rec)
    (Rp,) = cal_prior.values
    assert Rp["prior"] == (8e3, 1.0)
    assert Rp["value"] < R["value"] - 500.0, (Rp, R)


def test_a_bad_prior_is_refused() -> None:
    with pytest.raises(modelgap.DataError, match="prior"):
        EffectParam("R", lower=1.0, upper=2.0, prior=(1.5, 0.0))

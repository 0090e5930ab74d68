"""The measurement loop from Python: a hidden effect found, the error falls, nothing
invented for a right model; pickling and many recordings at once."""

from __future__ import annotations

import _thread
import json
import threading
import time
import pickle
import multiprocessing
import math
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path

import pytest

import modelgap
from modelgap import Effect, Recording
from modelgap.bond import BondModel, hidden_cases, hidden_recording


@pytest.fixture(scope="module")
def coulomb() -> Recording:
    return hidden_recording("coulomb", seed=1, duration=4.0)


@pytest.fixture(scope="module")
def coulomb_explained(coulomb: Recording) -> modelgap.Explanation:
    return modelgap.explain(BondModel.dc_motor(), coulomb)


def test_hidden_cases_are_listed():
    cases = hidden_cases()
    assert "coulomb" in cases and "nothing" in cases
    with pytest.raises(modelgap.DataError, match="unknown hidden-effect case `x`"):
        hidden_recording("x")


def test_compare_shows_where_the_model_fails(coulomb: Recording):
    c = modelgap.compare(BondModel.dc_motor(), coulomb)
    omega = c.output("omega")
    assert omega.unit == "rad/s"
    assert omega.rms > 3 * omega.noise_floor
    assert omega.windows and all(s < e for s, e, _ in omega.windows)
    assert omega.residual.shape == omega.measured.shape == c.t.shape
    assert "omega" in c.text()
    paper = modelgap.compare(BondModel.dc_motor(), coulomb, band_fraction=0.02)
    assert paper.output("omega").band != omega.band


def test_explain_finds_the_hidden_effect_and_the_error_falls(
    coulomb: Recording, coulomb_explained: modelgap.Explanation, tmp_path: Path
):
    ex = coulomb_explained
    motor = BondModel.dc_motor()
    assert ex.verdict == "effect-found"
    best = ex.ranked[0]
    assert best.id == "coulomb@1m" and ex.chosen[0].id == "coulomb@1m"
    (tau,) = best.params
    assert tau.name == "tau_c" and tau.unit == "N m"
    assert tau.value == pytest.approx(0.004, rel=0.05)
    assert 0 < tau.std_error < 0.1 * tau.value
    assert best.score > 10 and best.kind == "missing-element"
    assert "Coulomb" in ex.text()

    fixed = motor.with_effects(ex.effects)
    assert len(fixed.effects) == 1 and fixed.params["tau_c_1m"] == tau.value
    before = modelgap.compare(motor, coulomb)
    after = modelgap.compare(fixed, coulomb)
    for o in ("i", "omega"):
        assert after.output(o).rms < 0.5 * before.output(o).rms
    assert "added by explain" in fixed.to_toml()

    also = modelgap.fix(motor, coulomb)
    assert also.params == fixed.params

    page = modelgap.write_report(tmp_path / "report", before, ex, after)
    assert Path(page).name == "report.html" and Path(page).exists()
    assert (tmp_path / "report" / "comparison.mcap").exists()


def test_nothing_missing_for_a_right_model():
    rec = hidden_recording("nothing", seed=2, duration=2.0)
    ex = modelgap.explain(BondModel.dc_motor(), rec)
    assert ex.verdict == "nothing-missing"
    assert ex.chosen == [] and ex.effects == []


def test_progress_is_reported(coulomb: Recording):
    seen: list[tuple[int, int]] = []
    modelgap.explain(
        BondModel.dc_motor(),
        coulomb,
        only=["coulomb@1m", "deviation:R"],
        progress=lambda done, total: seen.append((done, total)),
    )
    # Fits counted as they finish, to the last: here only Coulomb friction is confirmed by a
    # fit (R being off removes too little beside it, and keeps the screen's size).
    assert seen and seen[-1][0] == seen[-1][1] >= 1


def test_progress_exception_stops_explain(coulomb: Recording):
    def boom(done: int, total: int) -> None:
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        modelgap.explain(BondModel.dc_motor(), coulomb, progress=boom)


def test_pickling_round_trips(coulomb: Recording, coulomb_explained: modelgap.Explanation):
    motor = BondModel.dc_motor().with_start("steady")
    fixed = motor.with_effects(coulomb_explained.effects)
    back = pickle.loads(pickle.dumps(fixed))
    assert back.params == fixed.params and back.start == "steady"
    assert back.effects == fixed.effects
    eff = coulomb_explained.effects[0]
    assert pickle.loads(pickle.dumps(eff)) == eff
    assert Effect.from_json(eff.to_json()) == eff
    rec = pickle.loads(pickle.dumps(coulomb))
    assert rec == coulomb


def test_an_effect_out_of_bounds_is_a_model_error(coulomb_explained: modelgap.Explanation):
    data = json.loads(coulomb_explained.effects[0].to_json())
    data["values"] = [-1.0]  # a negative friction torque: below the candidate's bound
    bad = Effect.from_json(json.dumps(data))
    with pytest.raises(modelgap.ModelError, match="coulomb@1m"):
        BondModel.dc_motor().with_effects([bad])


def test_explain_many_with_a_thread_pool():
    recs = [hidden_recording(c, seed=3, duration=2.0) for c in ("load", "nothing")]
    motor = BondModel.dc_motor()
    serial = modelgap.explain_many(motor, recs)
    with ThreadPoolExecutor(max_workers=2) as pool:
        parallel = modelgap.explain_many(motor, recs, executor=pool)
    assert [e.verdict for e in serial] == [e.verdict for e in parallel]
    assert serial[0].chosen[0].id == parallel[0].chosen[0].id == "load@1m"
    assert serial[1].verdict == "nothing-missing"


def test_ctrl_c_stops_explain():
    # A long explain; a simulated Ctrl-C (SIGINT) 0.2 s in must stop it between fits.
    rec = hidden_recording("coupling", seed=4, duration=30.0)
    timer = threading.Timer(0.2, _thread.interrupt_main)
    start = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            modelgap.explain(BondModel.dc_motor(), rec)
    finally:
        timer.cancel()
    assert time.perf_counter() - start < 10.0  # the whole explain takes about 3 s here


def test_results_pickle_with_their_infinities(
    coulomb: Recording, coulomb_explained: modelgap.Explanation
):
    ex = coulomb_explained
    back = pickle.loads(pickle.dumps(ex))
    assert back == ex and type(back) is modelgap.Explanation
    assert back.text() == ex.text() and back.effects == ex.effects
    # Some candidates sit at a bound: an infinite standard error survives the round trip.
    inf_errors = [p for r in ex.ranked for p in r.params if math.isinf(p.std_error)]
    back_inf = [p for r in back.ranked for p in r.params if math.isinf(p.std_error)]
    assert len(inf_errors) == len(back_inf)
    c = modelgap.compare(BondModel.dc_motor(), coulomb)
    again = pickle.loads(pickle.dumps(c))
    assert again == c and again.text() == c.text()
    with pytest.raises(modelgap.DataError, match="not the stored state of an explanation"):
        modelgap.Explanation._from_state("verdict = 3")


def test_explain_many_with_a_process_pool():
    # Everything explain_many sends (model, recordings, options, explanations) pickles, so
    # worker processes run it ("spawn": a fresh interpreter, as Dask or Ray workers are).
    recs = [hidden_recording(c, seed=3, duration=2.0) for c in ("load", "nothing")]
    motor = BondModel.dc_motor()
    serial = modelgap.explain_many(motor, recs, only=["load@1m", "coulomb@1m", "deviation:R"])
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=2, mp_context=context) as pool:
        parallel = modelgap.explain_many(
            motor, recs, executor=pool, only=["load@1m", "coulomb@1m", "deviation:R"]
        )
    assert parallel == serial
    assert parallel[0].chosen[0].id == "load@1m" and parallel[1].verdict == "nothing-missing"


def test_bounds_and_reasons_reach_python(coulomb_explained: modelgap.Explanation):
    ex = coulomb_explained
    (tau,) = ex.ranked[0].params
    assert tau.at_bound is None and math.isfinite(tau.std_error)
    # Every fit that ended on a bound says which, and gives no standard error.
    bound = [p for r in ex.ranked for p in r.params if p.at_bound is not None]
    assert bound, ex.text()
    assert all(p.at_bound in ("lower", "upper") and math.isinf(p.std_error) for p in bound)
    assert "bound" in repr(bound[0])
    # A signature tag comes with its reason in plain words.
    tagged = [r for r in ex.ranked if r.qualitative is not None]
    assert tagged and all("fault trees" in r.qualitative_reason for r in tagged), ex.text()
    assert isinstance(ex.ranked[0].indistinct, list)


def test_where_the_model_fails_reaches_python(coulomb_explained: modelgap.Explanation):
    ex = coulomb_explained
    places = ex.places
    assert places and places[0]["location"] == "1m", places
    assert 0.5 < places[0]["explained"] <= 1.0
    law = places[0]["law"]
    # Under this staircase drive the shaft's missing torque is nearly constant per step: the
    # menu's Coulomb friction names it; a law, when the screen finds one, is a dict.
    assert law is None or (law["terms"] and "formula" in law), law
    t, value, band = ex.missing("1m")
    assert t.shape == value.shape == band.shape and len(t) > 100
    assert (band >= 0).all()
    with pytest.raises(modelgap.DataError, match="no missing effort was estimated at 'x'"):
        ex.missing("x")


def test_stage_timings_and_floor_method_are_read(coulomb_explained: modelgap.Explanation):
    stages = [s for s, _, _ in coulomb_explained.timings]
    assert stages[0] == "calibrate" and "confirm" in stages and stages[-1] == "judge"
    assert all(wall >= 0.0 and (cpu is None or cpu >= 0.0) for _, wall, cpu in coulomb_explained.timings)
    # The bundled-style recording's noise is white: its floor comes from third differences.
    assert {o.noise_method for o in coulomb_explained.outputs} == {"white"}
    # The noise model the scores whiten each output with: an AR(1) coefficient up to its cap.
    assert all(
        o.noise_rho is not None and 0.0 <= o.noise_rho <= 0.999 for o in coulomb_explained.outputs
    )
    # Timings are not part of what an explanation says.
    again = pickle.loads(pickle.dumps(coulomb_explained))
    assert again == coulomb_explained and again.timings == coulomb_explained.timings

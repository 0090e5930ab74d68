"""Bond-graph models from Python: the DC motor's numbers, simulation, diagnosis."""

from __future__ import annotations

import pickle
import threading
import time

import numpy as np
import pytest

import modelgap
from modelgap import DataError
from modelgap.bond import BondModel, table7

# ω = kV / (Rβ + k²) for the built-in motor (k = 0.05, V = 12, R = 1, β = 1e-5).
OMEGA_STEADY = 0.05 * 12.0 / (1e-5 + 0.0025)


def test_dc_motor_steady_state(motor: BondModel):
    ss = motor.steady_state()
    assert ss["omega"] == pytest.approx(239.0438, abs=1e-4)
    assert ss["omega"] == pytest.approx(OMEGA_STEADY, rel=1e-9)
    assert motor.steady_state({"V": 6.0})["omega"] == pytest.approx(OMEGA_STEADY / 2, rel=1e-9)


def test_simulation_reaches_the_steady_state(motor: BondModel):
    rec = motor.simulate(np.linspace(0.0, 1.0, 1001))
    assert rec.names[:2] == ["V", "tau_L"] or "omega" in rec.names
    assert rec.signal("omega")[-1] == pytest.approx(239.0438, abs=1e-3)


def test_params_and_set(motor: BondModel):
    p = motor.params
    assert p["R"] == 1.0 and set(p) >= {"R", "L", "k", "J", "beta"}
    p["R"] = 5.0  # a fresh dict: the model does not change
    assert motor.params["R"] == 1.0
    motor.set("R", 2.0)
    assert motor.params["R"] == 2.0
    with pytest.raises(DataError, match="unknown parameter 'X'"):
        motor.set("X", 1.0)
    assert "BondModel dc-motor" in repr(motor)


def test_state_space_and_eigenvalues(motor: BondModel):
    ss = motor.state_space()
    assert ss["states"] == ["p3", "p8"]
    a = ss["A"]
    p = motor.params
    expected = np.array(
        [[-p["R"] / p["L"], -p["k"] / p["J"]], [p["k"] / p["L"], -p["beta"] / p["J"]]]
    )
    # A is linearised by finite differences (about 1e-12 relative here): 1e-8 leaves room.
    np.testing.assert_allclose(a, expected, rtol=1e-8)
    ev = motor.eigenvalues()
    np.testing.assert_allclose(
        np.sort_complex(ev), np.sort_complex(np.linalg.eigvals(a)), rtol=1e-9
    )
    assert all(e.real < 0 for e in ev)


def test_equations_in_the_papers_notation(motor: BondModel):
    text = motor.equations()
    assert "dp3 = e1 - e2 - e4" in text
    latex = motor.equations(latex=True)
    assert latex == motor._repr_latex_() and "align" in latex


def test_simulate_with_numpy_input(motor: BondModel):
    t = np.linspace(0.0, 0.5, 501)
    v = np.where(t < 0.25, 12.0, 6.0)
    rec = motor.simulate(t, {"V": (t, v)}, hold="zoh")
    np.testing.assert_array_equal(rec.signal("V"), v)
    omega = rec.signal("omega")
    assert omega[240] > omega[-1] > 0.0
    constant = motor.simulate(t, {"V": 6.0}, steady_start=True)
    assert constant.signal("omega")[0] == pytest.approx(OMEGA_STEADY / 2, rel=1e-6)


def test_simulate_pwm():
    buck = BondModel.buck_motor()
    t = np.linspace(0.0, 0.2, 2001)
    rec = buck.simulate(t, {"m": ("pwm", 0.5, 1000.0)})
    m = rec.signal("m")
    assert set(np.unique(m)) <= {0.0, 1.0} and 0.3 < m.mean() < 0.7
    assert rec.signal("omega")[-1] > 0.0
    with pytest.raises(DataError, match="PWM duty must be in"):
        buck.simulate(t, {"m": ("pwm", 1.5, 1000.0)})


def test_simulate_faults(motor: BondModel):
    t = np.linspace(0.0, 1.0, 1001)
    rec = motor.simulate(t, faults=[("R", 2.0, 0.5)], steady_start=True)
    i = rec.signal("i")
    assert i[400] == pytest.approx(i[0], rel=1e-6)
    assert i[-1] != pytest.approx(i[0], rel=1e-3)
    with pytest.raises(DataError, match="no such parameter"):
        motor.simulate(t, faults=[("X", 2.0, 0.5)])
    with pytest.raises(DataError, match="has no input `W`"):
        motor.simulate(t, {"W": 1.0})


def test_simulation_releases_the_gil(motor: BondModel):
    # A long run on a worker thread; the main thread must keep counting meanwhile.
    t = np.linspace(0.0, 20.0, 400_001)
    done = threading.Event()

    def work() -> None:
        motor.simulate(t, {"V": ("pwm", 0.5, 2000.0)}, solver="dopri5")
        done.set()

    worker = threading.Thread(target=work)
    start = time.perf_counter()
    worker.start()
    counts = 0
    while not done.is_set():
        counts += 1
        time.sleep(0.001)
    worker.join()
    elapsed = time.perf_counter() - start
    assert elapsed > 0.05, "the simulation was too short to tell"
    # Holding the GIL would freeze the loop: expect at least a quarter of the ideal count.
    assert counts > 0.25 * elapsed / 0.001 * 0.5


def test_diagnose_an_r_fault(motor: BondModel):
    t = np.linspace(0.0, 1.0, 1001)
    rec = motor.simulate(t, faults=[("R", 1.2, 0.2)], steady_start=True)
    d = motor.diagnose(rec, steady_start=True)
    assert "R" in d.parameters
    assert d.detected_at is not None and d.detected_at >= 0.2
    assert "R" in d.report()
    assert [r["output"] for r in d.residuals] == ["i", "omega"]


def test_causal_graph_fault_tree_arrs(motor: BondModel):
    assert motor.causal_graph_dot().startswith("digraph")
    assert "R" in motor.fault_tree("i", "-")
    with pytest.raises(DataError, match="qual must be"):
        motor.fault_tree("i", "x")
    assert "ARR" in motor.arrs() or "arr" in motor.arrs().lower()


def test_toml_round_trip_and_pickle(motor: BondModel, tmp_path):
    motor.set("R", 1.5)
    again = BondModel.from_toml(motor.to_toml())
    assert again.params == motor.params
    path = tmp_path / "m.toml"
    motor.save(path)
    assert BondModel.load(path).params["R"] == 1.5
    steady = motor.with_start("steady").with_hold("linear")
    back = pickle.loads(pickle.dumps(steady))
    assert (back.start, back.hold, back.params) == ("steady", "linear", steady.params)
    assert isinstance(back, BondModel)


def test_model_errors():
    with pytest.raises(DataError, match="unknown built-in model 'nope'"):
        BondModel.builtin("nope")
    with pytest.raises(DataError, match="at line 1"):
        BondModel.from_toml("name = [")
    motor = BondModel.dc_motor()
    menu = {c["id"]: c for c in motor.candidates()}
    assert "coulomb@1m" in menu and menu["coulomb@1m"]["params"] == ["tau_c"]
    with pytest.raises(DataError, match="start must be"):
        BondModel.dc_motor().with_start("moving")


def test_table7_matches_the_paper():
    rows = table7()
    assert len(rows) == 12
    assert all(r["contains_fault"] for r in rows)
    assert {r["fault"] for r in rows} >= {"R+", "J-", "m+"}


def test_compare_rejects_a_non_model(motor_run):
    with pytest.raises(TypeError, match="model must be a modelgap.bond.BondModel"):
        modelgap.compare("dc-motor", motor_run)  # type: ignore[arg-type]


def test_auto_hold_follows_what_the_recording_says(motor: BondModel):
    # A smooth voltage, recorded at 1 kHz as a sampled analog signal: read by a cubic
    # through its samples it is the drive the recording was made with.
    t = np.linspace(0.0, 0.5, 501)
    v = 12.0 + 4.0 * np.sin(2 * np.pi * 7.0 * t) + 2.0 * np.sin(2 * np.pi * 31.0 * t)
    rec = motor.simulate(t, {"V": (t, v)}, hold="cubic")
    assert motor.hold == "auto"
    notes = motor.hold_notes(rec)
    assert len(notes) == 1 and "input `V` is held by a smooth cubic" in notes[0], notes
    auto = modelgap.compare(motor, rec).output("omega").rms
    zoh = modelgap.compare(motor.with_hold("zoh"), rec).output("omega").rms
    assert zoh > 100 * auto, (auto, zoh)
    assert motor.with_hold("cubic").hold_notes(rec) == []
    assert motor.with_hold("cubic").hold == "cubic"
    with pytest.raises(DataError, match='hold must be "auto", "zoh", "linear" or "cubic", found "x"'):
        motor.with_hold("x")

"""The PWM-switched buck converter feeding the DC motor over 0-1 s from rest (1 kHz PWM,
duty 0.5, 1 kHz output), built and simulated with BondGraphTools, a Python bond-graph
toolkit (its simulator is SUNDIALS' IDA through scikits.odes).

Prints one JSON line: {"name", "median_ms", "min_ms", "runs", "final", ...} as the scipy
scripts do. Parameters come from crates/modelgap-bond/models/buck-motor.toml.

The graph is modelgap's buck-motor with one simplification BondGraphTools needs: it has no
modulated transformer, so the supply and the switch (Se:Vs -> MTF:m) become one effort
source Se of effort m(t) Vs. That is the same physics: the MTF's output effort is m Vs, and
its input flow (the supply current) feeds nothing. BondGraphTools integrates through the
PWM edges (its simulate has no breakpoints) with IDA's default tolerances.

Run: python benches/reference/toolkit_buck_motor.py [--repeat N]
"""

from __future__ import annotations

import contextlib
import io

import numpy as np

from _common import arguments, emit, model_values, note, time_runs

with contextlib.redirect_stdout(io.StringIO()):  # it prints a warning when it cannot simulate
    import BondGraphTools as bgt

DURATION = 1.0  # simulated time (s)
PWM_HZ = 1000.0  # switching frequency (Hz)
DUTY = 0.5
DT_OUT = 1e-3  # output interval (s)


def build(p: dict[str, float]):
    """The buck-motor as a BondGraphTools model; returns it and its I and C components."""
    model = bgt.new(name="buck_motor")
    source = bgt.new("Se", name="Vs_m")  # effort m(t) Vs: control variable u_0
    tau_l = bgt.new("Se", name="tau_L")  # load torque: control variable u_1
    j1c, j0c, j1e, j1m = (bgt.new("1", name="1c"), bgt.new("0", name="0c"),
                          bgt.new("1", name="1e"), bgt.new("1", name="1m"))
    lf = bgt.new("I", name="Lf", value=p["Lf"])
    rf = bgt.new("R", name="rf", value=p["rf"])
    cf = bgt.new("C", name="Cf", value=p["Cf"])
    r = bgt.new("R", name="R", value=p["R"])
    ind = bgt.new("I", name="L", value=p["L"])
    # BondGraphTools' GY takes both port flows as inward (e_0 = R f_1, e_1 = -R f_0);
    # modelgap's GY:k on a through path (bond 4 in, bond 5 out) has e4 = k f5, e5 = k f4,
    # which is R = -k here. With R = +k the shaft would turn the other way.
    gy = bgt.new("GY", name="k", value=-p["k"])
    beta = bgt.new("R", name="beta", value=p["beta"])
    inertia = bgt.new("I", name="J", value=p["J"])
    bgt.add(model, source, tau_l, j1c, j0c, j1e, j1m, lf, rf, cf, r, ind, gy, beta, inertia)
    # The bonds of buck-motor.toml, same directions (9 and 10 merged into the source's).
    bgt.connect(source, j1c)
    bgt.connect(j1c, lf)  # 11
    bgt.connect(j1c, rf)  # 12
    bgt.connect(j1c, j0c)  # 13
    bgt.connect(j0c, cf)  # 14
    bgt.connect(j0c, j1e)  # 1
    bgt.connect(j1e, r)  # 2
    bgt.connect(j1e, ind)  # 3
    bgt.connect(j1e, (gy, 0))  # 4
    bgt.connect((gy, 1), j1m)  # 5
    bgt.connect(j1m, beta)  # 6
    bgt.connect(j1m, tau_l)  # 7
    bgt.connect(j1m, inertia)  # 8
    return model


def state_index(model, component: str) -> int:
    """Index of a component's state in the model's state vector."""
    for name, (comp, _) in model.state_vars.items():
        if comp.name == component:
            return int(name.split("_")[1])
    raise SystemExit(f"BondGraphTools model has no state of {component}")


def main() -> None:
    args = arguments(__doc__.splitlines()[0])
    p, u = model_values("buck-motor")
    model = build(p)
    vs, tau_l = u["Vs"], u["tau_L"]
    period = 1.0 / PWM_HZ

    def supply(t, x, dx):
        # The switch: Vs for the first DUTY of each period, 0 after.
        return vs if (t % period) < DUTY * period else 0.0

    controls = {}
    for name, (comp, _) in model.control_vars.items():
        controls[name] = supply if comp.name == "Vs_m" else tau_l
    x0 = [0.0] * len(model.state_vars)

    def run():
        return bgt.simulate(model, timespan=[0.0, DURATION], x0=x0, dt=DT_OUT,
                            control_vars=controls)

    times, (t, x) = time_runs(run, args.repeat, args.min_time, max_runs=10)
    last = x[-1]
    p3 = last[state_index(model, "L")]
    p8 = last[state_index(model, "J")]
    p11 = last[state_index(model, "Lf")]
    q14 = last[state_index(model, "Cf")]
    omega = x[:, state_index(model, "J")] / p["J"]
    final = {"p3": p3, "p8": p8, "p11": p11, "q14": q14, "i": p3 / p["L"],
             "omega": p8 / p["J"], "v_c": q14 / p["Cf"]}
    name = "buck_motor_pwm_1s/bondgraphtools"
    emit(name, times, {k: float(v) for k, v in final.items()},
         omega_mean_last_10ms=float(np.mean(omega[-10:])), samples=len(t))
    note(f"{name}: median {np.median(times):.0f} ms over {len(times)} runs")


if __name__ == "__main__":
    main()

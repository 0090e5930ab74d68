"""The DC motor from rest at 12 V over 0-4 s, 1 kHz output, the scipy way: LSODA with a
hand-written numpy right-hand side, and LSODA with a sympy-lambdified one.

Prints one JSON line per route: {"name", "median_ms", "min_ms", "runs", "final", ...};
`final` holds the states (p3, p8) and outputs (i, omega) at t = 4 s, named as modelgap names
them. Parameters come from crates/modelgap-bond/models/dc-motor.toml.

Run: python benches/reference/scipy_dc_motor.py [--repeat N]
"""

from __future__ import annotations

import time

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from _common import arguments, emit, model_values, note, time_runs

DURATION = 4.0  # simulated time (s)
RATE_HZ = 1000.0  # output rate (Hz)
RTOL = 1e-8  # as modelgap's SimOptions default
ATOL = 1e-10


def main() -> None:
    args = arguments(__doc__.splitlines()[0])
    p, u = model_values("dc-motor")
    R, L, k, J, beta = p["R"], p["L"], p["k"], p["J"], p["beta"]
    V, tau_L = u["V"], u["tau_L"]
    t_eval = np.linspace(0.0, DURATION, int(round(DURATION * RATE_HZ)) + 1)  # 4001 points

    # (a) Hand-written numpy right-hand side. States: p3 (flux linkage of L, bond 3) and
    # p8 (angular momentum of J, bond 8). Electrical 1-junction: e1 = e2 + e3 + e4, so
    # dp3 = V - R i - k omega; mechanical 1-junction: e5 = e6 + e7 + e8, so
    # dp8 = k i - beta omega - tau_L, with i = p3/L, omega = p8/J.
    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        p3, p8 = y
        return np.array([V - R / L * p3 - k / J * p8, k / L * p3 - beta / J * p8 - tau_L])

    def lsoda_numpy():
        return solve_ivp(rhs, (0.0, DURATION), [0.0, 0.0], method="LSODA",
                         t_eval=t_eval, rtol=RTOL, atol=ATOL)

    # (b) The same equations built in sympy from the bond-graph relations and lambdified.
    t0 = time.perf_counter()
    ts, p3s, p8s = sp.symbols("t p3 p8")
    sym = dict(zip("R L k J beta V tau_L".split(), sp.symbols("R L k J beta V tau_L")))
    i_s, w_s = p3s / sym["L"], p8s / sym["J"]
    e2, e4 = sym["R"] * i_s, sym["k"] * w_s  # resistor, gyrator (e4 = k f5)
    e5, e6 = sym["k"] * i_s, sym["beta"] * w_s  # gyrator (e5 = k f4), friction
    dp3 = sym["V"] - e2 - e4
    dp8 = e5 - e6 - sym["tau_L"]
    values = {sym["R"]: R, sym["L"]: L, sym["k"]: k, sym["J"]: J, sym["beta"]: beta,
              sym["V"]: V, sym["tau_L"]: tau_L}
    f_sym = sp.lambdify((ts, (p3s, p8s)), [dp3.subs(values), dp8.subs(values)], "numpy")
    setup_ms = (time.perf_counter() - t0) * 1e3

    def lsoda_sympy():
        return solve_ivp(f_sym, (0.0, DURATION), [0.0, 0.0], method="LSODA",
                         t_eval=t_eval, rtol=RTOL, atol=ATOL)

    for name, route, extra in [
        ("dc_motor_4s_1khz/scipy_lsoda_numpy", lsoda_numpy, {}),
        ("dc_motor_4s_1khz/scipy_lsoda_sympy", lsoda_sympy, {"setup_ms": setup_ms}),
    ]:
        times, sol = time_runs(route, args.repeat, args.min_time)
        if not sol.success:
            raise SystemExit(f"{name}: solve_ivp failed: {sol.message}")
        p3, p8 = sol.y[:, -1]
        final = {"p3": p3, "p8": p8, "i": p3 / L, "omega": p8 / J}
        emit(name, times, final, rhs_evals=int(sol.nfev), samples=len(sol.t), **extra)
        note(f"{name}: median {np.median(times):.3f} ms over {len(times)} runs")


if __name__ == "__main__":
    main()

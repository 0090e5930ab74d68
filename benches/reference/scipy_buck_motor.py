"""The PWM-switched buck converter feeding the DC motor over 0-1 s from rest (1 kHz PWM,
duty 0.5, 1 kHz output), the scipy way: solve_ivp's LSODA with a hand-written numpy
right-hand side, integrated period by period with the switching instants as segment ends
(2000 segments), so that no step crosses an edge.

Prints one JSON line: {"name", "median_ms", "min_ms", "runs", "final", ...}; `final` holds
the states (p3, p8, p11, q14) and outputs (i, omega, v_c) at t = 1 s, named as modelgap
names them, and `omega_mean_last_10ms`. Parameters come from
crates/modelgap-bond/models/buck-motor.toml.

Run: python benches/reference/scipy_buck_motor.py [--repeat N]
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from _common import arguments, emit, model_values, note, time_runs

DURATION = 1.0  # simulated time (s)
PWM_HZ = 1000.0  # switching frequency (Hz); the output rate is the same, one sample per period
DUTY = 0.5
RTOL = 1e-8  # as modelgap's SimOptions default
ATOL = 1e-10


def main() -> None:
    args = arguments(__doc__.splitlines()[0])
    p, u = model_values("buck-motor")
    R, L, k, J, beta = p["R"], p["L"], p["k"], p["J"], p["beta"]
    Lf, rf, Cf = p["Lf"], p["rf"], p["Cf"]
    Vs, tau_L = u["Vs"], u["tau_L"]

    # The equations, derived by hand from buck-motor.toml's bonds:
    #   Se:Vs -9-> MTF:m -10-> 1c; 1c -11-> I:Lf, 1c -12-> R:rf, 1c -13-> 0c;
    #   0c -14-> C:Cf, 0c -1-> 1e (the motor: 1e -2-> R, -3-> I:L, -4-> GY:k -5-> 1m;
    #   1m -6-> R:beta, -7-> Se:tau_L, -8-> I:J).
    # States p3 (L), p8 (J), p11 (Lf), q14 (Cf); i = p3/L, omega = p8/J, i_f = p11/Lf,
    # v_c = q14/Cf. The MTF: e10 = m e9 = m Vs (and f9 = m f10, the supply current, which
    # nothing else reads). 1c (common flow i_f): e10 = e11 + e12 + e13, e12 = rf i_f, and
    # e13 = e14 = e1 = v_c at the 0-junction 0c, so dp11 = m Vs - rf i_f - v_c.
    # 0c (common effort v_c): f13 = f14 + f1, so dq14 = i_f - i.
    # 1e: e1 = e2 + e3 + e4, so dp3 = v_c - R i - k omega (GY: e4 = k f5 = k omega).
    # 1m: e5 = e6 + e7 + e8, so dp8 = k i - beta omega - tau_L (GY: e5 = k f4 = k i).
    def rhs(t: float, y: np.ndarray, m: float) -> np.ndarray:
        p3, p8, p11, q14 = y
        i, omega, i_f, v_c = p3 / L, p8 / J, p11 / Lf, q14 / Cf
        return np.array([
            v_c - R * i - k * omega,
            k * i - beta * omega - tau_L,
            m * Vs - rf * i_f - v_c,
            i_f - i,
        ])

    period = 1.0 / PWM_HZ
    n_periods = int(round(DURATION * PWM_HZ))

    def run() -> np.ndarray:
        # One sample per period end (= the 1 kHz output times), plus the start.
        y = np.zeros(4)
        out = np.empty((n_periods + 1, 4))
        out[0] = y
        for n in range(n_periods):
            t_on, t_edge, t_off = n * period, (n + DUTY) * period, (n + 1) * period
            for (a, b, m) in ((t_on, t_edge, 1.0), (t_edge, t_off, 0.0)):
                sol = solve_ivp(rhs, (a, b), y, method="LSODA", args=(m,),
                                rtol=RTOL, atol=ATOL)
                if not sol.success:
                    raise SystemExit(f"solve_ivp failed at t = {a} s: {sol.message}")
                y = sol.y[:, -1]
            out[n + 1] = y
        return out

    times, out = time_runs(run, args.repeat, args.min_time, max_runs=50)
    p3, p8, p11, q14 = out[-1]
    omega = out[:, 1] / J
    final = {"p3": p3, "p8": p8, "p11": p11, "q14": q14,
             "i": p3 / L, "omega": p8 / J, "v_c": q14 / Cf}
    name = "buck_motor_pwm_1s/scipy_lsoda_segments"
    # The mean over the last 10 ms: the last ten samples, one per period.
    emit(name, times, final, segments=2 * n_periods,
         omega_mean_last_10ms=float(np.mean(omega[-10:])))
    note(f"{name}: median {np.median(times):.1f} ms over {len(times)} runs")


if __name__ == "__main__":
    main()

//! What the hidden-effect test files share: a deterministic Gaussian noise
//! generator, and the one-line summary of an explanation the batteries print.

#![allow(dead_code)] // each test file uses its part

use modelgap::Explanation;

/// A small deterministic Gaussian generator (Box–Muller on a xorshift).
pub struct Noise(pub u64);

impl Noise {
    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Standard normal.
    pub fn gauss(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

/// A battery's row: the case, the verdict, each output's error after as a
/// multiple of its floor, and the chosen effects with their values.
pub fn summary(name: &str, ex: &Explanation) -> String {
    let chosen: Vec<String> = (ex.chosen.iter())
        .map(|c| {
            let ps: Vec<String> = (c.params.iter())
                .map(|p| format!("{}={:.4e}", p.name, p.value))
                .collect();
            format!("{} [{}]", c.candidate.id, ps.join(" "))
        })
        .collect();
    let floors: Vec<String> = (ex.outputs.iter())
        .map(|o| format!("{} {:.2}x", o.name, o.rms_after / o.noise_floor))
        .collect();
    let verdict: String = format!("{:?}", ex.verdict).chars().take(14).collect();
    format!(
        "{name:<32} {verdict:<14} {} | {}",
        floors.join(" "),
        chosen.join(" + ")
    )
}

/// The chosen effects' ids, their parameters by name, and the explanation's text.
pub fn chosen(ex: &Explanation) -> (Vec<String>, Vec<(String, f64)>, String) {
    let ids = ex.chosen.iter().map(|c| c.candidate.id.clone()).collect();
    let params = (ex.chosen.iter())
        .flat_map(|c| c.params.iter().map(|p| (p.name.clone(), p.value)))
        .collect();
    (ids, params, modelgap::story::explanation_text(ex, 6))
}

/// A parameter's value by name (the test fails, showing `text`, when there is none).
pub fn value(params: &[(String, f64)], name: &str, text: &str) -> f64 {
    (params.iter().find(|(n, _)| n == name))
        .unwrap_or_else(|| panic!("no {name}:\n{text}"))
        .1
}

/// Explains one case of a battery and prints its row with the time it took
/// (and the whole text when the `PROBE` environment variable names the case;
/// with `ONLY` set, only the cases whose name contains it).
pub fn print_row(name: &str, explain: impl FnOnce() -> Explanation) {
    if std::env::var("ONLY").is_ok_and(|o| !name.contains(&o)) {
        return;
    }
    let t0 = std::time::Instant::now();
    let ex = explain();
    println!(
        "{}  ({:.1} s)",
        summary(name, &ex),
        t0.elapsed().as_secs_f64()
    );
    if std::env::var("PROBE").is_ok_and(|p| name.contains(&p)) {
        println!("{}", modelgap::story::explanation_text(&ex, 8));
    }
}

impl Noise {
    /// `y` with white noise of `white` × its range and AR(0.9) noise of
    /// `coloured` × its range (unit variance before scaling) added.
    pub fn added(&mut self, y: Vec<f64>, white: f64, coloured: f64) -> Vec<f64> {
        let gain = (1.0_f64 - 0.81).sqrt();
        let range = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut ar = 0.0;
        y.iter()
            .map(|v| {
                ar = 0.9 * ar + gain * self.gauss();
                v + white * range * self.gauss() + coloured * range * ar
            })
            .collect()
    }
}

/// One classical Runge–Kutta step of `dx/dt = f(t, x)` from `t` over `h`.
pub fn rk4_step<const N: usize>(
    f: impl Fn(f64, [f64; N]) -> [f64; N],
    t: f64,
    x: &mut [f64; N],
    h: f64,
) {
    let add = |a: [f64; N], b: [f64; N], c: f64| std::array::from_fn(|i| a[i] + c * b[i]);
    let k1 = f(t, *x);
    let k2 = f(t + h / 2.0, add(*x, k1, h / 2.0));
    let k3 = f(t + h / 2.0, add(*x, k2, h / 2.0));
    let k4 = f(t + h, add(*x, k3, h));
    for i in 0..N {
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

/// Classical Runge–Kutta, the outside generators' integrator: `samples` samples `dt`
/// apart from t = 0, `sub` steps each; `sample(t, &state)` sees the state at each sample
/// time before the step on.
pub fn rk4<const N: usize>(
    mut s: [f64; N],
    f: impl Fn(f64, [f64; N]) -> [f64; N],
    dt: f64,
    samples: usize,
    sub: usize,
    mut sample: impl FnMut(f64, &[f64; N]),
) {
    let h = dt / sub as f64;
    let add = |a: [f64; N], b: [f64; N], c: f64| {
        let mut out = a;
        for (o, d) in out.iter_mut().zip(b) {
            *o += c * d;
        }
        out
    };
    for k in 0..samples {
        let t = k as f64 * dt;
        sample(t, &s);
        for j in 0..sub {
            let t0 = t + j as f64 * h;
            let k1 = f(t0, s);
            let k2 = f(t0 + h / 2.0, add(s, k1, h / 2.0));
            let k3 = f(t0 + h / 2.0, add(s, k2, h / 2.0));
            let k4 = f(t0 + h, add(s, k3, h));
            for i in 0..N {
                s[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
    }
}

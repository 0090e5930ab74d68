//! Hidden effects on a DC motor simulated by a generator that is not
//! modelgap's: the motor's equations written out by hand and integrated with
//! classical Runge–Kutta, each case adding one effect in a form the menu does
//! not have (sharp or asymmetric friction, an eccentric mass, a torque at a
//! fixed frequency, heating of the armature, cores that saturate in three
//! shapes, a lagging, quantised or drifting speed sensor, a driver gain below
//! one), with white or coloured noise.
//!
//! `cargo test --release --test outside_motor -- --ignored --nocapture`
//! prints the table the docs quote (docs/measurement-loop.md); the cases marked CI there
//! are also asserted in every run.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in tests, a panic is a failure

mod common;
use common::{Noise, chosen, print_row, value};

use modelgap::bond::simulate::Hold;
use modelgap::bond::{BondModel, library};
use modelgap::{ExplainOptions, Explanation, Recording, Signal, Verdict, explain};

/// What the hidden motor has beyond the nominal one.
#[derive(Clone, Copy, Debug, Default)]
struct Hidden {
    /// Extra shaft torque as a function of (ω, θ, t).
    torque: Option<fn(f64, f64, f64) -> f64>,
    /// The driver's gain on the commanded voltage.
    driver_gain: Option<f64>,
    /// R grows as R (1 + heating · E), E = ∫ R i² dt the heat it has dissipated.
    heating: f64,
    /// The inductor's flux saturates: its current at a flux ψ (Wb).
    core: Option<fn(f64) -> f64>,
    /// The speed sensor: first-order lag τ (s).
    sensor_lag: f64,
    /// The speed sensor: quantisation step (rad/s).
    sensor_step: f64,
    /// The driver's dead zone (V): it delivers sign(v) max(|v| − δ, 0).
    dead_zone: f64,
    /// The driver's limit (V): it delivers at most this either way.
    limit: Option<f64>,
    /// The speed sensor's gain (a tachometer constant off).
    sensor_gain: Option<f64>,
    /// The speed sensor's pure delay, in whole samples.
    sensor_delay: usize,
    /// Play in the drive: (the inertia behind the gap, the gap's half-width in
    /// rad). The motor keeps `J` less that inertia; the load is driven through
    /// a Hunt–Crossley contact (`k δ^1.5 + λ δ^1.5 δ̇`) once the gap closes.
    backlash: Option<(f64, f64)>,
    /// The torque constant varies around a turn, `K (1 + a sin nθ)`: (a, n) — a torque
    /// ripple in proportion to the current (a winding's field that is not sinusoidal).
    torque_ripple: Option<(f64, f64)>,
    /// The back-EMF follows the same `K (1 + a sin nθ)` (what energy conservation asks of
    /// a winding's torque ripple).
    emf_ripple: bool,
    /// The speed sensor's zero drifts at this rate ((rad/s)/s) from the start.
    sensor_drift: f64,
}

/// The Hunt–Crossley contact of the backlash case: stiffness (N m/rad^1.5)
/// and damping (N m s/rad^2.5).
const CONTACT_K: f64 = 8000.0;
const CONTACT_LAMBDA: f64 = 6000.0;

const R: f64 = 1.0;
const L: f64 = 5e-3;
const K: f64 = 0.05;
const J: f64 = 1e-4;
const BETA: f64 = 1e-5;

/// The motor's own inertia: `J`, less what sits behind a gap.
fn motor_inertia(h: &Hidden) -> f64 {
    J - h.backlash.map_or(0.0, |(jl, _)| jl)
}

/// State: [ψ (flux of the inductor), p = J ω, θ, E = ∫ R i² dt, sensor,
/// the load's momentum, the twist across the gap].
fn derivative(h: &Hidden, v: f64, t: f64, x: [f64; 7]) -> [f64; 7] {
    let i = h.core.map_or(x[0] / L, |current| current(x[0]));
    let w = x[1] / motor_inertia(h);
    // The contact torque on the load across the gap, and the load's speed.
    let (contact, w_load) = match h.backlash {
        None => (0.0, w),
        Some((jl, b)) => {
            let w_load = x[5] / jl;
            let depth = x[6].abs() - b;
            let torque = if depth > 0.0 {
                let d = depth.powf(1.5);
                x[6].signum() * CONTACT_K * d + CONTACT_LAMBDA * d * (w - w_load)
            } else {
                0.0
            };
            // A contact pushes; it never pulls.
            let torque = if torque * x[6].signum() > 0.0 {
                torque
            } else {
                0.0
            };
            (torque, w_load)
        }
    };
    let r = R * (1.0 + h.heating * x[3]);
    let vd = v.signum() * (v.abs() - h.dead_zone).max(0.0) * h.driver_gain.unwrap_or(1.0);
    let vd = h.limit.map_or(vd, |l| vd.clamp(-l, l));
    let extra = h.torque.map_or(0.0, |f| f(w, x[2], t));
    let sensor = if h.sensor_lag > 0.0 {
        (w - x[4]) / h.sensor_lag
    } else {
        0.0
    };
    let ripple = h
        .torque_ripple
        .map_or(1.0, |(a, n)| 1.0 + a * (n * x[2]).sin());
    let k_emf = if h.emf_ripple { K * ripple } else { K };
    [
        vd - r * i - k_emf * w,
        K * ripple * i - BETA * w - extra - contact,
        w,
        r * i * i,
        sensor,
        contact,
        w - w_load,
    ]
}

/// The saturation current of the cores below (A).
const SATURATION_CURRENT: f64 = 4.0;

/// A core whose flux saturates as `ψ = L i_s tanh(i/i_s)`: its current at a flux.
fn tanh_core(psi: f64) -> f64 {
    let is = SATURATION_CURRENT;
    is * (psi / (L * is)).clamp(-0.999_999, 0.999_999).atanh()
}

/// A Frohlich core, `ψ = L i / (1 + |i|/i_s)`: its current at a flux.
fn frohlich_core(psi: f64) -> f64 {
    let limit = L * SATURATION_CURRENT;
    psi / (L * (1.0 - (psi.abs() / limit).min(0.999_999)))
}

/// A core that saturates to the winding's air-core inductance, a tenth of `L`:
/// `ψ = L i / 10 + 0.9 L i_s tanh(i/i_s)` (no flux limit). Its current at a flux,
/// by Newton's method from the air core's current (the flux grows at least as
/// `L/10` per ampere, so each step lands at or before the root).
fn air_core(psi: f64) -> f64 {
    let is = SATURATION_CURRENT;
    let flux = |i: f64| 0.1 * L * i + 0.9 * L * is * (i / is).tanh();
    let slope = |i: f64| 0.1 * L + 0.9 * L / (i / is).cosh().powi(2);
    let mut i = psi / L;
    for _ in 0..60 {
        let step = (flux(i) - psi) / slope(i);
        i -= step;
        if step.abs() <= 1e-13 * i.abs().max(1.0) {
            break;
        }
    }
    i
}

fn drive(t: f64) -> f64 {
    use std::f64::consts::TAU;
    6.0 * (TAU * 0.7 * t).sin() + 2.0 * (TAU * 3.3 * t).sin() + 1.0 * (TAU * 11.0 * t).sin()
}

/// 6 s at 1 kHz; noise `white` × range, plus AR(0.9) noise `coloured` × range.
fn record(h: &Hidden, white: f64, coloured: f64, seed: u64) -> Recording {
    let dt = 1e-3;
    let n = 6000;
    let sub = 20;
    let mut x = [0.0; 7];
    let (mut ti, mut om, mut vs, mut ts) = (vec![], vec![], vec![], vec![]);
    for k in 0..=n {
        let t = k as f64 * dt;
        let i = h.core.map_or(x[0] / L, |current| current(x[0]));
        let w = if h.sensor_lag > 0.0 {
            x[4]
        } else {
            x[1] / motor_inertia(h)
        };
        let w = if h.sensor_step > 0.0 {
            (w / h.sensor_step).round() * h.sensor_step
        } else {
            w
        };
        let w = w + h.sensor_drift * t;
        ts.push(t);
        vs.push(drive(t));
        ti.push(i);
        om.push(w);
        let hh = dt / sub as f64;
        for s in 0..sub {
            let t0 = t + s as f64 * hh;
            let f = |tt: f64, xx: [f64; 7]| derivative(h, drive(tt), tt, xx);
            let add = |a: [f64; 7], b: [f64; 7], c: f64| {
                let mut o = a;
                for j in 0..7 {
                    o[j] += c * b[j];
                }
                o
            };
            let k1 = f(t0, x);
            let k2 = f(t0 + hh / 2.0, add(x, k1, hh / 2.0));
            let k3 = f(t0 + hh / 2.0, add(x, k2, hh / 2.0));
            let k4 = f(t0 + hh, add(x, k3, hh));
            for j in 0..7 {
                x[j] += hh / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
            }
        }
    }
    let mut rng = Noise(0x9E37_79B9_7F4A_7C15 ^ seed.wrapping_mul(0x2545_F491_4F6C_DD1D));
    let mut noisy = |y: &[f64]| -> Vec<f64> {
        let range = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut ar = 0.0;
        let gain = (1.0_f64 - 0.81).sqrt();
        y.iter()
            .map(|v| {
                ar = 0.9 * ar + gain * rng.gauss();
                v + white * range * rng.gauss() + coloured * range * ar
            })
            .collect()
    };
    if let Some(g) = h.sensor_gain {
        om.iter_mut().for_each(|w| *w *= g);
    }
    if h.sensor_delay > 0 {
        let d = h.sensor_delay;
        om = (0..om.len()).map(|k| om[k.saturating_sub(d)]).collect();
    }
    let ti = noisy(&ti);
    let om = if h.sensor_step > 0.0 { om } else { noisy(&om) };
    Recording::new(
        ts,
        vec![
            Signal {
                name: "V".into(),
                values: vs,
            },
            Signal {
                name: "i".into(),
                values: ti,
            },
            Signal {
                name: "omega".into(),
                values: om,
            },
        ],
    )
    .unwrap()
}

fn motor_model() -> BondModel {
    let mut g = library::builtin("dc-motor").unwrap();
    g.add_input("V", 12.0, "V", "armature voltage").unwrap();
    BondModel::new(g).with_hold(Hold::Linear)
}

fn explained(rec: &Recording) -> Explanation {
    explain(&motor_model(), rec, &ExplainOptions::default()).unwrap()
}

fn cases() -> Vec<(&'static str, Hidden)> {
    vec![
        ("control", Hidden::default()),
        (
            "sharp coulomb",
            Hidden {
                torque: Some(|w, _, _| 0.01 * (w / 0.01).tanh()),
                ..Hidden::default()
            },
        ),
        (
            "asymmetric coulomb",
            Hidden {
                torque: Some(|w, _, _| {
                    let s = (w / 0.05).tanh();
                    if s > 0.0 { 0.012 * s } else { 0.006 * s }
                }),
                ..Hidden::default()
            },
        ),
        (
            "periodic load 7.5 Hz",
            Hidden {
                // A neighbouring machine's vibration: a torque at a fixed frequency, locked
                // to time, not to the angle (none of the drive's 0.7, 3.3 and 11 Hz).
                torque: Some(|_, _, t| 0.004 * (std::f64::consts::TAU * 7.5 * t + 0.2).sin()),
                ..Hidden::default()
            },
        ),
        (
            "exponential Stribeck",
            Hidden {
                // A Stribeck dip that decays exponentially, not as a Gaussian.
                torque: Some(|w, _, _| {
                    (0.006 + 0.015 * (-w.abs() / 5.0).exp()) * (w / 0.05).tanh()
                }),
                ..Hidden::default()
            },
        ),
        (
            "viscous friction growing over the run",
            Hidden {
                // A bearing whose grease warms: its viscous friction rises from nothing to
                // 3e-5 N m s/rad (three times the model's) at a steady rate over the 6 s.
                torque: Some(|w, _, t| 5e-6 * t * w),
                ..Hidden::default()
            },
        ),
        (
            "speed sensor drifting 0.3 rad/s per s",
            Hidden {
                sensor_drift: 0.3,
                ..Hidden::default()
            },
        ),
        (
            "eccentric mass",
            Hidden {
                torque: Some(|_, th, _| 0.01 * (th + 0.3).sin()),
                ..Hidden::default()
            },
        ),
        (
            "cogging 6",
            Hidden {
                torque: Some(|_, th, _| 0.008 * (6.0 * th).sin()),
                ..Hidden::default()
            },
        ),
        (
            "torque ripple 6, 10 % of K i",
            Hidden {
                torque_ripple: Some((0.1, 6.0)),
                ..Hidden::default()
            },
        ),
        (
            "winding ripple 6, 10 % (torque and EMF)",
            Hidden {
                torque_ripple: Some((0.1, 6.0)),
                emf_ripple: true,
                ..Hidden::default()
            },
        ),
        (
            "load step 2.7 s",
            Hidden {
                torque: Some(|_, _, t| if t > 2.7 { 0.02 } else { 0.0 }),
                ..Hidden::default()
            },
        ),
        (
            "driver gain 0.85",
            Hidden {
                driver_gain: Some(0.85),
                ..Hidden::default()
            },
        ),
        (
            "armature heating",
            Hidden {
                heating: 0.01,
                ..Hidden::default()
            },
        ),
        (
            "saturation tanh",
            Hidden {
                core: Some(tanh_core),
                ..Hidden::default()
            },
        ),
        (
            "saturation Frohlich",
            Hidden {
                core: Some(frohlich_core),
                ..Hidden::default()
            },
        ),
        (
            "saturation to an air core",
            Hidden {
                core: Some(air_core),
                ..Hidden::default()
            },
        ),
        (
            "sensor lag 4 ms",
            Hidden {
                sensor_lag: 4e-3,
                ..Hidden::default()
            },
        ),
        (
            "fan",
            Hidden {
                torque: Some(|w, _, _| 2e-6 * w * w.abs()),
                ..Hidden::default()
            },
        ),
        (
            "stribeck",
            Hidden {
                torque: Some(|w, _, _| {
                    (0.008 + 0.012 * (-(w / 4.0) * (w / 4.0)).exp()) * (w / 0.2).tanh()
                }),
                ..Hidden::default()
            },
        ),
        (
            "driver dead zone",
            Hidden {
                dead_zone: 0.5,
                ..Hidden::default()
            },
        ),
        (
            "driver limit 6 V",
            Hidden {
                limit: Some(6.0),
                ..Hidden::default()
            },
        ),
        (
            "sensor lag+quantised",
            Hidden {
                sensor_lag: 4e-3,
                sensor_step: 0.5,
                ..Hidden::default()
            },
        ),
        (
            "speed sensor gain 0.97",
            Hidden {
                sensor_gain: Some(0.97),
                ..Hidden::default()
            },
        ),
        (
            "speed sensor delay 3 ms",
            Hidden {
                sensor_delay: 3,
                ..Hidden::default()
            },
        ),
        (
            "sensor quantised",
            Hidden {
                sensor_step: 0.5,
                ..Hidden::default()
            },
        ),
        (
            "backlash 0.03 rad",
            Hidden {
                backlash: Some((6e-5, 0.03)),
                ..Hidden::default()
            },
        ),
    ]
}

fn case(name: &str) -> Hidden {
    cases()
        .into_iter()
        .find(|(n, _)| *n == name)
        .map(|(_, h)| h)
        .unwrap()
}

/// Explain's options with the sensors' noise as their maker states it (2e-3 of
/// each range), instead of the floor estimated from the data.
fn makers_noise(rec: &Recording) -> ExplainOptions {
    let noise = ["i", "omega"].map(|name| {
        let y = &rec.signal(name).unwrap().values;
        (
            name.to_string(),
            2e-3 * y.iter().fold(0.0_f64, |m, v| m.max(v.abs())),
        )
    });
    ExplainOptions {
        noise: noise.into_iter().collect(),
        ..ExplainOptions::default()
    }
}

fn within(value: f64, truth: f64, tolerance: f64, text: &str) {
    assert!(
        (value - truth).abs() <= tolerance * truth.abs(),
        "{value} is not within {}% of {truth}:\n{text}",
        100.0 * tolerance
    );
}

fn at_floor(ex: &Explanation, text: &str) {
    for o in &ex.outputs {
        assert!(
            o.rms_after <= 1.3 * o.noise_floor,
            "{} left at {:.2}x the floor:\n{text}",
            o.name,
            o.rms_after / o.noise_floor
        );
    }
}

#[test]
fn backlash_in_the_drive_is_named_with_its_gap_and_the_inertia_behind_it() {
    let rec = record(&case("backlash 0.03 rad"), 2e-3, 0.0, 17);
    let ex = explain(&motor_model(), &rec, &makers_noise(&rec)).unwrap();
    let (ids, _, text) = chosen(&ex);
    println!("{text}");
    // The generator's contact is Hunt–Crossley (k δ^1.5 with damping λ δ^1.5 δ̇), the
    // candidate's a power law damped at a fixed ratio: the gap and the inertia behind it
    // are what must come out. Where in the gap the load sits is a state no force holds, so
    // an open-loop simulation's small errors there stay: the verdict is honest about what
    // is left (partial at 1.3x the floor, measured), not claimed at the floor.
    assert_eq!(
        ids.first().map(String::as_str),
        Some("backlash@1m"),
        "{text}"
    );
    let first: Vec<(String, f64)> = (ex.chosen[0].params.iter())
        .map(|p| (p.name.clone(), p.value))
        .collect();
    within(value(&first, "b", &text), 0.03, 0.1, &text);
    within(value(&first, "J2", &text), 6e-5, 0.05, &text);
    // What lies above the floor falls at least threefold on each output (measured: 8x on
    // the current, 3.5x on the speed).
    let excess = |rms: f64, floor: f64| (rms * rms - floor * floor).max(0.0).sqrt();
    for o in &ex.outputs {
        assert!(
            excess(o.rms_after, o.noise_floor) < excess(o.rms_before, o.noise_floor) / 3.0,
            "{}:\n{text}",
            o.name
        );
    }
    assert!(
        matches!(
            ex.verdict,
            Verdict::EffectFound | Verdict::TwoEffects | Verdict::Partial
        ),
        "{text}"
    );
}

#[test]
fn armature_heating_is_named_with_its_rate() {
    let ex = explained(&record(&case("armature heating"), 2e-3, 0.0, 11));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["heating@R"], "{text}");
    within(value(&params, "a_heat", &text), 0.01, 0.05, &text);
    at_floor(&ex, &text);
}

#[test]
fn an_eccentric_mass_under_coloured_noise_is_a_first_harmonic_of_the_angle() {
    let ex = explained(&record(&case("eccentric mass"), 1e-3, 2e-3, 12));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids.len(), 1, "{text}");
    assert!(ids[0].starts_with("law@1m:"), "{text}");
    let (s, c) = (
        value(&params, "c_sin1", &text),
        value(&params, "c_cos1", &text),
    );
    // 0.01 sin(θ + 0.3) = 0.01 cos 0.3 sin θ + 0.01 sin 0.3 cos θ.
    within(s.hypot(c), 0.01, 0.05, &text);
    assert!(
        (c.atan2(s) - 0.3).abs() < 0.05,
        "phase {}:\n{text}",
        c.atan2(s)
    );
}

#[test]
fn a_core_that_saturates_towards_a_flux_limit_is_named_with_its_limit() {
    // A Frohlich core, ψ = L i / (1 + |i|/i_s): its current is p/L (1 − |p|/(L i_s))^-1,
    // the family's n = 1, m = 1, and the flux it cannot pass is L i_s.
    let limit = L * SATURATION_CURRENT;
    let ex = explained(&record(&case("saturation Frohlich"), 2e-3, 0.0, 21));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["flux-limit@L"], "{text}");
    within(value(&params, "psi_lim", &text), limit, 0.05, &text);
    within(value(&params, "n_lim", &text), 1.0, 0.05, &text);
    within(value(&params, "m_lim", &text), 1.0, 0.1, &text);
    at_floor(&ex, &text);
    // A tanh flux, ψ = L i_s tanh(i/i_s): the same limit, a knee the family draws with
    // n ≈ 2 and m ≈ 1/3 (the pole of atanh is logarithmic, the family's a power).
    let ex = explained(&record(&case("saturation tanh"), 2e-3, 0.0, 22));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["flux-limit@L"], "{text}");
    within(value(&params, "psi_lim", &text), limit, 0.1, &text);
    at_floor(&ex, &text);
}

#[test]
fn a_torque_at_a_fixed_frequency_is_a_periodic_law_with_its_frequency_and_phase() {
    // 0.004 sin(2π · 7.5 t + 0.2) N m: locked to time, not to the angle, at none of the
    // drive's frequencies.
    let ex = explained(&record(&case("periodic load 7.5 Hz"), 2e-3, 0.0, 23));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids.len(), 1, "{text}");
    assert!(ids[0].starts_with("law@1m:"), "{text}");
    within(value(&params, "f_sint", &text), 7.5, 0.001, &text);
    let (s, c) = (
        value(&params, "c_sint", &text),
        value(&params, "c_cost", &text),
    );
    // 0.004 sin(ωt + 0.2) = 0.004 cos 0.2 sin ωt + 0.004 sin 0.2 cos ωt.
    within(s.hypot(c), 0.004, 0.05, &text);
    let phase = c.atan2(s);
    assert!((phase - 0.2).abs() < 0.05, "phase {phase}:\n{text}");
    at_floor(&ex, &text);
}

#[test]
fn a_viscous_friction_that_grows_over_the_run_is_the_time_times_the_speed() {
    // 5e-6 t ω: from nothing to three times the model's viscous friction over 6 s.
    let ex = explained(&record(
        &case("viscous friction growing over the run"),
        2e-3,
        0.0,
        25,
    ));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["law@1m:c_prod * t * '1m'.f"], "{text}");
    within(value(&params, "c_prod", &text), 5e-6, 0.05, &text);
    at_floor(&ex, &text);
}

#[test]
fn a_speed_sensor_whose_zero_drifts_under_coloured_noise_is_named_a_drift() {
    let ex = explained(&record(
        &case("speed sensor drifting 0.3 rad/s per s"),
        1e-3,
        2e-3,
        24,
    ));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["drift@omega"], "{text}");
    within(value(&params, "drift", &text), 0.3, 0.05, &text);
}

#[test]
fn a_lagging_quantised_speed_sensor_is_named_and_its_steps_recognised() {
    let ex = explained(&record(&case("sensor lag+quantised"), 2e-3, 0.0, 13));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["lag@omega"], "{text}");
    within(value(&params, "tau", &text), 4e-3, 0.05, &text);
    assert!(text.contains("quantised in steps of 0.5"), "{text}");
    at_floor(&ex, &text);
}

#[test]
fn a_speed_sensor_that_reads_low_or_late_is_named_as_such() {
    let ex = explained(&record(&case("speed sensor gain 0.97"), 2e-3, 0.0, 15));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["scale@omega"], "{text}");
    within(value(&params, "k_sensor", &text), 0.97, 0.005, &text);
    at_floor(&ex, &text);
    // Three samples late: a delay, not a lag (a lag of the same size leaves 1.06x).
    let ex = explained(&record(&case("speed sensor delay 3 ms"), 1e-3, 2e-3, 16));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["delay@omega"], "{text}");
    within(value(&params, "delay", &text), 3e-3, 0.05, &text);
}

#[test]
fn a_driver_at_its_rail_is_named_a_limit() {
    let ex = explained(&record(&case("driver limit 6 V"), 2e-3, 0.0, 17));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["limit@V"], "{text}");
    within(value(&params, "v_max", &text), 6.0, 0.05, &text);
    at_floor(&ex, &text);
}

#[test]
fn a_dead_zone_in_the_driver_is_named_with_its_width() {
    let ex = explained(&record(&case("driver dead zone"), 1e-3, 2e-3, 14));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["deadzone@V"], "{text}");
    within(value(&params, "delta", &text), 0.5, 0.05, &text);
}

#[test]
fn a_torque_ripple_in_proportion_to_the_current_is_the_current_times_a_harmonic() {
    // K (1 + 0.1 sin 6θ) i on the shaft: the missing torque is 0.1 K i sin 6θ, read
    // where it acts with the winding's current one gyrator away (the law's effort is
    // counted against the shaft's motion, as a friction's: −0.1 K).
    let ex = explained(&record(
        &case("torque ripple 6, 10 % of K i"),
        2e-3,
        0.0,
        21,
    ));
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids.len(), 1, "{text}");
    assert!(
        ids[0].starts_with("law@1m:") && ids[0].contains("* sin(6 *"),
        "{text}"
    );
    within(value(&params, "c_6sin", &text), -0.1 * K, 0.05, &text);
    at_floor(&ex, &text);
}

#[test]
fn a_winding_whose_constant_varies_around_a_turn_is_named_a_ripple_of_the_gyrator() {
    // K (1 + 0.1 sin 6θ) in the torque and the back-EMF alike: one effect at both ends
    // of the gyrator, where a law at either place sees half of it.
    let rec = record(
        &case("winding ripple 6, 10 % (torque and EMF)"),
        2e-3,
        0.0,
        22,
    );
    let (ids, _, text) = chosen(&explained(&rec));
    assert_eq!(ids, ["ripple@k"], "{text}");
    // The current's third differences carry the ripple itself, so its floor is suspect and
    // the verdict partial; with the sensors' noise as their maker states it (2e-3 of each
    // range), the ripple explains the recording.
    let ex = explain(&motor_model(), &rec, &makers_noise(&rec)).unwrap();
    let (ids, params, text) = chosen(&ex);
    assert_eq!(ids, ["ripple@k"], "{text}");
    within(value(&params, "a_rip_s", &text), 0.1, 0.05, &text);
    within(value(&params, "N_rip", &text), 6.0, 0.01, &text);
    assert!(value(&params, "a_rip_c", &text).abs() < 0.005, "{text}");
    at_floor(&ex, &text);
    assert_eq!(ex.verdict, Verdict::EffectFound, "{text}");
}

#[test]
#[ignore = "about two minutes in release: the battery the docs quote"]
fn battery() {
    for (white, coloured) in [(2e-3, 0.0), (1e-3, 2e-3)] {
        println!("noise: white {white}, AR(0.9) {coloured} of range");
        for (name, h) in cases() {
            let rec = record(&h, white, coloured, 7);
            print_row(name, || explained(&rec));
        }
    }
}

//! Honest verdicts (issue 11): "nothing is missing" only with the evidence. A
//! sensor that lags and quantises, a dead sensor, a time column written in
//! ms and a one-sample recording each get an honest answer — never
//! `nothing-missing` — while a right model on white and on coloured noise
//! keeps getting it, seed after seed (the false-alarm rate).

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed setup should stop the test

use modelgap::bond::hidden::{HiddenCase, RecordingOptions, cases, record};
use modelgap::bond::{BondModel, library};
use modelgap::{ExplainOptions, Explanation, Recording, Verdict, explain};

fn case(name: &str) -> HiddenCase {
    cases()
        .into_iter()
        .find(|c| c.name == name)
        .expect("a case of that name")
}

fn explained(rec: &Recording) -> Explanation {
    let model = BondModel::new(library::builtin("dc-motor").unwrap());
    explain(&model, rec, &ExplainOptions::default()).unwrap()
}

fn story(ex: &Explanation) -> String {
    modelgap::story::explanation_text(ex, 5)
}

#[test]
fn a_lagging_quantised_speed_sensor_is_never_nothing_missing() {
    // A 6 s run, the sensors lagging 3 ms and quantised at 0.4 % of full scale
    // (about 1 rad/s and 0.1 A). The motor is linear and both sensors lag alike, so one lag
    // of the driver (`actuator-lag@V`) predicts exactly what the two sensors' lags do, with
    // one parameter: it is named (before the driver's lag was on the menu, the speed
    // sensor's lag was, leaving the current's); what is left under the quantisation is
    // named too, never called noise.
    let rec = record(
        &case("nothing"),
        &RecordingOptions {
            duration: 6.0,
            sensor_lag: 3e-3,
            quantisation: 0.004,
            ..RecordingOptions::default()
        },
    )
    .unwrap();
    let ex = explained(&rec);
    assert!(
        matches!(ex.verdict, Verdict::Partial | Verdict::Unexplained),
        "{}",
        story(&ex)
    );
    let first = ex.chosen.first().expect("the lag is chosen");
    assert_eq!(first.candidate.id, "actuator-lag@V", "{}", story(&ex));
    let tau = first.params[0].value;
    assert!((2e-3..4e-3).contains(&tau), "tau = {tau}\n{}", story(&ex));
    assert!(
        ex.reasons
            .iter()
            .any(|r| r.starts_with("i:") || r.starts_with("omega:")),
        "the residual must be named:\n{}",
        story(&ex)
    );
}

#[test]
fn dead_sensors_cannot_be_judged() {
    let rec = record(
        &case("coulomb"),
        &RecordingOptions {
            dead: vec!["i".into(), "omega".into()],
            ..RecordingOptions::default()
        },
    )
    .unwrap();
    let ex = explained(&rec);
    assert_eq!(ex.verdict, Verdict::CannotJudge, "{}", story(&ex));
    assert!(story(&ex).contains("reads 0 throughout"), "{}", story(&ex));
    assert!(ex.ranked.is_empty());
}

#[test]
fn one_dead_sensor_is_left_out_and_said() {
    let rec = record(
        &case("coulomb"),
        &RecordingOptions {
            dead: vec!["i".into()],
            ..RecordingOptions::default()
        },
    )
    .unwrap();
    let ex = explained(&rec);
    assert_eq!(ex.outputs.len(), 1, "{}", story(&ex));
    assert_eq!(ex.outputs[0].name, "omega");
    assert!(
        ex.warnings.iter().any(|w| w.contains("i reads 0")),
        "{}",
        story(&ex)
    );
    assert_ne!(ex.verdict, Verdict::NothingMissing, "{}", story(&ex));
}

#[test]
fn a_time_column_in_ms_cannot_be_judged_and_says_why() {
    let rec = record(
        &case("fault"),
        &RecordingOptions {
            time_units_per_second: 1000.0,
            ..RecordingOptions::default()
        },
    )
    .unwrap();
    let ex = explained(&rec);
    assert_eq!(ex.verdict, Verdict::CannotJudge, "{}", story(&ex));
    let why = &ex.reasons[0];
    assert!(why.contains("samples 1 s apart"), "{why}");
    assert!(why.contains("in ms"), "{why}");
}

#[test]
fn a_recording_of_a_few_samples_cannot_be_judged() {
    let full = record(&case("nothing"), &RecordingOptions::default()).unwrap();
    for n in [1, 2, 12] {
        let t = full.t()[..n].to_vec();
        let signals = full
            .signals()
            .iter()
            .map(|s| modelgap::Signal::new(s.name.clone(), s.values[..n].to_vec()))
            .collect();
        let rec = Recording::new(t, signals).unwrap();
        let ex = explained(&rec);
        assert_eq!(
            ex.verdict,
            Verdict::CannotJudge,
            "{n} samples: {}",
            story(&ex)
        );
        assert!(
            ex.reasons[0].contains(&format!("{n} sample")),
            "{:?}",
            ex.reasons
        );
        assert!(
            ex.outputs.iter().all(|o| o.rms_before.is_finite()),
            "{n} samples"
        );
    }
}

/// Explains the right model's recordings over `seeds` noise seeds and returns the seeds
/// whose verdict is not "nothing is missing" (the false alarms), with their verdict.
fn false_alarms(
    case_name: &str,
    opts: &RecordingOptions,
    seeds: std::ops::Range<u64>,
) -> Vec<(u64, Verdict)> {
    let c = case(case_name);
    let model = BondModel::new(library::builtin(&c.model).unwrap());
    seeds
        .filter_map(|seed| {
            let rec = record(
                &c,
                &RecordingOptions {
                    seed,
                    ..opts.clone()
                },
            )
            .unwrap();
            let v = explain(&model, &rec, &ExplainOptions::default())
                .unwrap()
                .verdict;
            (v != Verdict::NothingMissing).then_some((seed, v))
        })
        .collect()
}

fn white_noise() -> RecordingOptions {
    RecordingOptions {
        white: 0.002,
        coloured: 0.0,
        sensor_lag: 0.0,
        ..RecordingOptions::default()
    }
}

/// Mostly AR(1) noise with ρ = 0.95: the third-difference floor sees a sixth of it, and the
/// judge must take the rest for noise.
fn coloured_noise() -> RecordingOptions {
    RecordingOptions {
        white: 0.0005,
        coloured: 0.003,
        rho: 0.95,
        ..RecordingOptions::default()
    }
}

#[test]
fn right_model_on_white_noise_gets_nothing_missing_over_20_seeds() {
    let short = RecordingOptions {
        duration: 2.0,
        ..white_noise()
    };
    let alarms = false_alarms("nothing", &short, 100..120);
    assert!(alarms.is_empty(), "false alarms: {alarms:?}");
}

#[test]
fn right_model_on_coloured_noise_gets_nothing_missing_over_20_seeds() {
    let short = RecordingOptions {
        duration: 2.0,
        ..coloured_noise()
    };
    let alarms = false_alarms("nothing", &short, 200..220);
    assert!(alarms.is_empty(), "false alarms: {alarms:?}");
}

/// The false-alarm rates stated in docs/measurement-loop.md:
/// `cargo test --release --test honest_verdicts -- --ignored --nocapture`.
#[test]
#[ignore = "long: 260 explains; prints the false-alarm rates"]
fn false_alarm_rates() {
    for (label, case_name, opts) in [
        ("dc-motor, white noise, 4 s", "nothing", white_noise()),
        (
            "dc-motor, AR(1) 0.95 noise, 4 s",
            "nothing",
            coloured_noise(),
        ),
        (
            "dc-motor, white + AR(1) 0.9, 50 µs lag, 4 s",
            "nothing",
            RecordingOptions::default(),
        ),
        (
            "buck-motor, white noise, 4 s",
            "buck-nothing",
            white_noise(),
        ),
        (
            "buck-motor, AR(1) 0.95 noise, 4 s",
            "buck-nothing",
            coloured_noise(),
        ),
    ] {
        let alarms = false_alarms(case_name, &opts, 1000..1050);
        println!(
            "{label}: {} false alarms in 50 seeds {alarms:?}",
            alarms.len()
        );
    }
}

/// The ± of a fitted effect covers its error, neither hiding it nor inflating it: a constant
/// load of 0.01 N m found under mostly AR(0.95) noise over 12 seeds. The ± is the sandwich
/// over the fit's own residual (`FitReport::robust_std_errors`); the white formula scaled by
/// the noise's effective samples had been 45× too wide where the residual is smooth.
#[test]
fn the_uncertainty_of_a_found_load_covers_its_error_under_coloured_noise() {
    let c = case("load");
    let model = BondModel::new(library::builtin(&c.model).unwrap());
    let mut found: Vec<(f64, f64)> = Vec::new();
    for seed in 300..312 {
        let rec = record(
            &c,
            &RecordingOptions {
                seed,
                duration: 2.0,
                ..coloured_noise()
            },
        )
        .unwrap();
        let ex = explain(&model, &rec, &ExplainOptions::default()).unwrap();
        let load = (ex.ranked.iter())
            .find(|r| r.candidate.id == "load@1m" && !r.screened)
            .unwrap_or_else(|| panic!("no confirmed load:\n{}", story(&ex)));
        let p = &load.params[0];
        found.push((p.value, p.std_error));
    }
    let z: Vec<f64> = found.iter().map(|(v, se)| (v - 0.01) / se).collect();
    let rms_z = (z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64).sqrt();
    let mean = found.iter().map(|(v, _)| v).sum::<f64>() / found.len() as f64;
    let spread = (found.iter().map(|(v, _)| (v - mean).powi(2)).sum::<f64>()
        / (found.len() - 1) as f64)
        .sqrt();
    let mut se: Vec<f64> = found.iter().map(|(_, s)| *s).collect();
    se.sort_by(f64::total_cmp);
    let typical = se[se.len() / 2];
    eprintln!("found {found:?}\nz {z:?}\nrms z {rms_z}, spread {spread}, typical ± {typical}");
    assert!(z.iter().all(|z| z.abs() < 4.0), "{z:?}");
    assert!((0.4..2.0).contains(&rms_z), "RMS z {rms_z}: {z:?}");
    assert!(
        (typical / spread) < 3.0 && (typical / spread) > 0.33,
        "± {typical} against the spread of the estimates {spread}"
    );
}

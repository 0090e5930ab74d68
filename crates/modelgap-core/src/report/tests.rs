//! Tests of the report page and the comparison MCAP on synthetic data: a sine measured, a
//! model that misses a bias over part of the run, and the corrected model.

use std::io::Cursor;

use super::*;
use crate::io::mcap::read_signals;
use crate::residual::failure_windows;
use svg::zoom_window;

/// Deterministic noise in [-1, 1] (xorshift64), so tests need no random-number crate.
fn noise(n: usize, seed: u64) -> Vec<f64> {
    let mut state = seed.max(1);
    (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        })
        .collect()
}

/// A measured sine with a missing effect (a bias of 0.3 between 0.8 s and 1.4 s of every
/// 2 s), the model without it and the model with it, sampled at `dt` for `n` samples.
struct Synthetic {
    t: Vec<f64>,
    measured: Vec<f64>,
    before: Vec<f64>,
    after: Vec<f64>,
}

fn synthetic(n: usize, dt: f64, seed: u64) -> Synthetic {
    let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
    let effect = |t: f64| {
        if (0.8..1.4).contains(&(t % 2.0)) {
            0.3
        } else {
            0.0
        }
    };
    let clean: Vec<f64> = t
        .iter()
        .map(|&t| 2.0 * (std::f64::consts::TAU * 1.5 * t).sin() + effect(t))
        .collect();
    let measured: Vec<f64> = clean
        .iter()
        .zip(noise(n, seed))
        .map(|(c, e)| c + 0.02 * e)
        .collect();
    let before: Vec<f64> = t
        .iter()
        .map(|&t| 2.0 * (std::f64::consts::TAU * 1.5 * t).sin())
        .collect();
    let after: Vec<f64> = t
        .iter()
        .map(|&t| 2.0 * (std::f64::consts::TAU * 1.5 * t).sin() + 0.98 * effect(t))
        .collect();
    Synthetic {
        t,
        measured,
        before,
        after,
    }
}

fn residual_of(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x - y).collect()
}

fn plots(name: &str, s: &Synthetic) -> (SeriesPlot, ResidualPlot) {
    let before = residual_of(&s.measured, &s.before);
    let after = residual_of(&s.measured, &s.after);
    let band = 0.06;
    let windows = failure_windows(&s.t, &before, band, 0.02);
    (
        SeriesPlot {
            title: name.to_owned(),
            unit: "A".to_owned(),
            t: s.t.clone(),
            measured: s.measured.clone(),
            before: s.before.clone(),
            after: Some(s.after.clone()),
            band,
            windows: windows.clone(),
        },
        ResidualPlot {
            title: name.to_owned(),
            unit: "A".to_owned(),
            t: s.t.clone(),
            before,
            after: Some(after),
            band,
            windows,
        },
    )
}

fn ranking() -> Vec<RankingBar> {
    vec![
        RankingBar {
            label: "Coulomb friction on the motor shaft".to_owned(),
            value: 91.4,
            highlight: true,
            note: "τ_c = 0.0312 ± 0.0004 N·m; ΔBIC = −812".to_owned(),
        },
        RankingBar {
            label: "viscous friction β off".to_owned(),
            value: 23.07,
            highlight: false,
            note: "β = 1.2e-4 N·m·s/rad".to_owned(),
        },
        RankingBar {
            label: "armature resistance R off".to_owned(),
            value: 4.2,
            highlight: false,
            note: String::new(),
        },
        RankingBar {
            label: "load torque <τ_L> & \"offset\"".to_owned(),
            value: -3.5,
            highlight: false,
            note: "makes the fit worse".to_owned(),
        },
    ]
}

fn report(n: usize, dt: f64, signals: usize) -> Report {
    let mut series = Vec::new();
    let mut residuals = Vec::new();
    for k in 0..signals {
        let s = synthetic(n, dt, 7 + k as u64);
        let (sp, rp) = plots(&format!("current i{k}"), &s);
        series.push(sp);
        residuals.push(rp);
    }
    Report {
        title: "DC motor <bench 3> & \"friction\" test".to_owned(),
        summary_html_paragraphs: vec![
            "The model follows the current except while the shaft turns slowly: there the \
             measurement sits above the model by up to 0.3 A."
                .to_owned(),
            "Adding Coulomb friction on the motor shaft removes 91 % of the error; what is left \
             is noise."
                .to_owned(),
        ],
        verdict: "Missing: Coulomb friction on the motor shaft (τ_c = 0.031 N·m)".to_owned(),
        table: vec![
            vec![
                "signal".to_owned(),
                "RMS before".to_owned(),
                "RMS after".to_owned(),
                "noise σ".to_owned(),
            ],
            vec![
                "i".to_owned(),
                "0.1344 A".to_owned(),
                "0.0121 A".to_owned(),
                "0.0115 A".to_owned(),
            ],
            vec!["ω <rad/s>".to_owned(), "2.1".to_owned()],
        ],
        series,
        residuals,
        ranking: ranking(),
        ranking_unit: "% of RMS² explained".to_owned(),
        extra_svgs: vec![(
            "A domain plot <inserted as is>".to_owned(),
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"200\" height=\"40\" \
             viewBox=\"0 0 200 40\"><rect width=\"200\" height=\"40\" fill=\"#eef\"/></svg>"
                .to_owned(),
        )],
    }
}

/// Whether `text` contains `NaN`, `inf` or `infinity` as a word.
fn has_non_finite_text(text: &str) -> bool {
    text.split(|c: char| !c.is_ascii_alphanumeric())
        .any(|w| w == "NaN" || w == "inf" || w.eq_ignore_ascii_case("infinity"))
}

/// The number of points of every `<polyline>` in `svg`.
fn polyline_points(svg: &str) -> Vec<usize> {
    svg.split("<polyline")
        .skip(1)
        .map(|rest| {
            let start = rest.find("points=\"").map_or(0, |i| i + 8);
            let end = rest[start..].find('"').map_or(start, |i| start + i);
            rest[start..end].split_whitespace().count()
        })
        .collect()
}

#[test]
fn page_has_escaped_title_one_svg_per_plot_and_no_non_finite_text() {
    let r = report(4000, 1e-3, 2);
    r.validate().unwrap();
    let html = render_html(&r);
    assert!(html.starts_with("<!DOCTYPE html>"));
    let escaped = "DC motor &lt;bench 3&gt; &amp; &quot;friction&quot; test";
    assert!(html.contains(&format!("<title>{escaped}</title>")));
    assert!(html.contains(&format!("<h1>{escaped}</h1>")));
    assert!(!html.contains("<bench 3>"));
    assert!(html.contains("load torque &lt;τ_L&gt; &amp; &quot;offset&quot;"));
    assert!(html.contains("ω &lt;rad/s&gt;"));
    // 2 series, 2 residuals, 1 ranking, 1 extra.
    assert_eq!(html.matches("<svg").count(), 6);
    assert_eq!(html.matches("<figure>").count(), 6);
    assert!(!has_non_finite_text(&html));
    // Self-contained: no scripts, no external resources.
    assert!(!html.contains("<script"));
    assert!(!html.contains("src=\"http") && !html.contains("href=\"http"));
    // Order: verdict, summary, table, series, residuals, ranking, extra.
    let at = |needle: &str| html.find(needle).unwrap();
    assert!(at("class=\"verdict\"") < at("class=\"summary\""));
    assert!(at("class=\"summary\"") < at("<table>"));
    assert!(at("<table>") < at("Measured against the model"));
    assert!(at("Measured against the model") < at("Residuals: where"));
    assert!(at("Residuals: where") < at("Which effect is missing"));
    assert!(at("Which effect is missing") < at("More plots"));
    // The residual caption names the failure windows.
    assert!(html.contains("failure windows: (1) 0.8"));
}

#[test]
fn non_finite_values_are_gaps_not_text() {
    let s = synthetic(1000, 1e-3, 3);
    let (mut sp, mut rp) = plots("diverged", &s);
    let after = sp.after.as_mut().unwrap();
    for v in &mut after[600..] {
        *v = f64::NAN;
    }
    after[500] = f64::INFINITY;
    rp.after = Some(residual_of(&s.measured, after));
    let r = Report {
        title: "diverged".to_owned(),
        series: vec![sp.clone()],
        residuals: vec![rp],
        ..Report::default()
    };
    r.validate().unwrap();
    let html = render_html(&r);
    assert!(!has_non_finite_text(&html));
    assert!(html.contains("non-finite values of model after not drawn"));
    // The measured line is whole; the line after breaks at the gaps.
    assert!(polyline_points(&series_svg(&sp)).len() >= 4);
}

#[test]
fn long_series_are_decimated_to_a_small_page() {
    let r = report(200_000, 1e-4, 4);
    let html = render_html(&r);
    assert!(html.len() < 2_000_000, "page is {} bytes", html.len());
    for p in &r.series {
        let points = polyline_points(&series_svg(p));
        assert!(points.len() >= 3);
        assert!(points.iter().all(|&n| n <= 2_000), "{points:?}");
    }
    let points = polyline_points(&residual_svg(&r.residuals[0]));
    assert!(points.iter().all(|&n| n <= 2_000), "{points:?}");
}

#[test]
fn plots_have_axes_legend_and_window_shading() {
    let r = report(4000, 1e-3, 1);
    let series = series_svg(&r.series[0]);
    assert!(series.contains("time (s)"));
    assert!(series.contains("value (A)"));
    assert!(series.contains("model after adding the effect"));
    let residual = residual_svg(&r.residuals[0]);
    assert!(residual.contains("noise band ±0.06 A"));
    assert!(residual.contains("model fails"));
    // The windows at 0.8–1.4 s and 2.8–3.4 s, each a shaded rectangle with its number.
    assert_eq!(r.residuals[0].windows.len(), 2);
    let ranking = ranking_svg(&r.ranking, &r.ranking_unit);
    assert!(ranking.contains("(chosen)"));
    assert!(ranking.contains("91.4"));
    assert!(ranking.contains("-3.5"));
    assert!(ranking_svg(&[], "%").contains("no candidate effects"));
}

#[test]
fn mismatched_lengths_name_the_series_and_never_panic() {
    let mut r = report(100, 1e-2, 1);
    r.series[0].before.pop();
    match r.validate() {
        Err(CoreError::LengthMismatch {
            name,
            expected,
            found,
        }) => {
            assert_eq!(name, "current i0: before");
            assert_eq!((expected, found), (100, 99));
        }
        other => panic!("expected LengthMismatch, got {other:?}"),
    }
    // Rendering still works: the plot becomes a notice.
    let html = render_html(&r);
    assert!(html.contains("cannot draw this plot"));
    assert_eq!(html.matches("<svg").count(), 4);
    let path =
        std::env::temp_dir().join(format!("modelgap-report-bad-{}.html", std::process::id()));
    assert!(matches!(
        write_html(&r, &path),
        Err(CoreError::LengthMismatch { .. })
    ));
    assert!(!path.exists());

    let mut r = report(100, 1e-2, 1);
    r.residuals[0].after.as_mut().unwrap().push(0.0);
    let err = r.validate().unwrap_err();
    assert!(err.to_string().contains("current i0: after"), "{err}");

    let mut r = report(100, 1e-2, 1);
    r.residuals[0].t[5] = f64::NAN;
    let err = r.validate().unwrap_err();
    assert!(
        matches!(err, CoreError::InvalidArgument { name: "t", .. }),
        "{err}"
    );
    assert!(err.to_string().contains("current i0"), "{err}");

    let mut r = report(100, 1e-2, 1);
    r.residuals[0].band = -1.0;
    assert!(matches!(
        r.validate(),
        Err(CoreError::InvalidArgument { name: "band", .. })
    ));
    assert!(residual_svg(&r.residuals[0]).contains("cannot draw"));

    let mut r = report(100, 1e-2, 1);
    r.ranking[1].value = f64::NAN;
    let err = r.validate().unwrap_err();
    assert!(err.to_string().contains("viscous friction"), "{err}");
    assert!(!has_non_finite_text(&render_html(&Report {
        ranking: r.ranking.clone(),
        ..Report::default()
    })));

    // Empty plots draw without panicking.
    let empty = Report {
        series: vec![SeriesPlot::default()],
        residuals: vec![ResidualPlot::default()],
        ..Report::default()
    };
    empty.validate().unwrap();
    assert_eq!(render_html(&empty).matches("<svg").count(), 2);
}

#[test]
fn write_html_writes_the_page() {
    let r = report(500, 1e-2, 1);
    let path = std::env::temp_dir().join(format!("modelgap-report-{}.html", std::process::id()));
    write_html(&r, &path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(text, render_html(&r));
}

/// Time, output names and the measured, before and after columns of a comparison.
type ChannelsData = (
    Vec<f64>,
    Vec<String>,
    Vec<Vec<f64>>,
    Vec<Vec<f64>>,
    Vec<Vec<f64>>,
);

fn channels_data(n: usize) -> ChannelsData {
    let s = synthetic(n, 1e-3, 11);
    let w: Vec<f64> = s.measured.iter().map(|v| 10.0 * v).collect();
    let names = vec!["i".to_owned(), "omega".to_owned()];
    let measured = vec![s.measured.clone(), w.clone()];
    let before = vec![
        s.before.clone(),
        s.before.iter().map(|v| 10.0 * v).collect(),
    ];
    let after = vec![s.after.clone(), s.after.iter().map(|v| 10.0 * v).collect()];
    (s.t, names, measured, before, after)
}

#[test]
fn comparison_mcap_round_trips_residual_at_sample_times() {
    let (t, names, measured, before, after) = channels_data(300);
    let c = ComparisonChannels {
        t: &t,
        names: &names,
        measured: &measured,
        before: &before,
        after: Some(&after),
    };
    let mut file = Cursor::new(Vec::new());
    write_comparison(&c, &mut file).unwrap();
    let bytes = file.into_inner();

    let residual = read_signals(&bytes, RESIDUAL_TOPIC).unwrap();
    assert_eq!(residual.t().len(), t.len());
    for (back, &ti) in residual.t().iter().zip(&t) {
        // Log times are whole nanoseconds.
        approx::assert_abs_diff_eq!(*back, ti, epsilon = 1e-9);
    }
    // Model and residuals keep 7 significant digits of each output's full scale.
    let full_scale = |k: usize| {
        [&measured[k], &before[k], &after[k]]
            .iter()
            .flat_map(|c| c.iter())
            .fold(0.0_f64, |m, v| m.max(v.abs()))
    };
    for (k, name) in names.iter().enumerate() {
        let expected = residual_of(&measured[k], &before[k]);
        let quantum = 10f64.powi(full_scale(k).log10().floor() as i32 - 6);
        for (back, want) in residual.values(name).unwrap().iter().zip(&expected) {
            approx::assert_abs_diff_eq!(*back, *want, epsilon = 0.5 * quantum * (1.0 + 1e-9));
        }
    }
    let model_after = read_signals(&bytes, MODEL_AFTER_TOPIC).unwrap();
    let quantum = 10f64.powi(full_scale(1).log10().floor() as i32 - 6);
    for (back, want) in model_after.values("omega").unwrap().iter().zip(&after[1]) {
        approx::assert_abs_diff_eq!(*back, *want, epsilon = 0.5 * quantum * (1.0 + 1e-9));
    }
    // The measured values, data, come back exactly (float_roundtrip JSON).
    let measured_back = read_signals(&bytes, MEASURED_TOPIC).unwrap();
    assert_eq!(measured_back.values("i").unwrap(), measured[0].as_slice());
    // Every message is what its schema says.
    let checked =
        crate::io::mcap::check_messages(&bytes, crate::io::json_schema::Strictness::Complete)
            .unwrap();
    assert_eq!(checked.len(), 5);
    assert!(checked.iter().all(|c| c.messages == t.len()));
    assert!(read_signals(&bytes, MODEL_TOPIC).is_ok());
    assert!(read_signals(&bytes, RESIDUAL_AFTER_TOPIC).is_ok());

    // To a file, without `after`.
    let path = std::env::temp_dir().join(format!("modelgap-report-{}.mcap", std::process::id()));
    write_comparison_mcap(&ComparisonChannels { after: None, ..c }, &path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert!(read_signals(&bytes, RESIDUAL_TOPIC).is_ok());
    assert!(matches!(
        read_signals(&bytes, MODEL_AFTER_TOPIC),
        Err(CoreError::TopicNotFound { .. })
    ));
}

#[test]
fn comparison_mcap_rejects_bad_input_naming_the_series() {
    let (t, names, measured, before, mut after) = channels_data(50);
    after[1].pop();
    let c = ComparisonChannels {
        t: &t,
        names: &names,
        measured: &measured,
        before: &before,
        after: Some(&after),
    };
    match write_comparison(&c, Cursor::new(Vec::new())) {
        Err(CoreError::LengthMismatch { name, .. }) => assert_eq!(name, "omega (after)"),
        other => panic!("expected LengthMismatch, got {other:?}"),
    }
    let path =
        std::env::temp_dir().join(format!("modelgap-report-bad-{}.mcap", std::process::id()));
    assert!(write_comparison_mcap(&c, &path).is_err());
    assert!(!path.exists());

    let one_column = &before[..1];
    let c = ComparisonChannels {
        t: &t,
        names: &names,
        measured: &measured,
        before: one_column,
        after: None,
    };
    let err = write_comparison(&c, Cursor::new(Vec::new())).unwrap_err();
    assert!(
        matches!(
            err,
            CoreError::InvalidArgument {
                name: "columns",
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("before"), "{err}");

    let mut shifted = t.clone();
    shifted[0] = -0.5;
    let c = ComparisonChannels {
        t: &shifted,
        names: &names,
        measured: &measured,
        before: &before,
        after: None,
    };
    assert!(matches!(
        write_comparison(&c, Cursor::new(Vec::new())),
        Err(CoreError::InvalidArgument { name: "t", .. })
    ));

    let mut diverged = before.clone();
    diverged[0][7] = f64::NAN;
    let c = ComparisonChannels {
        t: &t,
        names: &names,
        measured: &measured,
        before: &diverged,
        after: None,
    };
    let err = write_comparison(&c, Cursor::new(Vec::new())).unwrap_err();
    assert!(err.to_string().contains("`i` (before)"), "{err}");

    let twice = vec!["i".to_owned(), "i".to_owned()];
    let c = ComparisonChannels {
        t: &t,
        names: &twice,
        measured: &measured,
        before: &before,
        after: None,
    };
    assert!(matches!(
        write_comparison(&c, Cursor::new(Vec::new())),
        Err(CoreError::InvalidArgument { name: "names", .. })
    ));
}

/// Writes an example page to the temp directory to look at in a browser:
/// `cargo test -p modelgap-core report::tests::write_example_page -- --ignored`.
#[test]
#[ignore = "writes a file for a person to look at"]
fn write_example_page() {
    let mut r = report(20_000, 2e-4, 2);
    r.series[1].title = "current i1, without the corrected model".to_owned();
    r.series[1].after = None;
    r.residuals[1].after = None;
    let path = std::env::temp_dir().join("modelgap-report-example.html");
    write_html(&r, &path).unwrap();
}

/// Writes a page of edge cases to the temp directory to look at: a short series drawn with
/// dots, a diverged model (gaps), a plot with mismatched lengths (a notice), negative
/// ranking values only. `cargo test -p modelgap-core report::tests::write_edge_case_page --
/// --ignored`.
#[test]
#[ignore = "writes a file for a person to look at"]
fn write_edge_case_page() {
    let s = synthetic(120, 0.03, 5);
    let (short, short_residual) = plots("short series (dots)", &s);
    let (mut diverged, _) = plots("diverged model", &synthetic(3000, 1e-3, 9));
    for (k, v) in diverged.after.as_mut().unwrap()[2000..]
        .iter_mut()
        .enumerate()
    {
        *v = if k < 50 { 1.5 + k as f64 } else { f64::NAN };
    }
    let mut bad = short.clone();
    bad.title = "bad input".to_owned();
    bad.measured.truncate(100);
    let r = Report {
        title: "Edge cases".to_owned(),
        verdict: "Nothing is missing: the residual sits at the noise floor".to_owned(),
        series: vec![short, diverged, bad],
        residuals: vec![short_residual],
        ranking: vec![
            RankingBar {
                label: "a".to_owned(),
                value: -1.0,
                highlight: false,
                note: String::new(),
            },
            RankingBar {
                label: "b".to_owned(),
                value: -12.0,
                highlight: true,
                note: String::new(),
            },
        ],
        ranking_unit: "ΔBIC".to_owned(),
        ..Report::default()
    };
    let path = std::env::temp_dir().join("modelgap-report-edge-cases.html");
    std::fs::write(path, render_html(&r)).unwrap();
}

/// The figures' y-axis names and texts, as plotters writes them (`<text ...>name</text>`).
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let start = t.find('>')? + 1;
            let end = t.find("</text>")?;
            Some(t[start..end].trim().to_owned())
        })
        .collect()
}

// Issue 16: before and after lay on top of each other because the error is thinner than a
// line at full scale. The figure now carries the residual beneath it and a zoom.
#[test]
fn a_series_figure_shows_the_error_beneath_and_zoomed() {
    let r = report(4000, 1e-3, 1);
    let p = &r.series[0];
    let svg = series_svg(p);
    let texts = svg_texts(&svg);
    assert!(
        texts.iter().any(|t| t == "measured − model (A)"),
        "no residual strip: {texts:?}"
    );
    assert!(texts.iter().any(|t| t == "noise band ±0.06 A"), "{texts:?}");
    assert!(texts.iter().any(|t| t == "model fails"), "{texts:?}");
    // The windows are numbered in the strip.
    assert!(texts.iter().any(|t| t == "1") && texts.iter().any(|t| t == "2"));
    let zoom = texts
        .iter()
        .find(|t| t.starts_with("zoom on "))
        .expect("no zoom panel");
    assert!(
        zoom.contains("before") && zoom.contains("after"),
        "the zoom says how far before and after are off: {zoom}"
    );
    // The zoom centres on the missing bias (0.8–1.4 s of every 2 s), not on noise.
    let (a, b) = zoom_window(p).unwrap();
    let centre = (a + b) / 2.0 % 2.0;
    assert!((0.8..1.4).contains(&centre), "zoom {a}–{b} s");
    assert!(b - a < 0.2 * 4.0, "the zoom is a close look: {a}–{b} s");
    // Three time axes: the signal's ticks, the strip's and the zoom's, two named.
    assert_eq!(texts.iter().filter(|t| *t == "time (s)").count(), 2);
    let html = render_html(&r);
    assert!(
        html.contains("The bottom panel zooms into"),
        "caption says so"
    );
    assert!(html.contains("The strip beneath shows measured − model"));
}

#[test]
fn a_model_that_is_right_everywhere_gets_no_zoom() {
    let t: Vec<f64> = (0..500).map(|k| f64::from(k) * 1e-3).collect();
    let y: Vec<f64> = t.iter().map(|t| t.sin()).collect();
    let p = SeriesPlot {
        title: "exact".into(),
        unit: "V".into(),
        t,
        measured: y.clone(),
        before: y,
        ..SeriesPlot::default()
    };
    assert_eq!(zoom_window(&p), None);
    assert!(!series_svg(&p).contains("zoom on"));
}

#[test]
fn a_bad_band_on_a_series_is_named() {
    let r = report(400, 1e-3, 1);
    let mut p = r.series[0].clone();
    p.band = f64::NAN;
    let e = Report {
        series: vec![p],
        ..Report::default()
    }
    .validate()
    .unwrap_err();
    assert!(e.to_string().contains("band of plot `current i0`"), "{e}");
}

#[test]
fn long_ranking_notes_wrap_inside_the_chart() {
    let note = "x = 1 ± 0.1 N m; [signature disagrees] measured i below the model and omega \
                below it first (from 0.1 s); their fault trees point at L+, R+, k+; this effect \
                would show as beta+ or beta-, which is not among them"
        .to_owned();
    let bars = vec![RankingBar {
        label: "viscous friction".into(),
        value: 3.0,
        highlight: true,
        note: note.clone(),
    }];
    let svg = ranking_svg(&bars, "%");
    let lines: Vec<String> = svg_texts(&svg)
        .into_iter()
        .filter(|t| t.contains("signature") || t.contains("among them"))
        .collect();
    assert!(lines.len() >= 2, "{lines:?}");
    assert!(lines.iter().all(|l| l.chars().count() <= 150), "{lines:?}");
    // Nothing is lost: the lines hold the whole note.
    let joined = svg_texts(&svg).join(" ");
    assert!(joined.contains("which is not among them"));
    // The chart grows with the note instead of clipping it.
    let short = ranking_svg(
        &[RankingBar {
            note: "x = 1".into(),
            ..bars[0].clone()
        }],
        "%",
    );
    let height = |s: &str| {
        let h = s.split("height=\"").nth(1).unwrap();
        h[..h.find('"').unwrap()].parse::<u32>().unwrap()
    };
    assert!(height(&svg) > height(&short));
}

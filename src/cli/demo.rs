//! `modelgap demo`: the main job on bundled data. A DC-motor recording hides a physical
//! effect the built-in model lacks; the demo shows where the model fails, ranks the effects
//! that could be missing, adds the chosen one with its fitted value and shows the error
//! fall, and writes the report. Then the same loop on cloth: a marker recording of a
//! swinging cloth hides air drag; the demo shows which markers, regions and times the scene
//! gets wrong, names the missing effect, adds it and writes the cloth report (per-vertex
//! error map, error over time, the mesh coloured by error for Foxglove). It ends with the
//! DC-motor paper's Table 7 diagnosis.
//!
//! The recordings (`examples/data/motor_hidden_effect.csv`, made by
//! `cargo run --example make_demo_data`; `examples/data/cloth_hidden_effect.csv` and its
//! scene `examples/data/cloth_scene.toml`, made by
//! `cargo run --example make_cloth_demo_data`) are embedded at compile time, so the demo
//! runs from any directory. Every number printed comes from this run; the hidden truths
//! printed are [`demo_case`] and [`cloth_demo_case`], and tests check that the bundled
//! files are still the recordings of those cases.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use clap::Args;
use modelgap::bond::hidden::{Hidden, HiddenCase};
use modelgap::bond::table7::{Table7Options, table7, table7_text};
use modelgap::bond::{BondModel, library};
use modelgap::cloth::hidden::{
    HiddenCase as ClothCase, RecordingOptions, SWING_AMPLITUDE, SWING_FREQUENCY,
    cases as cloth_cases,
};
use modelgap::cloth::markers::read_markers_csv;
use modelgap::cloth::model::{ClothModel, markers_to_recording};
use modelgap::cloth::scenes::Scene;
use modelgap::report::format_number as num;
use modelgap::story::Story;
use modelgap::{Comparison, RankedCandidate, Recording};

use super::explain::before_after;
use super::report::{Loaded, ReportParts, report_line, stop_if_interrupted};

/// The bundled recording, as CSV text.
const DEMO_CSV: &str = include_str!("../../examples/data/motor_hidden_effect.csv");

/// Where the bundled recording lives in the repository.
const DEMO_PATH: &str = "examples/data/motor_hidden_effect.csv";

/// Ranked candidates shown.
const TOP: usize = 6;

/// The bundled cloth recording, as marker CSV text.
const CLOTH_CSV: &str = include_str!("../../examples/data/cloth_hidden_effect.csv");

/// Where the bundled cloth recording lives in the repository.
const CLOTH_CSV_PATH: &str = "examples/data/cloth_hidden_effect.csv";

/// The bundled cloth scene (the model), as scene-file text.
const CLOTH_SCENE: &str = include_str!("../../examples/data/cloth_scene.toml");

/// Where the bundled cloth scene lives in the repository.
const CLOTH_SCENE_PATH: &str = "examples/data/cloth_scene.toml";

/// Vertices per side of the demo cloth (as `examples/make_cloth_demo_data.rs`).
const CLOTH_GRID: usize = 7;

/// Arguments of `modelgap demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Write the report (report.html and comparison.mcap) into this directory
    #[arg(long, value_name = "DIR", default_value = "modelgap-report")]
    pub report: PathBuf,

    /// Leave out the cloth part, the loop on a bundled cloth marker recording
    #[arg(long)]
    pub skip_cloth: bool,

    /// Leave out the last part, the DC-motor paper's Table 7 diagnosis
    #[arg(long)]
    pub skip_table7: bool,
}

/// The bundled recording.
///
/// # Errors
///
/// The embedded CSV does not read (a build with a broken data file).
pub fn demo_recording() -> anyhow::Result<Recording> {
    modelgap::io::csv::read_signals(DEMO_CSV.as_bytes())
        .with_context(|| format!("reading the bundled recording {DEMO_PATH}"))
}

/// The hidden-effect case the bundled recording was made from, as in
/// `examples/make_demo_data.rs`: Coulomb friction of 0.012 N m on the DC motor's shaft.
pub fn demo_case() -> HiddenCase {
    HiddenCase {
        name: "demo".to_owned(),
        model: "dc-motor".to_owned(),
        hidden: vec![Hidden {
            id: "coulomb@1m".to_owned(),
            values: vec![0.012],
        }],
        drive_scale: 1.0,
    }
}

/// The hidden-effect case the bundled cloth recording was made from, as in
/// `examples/make_cloth_demo_data.rs`: the `drag` case of `modelgap::cloth::hidden` on a
/// 7 × 7 swing scene held by clips on every other vertex of its top row (air drag with
/// C_d = 0.8 the scene does not have).
///
/// # Errors
///
/// The case is gone from `modelgap::cloth::hidden`.
pub fn cloth_demo_case() -> anyhow::Result<ClothCase> {
    cloth_cases(CLOTH_GRID, CLOTH_GRID)
        .into_iter()
        .find(|c| c.name == "drag")
        .context("the `drag` case of modelgap::cloth::hidden is gone")
}

/// Runs the demo and prints its story.
///
/// # Errors
///
/// A report that cannot be written; simulation errors (none for the bundled data).
pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    super::model::check_report_dir("--report", &args.report)?;
    let rec = demo_recording()?;
    let case = demo_case();
    let model = BondModel::new(library::builtin(&case.model)?);
    let loaded = Loaded::new(Box::new(model), rec, DEMO_PATH)?;
    let rec = &loaded.rec;
    let story = loaded.story();

    let mut out = String::from(
        "modelgap demo: hold a motor model against a recording, find the physical effect it is\n\
         missing, add it and watch the error fall; then the DC-motor paper's Table 7 diagnosis.\n\n",
    );
    // 1. The recording.
    let v = rec.values("V").unwrap_or_default();
    let (v_min, v_max) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        });
    out.push_str(&format!(
        "1. The recording ({DEMO_PATH}, bundled):\n   {} samples of {} over {} s.\n   \
         The voltage V steps between {} V and {} V: the motor starts, reverses, slows down.\n   \
         The model is the built-in {}. The recording hides a physical effect the model lacks,\n   \
         plus a sensor lag and noise that no candidate models.\n\n",
        rec.len(),
        rec.names().join(", "),
        num(rec.duration()),
        num(v_min),
        num(v_max),
        loaded.model.name(),
    ));

    // 2. Where the model fails.
    let before = loaded.compare(loaded.model.as_ref())?;
    out.push_str("2. Where the model fails (the residual leaves its band of 4 noise σ):\n\n");
    out.push_str(&indent(&story.comparison_text(&before)));

    // 3. What is missing.
    super::print(&modelgap::story::wrap_text(&out, 99))?;
    out.clear();
    let ex = loaded.explain(false)?;
    stop_if_interrupted(story, &ex, false, TOP)?;
    out.push_str(&format!(
        "\n3. What is missing: {} candidate effects (parameters that are off, elements the model lacks,\n   \
         abrupt changes) fitted to the recording and ranked by evidence:\n\n",
        ex.ranked.len()
    ));
    out.push_str(&indent(&story.explanation_text(&ex, TOP)));

    // 4. The effect added.
    let (_, after) = before_after(&loaded, &ex)?;
    match &after {
        None => {
            out.push_str("\n4. Nothing to add: the model already leaves only what noise leaves.\n")
        }
        Some((_, after)) => {
            out.push_str("\n4. With the effect added to the model:\n\n");
            let hidden = case
                .hidden
                .iter()
                .map(|h| (h.id.as_str(), h.values.as_slice()));
            out.push_str(&added_text(
                story,
                &ex.chosen,
                (&before, after),
                hidden,
                "examples/make_demo_data.rs",
            ));
        }
    }

    // 5. The report.
    let page = loaded.write_report(
        &args.report,
        &ReportParts {
            before: &before,
            explanation: Some(&ex),
            after: after.as_ref().map(|(e, c)| (e.as_slice(), c)),
            data: "motor_hidden_effect.csv",
            verdict: None,
        },
    )?;
    out.push_str("\n5. The report, for people who were not watching the terminal:\n   ");
    out.push_str(&report_line(&page));
    out.push_str(
        "   On your own data: `modelgap explain --model dc-motor --data your.csv`, then\n   \
         `modelgap fix --model dc-motor --data your.csv --out fixed.toml` (see `modelgap help`).\n",
    );
    super::print(&modelgap::story::wrap_text(&out, 99))?;

    // 6. Cloth.
    if !args.skip_cloth {
        cloth_story(&args.report.join("cloth"))?;
    }

    // 7. Table 7.
    if args.skip_table7 {
        return Ok(());
    }
    super::interrupt::check("Table 7 was not run")?;
    let rows = table7(&Table7Options::default()).context("running the Table 7 faults")?;
    let mut out = String::from(
        "\n7. The DC-motor paper's Table 7 (bond-graph fault diagnosis of a buck converter feeding the\n   \
         motor): each ±20 % fault simulated, detected against the 2 % band, diagnosed by fault trees\n   \
         and temporal signatures, beside the paper's answer:\n\n",
    );
    out.push_str(&indent(&table7_text(&rows)));
    out.push_str(&indent(&super::table7::summary(&rows)));
    out.push_str(
        "\nNext: `modelgap bond table7 --json`,\n  \
         `modelgap bond diagnose --model dc-motor --data examples/data/dc_motor_r_fault.csv \
         --steady-start`.\n",
    );
    super::print(&modelgap::story::wrap_text(&out, 99))
}

/// The bundled cloth scene and markers, loaded: the scene as a model and the markers as its
/// recording.
///
/// # Errors
///
/// The embedded files do not read (a build with a broken data file).
pub fn cloth_demo_loaded() -> anyhow::Result<Loaded> {
    let scene = Scene::from_toml(CLOTH_SCENE, CLOTH_SCENE_PATH)
        .with_context(|| format!("reading the bundled scene {CLOTH_SCENE_PATH}"))?;
    let markers = read_markers_csv(CLOTH_CSV.as_bytes())
        .with_context(|| format!("reading the bundled markers {CLOTH_CSV_PATH}"))?;
    let rec = markers_to_recording(&markers)?;
    Loaded::new(Box::new(ClothModel::new(scene)), rec, CLOTH_CSV_PATH)
}

/// Part 6: the loop on the bundled cloth recording; writes the cloth report into `dir`.
///
/// # Errors
///
/// A report that cannot be written; simulation errors (none for the bundled data).
fn cloth_story(dir: &Path) -> anyhow::Result<()> {
    let loaded = cloth_demo_loaded()?;
    let case = cloth_demo_case()?;
    let scene = &case.scene;
    let story = loaded.story();
    let width = scene.cloth.spacing * (scene.cloth.nx - 1) as f64;
    let n_markers = loaded.rec.signals().len() / 3;
    let mut out = format!(
        "\n6. The same loop on cloth. The scene ({CLOTH_SCENE_PATH}, bundled) is a {} × {} cloth,\n   \
         {} m wide, hanging from clips on every other vertex of its top row, which swing {} m\n   \
         back and forth at {} Hz. The recording ({CLOTH_CSV_PATH}) holds {} markers\n   \
         (every third vertex) over {} s at {} Hz with {} mm of noise; it hides a physical effect\n   \
         the scene lacks.\n\n   \
         Where the scene fails (a marker fails where a coordinate leaves its band):\n\n",
        scene.cloth.nx,
        scene.cloth.nz,
        num(width),
        num(SWING_AMPLITUDE),
        num(SWING_FREQUENCY),
        n_markers,
        num(loaded.rec.duration()),
        num((loaded.rec.len() - 1) as f64 / loaded.rec.duration()),
        num(RecordingOptions::default().noise * 1e3),
    );
    let before = loaded.compare(loaded.model.as_ref())?;
    out.push_str(&indent(&story.comparison_text(&before)));
    super::print(&modelgap::story::wrap_text(&out, 99))?;
    out.clear();

    let ex = loaded.explain(false)?;
    stop_if_interrupted(story, &ex, false, TOP)?;
    out.push_str(&format!(
        "\n   What is missing: {} candidate effects fitted to the markers and ranked by evidence:\n\n",
        ex.ranked.len()
    ));
    out.push_str(&indent(&story.explanation_text(&ex, TOP)));
    let (_, after) = before_after(&loaded, &ex)?;
    match &after {
        None => {
            out.push_str("\n   Nothing to add: the scene already leaves only what noise leaves.\n")
        }
        Some((_, after)) => {
            out.push_str("\n   With the effect added to the scene:\n");
            let hidden = case
                .hidden
                .iter()
                .map(|h| (h.id.as_str(), h.values.as_slice()));
            out.push_str(&added_text(
                story,
                &ex.chosen,
                (&before, after),
                hidden,
                "examples/make_cloth_demo_data.rs",
            ));
        }
    }
    let page = loaded.write_report(
        dir,
        &ReportParts {
            before: &before,
            explanation: Some(&ex),
            after: after.as_ref().map(|(e, c)| (e.as_slice(), c)),
            data: "cloth_hidden_effect.csv",
            verdict: None,
        },
    )?;
    out.push_str("\n   The cloth report: the per-vertex error map and the error over time in the page; the\n   \
         mesh coloured by error (topics /cloth_error, /cloth_error_after, /tf) in the MCAP for\n   \
         Foxglove's 3D panel:\n   ");
    out.push_str(&report_line(&page));
    out.push_str(&format!(
        "   On your own markers:\n   \
         `modelgap explain --model {CLOTH_SCENE_PATH} --data your.csv`, then\n   \
         `modelgap fix --model {CLOTH_SCENE_PATH} --data your.csv --out fixed.toml`.\n"
    ));
    super::print(&modelgap::story::wrap_text(&out, 99))
}

/// What the demo prints once the chosen effects are built in: each effect added, the error
/// before → after, and how the fit compares with what the generator (`maker`) hid.
fn added_text<'a>(
    story: &dyn Story,
    chosen: &[RankedCandidate],
    (before, after): (&Comparison, &Comparison),
    hidden: impl IntoIterator<Item = (&'a str, &'a [f64])>,
    maker: &str,
) -> String {
    let mut s = String::new();
    for r in chosen {
        s.push_str(&format!("   added: {}\n", super::fix::effect_line(r)));
    }
    s.push_str("   error before → after:\n");
    s.push_str(&indent(&story.before_after_text(before, after)));
    s.push_str(&truth_text(hidden, chosen, maker));
    s
}

/// The hidden truth beside what was found: each hidden candidate as
/// `(id, true values)`, and the example (`maker`) that made the recording.
fn truth_text<'a>(
    hidden: impl IntoIterator<Item = (&'a str, &'a [f64])>,
    chosen: &[RankedCandidate],
    maker: &str,
) -> String {
    let mut s = String::new();
    for (id, values) in hidden {
        let Some(found) = chosen
            .iter()
            .find(|c| c.candidate.id == id || c.equivalent.iter().any(|e| e == id))
        else {
            s.push_str(&format!(
                "   The recording was made with {id} = {values:?} hidden in it: explain did not choose it.\n"
            ));
            continue;
        };
        for (p, truth) in found.params.iter().zip(values) {
            let unit = modelgap::story::unit_suffix(&p.unit);
            let found = match &p.at_bound {
                Some(bound) => format!("{}{unit} (at its {bound} bound)", num(p.value)),
                None if p.std_error.is_finite() => {
                    format!("{} ± {}{unit}", num(p.value), num(p.std_error))
                }
                None => format!("{}{unit}", num(p.value)),
            };
            s.push_str(&format!(
                "   The truth hidden in the recording ({maker}): {} = {}{unit};\n   \
                 explain, not told it, found {found}.\n",
                p.name,
                num(*truth),
            ));
        }
    }
    s
}

/// Every line of `text` indented by three spaces.
fn indent(text: &str) -> String {
    text.lines()
        .map(|l| {
            if l.trim().is_empty() {
                "\n".to_owned()
            } else {
                format!("   {l}\n")
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use modelgap::bond::hidden::{RecordingOptions, record};

    use super::*;

    /// The bundled file is the recording of [`demo_case`] with the default options, its
    /// outputs rounded to 6 significant digits (`examples/make_demo_data.rs`): so the truth
    /// the demo prints is the truth in the file.
    #[test]
    fn bundled_recording_is_the_demo_case() {
        let bundled = demo_recording().unwrap();
        let case = demo_case();
        let fresh = record(&case, &RecordingOptions::default()).unwrap();
        assert_eq!(bundled.t(), fresh.t());
        assert_eq!(bundled.names(), fresh.names());
        for name in fresh.names() {
            let a = bundled.values(name).unwrap();
            let b = fresh.values(name).unwrap();
            let worst = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs() / y.abs().max(1e-9))
                .fold(0.0, f64::max);
            // Six significant digits: a relative difference of at most 5e-6.
            assert!(worst <= 5e-6, "{name}: {worst}");
        }
    }

    /// The bundled cloth files are the scene and the recording of [`cloth_demo_case`] with
    /// the default options, positions rounded to 6 decimals
    /// (`examples/make_cloth_demo_data.rs`): so the truth the demo prints is in the file.
    #[test]
    fn bundled_cloth_files_are_the_cloth_demo_case() {
        let case = cloth_demo_case().unwrap();
        let scene = Scene::from_toml(CLOTH_SCENE, CLOTH_SCENE_PATH).unwrap();
        assert_eq!(scene.to_toml().unwrap(), case.scene.to_toml().unwrap());
        let bundled = cloth_demo_loaded().unwrap().rec;
        let fresh = modelgap::cloth::hidden::record(
            &case,
            &modelgap::cloth::hidden::RecordingOptions::default(),
        )
        .unwrap();
        assert_eq!(bundled.t(), fresh.t());
        assert_eq!(bundled.names(), fresh.names());
        for name in fresh.names() {
            let a = bundled.values(name).unwrap();
            let b = fresh.values(name).unwrap();
            let worst = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            // Six decimals of a metre leave 0.5 µm; builds at other optimisation levels
            // round differently and the solver stops at a tolerance, which moves markers
            // by a few µm more. 20 µm is 2 % of the 1 mm marker noise.
            assert!(worst <= 2e-5, "{name}: {worst}");
        }
    }
}

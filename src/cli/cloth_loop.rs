//! The measurement loop on cloth: `compare`, `explain` and `fix` with a scene file as
//! `--model` and a marker recording (`t,id,x,y,z` CSV or `/markers` MCAP) as `--data`.
//!
//! A `--model` file is a cloth scene when it has a `[cloth]` table ([`scene_file`]); the
//! commands then hold the scene ([`ClothModel`]) against the markers and tell the story per
//! marker, over time and per region of the mesh ([`modelgap::cloth::report`]). The report
//! directory gets `report.html` (with the per-vertex error map and the error over time) and
//! `comparison.mcap` (the mesh coloured by error as `foxglove.SceneUpdate`, `/tf`, the
//! markers and the error per marker).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use modelgap::cloth::markers::{MarkerRecording, read_markers_path_within};
use modelgap::cloth::model::{ClothModel, markers_to_recording, simulate_markers};
use modelgap::cloth::report::{
    ClothComparison, ErrorMcap, before_after_text, cloth_report, comparison_text, explanation_rms,
    explanation_text, write_error_mcap_path,
};
use modelgap::cloth::scenes::Scene;
use modelgap::report::write_html;
use modelgap::{
    CompareOptions, Comparison, Effect, Explanation, Model as _, RankedCandidate, Recording,
    Verdict, compare,
};
use serde_json::{Value, json};

use super::BadInput;
use super::compare::CompareArgs;
use super::explain::ExplainArgs;
use super::fix::{Addition, FixArgs, check_out, checked_pick, effect_line, what_to_add};
use super::report::{
    HoldArg, LoopArgs, args_text, args_text_with_model, explanation_json, json_text, print_notes,
    report_line, run_explain_model, stop_if_interrupted,
};

/// Worst markers listed in text.
const TOP_MARKERS: usize = 5;

/// The scene file `--model` names, when it is a cloth scene (a file with a `[cloth]`
/// table); `None` for bond-graph models and built-in names.
pub fn scene_file(args: &LoopArgs) -> Option<PathBuf> {
    let path = Path::new(&args.model.model);
    if !path.is_file() {
        return None;
    }
    let text = std::fs::read_to_string(path).ok()?;
    text.lines()
        .any(|l| l.trim_start().starts_with("[cloth]"))
        .then(|| path.to_path_buf())
}

/// A cloth scene and a marker recording, loaded and checked against each other.
pub struct ClothLoaded {
    /// The scene as a model.
    pub model: ClothModel,
    /// The scene file, when the scene came from one.
    pub scene_file: Option<PathBuf>,
    /// The measured markers.
    pub markers: MarkerRecording,
    /// The markers as signals `m{id}.x|y|z`.
    pub rec: Recording,
    /// Noise floors given with `--noise`, by signal.
    pub noise: BTreeMap<String, f64>,
    /// Findings worth telling the user.
    pub notes: Vec<String>,
    /// The failure band, in noise floors.
    pub band_sigmas: f64,
    /// The failure band as a fraction of the steady state, when chosen.
    pub band_fraction: Option<f64>,
}

impl ClothLoaded {
    /// A model and markers with the default options (the demo).
    ///
    /// # Errors
    ///
    /// [`BadInput`] for a marker id outside the scene's grid (`label` names the data).
    pub fn new(scene: Scene, markers: MarkerRecording, label: &str) -> anyhow::Result<Self> {
        check_ids(&scene, &markers, label)?;
        let rec = markers_to_recording(&markers)?;
        Ok(Self {
            model: ClothModel::new(scene),
            scene_file: None,
            markers,
            rec,
            noise: BTreeMap::new(),
            notes: Vec::new(),
            band_sigmas: CompareOptions::default().band_sigmas,
            band_fraction: None,
        })
    }

    /// Compare options with the user's noise floors and band.
    pub fn compare_options(&self) -> CompareOptions {
        CompareOptions {
            noise: self.noise.clone(),
            band_sigmas: self.band_sigmas,
            band_fraction: self.band_fraction,
            ..CompareOptions::default()
        }
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        self.model.scene()
    }

    /// Compares `model` (this scene, or one with effects built in) with the markers.
    ///
    /// # Errors
    ///
    /// The model cannot simulate the recording.
    pub fn compare(
        &self,
        model: &dyn modelgap::Model,
    ) -> anyhow::Result<(Comparison, ClothComparison)> {
        let c = compare(model, &self.rec, &self.compare_options())
            .with_context(|| format!("comparing scene {} with the markers", model.name()))?;
        let cloth = ClothComparison::new(&c, &self.scene().cloth)?;
        Ok((c, cloth))
    }

    /// Every vertex of `scene` at the recording's times, as the model simulates it.
    ///
    /// # Errors
    ///
    /// The scene cannot be simulated.
    pub fn mesh_frames(&self, scene: &Scene) -> anyhow::Result<Vec<Vec<[f64; 3]>>> {
        let n = (scene.cloth.nx * scene.cloth.nz) as u32;
        let ids: Vec<u32> = (0..n).collect();
        let pins = scene.pins_from_markers.then_some(&self.markers);
        let run = simulate_markers(scene, &ids, self.rec.t(), self.model.settings(), pins)
            .with_context(|| format!("simulating the mesh of scene {}", scene.name))?;
        Ok(run.positions().to_vec())
    }
}

/// Loads the scene at `scene_path` and the markers of `args`, and checks them.
///
/// # Errors
///
/// [`BadInput`] for bond-graph options (`--set`, `--steady-start`, `--hold linear`), a
/// missing data file, a `--noise` for a signal the markers do not hold, a non-positive
/// band; scene and marker read errors, which name the file, line and field (a marker id
/// outside the grid at the CSV line or MCAP message where it appears); a grid past its
/// particle limit.
pub fn load(args: &LoopArgs, scene_path: &Path) -> anyhow::Result<ClothLoaded> {
    if let Some(a) = args.model.set.first() {
        return Err(BadInput(format!(
            "--set {}={}: --set changes bond-graph models; edit the scene file {} instead",
            a.name,
            a.value,
            scene_path.display()
        ))
        .into());
    }
    if args.steady_start || args.hold != HoldArg::Zoh {
        return Err(BadInput(
            "--steady-start and --hold apply to bond-graph models; a cloth scene starts from \
             its own initial state"
                .to_owned(),
        )
        .into());
    }
    let scene = Scene::from_path(scene_path)
        .with_context(|| format!("loading scene {}", scene_path.display()))?;
    // The grid's size against its limit, before anything counts on nx × nz.
    let n_vertices = scene
        .cloth
        .n_vertices()
        .with_context(|| format!("loading scene {}", scene_path.display()))?;
    let path = &args.data;
    if path.is_dir() {
        return Err(BadInput(format!(
            "--data {} is a directory: give a marker recording (.csv or .mcap)",
            path.display()
        ))
        .into());
    }
    if !path.exists() {
        return Err(BadInput(format!("data file {} not found", path.display())).into());
    }
    // Ids outside the grid are refused at their own line (or message), before the reader
    // compares frames and blames a later line.
    let markers = read_markers_path_within(path, n_vertices).with_context(|| {
        format!(
            "reading markers {} for scene {} ({} x {} grid)",
            path.display(),
            scene.name,
            scene.cloth.nx,
            scene.cloth.nz
        )
    })?;
    let rec = markers_to_recording(&markers)?;
    let noise: BTreeMap<String, f64> = args
        .noise
        .iter()
        .map(|a| (a.name.clone(), a.value))
        .collect();
    for name in noise.keys() {
        if rec.signal(name).is_none() {
            return Err(BadInput(format!(
                "--noise {name}=…: the markers hold no signal `{name}` (marker signals are \
                 m{{id}}.x, m{{id}}.y, m{{id}}.z for ids {}) in {}",
                id_list(markers.ids()),
                path.display()
            ))
            .into());
        }
    }
    if !(args.band_sigmas.is_finite() && args.band_sigmas > 0.0) {
        return Err(BadInput(format!(
            "--band-sigmas must be positive, found {}",
            args.band_sigmas
        ))
        .into());
    }
    if let Some(f) = args.band_fraction
        && !(f.is_finite() && f > 0.0)
    {
        return Err(BadInput(format!("--band-fraction must be positive, found {f}")).into());
    }
    let mut notes = Vec::new();
    if scene.pins_from_markers {
        notes.push("pinned vertices with markers follow the recorded positions".to_owned());
    }
    Ok(ClothLoaded {
        model: ClothModel::new(scene),
        scene_file: Some(scene_path.to_path_buf()),
        markers,
        rec,
        noise,
        notes,
        band_sigmas: args.band_sigmas,
        band_fraction: args.band_fraction,
    })
}

/// Ids as `0, 3, 6, …, 360` (the first and last few when there are many).
fn id_list(ids: &[u32]) -> String {
    let text: Vec<String> = ids.iter().map(u32::to_string).collect();
    if text.len() <= 8 {
        text.join(", ")
    } else {
        format!(
            "{}, …, {}",
            text[..4].join(", "),
            text[text.len() - 2..].join(", ")
        )
    }
}

/// Refuses markers whose id is not a vertex of the scene's grid (markers given in memory;
/// files are checked line by line as they are read, see [`load`]).
fn check_ids(scene: &Scene, markers: &MarkerRecording, label: &str) -> anyhow::Result<()> {
    let n_vertices = scene.cloth.n_vertices()?;
    let Some(&bad) = markers.ids().iter().find(|&&id| id as usize >= n_vertices) else {
        return Ok(());
    };
    Err(BadInput(format!(
        "marker id {bad}, field `id`, is outside the mesh of scene {} ({} x {} grid, \
         vertices 0 to {}) in {label}",
        scene.name,
        scene.cloth.nx,
        scene.cloth.nz,
        n_vertices - 1
    ))
    .into())
}

/// What a cloth report shows.
pub struct ClothReport<'a> {
    /// The scene as given against the markers.
    pub before: (&'a Comparison, &'a ClothComparison),
    /// The explanation, if explain ran.
    pub explanation: Option<&'a Explanation>,
    /// The effects added and the comparison with them, if any.
    pub after: Option<(&'a [Effect], &'a Comparison, &'a ClothComparison)>,
    /// The recording, as named in the title.
    pub data: &'a str,
    /// A verdict in place of the explanation's.
    pub verdict: Option<String>,
}

/// Writes `report.html` (with the per-vertex error map) and `comparison.mcap` (the mesh
/// coloured by error for Foxglove) into `dir`; returns the page's path.
///
/// # Errors
///
/// The meshes cannot be simulated; the directory or a file cannot be written.
pub fn write_report(
    dir: &Path,
    loaded: &ClothLoaded,
    parts: ClothReport<'_>,
) -> anyhow::Result<PathBuf> {
    super::interrupt::check("the report was not written")?;
    let scene = loaded.scene();
    let triangles = modelgap::cloth::BuildMesh::build_mesh(&scene.cloth)?.triangles;
    let mut report = cloth_report(
        parts.before.0,
        parts.before.1,
        parts.explanation,
        parts.after.map(|a| (a.1, a.2)),
        &triangles,
    );
    report.title = format!(
        "modelgap: cloth scene {} against {}",
        scene.name, parts.data
    );
    if let Some(v) = parts.verdict {
        report.verdict = v;
    }
    std::fs::create_dir_all(dir)
        .with_context(|| format!("creating the report directory {}", dir.display()))?;
    let page = dir.join("report.html");
    write_html(&report, &page).with_context(|| format!("writing {}", page.display()))?;
    let mesh_before = loaded.mesh_frames(scene)?;
    let after_mesh = match parts.after {
        Some((effects, _, cloth_after)) => {
            let pairs: Vec<(&modelgap::Candidate, &[f64])> = effects
                .iter()
                .map(|e| (&e.candidate, e.values.as_slice()))
                .collect();
            let scene_after = loaded.model.edited(&pairs)?;
            Some((cloth_after, loaded.mesh_frames(&scene_after)?))
        }
        None => None,
    };
    let mcap = dir.join("comparison.mcap");
    write_error_mcap_path(
        &ErrorMcap {
            scene: &scene.name,
            triangles: &triangles,
            measured: &loaded.markers,
            before: parts.before.1,
            mesh_before: &mesh_before,
            after: after_mesh.as_ref().map(|(c, m)| (*c, m.as_slice())),
        },
        &mcap,
    )
    .with_context(|| format!("writing {}", mcap.display()))?;
    Ok(page)
}

/// A cloth comparison as JSON: overall error, noise floor, per marker, regions, windows,
/// error over time.
pub fn comparison_json(c: &ClothComparison) -> anyhow::Result<Value> {
    let mut value = serde_json::to_value(c)?;
    value["rms_over_floor"] = super::report::finite(c.rms_over_floor());
    value["worst_markers"] = json!(
        c.worst_markers(TOP_MARKERS)
            .iter()
            .map(|m| m.id)
            .collect::<Vec<_>>()
    );
    Ok(value)
}

/// `modelgap compare` on a cloth scene.
///
/// # Errors
///
/// As [`load`]; a scene that cannot be simulated; a report that cannot be written.
pub fn compare_command(args: &CompareArgs, scene_path: &Path) -> anyhow::Result<()> {
    let loaded = load(&args.common, scene_path)?;
    let (before, cloth) = loaded.compare(&loaded.model)?;
    let page = match &args.common.report {
        Some(dir) => Some(write_report(
            dir,
            &loaded,
            ClothReport {
                before: (&before, &cloth),
                explanation: None,
                after: None,
                data: &super::report::data_name(&args.common.data),
                verdict: None,
            },
        )?),
        None => None,
    };
    if args.json {
        let mut value = comparison_json(&cloth)?;
        value["data"] = json!(args.common.data.display().to_string());
        value["notes"] = json!(loaded.notes);
        if let Some(page) = &page {
            value["report"] = json!(page.display().to_string());
        }
        return super::print(&json_text(&value)?);
    }
    print_notes(&loaded.notes);
    let mut out = comparison_text(&cloth, TOP_MARKERS);
    if let Some(page) = &page {
        out.push_str(&report_line(page));
    }
    if !cloth.windows.is_empty() {
        out.push_str(&format!(
            "next: `modelgap explain {}` names the effect that is missing\n",
            args_text(&args.common)
        ));
    }
    super::print(&out)
}

/// `modelgap explain` on a cloth scene.
///
/// # Errors
///
/// As [`load`]; explain's errors; a report that cannot be written.
pub fn explain_command(args: &ExplainArgs, scene_path: &Path) -> anyhow::Result<()> {
    let loaded = load(&args.common, scene_path)?;
    if !args.json {
        print_notes(&loaded.notes);
    }
    let ex = run_explain_model(&loaded.model, &loaded.rec, &loaded.noise, args.json)?;
    stop_if_interrupted(&ex, args.json, args.top)?;
    let page = match &args.common.report {
        Some(dir) => {
            let (before, cloth) = loaded.compare(&loaded.model)?;
            let effects = ex.effects();
            let after = with_effects(&loaded, &effects)?;
            Some(write_report(
                dir,
                &loaded,
                ClothReport {
                    before: (&before, &cloth),
                    explanation: Some(&ex),
                    after: after.as_ref().map(|(c, cc)| (effects.as_slice(), c, cc)),
                    data: &super::report::data_name(&args.common.data),
                    verdict: None,
                },
            )?)
        }
        None => None,
    };
    if args.json {
        let mut value = explanation_json(&ex);
        let (before, after, floor) = explanation_rms(&ex);
        value["marker_rms"] = json!({
            "before": super::report::finite(before),
            "after": super::report::finite(after),
            "noise_floor": super::report::finite(floor),
        });
        value["data"] = json!(args.common.data.display().to_string());
        value["notes"] = json!(loaded.notes);
        if let Some(page) = &page {
            value["report"] = json!(page.display().to_string());
        }
        return super::print(&json_text(&value)?);
    }
    let mut out = format!(
        "scene {} explaining {} ({} candidate effects fitted)\n",
        ex.model,
        args.common.data.display(),
        ex.ranked.len()
    );
    out.push_str(&explanation_text(&ex, args.top));
    if let Some(page) = &page {
        out.push_str(&report_line(page));
    }
    if matches!(
        ex.verdict,
        Verdict::EffectFound | Verdict::TwoEffects | Verdict::Partial
    ) {
        out.push_str(&format!(
            "next: `modelgap fix {} --out {}-fixed.toml` writes the scene file with the new term \
             and shows the error fall\n",
            args_text(&args.common),
            ex.model
        ));
    }
    super::print(&out)
}

/// The comparison of the scene with `effects` built in (`None` without effects).
///
/// # Errors
///
/// The effects cannot be built in or the scene cannot be simulated.
pub fn with_effects(
    loaded: &ClothLoaded,
    effects: &[Effect],
) -> anyhow::Result<Option<(Comparison, ClothComparison)>> {
    if effects.is_empty() {
        return Ok(None);
    }
    let fixed = loaded
        .model
        .with_effects(effects)
        .context("building the effect into the scene")?;
    Ok(Some(loaded.compare(fixed.as_ref())?))
}

/// `modelgap fix` on a cloth scene: writes the scene file with the new term.
///
/// # Errors
///
/// As [`load`]; [`BadInput`] for an `--effect` that names no candidate or an `--out` that is
/// the input scene; explain's errors; a file that cannot be written.
pub fn fix_command(args: &FixArgs, scene_path: &Path) -> anyhow::Result<()> {
    let loaded = load(&args.common, scene_path)?;
    check_out(&args.out, loaded.scene_file.as_deref())?;
    let pick = checked_pick(args.effect.as_deref(), &loaded.model, "scene")?;
    print_notes(&loaded.notes);
    let ex = run_explain_model(&loaded.model, &loaded.rec, &loaded.noise, false)?;
    stop_if_interrupted(&ex, false, args.top)?;
    let mut out = format!(
        "scene {} explaining {} ({} candidate effects fitted)\n",
        ex.model,
        args.common.data.display(),
        ex.ranked.len()
    );
    out.push_str(&explanation_text(&ex, args.top));
    let Some(Addition {
        added,
        shown,
        verdict,
    }) = what_to_add(&ex, pick.as_ref(), args, &mut out)?
    else {
        return super::print(&out);
    };
    let effects: Vec<Effect> = added.iter().map(RankedCandidate::effect).collect();
    let fixed = loaded
        .model
        .with_effects(&effects)
        .context("building the effect into the scene")?;
    let text = fixed
        .to_file_text()
        .context("the scene with the effect cannot be written as a scene file")?;
    Scene::from_toml(&text, &args.out.display().to_string()).with_context(|| {
        format!(
            "the scene for {} does not read back (a bug; please report it)",
            args.out.display()
        )
    })?;
    super::interrupt::check("the new scene was not written")?;
    modelgap::io::atomic::write_atomic(&args.out, text.as_bytes())
        .with_context(|| format!("writing the new scene to {}", args.out.display()))?;
    out.push('\n');
    for r in &added {
        out.push_str(&format!("added: {}\n", effect_line(r)));
    }
    out.push_str(&format!("wrote {}\n", args.out.display()));
    let (before, cloth_before) = loaded.compare(&loaded.model)?;
    let (after, cloth_after) = loaded.compare(fixed.as_ref())?;
    out.push_str("error before → after:\n");
    out.push_str(&before_after_text(&cloth_before, &cloth_after));
    if let Some(dir) = &args.common.report {
        let page = write_report(
            dir,
            &loaded,
            ClothReport {
                before: (&before, &cloth_before),
                explanation: Some(&shown),
                after: Some((&effects, &after, &cloth_after)),
                data: &super::report::data_name(&args.common.data),
                verdict,
            },
        )?;
        out.push_str(&report_line(&page));
    }
    out.push_str(&format!(
        "next: `modelgap compare {}` holds the new scene against the markers\n",
        args_text_with_model(&args.common, Some(&args.out))
    ));
    super::print(&out)
}

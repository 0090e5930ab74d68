//! Loading a model and a recording for the measurement loop, whatever the model's kind: the
//! one place that knows the kinds. A model is named by a file or a built-in name; a file
//! with a `[cloth]` table is a cloth scene, any other model file a bond graph; the built-in
//! names are the bond graphs `dc-motor` and `buck-motor` and the cloth scenes `corner`,
//! `two-corners` and `drape`. Everything after loading — compare, explain, fix, the report,
//! the text and JSON — goes through [`Model`] and its [`Story`](crate::story::Story), with no
//! branch per kind.
//!
//! ```
//! use modelgap::load::{LoadOptions, load_model, load_recording};
//! use modelgap::{CompareOptions, compare};
//!
//! let motor = load_model("dc-motor", &LoadOptions::default())?;
//! let rec = load_recording("examples/data/motor_hidden_effect.csv".as_ref(), motor.as_ref())?;
//! let c = compare(motor.as_ref(), &rec, &CompareOptions::default())?;
//! println!("{}", motor.story().comparison_text(&c));
//! # Ok::<(), modelgap::Error>(())
//! ```

use std::path::Path;

use modelgap_bond::element::Range;
use modelgap_bond::input_hold::HoldReason;
use modelgap_bond::model::Start;
pub use modelgap_bond::simulate::Hold;
use modelgap_bond::{BondModel, file::read_model_path, library};
use modelgap_cloth::model::ClothModel;
use modelgap_cloth::scenes::{self, Scene};
use modelgap_core::io::csv::CsvOptions;
use modelgap_core::{Model, Recording};

use crate::{Error, Result};

/// The kinds of model the loop holds against recordings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelKind {
    /// A bond graph: a model file, `dc-motor` or `buck-motor`.
    BondGraph,
    /// A cloth scene: a scene file (with a `[cloth]` table), `corner`, `two-corners` or `drape`.
    ClothScene,
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ModelKind::BondGraph => "bond-graph model",
            ModelKind::ClothScene => "cloth scene",
        })
    }
}

/// The built-in cloth scenes, by name.
pub const CLOTH_SCENES: [&str; 3] = ["corner", "two-corners", "drape"];

/// How a model is loaded for the loop. The options of one kind are refused, with a typed
/// error saying so, for a model of the other.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// Parameters or input defaults set first, in order (bond graphs: `--set R=1.2`; a
    /// cloth scene is edited in its file).
    pub set: Vec<(String, f64)>,
    /// Start at the steady state under the recording's first inputs instead of at rest
    /// (bond graphs; a cloth scene starts from its own initial state). Default false.
    pub steady_start: bool,
    /// How recorded inputs are held between samples (bond graphs); `None` (the default):
    /// chosen per input from the recording by [`settle_holds`] (zero-order hold until then).
    pub hold: Option<Hold>,
    /// Parameters to mark unknown for calibration, with their bounds (`None`: the default
    /// bounds around the value, see [`modelgap_bond::element::Range::around`]), beside those
    /// the model file marks `free` (bond graphs: `modelgap fit --free k1=0:1`).
    pub free: Vec<(String, Option<(f64, f64)>)>,
}

/// The names of every built-in model, comma-separated.
pub fn builtin_names() -> String {
    library::BUILTINS
        .iter()
        .map(|(name, _)| *name)
        .chain(CLOTH_SCENES)
        .collect::<Vec<_>>()
        .join(", ")
}

/// True for text that names a file rather than a built-in model.
fn looks_like_path(text: &str) -> bool {
    text.contains('/') || text.contains('\\') || text.to_ascii_lowercase().ends_with(".toml")
}

/// What a path or name holds: a file with a `[cloth]` table is a cloth scene, any other file
/// a bond-graph model; a name is a built-in.
///
/// # Errors
/// [`Error::Input`] for a directory, a missing file, or a name that is no built-in (the
/// message lists them).
pub fn model_kind(path_or_name: &str) -> Result<ModelKind> {
    let path = Path::new(path_or_name);
    let builtin_bond = library::builtin(path_or_name).is_ok();
    let builtin_cloth = CLOTH_SCENES.contains(&path_or_name.replace('_', "-").as_str());
    if path.is_file() {
        let text = std::fs::read_to_string(path)
            .map_err(|e| modelgap_core::CoreError::io(e, Some(path)))?;
        let cloth = text.lines().any(|l| l.trim_start().starts_with("[cloth]"));
        return Ok(if cloth {
            ModelKind::ClothScene
        } else {
            ModelKind::BondGraph
        });
    }
    // A directory that happens to share a built-in's name does not hide the built-in.
    if builtin_bond {
        return Ok(ModelKind::BondGraph);
    }
    if builtin_cloth {
        return Ok(ModelKind::ClothScene);
    }
    if path.is_dir() {
        return Err(Error::Input(format!(
            "model {} is a directory: give a model file (.toml) or a built-in model ({})",
            path.display(),
            builtin_names()
        )));
    }
    if looks_like_path(path_or_name) {
        return Err(Error::Input(format!(
            "model file {} not found (built-in models: {})",
            path.display(),
            builtin_names()
        )));
    }
    Err(Error::Input(format!(
        "`{path_or_name}` is neither a model file nor a built-in model ({})",
        builtin_names()
    )))
}

/// A model as loaded, of its own kind (for bindings that hand out a class per kind; the loop
/// itself takes [`AnyModel::into_model`]).
#[derive(Clone, Debug)]
pub enum AnyModel {
    /// A bond graph.
    BondGraph(Box<BondModel>),
    /// A cloth scene.
    ClothScene(Box<ClothModel>),
}

impl AnyModel {
    /// The model behind the loop's seam.
    #[must_use]
    pub fn into_model(self) -> Box<dyn Model> {
        match self {
            AnyModel::BondGraph(m) => m,
            AnyModel::ClothScene(m) => m,
        }
    }
}

/// Loads a model for the loop from a file or a built-in name, with `opts` applied.
///
/// # Errors
/// As [`model_kind`]; the model file's read errors (line, column, element); a `--set` of an
/// unknown or unphysical value ([`Error::Set`]); [`Error::Input`] for an option the model's
/// kind does not take.
pub fn load_model(path_or_name: &str, opts: &LoadOptions) -> Result<Box<dyn Model>> {
    Ok(load(path_or_name, opts)?.into_model())
}

/// Loads a model as [`load_model`] does, keeping its kind.
///
/// # Errors
/// As [`load_model`].
pub fn load(path_or_name: &str, opts: &LoadOptions) -> Result<AnyModel> {
    match model_kind(path_or_name)? {
        ModelKind::BondGraph => Ok(AnyModel::BondGraph(Box::new(load_bond(
            path_or_name,
            opts,
        )?))),
        ModelKind::ClothScene => Ok(AnyModel::ClothScene(Box::new(load_cloth(
            path_or_name,
            opts,
        )?))),
    }
}

/// A bond-graph model file or built-in, with `--set`, start and hold applied.
fn load_bond(path_or_name: &str, opts: &LoadOptions) -> Result<BondModel> {
    let path = Path::new(path_or_name);
    let mut g = if path.is_file() {
        read_model_path(path)?
    } else {
        library::builtin(path_or_name)?
    };
    for (name, value) in &opts.set {
        g.set_param(name, *value).map_err(|source| Error::Set {
            name: name.clone(),
            value: *value,
            source: Box::new(source),
        })?;
    }
    for (name, bounds) in &opts.free {
        let value = g
            .param(name)
            .map_err(|e| Error::Input(format!("--free {name}: {e}")))?;
        let range = match bounds {
            Some((lower, upper)) => Some(Range {
                lower: *lower,
                upper: *upper,
            }),
            None => Some(Range::around(value, None, None).ok_or_else(|| {
                Error::Input(format!(
                    "--free {name}: its value is 0, which gives no default bounds; write \
                     --free {name}=LO:HI"
                ))
            })?),
        };
        g.set_free(name, range)
            .map_err(|e| Error::Input(format!("--free {name}: {e}")))?;
    }
    let start = if opts.steady_start {
        Start::SteadyState
    } else {
        Start::Rest
    };
    Ok(BondModel::new(g)
        .with_start(start)
        .with_hold(opts.hold.unwrap_or(Hold::Zero)))
}

/// A cloth scene file or built-in; the bond-graph options are refused.
fn load_cloth(path_or_name: &str, opts: &LoadOptions) -> Result<ClothModel> {
    let path = Path::new(path_or_name);
    if let Some((name, value)) = opts.set.first() {
        return Err(Error::Input(format!(
            "--set {name}={value}: --set changes bond-graph models; edit the scene file \
             {path_or_name} instead"
        )));
    }
    if let Some((name, _)) = opts.free.first() {
        return Err(Error::Input(format!(
            "--free {name}: a cloth scene has no parameters to calibrate this way; its \
             candidates fit its material and air"
        )));
    }
    if opts.steady_start || opts.hold.is_some() {
        return Err(Error::Input(
            "--steady-start and --hold apply to bond-graph models; a cloth scene starts from its \
             own initial state"
                .to_owned(),
        ));
    }
    let scene = if path.is_file() {
        Scene::from_path(path)?
    } else {
        scenes::by_name(path_or_name)?
    };
    // The grid's size against its limit, before anything counts on nx × nz.
    scene.cloth.n_vertices()?;
    Ok(ClothModel::new(scene))
}

/// Reads a recording for `model` ([`Model::read_recording`]: signals for a bond graph,
/// markers checked against the grid for a cloth scene).
///
/// # Errors
/// [`Error::Input`] for a directory or a missing file; the reader's errors, which name the
/// file and the line, field or message.
pub fn load_recording(path: &Path, model: &dyn Model) -> Result<Recording> {
    check_recording_path(path)?;
    Ok(model.read_recording(path)?)
}

/// Reads a recording for `model` as [`load_recording`] does, a bond graph's CSV signals with
/// `csv` (the time column, separator and decimal mark; see
/// [`modelgap_core::io::csv`]); returns it with the reader's notes (an index column left
/// out, a unit row read, a time unit converted, a separator or decimal mark detected).
///
/// # Errors
/// As [`load_recording`]; [`Error::Input`] for CSV options other than the defaults with a
/// cloth scene, whose marker files (`t,id,x,y,z`) are read as written, and
/// [`modelgap_core::CoreError::InvalidArgument`] with an MCAP file.
pub fn load_recording_with(
    path: &Path,
    model: &AnyModel,
    csv: &CsvOptions,
) -> Result<(Recording, Vec<String>)> {
    check_recording_path(path)?;
    match model {
        AnyModel::BondGraph(_) => Ok(modelgap_core::io::read_recording_path_with(path, csv)?),
        AnyModel::ClothScene(m) => {
            if !csv.is_default() {
                return Err(Error::Input(
                    "--time, --delimiter and --decimal-comma apply to signal recordings; a cloth \
                     scene reads marker files (`t,id,x,y,z`) as they are written"
                        .to_owned(),
                ));
            }
            Ok((m.read_recording(path)?, Vec::new()))
        }
    }
}

/// Chooses how a bond graph holds each input `rec` records between samples
/// ([`BondModel::settle_holds`]: an input that steps is held at each sample's value; any
/// other the way the model predicts the recording better) and returns a note for each
/// input that does not step, saying how it is held and why (a stepping input held at its
/// samples' values goes without saying); nothing for a cloth scene.
pub fn settle_holds(model: &mut AnyModel, rec: &Recording) -> Vec<String> {
    match model {
        AnyModel::BondGraph(m) => (m.settle_holds(rec).iter())
            .filter(|h| !matches!(h.reason, HoldReason::Steps { .. }))
            .map(ToString::to_string)
            .collect(),
        AnyModel::ClothScene(_) => Vec::new(),
    }
}

/// Refuses a recording path that is a directory or does not exist.
fn check_recording_path(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::Input(format!(
            "{} is a directory: give a recording file (.csv, .mcap or .parquet)",
            path.display()
        )));
    }
    if !path.exists() {
        return Err(Error::Input(format!(
            "recording {} not found",
            path.display()
        )));
    }
    Ok(())
}

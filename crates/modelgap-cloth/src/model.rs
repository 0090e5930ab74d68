//! [`ClothModel`]: a cloth scene as a [`modelgap_core::Model`], the seam the
//! measurement loop (compare, explain, add an effect) works through.
//!
//! # API (stable: the CLI, the report and Python build on it)
//!
//! - [`ClothModel::new`]`(scene)`, [`ClothModel::from_path`]`(path)`;
//!   [`ClothModel::scene`], [`ClothModel::settings`],
//!   [`ClothModel::with_settings`] ([`PredictSettings`]: solver method,
//!   tolerance, step divisor).
//! - The [`Model`] impl: outputs `m{id}.x`, `m{id}.y`, `m{id}.z` for every
//!   vertex `id` of the scene's grid (`row * nx + col`), unit `m`;
//!   `predict_with` runs the scene **from its initial state** (simulated time
//!   0 is recording time 0) and predicts the marker signals the recording
//!   holds, at its times (linear between steps when a sample falls between
//!   two); pinned vertices follow the recording's markers when the scene
//!   says `pins.from_markers`. `candidates` is the menu below;
//!   `with_effects` returns a new `ClothModel` whose scene holds the fitted
//!   terms; `to_file_text` is that scene's TOML file;
//!   `prediction_spread` is the model's predictability band.
//! - [`markers_to_recording`] / [`recording_to_markers`]: a
//!   [`MarkerRecording`] as a core [`Recording`] with signals `m{id}.x|y|z`
//!   and back; [`marker_signal`] and [`parse_marker_signal`] name them.
//! - [`simulate_markers`]: the scene (with effects) at given times, as marker
//!   frames — what recordings are made with ([`crate::hidden`]).
//!
//! # Candidate effects
//!
//! | id | name | parameters |
//! |---|---|---|
//! | `air-drag` | aerodynamic drag on the cloth's triangles | `drag_coefficient` (1) |
//! | `wind` | a constant wind (drag on the velocity relative to the air) | (`drag_coefficient`), `wind_x`, `wind_y`, `wind_z` (m/s) |
//! | `skin-friction` | tangential air drag: skin friction on the velocity along the cloth | `skin_friction` (1; fitted from 3 starts across its bounds) |
//! | `damping` | velocity damping −c m v | `damping` (1/s) |
//! | `bending` | bending stiffness: the quadratic bending energy ([`crate::bending`]) | `bending_length` (m; the rigidity is `w c³`, `w` the weight per area; 11 starts) |
//! | `bend-springs` | (scenes with bend springs) their stiffness is off | `bend_stiffness` (N/m) |
//! | `compliance` | stretch compliance (the cloth is not quite inextensible) | `compliance`, or `warp_compliance` and `weft_compliance` when the scene sets them apart (m/N) |
//! | `compliance@{region}` | (per `[[materials]]` region) its stretch compliance | as `compliance` |
//! | `bending@{region}` | its bending stiffness | `bending_length` (m) |
//! | `damping@{region}` | its velocity damping | `damping` (1/s) |
//! | `mass` | the cloth's total mass is off | `total_mass` (kg) |
//! | `point-mass` | an extra point mass at a vertex | `col`, `row` (vertices: grid starts, then a lattice search), `mass` (kg) |
//! | `friction@collider{k}` | friction on collider k is off | `friction` (1) |
//!
//! `wind` fits the drag coefficient too when the scene has no drag.
//! `skin-friction` starts from 0, 2.5 and 5: from 0 alone the fit stayed at 0 on a
//! curtain sliding in its own plane (hidden `C_f = 0.5`, 12 × 12) and explain chose
//! damping first; from three starts it finds 0.504. The
//! point mass sits at a vertex `(col, row)`, two parameters on the lattice of
//! vertices ([`EffectParam::step`]): the grid of starts (4 × 4 places spread
//! over the grid, each scored with its best mass) picks the region, the fit
//! refines the mass, and a compass search moves the place vertex by vertex
//! while the error falls; `fix` writes it as a `[[point_masses]]` entry. (A
//! mass split bilinearly over the four vertices around a fractional place
//! makes the cost kinked at every vertex, and the fit stalls beside the true
//! one.) Bounds keep the
//! explicit forces stable at the scene's step (damping `c h ≤ 0.2`,
//! bend springs `k h²/m ≤ 0.25`); quadratic bending is implicit, and its
//! bound is physics: its parameter is the cloth's bending length
//! `c = (B/w)^(1/3)` (`w` the weight per area, `B = w c³` written to the
//! file), at most half the cloth's width (a stiffer sheet hardly drapes); its
//! fit starts from the best of 11 lengths across the bounds.
//!
//! # Example
//!
//! ```
//! use modelgap_cloth::model::{ClothModel, markers_to_recording, simulate_markers};
//! use modelgap_cloth::scenes;
//! use modelgap_core::Model as _;
//!
//! let scene = scenes::corner().resized(5, 5)?;
//! let model = ClothModel::new(scene.clone());
//! let t: Vec<f64> = (0..=10).map(|k| 0.01 * k as f64).collect();
//! let frames = simulate_markers(&scene, &[24], &t, model.settings(), None)?;
//! let rec = markers_to_recording(&frames)?;
//! let drag = model.candidates().into_iter().find(|c| c.id == "air-drag").unwrap();
//! let slowed = model.predict_with(&rec, &[(&drag, &[2.0])])?;
//! // The far corner falls less with drag.
//! assert!(slowed.get("m24.y").unwrap()[10] > rec.values("m24.y")?[10]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt::Write as _;
use std::path::Path;

use modelgap_core::noise::Gaussian;
use modelgap_core::{
    Candidate, CoreError, Effect, EffectKind, EffectParam, Model, Prediction, Recording, Signal,
};
use nalgebra::Vector3;

use crate::error::{ClothError, Result};
use crate::forces::PointMass;
use crate::markers::MarkerRecording;
use crate::material::Material;
use crate::scene_world::SceneWorld;
use crate::scenes::Scene;
use crate::solver::Method;
use crate::world::Stagnation;

/// Factor on the predictability spread: the spread between runs at `h` and
/// `h/2` is half the error of the `h` run for a first-order scheme
/// (Richardson), and one perturbed run samples the branching of a snap once.
pub const SPREAD_FACTOR: f64 = 2.0;

/// Size of the random initial perturbation of the spread's perturbed run (m):
/// far below any measurement, above rounding.
pub const SPREAD_PERTURBATION: f64 = 1e-6;

/// Half-width of the running maximum that turns the spread into an envelope
/// (samples): two runs that cross each other are not in agreement there.
pub const SPREAD_ENVELOPE: usize = 10;

/// How much tighter than the model's the stretch tolerance of
/// [`numerical_error`](modelgap_core::Model::numerical_error)'s third run is.
pub const TIGHTER_TOLERANCE: f64 = 100.0;

/// Largest damping rate × step of the `damping` candidate (dimensionless).
const MAX_DAMPING_STEP: f64 = 0.2;

/// The finite-difference step of a fit, as a fraction of each parameter's
/// scale ([`Model::fd_step`]): a stretch solved to 1e-4 scatters the markers by
/// about a micrometre from run to run of nearby parameters, and a compliance
/// moved by 1e-4 of its scale (1 % stretch under a column's weight) moves
/// them less than that — the fit of a hidden 3e-3 m/N stayed at its start of
/// 0 on the curtain. A twentieth of the scale moves them well above it.
const FD_STEP: f64 = 0.05;

/// Largest bending stiffness × step² / particle mass of the `bend-springs` candidate.
const MAX_BEND_STEP: f64 = 0.25;

/// The `bending` candidates' scale, a fraction of the cloth's width.
const BENDING_SCALE: f64 = 0.02;

/// Evenly spaced starts of the `bending` candidates' fit across their bounds
/// (bending lengths about 5 % of the width apart).
const BENDING_STARTS: usize = 11;

/// How a [`ClothModel`] simulates.
#[derive(Clone, Debug, PartialEq)]
pub struct PredictSettings {
    /// Constraint method; default [`Method::Newton`].
    pub method: Method,
    /// Relative stretch tolerance; `None` (default) uses the scene's.
    pub stretch_tolerance: Option<f64>,
    /// Iteration limit per step; default 200.
    pub max_iterations: usize,
    /// Steps per scene step (the step is the scene's `dt` divided by it); default 1.
    pub step_divisor: usize,
    /// Standard deviation of a random displacement of every dynamic vertex at
    /// the start (m); default 0.
    pub perturbation: f64,
    /// Seed of that displacement.
    pub seed: u64,
}

impl Default for PredictSettings {
    fn default() -> Self {
        Self {
            method: Method::Newton,
            stretch_tolerance: None,
            max_iterations: 200,
            step_divisor: 1,
            perturbation: 0.0,
            seed: 1,
        }
    }
}

/// A cloth scene that the measurement loop can hold against a marker recording.
#[derive(Clone, Debug)]
pub struct ClothModel {
    scene: Scene,
    settings: PredictSettings,
    /// The worst stretch tolerance out of reach that a prediction met (shared by
    /// the clones a fit makes), for [`Model::notes`].
    stagnation: std::sync::Arc<std::sync::Mutex<Option<Stagnation>>>,
    /// Plain descriptions of the effects built in, for the file's header.
    added: Vec<String>,
    /// The scene as text, taken once: what [`Model::vanishes`] compares an
    /// edited scene with.
    scene_text: std::sync::OnceLock<String>,
}

impl ClothModel {
    /// A model of `scene`, simulated with the default [`PredictSettings`].
    #[must_use]
    pub fn new(scene: Scene) -> Self {
        Self {
            scene,
            settings: PredictSettings::default(),
            stagnation: std::sync::Arc::default(),
            added: Vec::new(),
            scene_text: std::sync::OnceLock::new(),
        }
    }

    /// A model of the scene file at `path`.
    ///
    /// # Errors
    /// As [`Scene::from_path`].
    pub fn from_path(path: &Path) -> Result<Self> {
        Ok(Self::new(Scene::from_path(path)?))
    }

    /// The same model simulated with `settings`.
    #[must_use]
    pub fn with_settings(mut self, settings: PredictSettings) -> Self {
        self.settings = settings;
        self
    }

    /// The scene (with every effect built in so far).
    #[must_use]
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// How the model simulates.
    #[must_use]
    pub fn settings(&self) -> &PredictSettings {
        &self.settings
    }

    /// The scene with `effects` applied in turn.
    ///
    /// # Errors
    /// [`ClothError::Scene`] for an effect the scene does not offer, or
    /// values of the wrong count, non-finite, or outside the candidate's bounds.
    pub fn edited(&self, effects: &[(&Candidate, &[f64])]) -> Result<Scene> {
        let mut scene = self.scene.clone();
        for (candidate, values) in effects {
            apply(&mut scene, candidate, values)?;
        }
        Ok(scene)
    }

    /// The largest distance, per marker coordinate and sample, of the nominal prediction
    /// from the runs with `settings` (m).
    fn largest_distance(
        &self,
        rec: &Recording,
        settings: &[PredictSettings],
    ) -> modelgap_core::Result<Prediction> {
        let nominal = self.predict(rec)?;
        let mut largest: Vec<Vec<f64>> =
            nominal.values.iter().map(|v| vec![0.0; v.len()]).collect();
        for settings in settings {
            let other = self
                .predict_settings(rec, &[], settings)
                .map_err(|e| model_error(&[], e))?;
            for ((l, a), b) in largest.iter_mut().zip(&nominal.values).zip(&other.values) {
                for ((l, a), b) in l.iter_mut().zip(a).zip(b) {
                    *l = l.max((a - b).abs());
                }
            }
        }
        Ok(Prediction {
            names: nominal.names,
            values: largest,
        })
    }

    /// Predicts the recording's marker signals with `effects`, simulated with `settings`.
    fn predict_settings(
        &self,
        rec: &Recording,
        effects: &[(&Candidate, &[f64])],
        settings: &PredictSettings,
    ) -> Result<Prediction> {
        let scene = self.edited(effects)?;
        let n_vertices = scene.cloth.nx * scene.cloth.nz;
        let signals: Vec<(&str, u32, usize)> = rec
            .signals()
            .iter()
            .filter_map(|s| {
                let (id, axis) = parse_marker_signal(&s.name)?;
                ((id as usize) < n_vertices).then_some((s.name.as_str(), id, axis))
            })
            .collect();
        if signals.is_empty() {
            return Err(ClothError::Scene {
                scene: scene.name.clone(),
                message: format!(
                    "the recording holds no marker signal m{{id}}.x|y|z of the grid's {n_vertices} vertices"
                ),
            });
        }
        let mut ids: Vec<u32> = signals.iter().map(|s| s.1).collect();
        ids.sort_unstable();
        ids.dedup();
        let pins = if scene.pins_from_markers {
            Some(recording_to_markers(rec)?)
        } else {
            None
        };
        let (frames, stagnation) =
            simulate_markers_report(&scene, &ids, rec.t(), settings, pins.as_ref())?;
        if let Some(found) = stagnation
            && let Ok(mut worst) = self.stagnation.lock()
            && worst.is_none_or(|w| found.reached > w.reached)
        {
            *worst = Some(found);
        }
        let values = signals
            .iter()
            .map(|&(_, id, axis)| {
                let k = ids.binary_search(&id).unwrap_or(0);
                frames.positions().iter().map(|f| f[k][axis]).collect()
            })
            .collect();
        Ok(Prediction {
            names: signals.iter().map(|s| s.0.to_string()).collect(),
            values,
        })
    }
}

impl From<Scene> for ClothModel {
    fn from(scene: Scene) -> Self {
        Self::new(scene)
    }
}

/// The name of a marker coordinate signal: `m{id}.x` (axis 0), `.y` (1), `.z` (2).
#[must_use]
pub fn marker_signal(id: u32, axis: usize) -> String {
    format!("m{id}.{}", ["x", "y", "z"][axis.min(2)])
}

/// The marker id and axis (0, 1, 2 for x, y, z) of a signal named `m{id}.x|y|z`.
#[must_use]
pub fn parse_marker_signal(name: &str) -> Option<(u32, usize)> {
    let rest = name.strip_prefix('m')?;
    let (id, axis) = rest.split_once('.')?;
    let axis = match axis {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        _ => return None,
    };
    if id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((id.parse().ok()?, axis))
}

/// A marker recording as a core recording: signals `m{id}.x`, `m{id}.y`,
/// `m{id}.z` per marker, in the recording's marker order.
///
/// # Errors
/// [`ClothError::Core`] if the recording cannot be built (it always can from
/// a valid [`MarkerRecording`]).
pub fn markers_to_recording(markers: &MarkerRecording) -> Result<Recording> {
    let mut signals = Vec::with_capacity(3 * markers.n_markers());
    for (k, &id) in markers.ids().iter().enumerate() {
        for axis in 0..3 {
            let values = markers.positions().iter().map(|f| f[k][axis]).collect();
            signals.push(Signal::new(marker_signal(id, axis), values));
        }
    }
    Ok(Recording::new(markers.t().to_vec(), signals)?)
}

/// The markers of a core recording: every id with all three signals
/// `m{id}.x|y|z`, in the order of their first signal; other signals are ignored.
///
/// # Errors
/// [`ClothError::MarkerField`] when the recording holds no complete marker.
pub fn recording_to_markers(rec: &Recording) -> Result<MarkerRecording> {
    let mut ids: Vec<u32> = Vec::new();
    for s in rec.signals() {
        if let Some((id, _)) = parse_marker_signal(&s.name)
            && !ids.contains(&id)
        {
            ids.push(id);
        }
    }
    let mut tracks: Vec<(u32, [&[f64]; 3])> = Vec::new();
    for id in ids {
        let axis = |a: usize| {
            rec.signal(&marker_signal(id, a))
                .map(|s| s.values.as_slice())
        };
        if let (Some(x), Some(y), Some(z)) = (axis(0), axis(1), axis(2)) {
            tracks.push((id, [x, y, z]));
        }
    }
    if tracks.is_empty() {
        return MarkerRecording::new(rec.t().to_vec(), Vec::new(), Vec::new());
    }
    let frames = (0..rec.len())
        .map(|k| {
            tracks
                .iter()
                .map(|(_, [x, y, z])| [x[k], y[k], z[k]])
                .collect()
        })
        .collect();
    MarkerRecording::new(
        rec.t().to_vec(),
        tracks.iter().map(|t| t.0).collect(),
        frames,
    )
}

/// Runs `scene` from its initial state and records vertices `ids` at times
/// `t` (s; simulated time 0 is the scene's start, samples at or before it
/// get the initial positions, samples between steps are interpolated
/// linearly). The scene's effects act: forces each step, compliance, point
/// masses. With `pins`, pinned vertices whose ids it holds follow it.
///
/// # Errors
/// [`ClothError::VertexOutOfRange`] for an id past the grid; the scene's and
/// the steps' errors; [`ClothError::MarkerField`] etc. if the frames cannot
/// form a recording (an empty `t` or `ids`).
pub fn simulate_markers(
    scene: &Scene,
    ids: &[u32],
    t: &[f64],
    settings: &PredictSettings,
    pins: Option<&MarkerRecording>,
) -> Result<MarkerRecording> {
    simulate_markers_report(scene, ids, t, settings, pins).map(|(frames, _)| frames)
}

/// As [`simulate_markers`], with where the stretch tolerance proved out of reach
/// ([`crate::Stagnation`], `None` when every step reached it).
///
/// # Errors
/// As [`simulate_markers`].
pub fn simulate_markers_report(
    scene: &Scene,
    ids: &[u32],
    t: &[f64],
    settings: &PredictSettings,
    pins: Option<&MarkerRecording>,
) -> Result<(MarkerRecording, Option<Stagnation>)> {
    let mut sw = SceneWorld::new(scene, pins)?;
    let n = sw.positions().len();
    if let Some(&bad) = ids.iter().find(|&&id| id as usize >= n) {
        return Err(ClothError::VertexOutOfRange {
            vertex: bad as usize,
            n_vertices: n,
        });
    }
    {
        let p = sw.world.params_mut();
        p.method = settings.method;
        p.max_iterations = settings.max_iterations;
        if let Some(tol) = settings.stretch_tolerance {
            p.stretch_tolerance = tol;
        }
    }
    if settings.perturbation > 0.0 {
        let first = sw.world.particle(sw.cloth, 0)?.index();
        let mut g = Gaussian::new(settings.seed);
        let ps = sw.world.particles_mut();
        for i in first..first + n {
            if ps.inv_mass[i] > 0.0 {
                let d = Vector3::new(g.sample(), g.sample(), g.sample());
                ps.positions[i] += settings.perturbation * d;
            }
        }
    }
    let h = scene.dt / settings.step_divisor.max(1) as f64;
    let take = |x: &[Vector3<f64>]| -> Vec<[f64; 3]> {
        ids.iter()
            .map(|&id| {
                let p = x[id as usize];
                [p.x, p.y, p.z]
            })
            .collect()
    };
    let mut frames = Vec::with_capacity(t.len());
    let mut steps = 0usize;
    let mut prev = take(sw.positions());
    for &tj in t {
        // Step until the step's end reaches the sample (to within rounding).
        while (steps as f64) * h < tj - 1e-9 * h {
            prev = take(sw.positions());
            sw.step(h)?;
            steps += 1;
        }
        let now = take(sw.positions());
        let t_now = steps as f64 * h;
        if steps == 0 || (t_now - tj).abs() <= 1e-9 * h {
            frames.push(now);
        } else {
            // Between the last two steps.
            let s = 1.0 - (t_now - tj) / h;
            frames.push(
                prev.iter()
                    .zip(&now)
                    .map(|(a, b)| std::array::from_fn(|i| a[i] + s * (b[i] - a[i])))
                    .collect(),
            );
        }
    }
    let stagnation = sw.world.stagnation().copied();
    Ok((
        MarkerRecording::new(t.to_vec(), ids.to_vec(), frames)?,
        stagnation,
    ))
}

/// The typical sizes of a scene that set the candidates' scales and bounds.
struct SceneScales {
    n_vertices: usize,
    particle_mass: f64,
    spacing: f64,
    gravity: f64,
    dt: f64,
    /// The cloth's width (m).
    size: f64,
}

impl SceneScales {
    fn of(scene: &Scene) -> Self {
        let c = &scene.cloth;
        Self {
            n_vertices: c.nx * c.nz,
            particle_mass: c.particle_mass,
            spacing: c.spacing,
            gravity: scene.params.gravity.norm().max(1e-3),
            dt: scene.dt,
            size: c.spacing * (c.nx.max(2) - 1) as f64,
        }
    }
}

/// The cloth's weight per area `w` (N/m²): what turns a bending length `c`
/// into a rigidity, `B = w c³`.
fn weight_per_area(scene: &Scene) -> f64 {
    let c = &scene.cloth;
    c.particle_mass * scene.params.gravity.norm().max(1e-3) / (c.spacing * c.spacing)
}

/// The `bending_length` parameter (m) of a bending candidate whose rigidity is
/// `current` (N·m): the cloth's bending length `c = (B / w)^(1/3)` (Peirce's,
/// what a cantilever test of a fabric measures; `w` the weight per area), so
/// `B = w c³`. From a fifth of the grid spacing (a rigidity no recording can
/// tell from none; not 0, where `B` has no slope in `c`) to half the cloth's
/// width — past it a sheet hardly drapes, it is a plate. The implicit step is
/// stable for any value ([`crate::bending`]): the bound is physics, not the
/// step. The fit starts from the best of [`BENDING_STARTS`] lengths across the
/// bounds: the response of a driven cloth is resonant in `B`, and on the
/// swinging curtain (hidden `B = 0.01` N·m) the error has a plateau at 1e-3 to
/// 3e-3 N·m that a fit of `B` from 0 stopped on (found 1.5e-3).
fn bending_length_param(s: &SceneScales, w: f64, current: f64) -> EffectParam {
    let lower = 0.2 * s.spacing;
    let c = (current.max(0.0) / w).cbrt();
    EffectParam::new(
        "bending_length",
        "m",
        c.max(lower),
        (lower, (0.5 * s.size).max(2.0 * c)),
        BENDING_SCALE * s.size,
    )
    .with_grid(BENDING_STARTS)
}

/// The compliance parameters of a material at `current` (its values, those
/// underneath filled in): `compliance`, or `warp_compliance` and
/// `weft_compliance` when `declared` (the cloth, or the region) sets warp or
/// weft apart. Scale: 1 % stretch of a link under the weight of a column of
/// the grid.
fn compliance_params(
    scene: &Scene,
    s: &SceneScales,
    current: &Material,
    declared: &Material,
) -> Vec<EffectParam> {
    let column_weight = s.particle_mass * s.gravity * scene.cloth.nz as f64;
    let scale = 0.01 * s.spacing / column_weight;
    let param = |name: &str, value: f64| {
        EffectParam::new(
            name,
            "m/N",
            value,
            (0.0, (20.0 * scale).max(2.0 * value)),
            scale,
        )
    };
    let c = current.compliance.unwrap_or(0.0);
    if declared.is_anisotropic() || scene.effects.compliance_is_anisotropic() {
        vec![
            param("warp_compliance", current.warp_compliance.unwrap_or(c)),
            param("weft_compliance", current.weft_compliance.unwrap_or(c)),
        ]
    } else {
        vec![param("compliance", c)]
    }
}

/// The candidate effects of a scene (see the [module docs](self)).
#[must_use]
pub fn candidates(scene: &Scene) -> Vec<Candidate> {
    let s = SceneScales::of(scene);
    let fx = &scene.effects.forces;
    let kind = |current: f64| {
        if current > 0.0 {
            EffectKind::ParameterDeviation
        } else {
            EffectKind::MissingElement
        }
    };
    let cd_bounds = (0.0, 5.0);
    let mut out = vec![Candidate {
        id: "air-drag".into(),
        name: "aerodynamic drag on the cloth's triangles".into(),
        kind: kind(fx.drag_coefficient),
        acts_on: "cloth".into(),
        params: vec![EffectParam::new(
            "drag_coefficient",
            "1",
            fx.drag_coefficient,
            cd_bounds,
            0.2,
        )],
    }];
    let mut wind = Vec::new();
    if fx.drag_coefficient == 0.0 {
        wind.push(EffectParam::new(
            "drag_coefficient",
            "1",
            1.0,
            cd_bounds,
            0.2,
        ));
    }
    for (axis, w) in ["wind_x", "wind_y", "wind_z"].iter().zip(fx.wind.iter()) {
        wind.push(EffectParam::new(*axis, "m/s", *w, (-20.0, 20.0), 0.5));
    }
    out.push(Candidate {
        id: "wind".into(),
        name: "a constant wind".into(),
        kind: if fx.wind == Vector3::zeros() {
            EffectKind::MissingElement
        } else {
            EffectKind::ParameterDeviation
        },
        acts_on: "cloth".into(),
        params: wind,
    });
    out.push(Candidate {
        id: "skin-friction".into(),
        name: "tangential air drag (skin friction along the cloth)".into(),
        kind: kind(fx.skin_friction),
        acts_on: "cloth".into(),
        params: vec![
            EffectParam::new(
                "skin_friction",
                "1",
                fx.skin_friction,
                (0.0, (5.0_f64).max(2.0 * fx.skin_friction)),
                0.2,
            )
            .with_grid(3),
        ],
    });
    let max_damping = MAX_DAMPING_STEP / s.dt;
    out.push(Candidate {
        id: "damping".into(),
        name: "velocity damping (a force -c m v on every particle)".into(),
        kind: kind(fx.damping),
        acts_on: "cloth".into(),
        params: vec![EffectParam::new(
            "damping",
            "1/s",
            fx.damping,
            (0.0, max_damping.max(fx.damping)),
            max_damping / 40.0,
        )],
    });
    let effects = &scene.effects;
    let w = weight_per_area(scene);
    let bending = |id: String, name: String, acts_on: String, current: f64| Candidate {
        id,
        name,
        kind: kind(current),
        acts_on,
        params: vec![bending_length_param(&s, w, current)],
    };
    out.push(bending(
        "bending".into(),
        "bending stiffness (quadratic bending energy about the flat state)".into(),
        "cloth".into(),
        effects.bending_rigidity,
    ));
    if fx.bend_stiffness > 0.0 {
        let max_bend = MAX_BEND_STEP * s.particle_mass / (s.dt * s.dt);
        out.push(Candidate {
            id: "bend-springs".into(),
            name: "the bend springs' stiffness is off".into(),
            kind: EffectKind::ParameterDeviation,
            acts_on: "cloth".into(),
            params: vec![EffectParam::new(
                "bend_stiffness",
                "N/m",
                fx.bend_stiffness,
                (0.0, max_bend.max(fx.bend_stiffness)),
                max_bend / 20.0,
            )],
        });
    }
    let base = effects.base_material();
    out.push(Candidate {
        id: "compliance".into(),
        name: if base.is_anisotropic() {
            "stretch compliance, warp and weft (the cloth is not quite inextensible)".into()
        } else {
            "stretch compliance (the cloth is not quite inextensible)".into()
        },
        kind: kind(
            effects.compliance.max(
                base.warp_compliance
                    .unwrap_or(0.0)
                    .max(base.weft_compliance.unwrap_or(0.0)),
            ),
        ),
        acts_on: "cloth".into(),
        params: compliance_params(scene, &s, &base, &base),
    });
    for region in &effects.materials {
        let m = &region.material;
        let acts_on = format!("material region \"{}\"", region.name);
        let under = Material {
            compliance: m.compliance.or(Some(effects.compliance)),
            warp_compliance: m.warp_compliance.or(base.warp_compliance),
            weft_compliance: m.weft_compliance.or(base.weft_compliance),
            ..m.clone()
        };
        let params = compliance_params(scene, &s, &under, m);
        out.push(Candidate {
            id: format!("compliance@{}", region.name),
            name: format!(
                "stretch compliance{} of region {}",
                if params.len() == 2 {
                    ", warp and weft,"
                } else {
                    ""
                },
                region.name
            ),
            kind: kind(params.iter().map(|p| p.initial).fold(0.0, f64::max)),
            acts_on: acts_on.clone(),
            params,
        });
        let region_b = m.bending_rigidity.unwrap_or(effects.bending_rigidity);
        out.push(bending(
            format!("bending@{}", region.name),
            format!("bending stiffness of region {}", region.name),
            acts_on.clone(),
            region_b,
        ));
        let region_c = m.damping.unwrap_or(fx.damping);
        out.push(Candidate {
            id: format!("damping@{}", region.name),
            name: format!("velocity damping of region {}", region.name),
            kind: kind(region_c),
            acts_on,
            params: vec![EffectParam::new(
                "damping",
                "1/s",
                region_c,
                (0.0, max_damping.max(region_c)),
                max_damping / 40.0,
            )],
        });
    }

    let total = s.particle_mass * s.n_vertices as f64;
    out.push(Candidate {
        id: "mass".into(),
        name: "the cloth's total mass is off".into(),
        kind: EffectKind::ParameterDeviation,
        acts_on: "cloth".into(),
        params: vec![EffectParam::new(
            "total_mass",
            "kg",
            total,
            (0.1 * total, 10.0 * total),
            0.1 * total,
        )],
    });
    let (nx, nz) = (scene.cloth.nx, scene.cloth.nz);
    let col = EffectParam::new("col", "1", 0.0, (0.0, (nx - 1) as f64), 1.0)
        .with_grid(nx.min(4))
        .with_step(1.0);
    let row = EffectParam::new("row", "1", 0.0, (0.0, (nz - 1) as f64), 1.0)
        .with_grid(nz.min(4))
        .with_step(1.0);
    out.push(Candidate {
        id: "point-mass".into(),
        name: "an extra point mass at a vertex".into(),
        kind: EffectKind::MissingElement,
        acts_on: "a vertex (col, row) of the grid".into(),
        params: vec![
            col,
            row,
            EffectParam::new("mass", "kg", 0.0, (0.0, total), 5.0 * s.particle_mass),
        ],
    });
    for (k, c) in scene.colliders.iter().enumerate() {
        out.push(Candidate {
            id: format!("friction@collider{k}"),
            name: format!("friction on collider {k} is off"),
            kind: EffectKind::ParameterDeviation,
            acts_on: format!("collider {k}"),
            params: vec![EffectParam::new(
                "friction",
                "1",
                c.friction,
                (0.0, 2.0),
                0.1,
            )],
        });
    }
    out
}

/// Applies a candidate's values to a scene.
fn apply(scene: &mut Scene, candidate: &Candidate, values: &[f64]) -> Result<()> {
    let w = weight_per_area(scene);
    let bad = |message: String| ClothError::Scene {
        scene: scene.name.clone(),
        message: format!("effect {}: {message}", candidate.id),
    };
    if values.len() != candidate.params.len() {
        return Err(bad(format!(
            "expected {} values ({}), found {}",
            candidate.params.len(),
            candidate
                .params
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            values.len()
        )));
    }
    for (p, &v) in candidate.params.iter().zip(values) {
        if !(v.is_finite() && v >= p.lower && v <= p.upper) {
            return Err(bad(format!(
                "{} must be in [{}, {}] {}, found {v}",
                p.name, p.lower, p.upper, p.unit
            )));
        }
    }
    let value = |name: &str| {
        candidate
            .params
            .iter()
            .position(|p| p.name == name)
            .map(|i| values[i])
    };
    let (nx, nz) = (scene.cloth.nx, scene.cloth.nz);
    if candidate.id == "point-mass" {
        let (Some(col), Some(row), Some(mass)) = (value("col"), value("row"), value("mass")) else {
            return Err(bad("expected parameters col, row and mass".into()));
        };
        if mass > 0.0 {
            scene.effects.point_masses.push(PointMass {
                vertex: nearest_vertex(col, row, nx, nz),
                mass,
            });
        }
        return Ok(());
    }
    if let Some(k) = candidate.id.strip_prefix("friction@collider") {
        let collider = k
            .parse::<usize>()
            .ok()
            .and_then(|k| scene.colliders.get_mut(k));
        let (Some(collider), Some(mu)) = (collider, value("friction")) else {
            return Err(bad(format!(
                "the scene has {} colliders",
                scene.colliders.len()
            )));
        };
        collider.friction = mu;
        return Ok(());
    }
    if let Some((what, region)) = candidate.id.split_once('@')
        && matches!(what, "compliance" | "bending" | "damping")
    {
        let Some(r) = scene
            .effects
            .materials
            .iter_mut()
            .find(|r| r.name == region)
        else {
            let known: Vec<&str> = scene
                .effects
                .materials
                .iter()
                .map(|r| r.name.as_str())
                .collect();
            return Err(bad(format!(
                "the scene has no material region \"{region}\" ({})",
                if known.is_empty() {
                    "it declares none".to_owned()
                } else {
                    format!("known: {}", known.join(", "))
                }
            )));
        };
        let m = &mut r.material;
        for (p, &v) in candidate.params.iter().zip(values) {
            match p.name.as_str() {
                "compliance" => m.compliance = Some(v),
                "warp_compliance" => m.warp_compliance = Some(v),
                "weft_compliance" => m.weft_compliance = Some(v),
                "bending_length" => m.bending_rigidity = Some(w * v.powi(3)),
                "damping" => m.damping = Some(v),
                other => return Err(bad(format!("unknown parameter {other}"))),
            }
        }
        return Ok(());
    }
    let fx = &mut scene.effects.forces;
    let mut known = false;
    for (p, &v) in candidate.params.iter().zip(values) {
        known = true;
        match p.name.as_str() {
            "drag_coefficient" => fx.drag_coefficient = v,
            "skin_friction" => fx.skin_friction = v,
            "wind_x" => fx.wind.x = v,
            "wind_y" => fx.wind.y = v,
            "wind_z" => fx.wind.z = v,
            "damping" => fx.damping = v,
            "bend_stiffness" => fx.bend_stiffness = v,
            "compliance" => scene.effects.compliance = v,
            "warp_compliance" => scene.effects.warp_compliance = Some(v),
            "weft_compliance" => scene.effects.weft_compliance = Some(v),
            "bending_length" => scene.effects.bending_rigidity = w * v.powi(3),
            "total_mass" => scene.cloth.particle_mass = v / (nx * nz) as f64,
            other => return Err(bad(format!("unknown parameter {other}"))),
        }
    }
    if !known {
        return Err(bad("the effect has no parameters".into()));
    }
    Ok(())
}

/// The vertex nearest to the grid place `(col, row)` (clamped to the grid).
fn nearest_vertex(col: f64, row: f64, nx: usize, nz: usize) -> u32 {
    let c = (col.round().max(0.0) as usize).min(nx - 1);
    let r = (row.round().max(0.0) as usize).min(nz - 1);
    (r * nx + c) as u32
}

/// The loop's error for a failed prediction or edit, naming the effects.
fn model_error(effects: &[(&Candidate, &[f64])], e: ClothError) -> CoreError {
    let context = (!effects.is_empty()).then(|| {
        format!(
            "with {}",
            effects
                .iter()
                .map(|(c, v)| format!("{} at {v:?}", c.id))
                .collect::<Vec<_>>()
                .join(", ")
        )
    });
    match e {
        ClothError::Core(core) if context.is_none() => core,
        other => CoreError::from_model(context, other),
    }
}

/// Running maximum over ±`half` samples.
fn envelope(x: &[f64], half: usize) -> Vec<f64> {
    (0..x.len())
        .map(|k| {
            let lo = k.saturating_sub(half);
            let hi = (k + half + 1).min(x.len());
            x[lo..hi].iter().copied().fold(0.0, f64::max)
        })
        .collect()
}

impl Model for ClothModel {
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// Per marker and region ([`crate::report::story`]).
    fn story(&self) -> &dyn modelgap_core::story::Story {
        self
    }

    /// A marker recording (`t,id,x,y,z` CSV or `/markers` MCAP) as signals
    /// `m{id}.x|y|z`, every id checked against the grid at its own line or message.
    fn read_recording(&self, path: &Path) -> modelgap_core::Result<Recording> {
        let n = self
            .scene
            .cloth
            .n_vertices()
            .map_err(crate::report::story::seam)?;
        let markers = crate::markers::read_markers_path_within(path, n).map_err(|e| match e {
            ClothError::Core(core) => core,
            other => CoreError::from_model(
                Some(format!(
                    "reading markers for scene {} ({} x {} grid)",
                    self.scene.name, self.scene.cloth.nx, self.scene.cloth.nz
                )),
                other,
            ),
        })?;
        markers_to_recording(&markers).map_err(crate::report::story::seam)
    }

    /// Whether pinned vertices follow the recorded markers; the grid's unmarked vertices
    /// are not listed (a recording marks a few of them).
    /// Pinned vertices following the markers; and, once a prediction has run, a
    /// stretch tolerance the solver could not reach (the level it held instead).
    fn notes(&self, rec: &Recording) -> Vec<String> {
        let _ = rec;
        let mut notes = Vec::new();
        if self.scene.pins_from_markers {
            notes.push("pinned vertices with markers follow the recorded positions".to_owned());
        }
        if let Ok(found) = self.stagnation.lock()
            && let Some(s) = *found
        {
            notes.push(format!("the cloth solver: {s}"));
        }
        notes
    }

    fn outputs(&self) -> Vec<String> {
        let n = (self.scene.cloth.nx * self.scene.cloth.nz) as u32;
        (0..n)
            .flat_map(|id| (0..3).map(move |axis| marker_signal(id, axis)))
            .collect()
    }

    fn unit(&self, output: &str) -> String {
        if parse_marker_signal(output).is_some() {
            "m".into()
        } else {
            String::new()
        }
    }

    fn predict_with(
        &self,
        rec: &Recording,
        effects: &[(&Candidate, &[f64])],
    ) -> modelgap_core::Result<Prediction> {
        self.predict_settings(rec, effects, &self.settings)
            .map_err(|e| model_error(effects, e))
    }

    fn candidates(&self) -> Vec<Candidate> {
        candidates(&self.scene)
    }

    /// `(1e-6, 1e-4)`: a simulation is exact only to its stretch tolerance,
    /// so a fit stops when a step changes the cost by under 1e-6 or the
    /// parameters by under 1e-4 of their scales (on the 30 × 30 drag case
    /// this halved explain's time, 178 → 80 s, with C_d still within 0.1 %).
    fn fit_tolerances(&self) -> Option<(f64, f64)> {
        Some((1e-6, 1e-4))
    }

    fn fd_step(&self) -> Option<f64> {
        Some(FD_STEP)
    }

    /// A prediction is a whole simulation of the cloth (0.1–0.4 s for a 24 × 24 curtain
    /// over 3 s): fits update their Jacobian by secant steps.
    fn costly_predictions(&self) -> bool {
        true
    }

    /// Where the edit leaves the scene as it is (a point mass of 0 kg, a
    /// drag coefficient at its current value).
    fn vanishes(&self, c: &Candidate, values: &[f64]) -> bool {
        let nominal = self.scene_text.get_or_init(|| format!("{:?}", self.scene));
        self.edited(&[(c, values)])
            .is_ok_and(|edited| format!("{edited:?}") == *nominal)
    }

    fn with_effects(&self, effects: &[Effect]) -> modelgap_core::Result<Box<dyn Model>> {
        let pairs: Vec<(&Candidate, &[f64])> = effects
            .iter()
            .map(|e| (&e.candidate, e.values.as_slice()))
            .collect();
        let scene = self.edited(&pairs).map_err(|e| model_error(&pairs, e))?;
        let mut added = self.added.clone();
        added.extend(effects.iter().map(|e| e.to_string()));
        Ok(Box::new(ClothModel {
            scene,
            settings: self.settings.clone(),
            stagnation: std::sync::Arc::default(),
            added,
            scene_text: std::sync::OnceLock::new(),
        }))
    }

    /// The scene file ([`Scene::to_toml`]), headed by a comment line per
    /// effect built in; `None` when the scene holds a collider the file
    /// format cannot write.
    fn to_file_text(&self) -> Option<String> {
        let mut s = String::new();
        for a in &self.added {
            let _ = writeln!(s, "# added by explain: {a}");
        }
        s.push_str(&self.scene.to_toml().ok()?);
        Some(s)
    }

    fn file_extension(&self) -> &'static str {
        "toml"
    }

    /// The largest distance of the scene's prediction from a run at half the step, from
    /// one with every dynamic vertex displaced at the start by [`SPREAD_PERTURBATION`]
    /// (Gaussian), and from one at a [`TIGHTER_TOLERANCE`] times tighter stretch tolerance,
    /// per marker coordinate and sample. Costs about five simulations (one at half the
    /// step, one at the tighter tolerance). On the curtain of `examples/data/curtain.toml`
    /// the paper's step at 1e-4 lies 1.6 mm from the same step at 1e-6: more than the
    /// markers' noise, and explain named it a skin friction.
    fn numerical_error(&self, rec: &Recording) -> modelgap_core::Result<Option<Prediction>> {
        let half = PredictSettings {
            step_divisor: 2 * self.settings.step_divisor.max(1),
            ..self.settings.clone()
        };
        let nudged = PredictSettings {
            perturbation: SPREAD_PERTURBATION,
            ..self.settings.clone()
        };
        let tolerance =
            (self.settings.stretch_tolerance).unwrap_or(self.scene.params.stretch_tolerance);
        let tighter = PredictSettings {
            stretch_tolerance: Some(tolerance / TIGHTER_TOLERANCE),
            ..self.settings.clone()
        };
        self.largest_distance(rec, &[half, nudged, tighter])
            .map(Some)
    }

    /// The spread of the scene's prediction: [`SPREAD_FACTOR`] times the
    /// largest distance from it of three runs — at half the step, with every
    /// dynamic vertex displaced at the start by [`SPREAD_PERTURBATION`]
    /// (Gaussian), and both — per marker coordinate, as an envelope over
    /// ±[`SPREAD_ENVELOPE`] samples. Costs four simulations (two at half the step).
    fn prediction_spread(&self, rec: &Recording) -> modelgap_core::Result<Option<Prediction>> {
        let divisor = self.settings.step_divisor.max(1);
        let half = PredictSettings {
            step_divisor: 2 * divisor,
            ..self.settings.clone()
        };
        let perturbed = PredictSettings {
            perturbation: SPREAD_PERTURBATION,
            ..self.settings.clone()
        };
        let half_perturbed = PredictSettings {
            perturbation: SPREAD_PERTURBATION,
            seed: self.settings.seed.wrapping_add(1),
            ..half.clone()
        };
        let largest = self.largest_distance(rec, &[half, perturbed, half_perturbed])?;
        let spread = Prediction {
            names: largest.names,
            values: largest
                .values
                .iter()
                .map(|l| {
                    envelope(l, SPREAD_ENVELOPE)
                        .into_iter()
                        .map(|v| SPREAD_FACTOR * v)
                        .collect()
                })
                .collect(),
        };
        Ok(Some(spread))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes;

    const EFFECTS: &str = r#"
name = "fx"
duration = 0.5
dt = 0.01
[cloth]
nx = 4
nz = 3
size = 0.3
pins = [0]
compliance = 0.002
bend_stiffness = 0.5
damping = 0.25
[air]
drag_coefficient = 1.1
wind = [1.0, 0.0, -0.5]
[[point_masses]]
vertex = 11
mass = 0.004
[[colliders]]
shape = "ball"
center = [0.1, -0.4, 0.1]
radius = 0.1
friction = 0.3
"#;

    #[test]
    fn scene_effect_fields_round_trip_through_the_file() {
        let scene = Scene::from_toml(EFFECTS, "fx.toml").unwrap();
        let fx = &scene.effects;
        assert_eq!(fx.forces.drag_coefficient, 1.1);
        assert_eq!(fx.forces.wind, Vector3::new(1.0, 0.0, -0.5));
        assert_eq!((fx.forces.damping, fx.forces.bend_stiffness), (0.25, 0.5));
        assert_eq!(fx.compliance, 0.002);
        assert_eq!(
            fx.point_masses,
            vec![PointMass {
                vertex: 11,
                mass: 0.004
            }]
        );
        let text = scene.to_toml().unwrap();
        let back = Scene::from_toml(&text, "back.toml").unwrap();
        assert_eq!(back.effects, scene.effects);
        assert_eq!(back.to_toml().unwrap(), text);
    }

    #[test]
    fn bad_effect_fields_are_named() {
        let with = |extra: &str| {
            let text = format!(
                "name = 'x'\nduration = 1.0\ndt = 0.01\n[cloth]\nnx = 2\nnz = 2\nsize = 1.0\n{extra}"
            );
            Scene::from_toml(&text, "x").unwrap_err().to_string()
        };
        let e = with("[air]\ndrag_coefficient = -1.0\n");
        assert!(e.contains("air.drag_coefficient"), "{e}");
        let e = with("[[point_masses]]\nvertex = 4\nmass = 0.1\n");
        assert!(e.contains("point_masses[0].vertex"), "{e}");
        let e = with("compliance = -0.1\n");
        assert!(e.contains("cloth.compliance"), "{e}");
    }

    #[test]
    fn markers_and_recordings_convert_both_ways() {
        let markers = MarkerRecording::new(
            vec![0.0, 0.1],
            vec![7, 2],
            vec![
                vec![[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]],
                vec![[0.5, 1.5, 2.5], [3.5, 4.5, 5.5]],
            ],
        )
        .unwrap();
        let rec = markers_to_recording(&markers).unwrap();
        assert_eq!(rec.names()[..3], ["m7.x", "m7.y", "m7.z"]);
        assert_eq!(rec.values("m2.z").unwrap(), &[5.0, 5.5]);
        assert_eq!(recording_to_markers(&rec).unwrap(), markers);
        assert_eq!(parse_marker_signal("m12.y"), Some((12, 1)));
        assert_eq!(parse_marker_signal("m.x"), None);
        assert_eq!(parse_marker_signal("m1.w"), None);
        assert_eq!(parse_marker_signal("omega"), None);
    }

    #[test]
    fn fix_writes_the_fitted_terms_into_the_scene_file() {
        let model = ClothModel::new(scenes::corner().resized(4, 4).unwrap());
        let menu = model.candidates();
        let pick = |id: &str| menu.iter().find(|c| c.id == id).unwrap().clone();
        let effects = vec![
            Effect {
                candidate: pick("air-drag"),
                values: vec![0.7],
            },
            Effect {
                candidate: pick("point-mass"),
                values: vec![2.6, 3.0, 0.002],
            },
        ];
        let fixed = model.with_effects(&effects).unwrap();
        let text = fixed.to_file_text().unwrap();
        assert!(
            text.starts_with("# added by explain: aerodynamic drag"),
            "{text}"
        );
        let back = Scene::from_toml(&text, "fixed.toml").unwrap();
        assert_eq!(back.effects.forces.drag_coefficient, 0.7);
        assert_eq!(
            back.effects.point_masses,
            vec![PointMass {
                vertex: 15,
                mass: 0.002
            }]
        );
        // Out of bounds is an error naming the parameter.
        let e = model
            .with_effects(&[Effect {
                candidate: pick("air-drag"),
                values: vec![-1.0],
            }])
            .err()
            .unwrap();
        assert!(e.to_string().contains("drag_coefficient"), "{e}");
    }

    #[test]
    fn samples_between_steps_are_interpolated() {
        let scene = scenes::corner().resized(3, 3).unwrap();
        let settings = PredictSettings::default();
        let at = |t: Vec<f64>| simulate_markers(&scene, &[8], &t, &settings, None).unwrap();
        let steps = at(vec![0.0, 0.01, 0.02]);
        let mid = at(vec![0.015]);
        let y = |m: &MarkerRecording, k: usize| m.positions()[k][0][1];
        approx::assert_relative_eq!(
            y(&mid, 0),
            0.5 * (y(&steps, 1) + y(&steps, 2)),
            epsilon = 1e-12
        );
        assert!(y(&steps, 2) < y(&steps, 0));
    }
}

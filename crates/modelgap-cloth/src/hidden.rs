//! Cloth recordings with a hidden effect: what the measurement loop is judged on.
//!
//! Each case takes a nominal scene — the [`swing`] scene: a cloth hanging from
//! its top row, which kinematic pin paths swing back and forth perpendicular
//! to its plane — builds the "true" scene from it with the hidden effect (or
//! nothing), runs it with a **richer simulation** than the model's (a 10×
//! tighter stretch tolerance, 1e-6), samples marker vertices at 100 Hz and
//! adds Gaussian marker noise (1 mm by default, seeded). The nominal
//! [`ClothModel`] held against the recording must find the hidden effect (or
//! nothing).
//!
//! The truth keeps the model's step. This solver is first order in time: at
//! half the step the swing scene moves by about 1.4 cm RMS (measured on a
//! 10 × 10 grid, 2 s), fourteen times the marker noise, so the step is part
//! of the model (the scene file's `dt`), and that spread is what
//! [`ClothModel`]'s predictability band ([`modelgap_core::Model::prediction_spread`])
//! lets compare allow for.
//!
//! # Example
//!
//! ```no_run
//! use modelgap_cloth::hidden::{RecordingOptions, cases, record};
//! use modelgap_cloth::model::ClothModel;
//! use modelgap_core::{ExplainOptions, explain};
//!
//! let case = cases(10, 10).into_iter().find(|c| c.name == "drag").unwrap();
//! let rec = record(&case, &RecordingOptions::default())?;
//! let ex = explain(&ClothModel::new(case.scene.clone()), &rec, &ExplainOptions::default())?;
//! assert_eq!(ex.chosen[0].candidate.id, "air-drag");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::f64::consts::{FRAC_PI_2, TAU};

use modelgap_core::noise::Gaussian;
use modelgap_core::{Model as _, Recording};
use nalgebra::{Isometry3, Vector3};

use crate::error::{ClothError, Result};
use crate::kinematic::PinPath;
use crate::markers::MarkerRecording;
use crate::mesh::GridCloth;
use crate::model::{ClothModel, PredictSettings, markers_to_recording, simulate_markers};
use crate::scenes::Scene;
use crate::solver::SolverParams;

/// Amplitude of the swing scene's pin motion (m).
pub const SWING_AMPLITUDE: f64 = 0.1;

/// Frequency of the swing scene's pin motion (Hz).
pub const SWING_FREQUENCY: f64 = 1.0;

/// The swing scene: an `nx × nz` grid, 1 m wide, 1 g per vertex, hanging in
/// the x–y plane from its top row (row 0, at y = 0), every vertex of which
/// follows a kinematic pin path `z(t) = A sin(2π f t)` (A =
/// [`SWING_AMPLITUDE`], f = [`SWING_FREQUENCY`], linear between points every
/// step) for `duration` s; `h` = 0.01 s, tolerance 1e-4. It starts at rest in
/// equilibrium, so nothing but the pins moves it: no snap.
///
/// # Errors
/// [`ClothError::BadGrid`] for fewer than 2 × 2 vertices,
/// [`ClothError::BadParameter`] for a non-positive duration.
pub fn swing(nx: usize, nz: usize, duration: f64) -> Result<Scene> {
    if nx < 2 || nz < 2 {
        return Err(ClothError::BadGrid { nx, nz });
    }
    if !(duration > 0.0 && duration.is_finite()) {
        return Err(ClothError::BadParameter {
            name: "duration",
            expected: "positive and finite (s)",
            value: duration,
        });
    }
    let dt = 0.01;
    let spacing = 1.0 / (nx - 1) as f64;
    // Turn the grid's x–z plane about x: rows hang along −y.
    let pose = Isometry3::new(Vector3::zeros(), Vector3::new(FRAC_PI_2, 0.0, 0.0));
    let mut cloth = GridCloth::new(nx, nz, spacing).world_from_local(pose);
    let n_points = (duration / dt).round() as usize + 1;
    let mut pin_paths = Vec::with_capacity(nx);
    for col in (0..nx).step_by(2) {
        let x = col as f64 * spacing;
        let t: Vec<f64> = (0..n_points).map(|k| k as f64 * dt).collect();
        let points = t
            .iter()
            .map(|&t| Vector3::new(x, 0.0, SWING_AMPLITUDE * (TAU * SWING_FREQUENCY * t).sin()))
            .collect();
        cloth = cloth.pin(col as u32);
        pin_paths.push((col as u32, PinPath::new(t, points)?));
    }
    // Slightly compliant links (1 % stretch of a link under the weight of a
    // column): the top row hangs between pins as a shallow catenary. An
    // inextensible top row would be straight between its pins and could hold
    // no load (infinite tension; the solver stalls and its answer depends on
    // the tolerance), and pinning every top vertex is not allowed (an edge
    // between two pins).
    let compliance = 0.01 * spacing / (cloth.particle_mass * 9.81 * nz as f64);
    Ok(Scene {
        name: "swing".into(),
        description: format!(
            "{nx} x {nz} cloth hanging from its top row, swung {} m at {} Hz",
            SWING_AMPLITUDE, SWING_FREQUENCY
        ),
        duration,
        dt,
        // A tenth of the paper's tolerance: over a hanging column of links
        // the paper's 1e-4 adds up to a millimetre, the marker noise.
        params: SolverParams {
            stretch_tolerance: 1e-5,
            ..SolverParams::default()
        },
        cloth,
        colliders: Vec::new(),
        pin_paths,
        rails: Vec::new(),
        rail_pins: Vec::new(),
        pins_from_markers: false,
        pin_markers: None,
        effects: crate::forces::ClothEffects {
            compliance,
            ..crate::forces::ClothEffects::default()
        },
    })
}

/// A hidden effect: a candidate id of the nominal model and its true values.
#[derive(Clone, Debug, PartialEq)]
pub struct Hidden {
    /// The candidate's id (`air-drag`).
    pub id: String,
    /// Its true parameter values, in the candidate's order.
    pub values: Vec<f64>,
}

/// A hidden-effect case.
#[derive(Clone, Debug)]
pub struct HiddenCase {
    /// Short name (`drag`).
    pub name: String,
    /// The nominal scene: what the model is.
    pub scene: Scene,
    /// The hidden effects (none for the control).
    pub hidden: Vec<Hidden>,
    /// The recorded vertices.
    pub markers: Vec<u32>,
}

/// How a recording is made.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordingOptions {
    /// Sample rate (Hz); default 100.
    pub rate_hz: f64,
    /// Marker noise standard deviation per coordinate (m); default 1e-3.
    pub noise: f64,
    /// Noise seed; default 1.
    pub seed: u64,
    /// The true system's simulation: default the model's step with a
    /// stretch tolerance of 1e-6.
    pub truth: PredictSettings,
}

impl Default for RecordingOptions {
    fn default() -> Self {
        Self {
            rate_hz: 100.0,
            noise: 1e-3,
            seed: 1,
            truth: PredictSettings {
                stretch_tolerance: Some(1e-6),
                ..PredictSettings::default()
            },
        }
    }
}

/// Every `stride`-th vertex along rows and columns (the last row and column
/// always included): a marker set as a motion-capture setup would place it.
#[must_use]
pub fn marker_grid(nx: usize, nz: usize, stride: usize) -> Vec<u32> {
    let pick = |n: usize| {
        let mut v: Vec<usize> = (0..n).step_by(stride.max(1)).collect();
        if v.last() != Some(&(n - 1)) {
            v.push(n - 1);
        }
        v
    };
    let mut ids = Vec::new();
    for row in pick(nz) {
        for col in pick(nx) {
            ids.push((row * nx + col) as u32);
        }
    }
    ids
}

fn case(name: &str, scene: &Scene, hidden: &[(&str, &[f64])], markers: &[u32]) -> HiddenCase {
    HiddenCase {
        name: name.into(),
        scene: scene.clone(),
        hidden: hidden
            .iter()
            .map(|(id, v)| Hidden {
                id: (*id).into(),
                values: v.to_vec(),
            })
            .collect(),
        markers: markers.to_vec(),
    }
}

/// The project's hidden-effect cases on a swing scene of `nx × nz` vertices
/// (2 s), markers every third vertex: air drag (`C_d` = 0.8), stretch
/// compliance (links stretch about 0.9 % under a column's weight), an extra
/// point mass (ten particle masses at the bottom row, two thirds across)
/// and the control with nothing hidden.
///
/// # Panics
/// Never for `nx, nz ≥ 2` (smaller grids give the swing scene's error as a panic message).
#[must_use]
pub fn cases(nx: usize, nz: usize) -> Vec<HiddenCase> {
    let scene = match swing(nx.max(2), nz.max(2), 2.0) {
        Ok(s) => s,
        Err(e) => panic!("the swing scene is valid for any grid of at least 2 x 2: {e}"),
    };
    let (nx, nz) = (scene.cloth.nx, scene.cloth.nz);
    let markers = marker_grid(nx, nz, 3);
    let m = scene.cloth.particle_mass;
    // The links stretch 2.5 times more than the model says.
    let compliance = 2.5 * scene.effects.compliance;
    // On the marker grid's last row, the column two thirds across.
    let col = markers
        .iter()
        .map(|&v| v as usize % nx)
        .filter(|&c| 3 * c >= 2 * (nx - 1))
        .min()
        .unwrap_or(nx - 1);
    let col = col as f64;
    let row = (nz - 1) as f64;
    vec![
        case("drag", &scene, &[("air-drag", &[0.8])], &markers),
        case(
            "compliance",
            &scene,
            &[("compliance", &[compliance])],
            &markers,
        ),
        case(
            "point-mass",
            &scene,
            &[("point-mass", &[col, row, 10.0 * m])],
            &markers,
        ),
        case("nothing", &scene, &[], &markers),
    ]
}

/// The true scene of a case: its nominal scene with the hidden effects built in.
///
/// # Errors
/// [`ClothError::Scene`] for a hidden id the scene does not offer or values
/// outside the candidate's bounds.
pub fn true_scene(case: &HiddenCase) -> Result<Scene> {
    let model = ClothModel::new(case.scene.clone());
    let menu = model.candidates();
    let mut effects = Vec::with_capacity(case.hidden.len());
    for h in &case.hidden {
        let c = menu
            .iter()
            .find(|c| c.id == h.id)
            .ok_or_else(|| ClothError::Scene {
                scene: case.scene.name.clone(),
                message: format!("no candidate effect '{}'", h.id),
            })?;
        effects.push((c, h.values.as_slice()));
    }
    model.edited(&effects)
}

/// Records a case: the true scene run with the richer simulation, sampled at
/// `rate_hz` over the scene's duration, with Gaussian noise on every
/// marker coordinate.
///
/// # Errors
/// As [`true_scene`] and [`simulate_markers`].
pub fn record(case: &HiddenCase, opts: &RecordingOptions) -> Result<Recording> {
    let truth = true_scene(case)?;
    let n = (truth.duration * opts.rate_hz).round() as usize;
    let t: Vec<f64> = (0..=n).map(|k| k as f64 / opts.rate_hz).collect();
    let clean = simulate_markers(&truth, &case.markers, &t, &opts.truth, None)?;
    let mut g = Gaussian::new(opts.seed);
    let noisy: Vec<Vec<[f64; 3]>> = clean
        .positions()
        .iter()
        .map(|frame| {
            frame
                .iter()
                .map(|p| p.map(|c| c + opts.noise * g.sample()))
                .collect()
        })
        .collect();
    let markers = MarkerRecording::new(t, case.markers.clone(), noisy)?;
    markers_to_recording(&markers)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn swing_scene_round_trips_through_its_file() {
        let scene = swing(5, 4, 0.5).unwrap();
        let text = scene.to_toml().unwrap();
        let back = Scene::from_toml(&text, "swing").unwrap();
        assert_eq!(back.to_toml().unwrap(), text);
        assert_eq!(back.pin_paths.len(), 3);
        approx::assert_relative_eq!(back.effects.compliance, scene.effects.compliance);
    }

    #[test]
    fn marker_grid_keeps_the_last_row_and_column() {
        assert_eq!(marker_grid(5, 4, 3), vec![0, 3, 4, 15, 18, 19]);
    }
}

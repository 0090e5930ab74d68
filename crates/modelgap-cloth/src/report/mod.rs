//! The cloth side of the measurement loop's story: where on the mesh and when a cloth model
//! fails, as numbers, text, an SVG error map and a Foxglove MCAP.
//!
//! A cloth model's outputs are marker coordinates named `m{id}.x`, `m{id}.y`, `m{id}.z`
//! (`id` is the vertex index in the scene's grid). A core [`Comparison`] holds one residual
//! per coordinate; [`ClothComparison`] turns those into what a person asks about cloth:
//!
//! - the **error per marker**: the RMS over time of the 3D distance between the measured
//!   and the predicted marker (m), beside the marker's noise floor (the 3D RMS a perfect
//!   model would leave, from the per-axis floors);
//! - the **error over time**: at each frame, the RMS over markers of that distance;
//! - the **worst markers** and the **worst regions** of the grid (a 3 × 3 split of its rows
//!   and columns, named by where they are: a corner, an edge, the centre);
//! - the **failure windows**: the times when some marker coordinate leaves its band (the
//!   windows of the core comparison, merged across markers), with how many markers fail and
//!   the one furthest from the model.
//!
//! [`comparison_text`], [`explanation_text`] and [`before_after_text`] print these;
//! [`cloth_report`] builds the HTML report page (the core page with a per-vertex error map
//! and the error over time); [`write_error_mcap`] writes the mesh coloured by error as
//! `foxglove.SceneUpdate` with a `/tf` frame, so Foxglove's 3D panel shows where the model
//! fails.
//!
//! # Example
//!
//! ```
//! use modelgap_cloth::GridCloth;
//! use modelgap_cloth::report::{ClothComparison, comparison_text};
//! use modelgap_core::{Comparison, OutputComparison};
//!
//! // Two markers on a 3 × 3 grid, 3 frames; marker 8 drifts 1 cm in y.
//! let output = |name: &str, residual: [f64; 3]| OutputComparison {
//!     name: name.into(),
//!     unit: "m".into(),
//!     measured: vec![0.0; 3],
//!     predicted: residual.iter().map(|r| -r).collect(),
//!     residual: residual.to_vec(),
//!     stats: modelgap_core::residual::stats(&[0.0; 3], &residual.map(|r| -r)),
//!     noise_floor: 1e-4,
//!     noise_given: true,
//!     noise_method: Default::default(),
//!     quantum: None,
//!     band: 4e-4,
//!     windows: Vec::new(),
//!     effective_samples: 3.0,
//!     finding: None,
//! };
//! let mut outputs = Vec::new();
//! for axis in ["x", "y", "z"] {
//!     outputs.push(output(&format!("m0.{axis}"), [0.0; 3]));
//!     let drift = if axis == "y" { [0.0, 0.005, 0.01] } else { [0.0; 3] };
//!     outputs.push(output(&format!("m8.{axis}"), drift));
//! }
//! let c = Comparison { model: "corner".into(), t: vec![0.0, 0.01, 0.02], outputs, warnings: vec![] };
//! let cloth = ClothComparison::new(&c, &GridCloth::new(3, 3, 0.1).pin(0))?;
//! assert_eq!(cloth.worst_markers(1)[0].id, 8);
//! assert!(comparison_text(&cloth, 5).contains("m8"));
//! # Ok::<(), modelgap_cloth::ClothError>(())
//! ```

use std::collections::BTreeMap;
use std::fmt::Write as _;

use modelgap_core::report::{Report, ResidualPlot, SeriesPlot, format_number, residual_svg};
use modelgap_core::story::{TEXT_WIDTH, build_report, param_text, verdict_sentence, wrap_text};
use modelgap_core::{Comparison, CoreError, Explanation, Verdict};
use serde::Serialize;

use crate::error::{ClothError, Result};
use crate::mesh::GridCloth;
use crate::model::parse_marker_signal;

mod foxglove;
mod map;
pub mod story;

pub use foxglove::{
    CLOTH_ERROR_AFTER_TOPIC, CLOTH_ERROR_TOPIC, ERROR_DECIMALS, ErrorMcap,
    MARKER_ERROR_AFTER_TOPIC, MARKER_ERROR_TOPIC, MEASURED_MARKERS_TOPIC, write_error_mcap,
    write_error_mcap_path,
};
pub use map::{error_colour, error_map_svg};

/// The shortest failure window, in sample periods (as the core comparison's default).
const MIN_WINDOW_SAMPLES: f64 = 5.0;

/// Regions listed in text.
const TOP_REGIONS: usize = 3;

/// Up to this many markers, the text lists every marker's RMS.
const PER_MARKER_LISTED: usize = 48;

/// One marker (a mesh vertex) held against the model over the whole recording.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MarkerError {
    /// The marker id: its vertex index in the grid.
    pub id: u32,
    /// The vertex's column in the grid (along the cloth's local +x).
    pub col: usize,
    /// The vertex's row in the grid (along the cloth's local +z).
    pub row: usize,
    /// RMS over time of the 3D distance between measured and predicted position (m).
    pub rms: f64,
    /// The largest distance (m).
    pub max: f64,
    /// When the largest distance occurs (s).
    pub max_time: f64,
    /// The marker's noise floor: the 3D RMS a perfect model would leave (m), the per-axis
    /// floors combined.
    pub noise_floor: f64,
    /// The marker's noise band (m): the per-axis bands of the comparison combined in 3D
    /// (where a coordinate leaves its own band, widened by the model's predictability
    /// spread, the marker fails).
    pub band: f64,
    /// The 3D distance per frame (m).
    #[serde(skip)]
    pub distance: Vec<f64>,
}

impl MarkerError {
    /// RMS over noise floor: about 1 for a right model.
    #[must_use]
    pub fn rms_over_floor(&self) -> f64 {
        ratio(self.rms, self.noise_floor)
    }
}

/// A region of the grid (a ninth of it) and the error of the markers in it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Region {
    /// Where it is: `the corner at vertex 29`, `the edge at row 0`, `the centre`.
    pub name: String,
    /// Its rows, first and last.
    pub rows: [usize; 2],
    /// Its columns, first and last.
    pub cols: [usize; 2],
    /// Pinned vertices in it.
    pub pins: Vec<u32>,
    /// Markers in it.
    pub n_markers: usize,
    /// RMS of its markers' errors (m).
    pub rms: f64,
}

/// A time window in which some marker leaves its band.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ClothWindow {
    /// First frame outside (s).
    pub start: f64,
    /// Last frame outside (s).
    pub end: f64,
    /// How many markers leave their band in the window.
    pub n_markers: usize,
    /// The marker furthest from the model in the window.
    pub worst_id: u32,
    /// Its distance from the model there (m).
    pub peak: f64,
    /// When (s).
    pub peak_time: f64,
}

/// A cloth comparison per marker, over time and per region (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ClothComparison {
    /// The model's name.
    pub model: String,
    /// Frame times (s).
    pub t: Vec<f64>,
    /// Grid vertices along x.
    pub nx: usize,
    /// Grid vertices along z.
    pub nz: usize,
    /// Pinned vertices.
    pub pins: Vec<u32>,
    /// One entry per marker, in increasing id.
    pub markers: Vec<MarkerError>,
    /// RMS over markers of the 3D distance, per frame (m).
    pub error_over_time: Vec<f64>,
    /// RMS over markers and time of the 3D distance (m).
    pub rms: f64,
    /// The noise floor of [`rms`](Self::rms): RMS over markers of their floors (m).
    pub noise_floor: f64,
    /// The band of [`error_over_time`](Self::error_over_time) drawn in plots (m): the RMS
    /// over markers of their bands.
    pub band: f64,
    /// When markers leave their band.
    pub windows: Vec<ClothWindow>,
    /// The grid's regions that hold markers, worst first.
    pub regions: Vec<Region>,
}

impl ClothComparison {
    /// Groups a core comparison's `m{id}.{x|y|z}` outputs by marker on the grid `cloth`.
    ///
    /// # Errors
    ///
    /// [`ClothError::Core`] when the comparison has no marker output or its residuals are
    /// not one per frame; [`ClothError::VertexOutOfRange`] for a marker id outside the grid.
    pub fn new(c: &Comparison, cloth: &GridCloth) -> Result<Self> {
        let n_frames = c.t.len();
        let n_vertices = cloth.nx * cloth.nz;
        // Per id: (sum of squared residuals per frame, sum of squared floors, of bands).
        let mut by_id: BTreeMap<u32, (Vec<f64>, f64, f64)> = BTreeMap::new();
        let mut windows_by_id: BTreeMap<u32, Vec<(f64, f64)>> = BTreeMap::new();
        for o in &c.outputs {
            let Some((id, _axis)) = parse_marker_signal(&o.name) else {
                continue;
            };
            if id as usize >= n_vertices {
                return Err(ClothError::VertexOutOfRange {
                    vertex: id as usize,
                    n_vertices,
                });
            }
            if o.residual.len() != n_frames {
                return Err(CoreError::LengthMismatch {
                    name: o.name.clone(),
                    expected: n_frames,
                    found: o.residual.len(),
                }
                .into());
            }
            let entry = by_id
                .entry(id)
                .or_insert_with(|| (vec![0.0; n_frames], 0.0, 0.0));
            for (s, r) in entry.0.iter_mut().zip(&o.residual) {
                *s += r * r;
            }
            entry.1 += o.noise_floor * o.noise_floor;
            windows_by_id
                .entry(id)
                .or_default()
                .extend(o.windows.iter().map(|w| (w.start, w.end)));
            entry.2 += o.band * o.band;
        }
        if by_id.is_empty() {
            return Err(CoreError::InvalidArgument {
                name: "comparison",
                reason: format!(
                    "it holds no marker output (`m{{id}}.x`, `.y`, `.z`); its outputs are {}",
                    c.outputs
                        .iter()
                        .map(|o| o.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            }
            .into());
        }
        let markers: Vec<MarkerError> = by_id
            .into_iter()
            .map(|(id, (squares, floor2, band2))| {
                let distance: Vec<f64> = squares.iter().map(|s| s.sqrt()).collect();
                let (max_k, max) = distance
                    .iter()
                    .copied()
                    .enumerate()
                    .fold((0, 0.0_f64), |a, (k, d)| if d > a.1 { (k, d) } else { a });
                MarkerError {
                    id,
                    col: id as usize % cloth.nx,
                    row: id as usize / cloth.nx,
                    rms: mean_sqrt(&squares),
                    max,
                    max_time: c.t.get(max_k).copied().unwrap_or(0.0),
                    noise_floor: floor2.sqrt(),
                    band: band2.sqrt(),
                    distance,
                }
            })
            .collect();
        let n = markers.len() as f64;
        let error_over_time: Vec<f64> = (0..n_frames)
            .map(|k| (markers.iter().map(|m| m.distance[k].powi(2)).sum::<f64>() / n).sqrt())
            .collect();
        let rms_of = |f: fn(&MarkerError) -> f64| {
            (markers.iter().map(|m| f(m).powi(2)).sum::<f64>() / n).sqrt()
        };
        let rms = rms_of(|m| m.rms);
        let noise_floor = rms_of(|m| m.noise_floor);
        let band = rms_of(|m| m.band);
        let windows = windows(&c.t, &markers, &windows_by_id);
        let pins = cloth.pinned.clone();
        let regions = regions(&markers, cloth.nx, cloth.nz, &pins);
        Ok(Self {
            model: c.model.clone(),
            t: c.t.clone(),
            nx: cloth.nx,
            nz: cloth.nz,
            pins,
            markers,
            error_over_time,
            rms,
            noise_floor,
            band,
            windows,
            regions,
        })
    }

    /// [`rms`](Self::rms) per coordinate: the RMS of the x, y and z residuals over
    /// markers and time, the 3-D RMS / √3 (m).
    #[must_use]
    pub fn rms_per_coordinate(&self) -> f64 {
        self.rms / 3f64.sqrt()
    }

    /// [`noise_floor`](Self::noise_floor) per coordinate: the 3-D floor / √3 (m).
    #[must_use]
    pub fn noise_floor_per_coordinate(&self) -> f64 {
        self.noise_floor / 3f64.sqrt()
    }

    /// RMS over noise floor: about 1 for a right model.
    #[must_use]
    pub fn rms_over_floor(&self) -> f64 {
        ratio(self.rms, self.noise_floor)
    }

    /// The `n` markers with the largest RMS error, worst first.
    #[must_use]
    pub fn worst_markers(&self, n: usize) -> Vec<&MarkerError> {
        let mut sorted: Vec<&MarkerError> = self.markers.iter().collect();
        sorted.sort_by(|a, b| b.rms.total_cmp(&a.rms).then(a.id.cmp(&b.id)));
        sorted.truncate(n);
        sorted
    }

    /// The marker of an id.
    #[must_use]
    pub fn marker(&self, id: u32) -> Option<&MarkerError> {
        self.markers.iter().find(|m| m.id == id)
    }

    /// The largest distance of any marker, and that marker.
    #[must_use]
    pub fn largest(&self) -> Option<&MarkerError> {
        self.markers
            .iter()
            .max_by(|a, b| a.max.total_cmp(&b.max).then(b.id.cmp(&a.id)))
    }
}

fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 { a / b } else { f64::INFINITY }
}

fn mean_sqrt(squares: &[f64]) -> f64 {
    if squares.is_empty() {
        0.0
    } else {
        (squares.iter().sum::<f64>() / squares.len() as f64).sqrt()
    }
}

/// The failure windows of the cloth: the per-coordinate windows of the core comparison
/// (where a residual leaves its band, noise band plus the model's predictability spread),
/// merged across markers when they overlap or are less than `MIN_WINDOW_SAMPLES` frames
/// apart; in each, the markers that fail and the one furthest from the model.
fn windows(
    t: &[f64],
    markers: &[MarkerError],
    per_id: &BTreeMap<u32, Vec<(f64, f64)>>,
) -> Vec<ClothWindow> {
    let dt = if t.len() > 1 {
        (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64
    } else {
        0.0
    };
    let mut all: Vec<(f64, f64, u32)> = per_id
        .iter()
        .flat_map(|(&id, ws)| ws.iter().map(move |&(a, b)| (a, b, id)))
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut merged: Vec<(f64, f64, Vec<u32>)> = Vec::new();
    for (start, end, id) in all {
        match merged.last_mut() {
            Some(last) if start <= last.1 + MIN_WINDOW_SAMPLES * dt => {
                last.1 = last.1.max(end);
                if !last.2.contains(&id) {
                    last.2.push(id);
                }
            }
            _ => merged.push((start, end, vec![id])),
        }
    }
    merged
        .into_iter()
        .map(|(start, end, ids)| {
            let mut worst = (0_u32, 0.0_f64, start);
            for m in markers.iter().filter(|m| ids.contains(&m.id)) {
                for (k, &tk) in t.iter().enumerate() {
                    if tk >= start && tk <= end && m.distance[k] > worst.1 {
                        worst = (m.id, m.distance[k], tk);
                    }
                }
            }
            ClothWindow {
                start,
                end,
                n_markers: ids.len(),
                worst_id: worst.0,
                peak: worst.1,
                peak_time: worst.2,
            }
        })
        .collect()
}

/// The first and last index of each third of `0..n`.
fn thirds(n: usize) -> [[usize; 2]; 3] {
    let cut = |k: usize| (k * n).div_ceil(3);
    [
        [0, cut(1).max(1) - 1],
        [cut(1), cut(2).max(cut(1) + 1) - 1],
        [cut(2), n - 1],
    ]
}

fn regions(markers: &[MarkerError], nx: usize, nz: usize, pins: &[u32]) -> Vec<Region> {
    let rows = thirds(nz);
    let cols = thirds(nx);
    let mut out = Vec::new();
    for (rb, r) in rows.iter().enumerate() {
        for (cb, c) in cols.iter().enumerate() {
            if r[0] > r[1] || c[0] > c[1] {
                continue;
            }
            let inside = |row: usize, col: usize| {
                (r[0]..=r[1]).contains(&row) && (c[0]..=c[1]).contains(&col)
            };
            let ms: Vec<&MarkerError> = markers.iter().filter(|m| inside(m.row, m.col)).collect();
            if ms.is_empty() {
                continue;
            }
            let vertex = |row: usize, col: usize| row * nx + col;
            let edge_row = if rb == 0 { 0 } else { nz - 1 };
            let edge_col = if cb == 0 { 0 } else { nx - 1 };
            let name = match (rb, cb) {
                (1, 1) => "the centre".to_owned(),
                (1, _) => format!("the edge at column {edge_col}"),
                (_, 1) => format!("the edge at row {edge_row}"),
                _ => format!("the corner at vertex {}", vertex(edge_row, edge_col)),
            };
            let region_pins: Vec<u32> = pins
                .iter()
                .copied()
                .filter(|&p| inside(p as usize / nx, p as usize % nx))
                .collect();
            let rms = (ms.iter().map(|m| m.rms.powi(2)).sum::<f64>() / ms.len() as f64).sqrt();
            out.push(Region {
                name,
                rows: *r,
                cols: *c,
                pins: region_pins,
                n_markers: ms.len(),
                rms,
            });
        }
    }
    out.sort_by(|a, b| b.rms.total_cmp(&a.rms));
    out
}

/// A length in metres as text in millimetres (`12.3 mm`), the unit cloth errors live in.
#[must_use]
pub fn mm(metres: f64) -> String {
    format!("{} mm", format_number(metres * 1e3))
}

/// A marker RMS (the 3-D distance, m) in millimetres and, beside it, per coordinate
/// (the RMS of the x, y and z residuals: the 3-D RMS / √3): `4.2 mm 3-D (2.425 mm per
/// coordinate)`. Users quote either; every table says which.
#[must_use]
pub fn mm3(metres: f64) -> String {
    format!(
        "{} 3-D ({} per coordinate)",
        mm(metres),
        mm(metres / 3f64.sqrt())
    )
}

fn region_text(r: &Region) -> String {
    let pins = match r.pins.as_slice() {
        [] => String::new(),
        [p] => format!(", holding pin {p}"),
        ps => format!(
            ", holding pins {}",
            ps.iter().map(u32::to_string).collect::<Vec<_>>().join(", ")
        ),
    };
    format!(
        "{} (rows {}–{}, columns {}–{}{pins}): {} 3-D RMS over {} marker{}",
        r.name,
        r.rows[0],
        r.rows[1],
        r.cols[0],
        r.cols[1],
        mm(r.rms),
        r.n_markers,
        if r.n_markers == 1 { "" } else { "s" }
    )
}

fn window_text(w: &ClothWindow, n_markers: usize) -> String {
    format!(
        "{}–{} s ({} of {n_markers} markers; worst m{}, {} off at {} s)",
        format_number(w.start),
        format_number(w.end),
        w.n_markers,
        w.worst_id,
        mm(w.peak),
        format_number(w.peak_time)
    )
}

/// Where the cloth model fails, as text: the error over all markers against its noise
/// floor, the `top` worst markers, the worst regions and the failure windows.
#[must_use]
pub fn comparison_text(c: &ClothComparison, top: usize) -> String {
    let mut s = String::new();
    let duration = c.t.last().copied().unwrap_or(0.0) - c.t.first().copied().unwrap_or(0.0);
    let _ = writeln!(
        s,
        "model {} against the markers ({} markers on its {} × {} grid, {} frames, {} s):",
        c.model,
        c.markers.len(),
        c.nx,
        c.nz,
        c.t.len(),
        format_number(duration)
    );
    let largest = c.largest().map_or(String::new(), |m| {
        format!(
            ", largest distance {} (m{} at {} s)",
            mm(m.max),
            m.id,
            format_number(m.max_time)
        )
    });
    let _ = writeln!(
        s,
        "  marker error RMS {}, {:.1}× the noise floor {}{largest}",
        mm3(c.rms),
        c.rms_over_floor(),
        mm3(c.noise_floor)
    );
    let worst: Vec<String> = c
        .worst_markers(top)
        .iter()
        .map(|m| {
            format!(
                "m{} (row {}, col {}) {} ({:.0}×)",
                m.id,
                m.row,
                m.col,
                mm(m.rms),
                m.rms_over_floor()
            )
        })
        .collect();
    let _ = writeln!(s, "  worst markers: {} (3-D RMS)", worst.join(", "));
    if c.markers.len() <= PER_MARKER_LISTED {
        let all: Vec<String> = c
            .markers
            .iter()
            .map(|m| format!("m{} {}", m.id, format_number(m.rms * 1e3)))
            .collect();
        for (k, chunk) in all.chunks(6).enumerate() {
            let head = if k == 0 {
                "  per marker (3-D RMS, mm):"
            } else {
                "                           "
            };
            let _ = writeln!(s, "{head} {}", chunk.join(", "));
        }
    }
    let _ = writeln!(s, "  worst regions (the grid cut in 3 × 3):");
    for r in c.regions.iter().take(TOP_REGIONS) {
        let _ = writeln!(s, "    {}", region_text(r));
    }
    if c.windows.is_empty() {
        let _ = writeln!(
            s,
            "  never fails: every marker coordinate stays within its band (noise bands of {} RMS \
             over markers in 3D)",
            mm(c.band)
        );
    } else {
        let shown: Vec<String> = c
            .windows
            .iter()
            .take(6)
            .map(|w| window_text(w, c.markers.len()))
            .collect();
        let more = if c.windows.len() > 6 {
            format!(" and {} more", c.windows.len() - 6)
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "  fails (a marker coordinate leaves its band) at {}{more}",
            shown.join(", ")
        );
    }
    wrap_text(&s, TEXT_WIDTH)
}

/// The RMS over markers of the 3D error that per-coordinate RMS values leave, from the
/// squares of the `m{id}.{axis}` entries: `sqrt(Σ rms² / n_markers)` (m).
fn marker_rms<'a>(names: impl Iterator<Item = &'a str>, rms: impl Iterator<Item = f64>) -> f64 {
    let mut ids = std::collections::BTreeSet::new();
    let mut sum = 0.0;
    for (name, v) in names.zip(rms) {
        if let Some((id, _)) = parse_marker_signal(name) {
            ids.insert(id);
            sum += v * v;
        }
    }
    if ids.is_empty() {
        f64::NAN
    } else {
        (sum / ids.len() as f64).sqrt()
    }
}

/// The marker error RMS (m) before any effect, after the chosen effects and the noise
/// floor, from an explanation of a cloth model.
#[must_use]
pub fn explanation_rms(ex: &Explanation) -> (f64, f64, f64) {
    let names = || ex.outputs.iter().map(|o| o.name.as_str());
    (
        marker_rms(names(), ex.outputs.iter().map(|o| o.rms_before)),
        marker_rms(names(), ex.outputs.iter().map(|o| o.rms_after)),
        marker_rms(names(), ex.outputs.iter().map(|o| o.noise_floor)),
    )
}

/// The ranking and the verdict of a cloth explanation as text: per candidate its fitted
/// parameters and the marker error RMS it leaves (not one line per coordinate).
#[must_use]
pub fn explanation_text(ex: &Explanation, top: usize) -> String {
    let mut s = String::new();
    let names = || ex.outputs.iter().map(|o| o.name.as_str());
    let (before, after, floor) = explanation_rms(ex);
    if !ex.ranked.is_empty() {
        let _ = writeln!(
            s,
            "candidate effects, best first (score = evidence: {}):",
            modelgap_core::story::scoring_basis(ex)
        );
    }
    for (i, r) in ex.ranked.iter().take(top).enumerate() {
        let params: Vec<String> = r.params.iter().map(param_text).collect();
        let left = marker_rms(names(), r.rms_after.iter().copied());
        // The score first, so a long name never pushes it out of its column.
        let _ = writeln!(
            s,
            "  {:>2}. score {:>7}  {}",
            i + 1,
            format_number(r.score),
            r.candidate.name
        );
        let _ = writeln!(
            s,
            "      {}; marker RMS (3-D) {} → {}",
            if params.is_empty() {
                "no parameters".to_owned()
            } else {
                params.join(", ")
            },
            mm(before),
            mm(left)
        );
        if let Some(e) = &r.error {
            let _ = writeln!(s, "      fit failed: {e}");
        }
    }
    if !ex.ranked.is_empty() {
        let _ = writeln!(s, "margin to the runner-up: {}", format_number(ex.margin));
    }
    let _ = writeln!(s, "\nverdict: {}", verdict_sentence(ex));
    if matches!(ex.verdict, Verdict::CannotJudge | Verdict::Interrupted) {
        let _ = writeln!(s, "  marker RMS {} (not judged)", mm3(before));
    } else {
        let _ = writeln!(
            s,
            "  marker RMS {} → {} (noise floor {}, {:.2}× the floor after)",
            mm3(before),
            mm3(after),
            mm3(floor),
            ratio(after, floor)
        );
    }
    if ex.verdict == Verdict::Partial {
        let failing = ex
            .outputs
            .iter()
            .filter(|o| !o.remaining_windows.is_empty())
            .filter_map(|o| parse_marker_signal(&o.name).map(|(id, _)| id))
            .collect::<std::collections::BTreeSet<u32>>();
        if !failing.is_empty() {
            let _ = writeln!(
                s,
                "  {} markers still leave their band after it",
                failing.len()
            );
        }
    }
    // Among dozens of marker coordinates, the first few reasons say enough.
    const SHOWN: usize = 6;
    let skip = usize::from(ex.verdict == Verdict::CannotJudge);
    for r in ex.reasons.iter().skip(skip).take(SHOWN) {
        let _ = writeln!(s, "  why: {r}");
    }
    if ex.reasons.len() > skip + SHOWN {
        let _ = writeln!(
            s,
            "  why: … and {} more coordinates",
            ex.reasons.len() - skip - SHOWN
        );
    }
    for w in &ex.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    wrap_text(&s, TEXT_WIDTH)
}

/// The error before → after, over all markers and for the worst markers before.
#[must_use]
pub fn before_after_text(before: &ClothComparison, after: &ClothComparison) -> String {
    let share = |w: &[ClothWindow], t: &[f64]| {
        modelgap_core::residual::share_outside(w.iter().map(|w| (w.start, w.end)), t)
    };
    let change = |b: f64, a: f64| {
        if b > 0.0 {
            let r = a / b;
            if r <= 1.0 {
                format!("{:.0} % lower", 100.0 * (1.0 - r))
            } else {
                format!("{:.0} % higher", 100.0 * (r - 1.0))
            }
        } else {
            "was already 0".to_owned()
        }
    };
    let mut s = format!(
        "  marker RMS {} → {} ({}; {:.1}× → {:.1}× the noise floor {}), outside the band {:.0} % \
         → {:.0} % of the record\n",
        mm3(before.rms),
        mm3(after.rms),
        change(before.rms, after.rms),
        before.rms_over_floor(),
        after.rms_over_floor(),
        mm3(before.noise_floor),
        100.0 * share(&before.windows, &before.t),
        100.0 * share(&after.windows, &after.t),
    );
    let worst: Vec<String> = before
        .worst_markers(3)
        .iter()
        .filter_map(|m| {
            after
                .marker(m.id)
                .map(|a| format!("m{} {} → {}", m.id, mm(m.rms), mm(a.rms)))
        })
        .collect();
    if !worst.is_empty() {
        let _ = writeln!(s, "  worst markers before: {}", worst.join(", "));
    }
    wrap_text(&s, TEXT_WIDTH)
}

/// The HTML report of a cloth comparison: the core page (verdict, ranking) with the table,
/// summary and plots made for cloth — the worst markers' coordinates against the model, the
/// per-vertex error map of the mesh and the error over time.
///
/// `before` and `after` are the core comparisons behind `cloth_before` and `cloth_after`.
#[must_use]
pub fn cloth_report(
    before: &Comparison,
    cloth_before: &ClothComparison,
    explanation: Option<&Explanation>,
    after: Option<(&Comparison, &ClothComparison)>,
    triangles: &[[u32; 3]],
) -> Report {
    let mut report = build_report(before, explanation, after.map(|a| a.0));
    let cb = cloth_before;
    let ca = after.map(|a| a.1);
    let mut summary = vec![format!(
        "The model as given leaves a marker error of {} RMS over {} markers ({:.1}× the noise \
         floor of {}); {}.",
        mm(cb.rms),
        cb.markers.len(),
        cb.rms_over_floor(),
        mm(cb.noise_floor),
        match cb.windows.first() {
            None => "no marker ever leaves its band".to_owned(),
            Some(w) => format!(
                "markers leave their band in {} window(s), the first {}",
                cb.windows.len(),
                window_text(w, cb.markers.len())
            ),
        }
    )];
    if let Some(r) = cb.regions.first() {
        summary.push(format!("The worst region is {}.", region_text(r)));
    }
    if let Some(ex) = explanation {
        for c in &ex.chosen {
            let params: Vec<String> = c.params.iter().map(param_text).collect();
            summary.push(format!(
                "Chosen effect: {} (acts on {}), {}.",
                c.candidate.name,
                c.candidate.acts_on,
                params.join(", ")
            ));
        }
    }
    if let Some(a) = ca {
        summary.push(format!(
            "With the effect added: marker error {} RMS ({:.1}× the noise floor), {} failure \
             window(s).",
            mm(a.rms),
            a.rms_over_floor(),
            a.windows.len()
        ));
    }
    report.summary_html_paragraphs = summary;
    let mut table = vec![vec![
        "marker (row, col)".to_owned(),
        "noise floor (mm)".to_owned(),
        "3-D RMS before (mm)".to_owned(),
        "largest before (mm)".to_owned(),
    ]];
    if ca.is_some() {
        table[0].push("3-D RMS after (mm)".to_owned());
    }
    let mut rows: Vec<(String, &MarkerError, Option<f64>)> = vec![];
    for m in cb.worst_markers(8) {
        rows.push((
            format!("m{} ({}, {})", m.id, m.row, m.col),
            m,
            ca.and_then(|a| a.marker(m.id)).map(|a| a.rms),
        ));
    }
    let k = |v: f64| format_number(v * 1e3);
    table.push({
        let mut row = vec![
            format!("all {} markers", cb.markers.len()),
            k(cb.noise_floor),
            k(cb.rms),
            cb.largest().map_or("—".to_owned(), |m| k(m.max)),
        ];
        if let Some(a) = ca {
            row.push(k(a.rms));
        }
        row
    });
    for (label, m, a) in rows {
        let mut row = vec![label, k(m.noise_floor), k(m.rms), k(m.max)];
        if ca.is_some() {
            row.push(a.map_or("—".to_owned(), k));
        }
        table.push(row);
    }
    report.table = table;
    // The worst marker's three coordinates against the model, in mm like every length on
    // the page (the table, the summary, the error map).
    let to_mm = |v: &[f64]| v.iter().map(|x| x * 1e3).collect::<Vec<f64>>();
    let windows_mm = |ws: &[modelgap_core::residual::FailureWindow]| {
        ws.iter()
            .map(|w| modelgap_core::residual::FailureWindow {
                peak: w.peak * 1e3,
                ..*w
            })
            .collect::<Vec<_>>()
    };
    report.series = cb
        .worst_markers(1)
        .iter()
        .flat_map(|m| {
            ["x", "y", "z"].into_iter().filter_map(move |axis| {
                let name = format!("m{}.{axis}", m.id);
                let o = before.output(&name)?;
                Some(SeriesPlot {
                    title: format!("{name}: the worst marker's {axis} coordinate"),
                    unit: "mm".to_owned(),
                    t: before.t.clone(),
                    measured: to_mm(&o.measured),
                    before: to_mm(&o.predicted),
                    after: after
                        .and_then(|a| a.0.output(&name))
                        .map(|a| to_mm(&a.predicted)),
                    band: o.band * 1e3,
                    windows: windows_mm(&o.windows),
                })
            })
        })
        .collect();
    report.residuals = Vec::new();
    let over_time = ResidualPlot {
        title: "marker error over time (RMS over markers of the 3D distance)".to_owned(),
        unit: "mm".to_owned(),
        t: cb.t.clone(),
        before: to_mm(&cb.error_over_time),
        after: ca.map(|a| to_mm(&a.error_over_time)),
        band: cb.band * 1e3,
        windows: cb
            .windows
            .iter()
            .map(|w| modelgap_core::residual::FailureWindow {
                start: w.start,
                end: w.end,
                peak: w.peak * 1e3,
                peak_time: w.peak_time,
                sign: 1,
            })
            .collect(),
    };
    report.extra_svgs = vec![
        (
            "Where the cloth model fails: each vertex of the mesh (laid flat, row 0 at the top) \
             coloured by the RMS distance between measured and predicted marker, interpolated \
             between markers (circles); black squares are pins. The same colour scale is used \
             before and after the effect was added."
                .to_owned(),
            error_map_svg(cb, ca, triangles),
        ),
        (
            "When it fails: the RMS over markers of the 3D distance at each frame, before (red) \
             and after (blue) the effect was added. Grey: the band, shaded: the windows where \
             some marker leaves its band."
                .to_owned(),
            residual_svg(&over_time),
        ),
    ];
    report
}

#[cfg(test)]
mod tests;

//! The cloth's reading of the loop's results: [`Story`] for [`ClothModel`]. A comparison
//! reads per marker, over time and per region of the mesh ([`ClothComparison`]); an
//! explanation with the marker error each candidate leaves; the report adds the per-vertex
//! error map and the error over time, and its MCAP holds the mesh coloured by error for
//! Foxglove's 3D panel. The command line and Python reach it through
//! [`Model::story`](modelgap_core::Model::story), as they reach every model's.

use std::path::{Path, PathBuf};

use modelgap_core::report::write_html;
use modelgap_core::story::{ReportParts, Story};
use modelgap_core::{Candidate, Comparison, CoreError, Explanation, Recording};
use serde_json::{Value, json};

use super::{
    ClothComparison, ErrorMcap, before_after_text, cloth_report, comparison_text, explanation_rms,
    explanation_text, write_error_mcap_path,
};
use crate::error::ClothError;
use crate::mesh::BuildMesh as _;
use crate::model::{ClothModel, recording_to_markers, simulate_markers};
use crate::scenes::Scene;

/// Worst markers listed in text and JSON.
pub const TOP_MARKERS: usize = 5;

/// A cloth error at the seam of the loop.
pub(crate) fn seam(e: ClothError) -> CoreError {
    match e {
        ClothError::Core(core) => core,
        other => CoreError::from_model(None, other),
    }
}

impl ClothModel {
    /// The comparison grouped by marker and region on this scene's grid.
    ///
    /// # Errors
    /// A marker signal outside the grid.
    pub fn cloth_comparison(&self, c: &Comparison) -> crate::Result<ClothComparison> {
        ClothComparison::new(c, &self.scene().cloth)
    }

    /// Every vertex of `scene` at the recording's times, as this model simulates it
    /// (pinned vertices following the recording's markers when the scene says so).
    fn mesh_frames(&self, scene: &Scene, rec: &Recording) -> crate::Result<Vec<Vec<[f64; 3]>>> {
        let n = scene.cloth.n_vertices()? as u32;
        let ids: Vec<u32> = (0..n).collect();
        let markers = recording_to_markers(rec)?;
        let pins = scene.pins_from_markers.then_some(&markers);
        let run = simulate_markers(scene, &ids, rec.t(), self.settings(), pins)?;
        Ok(run.positions().to_vec())
    }

    fn write_cloth_report(
        &self,
        dir: &Path,
        rec: &Recording,
        parts: &ReportParts<'_>,
    ) -> crate::Result<PathBuf> {
        let scene = self.scene();
        let triangles = scene.cloth.build_mesh()?.triangles;
        let cloth_before = self.cloth_comparison(parts.before)?;
        let cloth_after = match parts.after {
            Some((_, c)) => Some(self.cloth_comparison(c)?),
            None => None,
        };
        let mut report = cloth_report(
            parts.before,
            &cloth_before,
            parts.explanation,
            parts.after.map(|(_, c)| c).zip(cloth_after.as_ref()),
            &triangles,
        );
        report.title = format!(
            "modelgap: cloth scene {} against {}",
            scene.name, parts.data
        );
        if let Some(v) = &parts.verdict {
            report.verdict.clone_from(v);
        }
        std::fs::create_dir_all(dir).map_err(|e| CoreError::io(e, Some(dir)))?;
        let page = dir.join("report.html");
        write_html(&report, &page)?;
        let mesh_before = self.mesh_frames(scene, rec)?;
        let after_mesh = match (parts.after, &cloth_after) {
            (Some((effects, _)), Some(ca)) => {
                let pairs: Vec<(&Candidate, &[f64])> = effects
                    .iter()
                    .map(|e| (&e.candidate, e.values.as_slice()))
                    .collect();
                let scene_after = self.edited(&pairs)?;
                Some((ca, self.mesh_frames(&scene_after, rec)?))
            }
            _ => None,
        };
        let markers = recording_to_markers(rec)?;
        write_error_mcap_path(
            &ErrorMcap {
                scene: &scene.name,
                triangles: &triangles,
                measured: &markers,
                before: &cloth_before,
                mesh_before: &mesh_before,
                after: after_mesh.as_ref().map(|(c, m)| (*c, m.as_slice())),
            },
            &dir.join("comparison.mcap"),
        )?;
        Ok(page)
    }
}

impl Story for ClothModel {
    fn comparison_text(&self, c: &Comparison) -> String {
        match self.cloth_comparison(c) {
            Ok(cc) => comparison_text(&cc, TOP_MARKERS),
            Err(_) => modelgap_core::story::comparison_text(c),
        }
    }

    /// The comparison per marker (`rms`, `noise_floor`, `markers` with `id`, `row`, `col`,
    /// `rms`, `max`, `noise_floor`, `regions`, `windows`, `error_over_time`,
    /// `worst_markers`, `rms_over_floor`; `rms` and `noise_floor` are of the 3-D distance,
    /// `rms_per_coordinate` and `noise_floor_per_coordinate` the same per coordinate) and
    /// the recording's `warnings`.
    fn comparison_json(&self, c: &Comparison) -> Value {
        let Ok(cc) = self.cloth_comparison(c) else {
            return modelgap_core::json::comparison_json(c);
        };
        let mut value = serde_json::to_value(&cc).unwrap_or(Value::Null);
        value["rms_over_floor"] = modelgap_core::json::finite(cc.rms_over_floor());
        value["rms_per_coordinate"] = modelgap_core::json::finite(cc.rms_per_coordinate());
        value["noise_floor_per_coordinate"] =
            modelgap_core::json::finite(cc.noise_floor_per_coordinate());
        value["worst_markers"] = json!(
            cc.worst_markers(TOP_MARKERS)
                .iter()
                .map(|m| m.id)
                .collect::<Vec<_>>()
        );
        value["warnings"] = json!(c.warnings);
        value
    }

    fn fails(&self, c: &Comparison) -> bool {
        self.cloth_comparison(c)
            .is_ok_and(|cc| !cc.windows.is_empty())
    }

    fn explanation_text(&self, ex: &Explanation, top: usize) -> String {
        explanation_text(ex, top)
    }

    /// The core explanation JSON with `marker_rms`: `before`, `after` and `noise_floor` of
    /// the marker error (m).
    fn explanation_json(&self, ex: &Explanation) -> Value {
        let mut value = modelgap_core::json::explanation_json(ex);
        let (before, after, floor) = explanation_rms(ex);
        value["marker_rms"] = json!({
            "before": modelgap_core::json::finite(before),
            "after": modelgap_core::json::finite(after),
            "noise_floor": modelgap_core::json::finite(floor),
        });
        value
    }

    fn before_after_text(&self, before: &Comparison, after: &Comparison) -> String {
        match (self.cloth_comparison(before), self.cloth_comparison(after)) {
            (Ok(b), Ok(a)) => before_after_text(&b, &a),
            _ => modelgap_core::story::before_after_text(before, after),
        }
    }

    /// `report.html` with the per-vertex error map and the error over time, and
    /// `comparison.mcap` with the mesh coloured by error (`foxglove.SceneUpdate`), `/tf`,
    /// the markers and the error per marker.
    fn write_report(
        &self,
        dir: &Path,
        rec: &Recording,
        parts: &ReportParts<'_>,
    ) -> modelgap_core::Result<PathBuf> {
        self.write_cloth_report(dir, rec, parts).map_err(seam)
    }
}

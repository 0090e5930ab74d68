use std::io::Cursor;

use modelgap_core::io::mcap::read_signals;
use modelgap_core::residual::{failure_windows, stats};
use modelgap_core::{Comparison, OutputComparison};

use super::*;
use crate::markers::{MarkerRecording, read_markers_mcap};
use crate::mesh::BuildMesh as _;

/// Noise floor per axis of the synthetic comparisons (m).
const FLOOR: f64 = 1e-4;

/// One coordinate's comparison at times `t`, its windows as core compare finds them.
fn output(name: String, t: &[f64], residual: Vec<f64>) -> OutputComparison {
    let measured = vec![0.0; residual.len()];
    let windows = failure_windows(t, &residual, 4.0 * FLOOR, 5.0 * 0.01);
    let predicted: Vec<f64> = residual.iter().map(|r| -r).collect();
    OutputComparison {
        unit: "m".into(),
        stats: stats(&measured, &predicted),
        name,
        measured,
        predicted,
        residual,
        noise_floor: FLOOR,
        noise_given: true,
        noise_method: Default::default(),
        quantum: None,
        finding: None,
        band: 4.0 * FLOOR,
        windows,
        effective_samples: 10.0,
    }
}

/// A 9 × 9 grid with markers every 2nd vertex; from frame 50 on, the y error of each marker
/// grows with its column and row: the far corner (vertex 80) is worst.
fn comparison(grow: bool) -> (Comparison, GridCloth) {
    let cloth = GridCloth::new(9, 9, 0.1).pin(0);
    let t: Vec<f64> = (0..100).map(|k| f64::from(k) * 0.01).collect();
    let mut outputs = Vec::new();
    for row in (0..9).step_by(2) {
        for col in (0..9).step_by(2) {
            let id = row * 9 + col;
            for axis in ["x", "y", "z"] {
                let residual: Vec<f64> = (0..t.len())
                    .map(|k| {
                        if grow && axis == "y" && k >= 50 {
                            1e-3 * (row + col) as f64 * (k - 49) as f64 / 50.0
                        } else {
                            0.0
                        }
                    })
                    .collect();
                outputs.push(output(format!("m{id}.{axis}"), &t, residual));
            }
        }
    }
    (
        Comparison {
            model: "grid".into(),
            t,
            outputs,
            warnings: Vec::new(),
        },
        cloth,
    )
}

#[test]
fn worst_marker_region_and_window_are_where_the_error_grows() {
    let (c, cloth) = comparison(true);
    let cc = ClothComparison::new(&c, &cloth).unwrap();
    assert_eq!(cc.markers.len(), 25);
    assert_eq!(cc.worst_markers(1)[0].id, 80);
    assert_eq!(cc.regions[0].name, "the corner at vertex 80");
    assert_eq!(cc.regions.last().map(|r| r.pins.clone()), Some(vec![0]));
    assert_eq!(cc.windows.len(), 1);
    let w = &cc.windows[0];
    assert_eq!(w.worst_id, 80);
    // The error starts at frame 50 and leaves the 4-floor band soon after; it never returns.
    assert!(w.start > 0.5 && w.start < 0.6, "{w:?}");
    approx::assert_relative_eq!(w.end, 0.99, epsilon = 1e-12);
    // Marker 80: row 8 + col 8 = 16 mm at the last frame, in y only.
    approx::assert_relative_eq!(w.peak, 16e-3, epsilon = 1e-12);
    assert!(cc.error_over_time[10] == 0.0 && cc.error_over_time[99] > 0.0);
    // 3 axes of floor 0.1 mm: a 3D floor of √3 × 0.1 mm.
    approx::assert_relative_eq!(cc.noise_floor, 3f64.sqrt() * FLOOR, epsilon = 1e-15);
    let text = comparison_text(&cc, 3);
    assert!(text.contains("worst markers: m80"), "{text}");
    assert!(text.contains("the corner at vertex 80"), "{text}");
    assert!(text.contains("fails"), "{text}");
}

#[test]
fn a_right_model_never_fails() {
    let (c, cloth) = comparison(false);
    let cc = ClothComparison::new(&c, &cloth).unwrap();
    assert!(cc.windows.is_empty());
    assert_eq!(cc.rms, 0.0);
    assert!(comparison_text(&cc, 3).contains("never fails"));
}

#[test]
fn marker_outside_the_grid_is_an_error() {
    let (mut c, cloth) = comparison(false);
    c.outputs[0].name = "m81.x".into();
    let err = ClothComparison::new(&c, &cloth).unwrap_err();
    assert!(matches!(
        err,
        ClothError::VertexOutOfRange {
            vertex: 81,
            n_vertices: 81
        }
    ));
    c.outputs.retain(|o| o.name == "m81.x");
    c.outputs[0].name = "i".into();
    assert!(ClothComparison::new(&c, &cloth).is_err());
}

#[test]
fn error_map_draws_every_triangle_marker_and_pin() {
    let (c, cloth) = comparison(true);
    let cc = ClothComparison::new(&c, &cloth).unwrap();
    let mesh = cloth.build_mesh().unwrap();
    let svg = error_map_svg(&cc, Some(&cc), &mesh.triangles);
    assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
    assert_eq!(svg.matches("<polygon").count(), 2 * mesh.triangles.len());
    assert_eq!(svg.matches("<circle").count(), 2 * 25);
    assert!(svg.contains("<title>pin 0</title>"));
    // The worst marker is drawn at its place on the scale, the untouched pin corner at 0.
    let worst = cc.worst_markers(1)[0].rms;
    let top = map::nice_ceiling(worst);
    assert!(svg.contains(&format!(
        "fill=\"{}\" stroke=\"#212529\" stroke-width=\"0.8\"><title>m80 ",
        map_hex(error_colour(worst / top))
    )));
    assert!(svg.contains(&format!("fill=\"{}\"", map_hex(error_colour(0.0)))));
}

fn map_hex(c: [f64; 3]) -> String {
    let byte = |v: f64| (v * 255.0).round() as u8;
    format!("#{:02x}{:02x}{:02x}", byte(c[0]), byte(c[1]), byte(c[2]))
}

#[test]
fn colour_scale_runs_from_blue_to_red() {
    let low = error_colour(0.0);
    let high = error_colour(1.0);
    assert!(low[2] > low[0] && high[0] > high[2]);
    assert_eq!(error_colour(2.0), high);
    assert_eq!(error_colour(-1.0), low);
    approx::assert_relative_eq!(map::nice_ceiling(0.013), 0.02, epsilon = 1e-15);
    approx::assert_relative_eq!(map::nice_ceiling(0.05), 0.05, epsilon = 1e-15);
}

#[test]
fn vertex_weights_sum_to_one_and_markers_keep_their_value() {
    let (c, cloth) = comparison(true);
    let cc = ClothComparison::new(&c, &cloth).unwrap();
    let w = map::vertex_weights(&cc);
    assert_eq!(w.len(), 81);
    for ws in &w {
        approx::assert_relative_eq!(ws.iter().map(|x| x.1).sum::<f64>(), 1.0, epsilon = 1e-12);
    }
    let rms: Vec<f64> = cc.markers.iter().map(|m| m.rms).collect();
    let values = map::interpolate(&w, &rms);
    let m80 = cc.marker(80).unwrap();
    approx::assert_relative_eq!(values[80], m80.rms, epsilon = 1e-15);
}

#[test]
fn error_mcap_holds_the_coloured_mesh_the_markers_and_the_errors() {
    let (c, cloth) = comparison(true);
    let cc = ClothComparison::new(&c, &cloth).unwrap();
    let mesh = cloth.build_mesh().unwrap();
    let frame: Vec<[f64; 3]> = mesh.positions.iter().map(|p| [p.x, p.y, p.z]).collect();
    let frames = vec![frame; c.t.len()];
    let ids: Vec<u32> = cc.markers.iter().map(|m| m.id).collect();
    let positions: Vec<Vec<[f64; 3]>> = (0..c.t.len())
        .map(|_| ids.iter().map(|&id| frames[0][id as usize]).collect())
        .collect();
    let measured = MarkerRecording::new(c.t.clone(), ids.clone(), positions).unwrap();
    let m = ErrorMcap {
        scene: "grid",
        triangles: &mesh.triangles,
        measured: &measured,
        before: &cc,
        mesh_before: &frames,
        after: Some((&cc, &frames)),
    };
    let mut file = Cursor::new(Vec::new());
    write_error_mcap(&m, &mut file).unwrap();
    let bytes = file.into_inner();
    let back = read_markers_mcap(&bytes).unwrap();
    assert_eq!(back.ids(), ids.as_slice());
    assert_eq!(back.n_frames(), 100);
    let errors = read_signals(&bytes, MARKER_ERROR_TOPIC).unwrap();
    approx::assert_relative_eq!(errors.values("m80").unwrap()[99], 16e-3, epsilon = 1e-12);
    // Rounded to 1 µm.
    approx::assert_abs_diff_eq!(
        errors.values("rms").unwrap()[99],
        cc.error_over_time[99],
        epsilon = 0.5e-6
    );
    let scenes =
        modelgap_core::io::mcap::read_topic_messages(&bytes, CLOTH_ERROR_AFTER_TOPIC).unwrap();
    assert_eq!(scenes.len(), 100);
    let spheres =
        modelgap_core::io::mcap::read_topic_messages(&bytes, foxglove::MEASURED_MARKERS_TOPIC)
            .unwrap();
    assert_eq!(spheres.len(), 100);
    let tf =
        modelgap_core::io::mcap::read_topic_messages(&bytes, crate::trajectory::TF_TOPIC).unwrap();
    assert_eq!(tf.len(), 1);
    crate::trajectory::tests::assert_foxglove_file(&bytes, 3);

    // A mesh with a frame missing is refused before anything is written.
    let short = &frames[..99];
    let bad = ErrorMcap {
        mesh_before: short,
        ..m
    };
    assert!(write_error_mcap(&bad, Cursor::new(Vec::new())).is_err());
}

//! The per-vertex error map: the grid laid flat, each triangle coloured by the marker error
//! interpolated to its vertices, markers as circles, pins as squares, a colour bar in mm.

use std::fmt::Write as _;

use modelgap_core::report::format_number;

use super::ClothComparison;

/// Page width of the map (px), as the core report's plots.
const WIDTH: f64 = 960.0;
/// Height of the title row (px).
const TITLE: f64 = 34.0;
/// Height of the colour bar and its labels (px).
const BAR: f64 = 58.0;
/// Space around a panel (px).
const PAD: f64 = 24.0;
/// Largest panel height (px).
const MAX_PANEL: f64 = 420.0;
/// Markers the map labels with their id.
const LABELLED: usize = 5;
/// Markers whose errors are blended into a vertex's colour.
const NEAREST: usize = 4;

/// Stops of the colour scale, from no error (blue) to the scale's top (red): ColorBrewer's
/// RdYlBu, reversed.
const STOPS: [[f64; 3]; 5] = [
    [0.173, 0.482, 0.714],
    [0.671, 0.851, 0.914],
    [1.0, 1.0, 0.749],
    [0.992, 0.682, 0.380],
    [0.843, 0.098, 0.110],
];

/// The colour (r, g, b in 0..1) of `fraction` of the colour scale (clamped to 0..1; NaN is
/// the top).
#[must_use]
pub fn error_colour(fraction: f64) -> [f64; 3] {
    let f = if fraction.is_nan() {
        1.0
    } else {
        fraction.clamp(0.0, 1.0)
    };
    let x = f * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let u = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [
        a[0] + u * (b[0] - a[0]),
        a[1] + u * (b[1] - a[1]),
        a[2] + u * (b[2] - a[2]),
    ]
}

fn hex(c: [f64; 3]) -> String {
    let byte = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    format!("#{:02x}{:02x}{:02x}", byte(c[0]), byte(c[1]), byte(c[2]))
}

/// For each vertex of the grid, the markers blended into its value and their weights
/// (inverse squared grid distance to the [`NEAREST`] markers; a vertex that is a marker
/// takes that marker's value). Weights sum to 1.
pub(crate) fn vertex_weights(c: &ClothComparison) -> Vec<Vec<(usize, f64)>> {
    let n = c.nx * c.nz;
    (0..n)
        .map(|v| {
            let (col, row) = ((v % c.nx) as f64, (v / c.nx) as f64);
            let mut near: Vec<(usize, f64)> = c
                .markers
                .iter()
                .enumerate()
                .map(|(i, m)| {
                    let d2 = (m.col as f64 - col).powi(2) + (m.row as f64 - row).powi(2);
                    (i, d2)
                })
                .collect();
            near.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            near.truncate(NEAREST);
            if let Some(&(i, d2)) = near.first()
                && d2 == 0.0
            {
                return vec![(i, 1.0)];
            }
            let total: f64 = near.iter().map(|(_, d2)| 1.0 / d2).sum();
            near.into_iter()
                .map(|(i, d2)| (i, 1.0 / d2 / total))
                .collect()
        })
        .collect()
}

/// The value at every vertex from one value per marker, with [`vertex_weights`].
pub(crate) fn interpolate(weights: &[Vec<(usize, f64)>], per_marker: &[f64]) -> Vec<f64> {
    weights
        .iter()
        .map(|w| w.iter().map(|&(i, wt)| wt * per_marker[i]).sum())
        .collect()
}

/// A scale top that reads well: 1, 2 or 5 times a power of ten, at or above `v`.
pub(crate) fn nice_ceiling(v: f64) -> f64 {
    if !(v.is_finite() && v > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(v.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|k| k * p)
        .find(|&s| s >= v * (1.0 - 1e-12))
        .unwrap_or(10.0 * p)
}

/// The per-vertex error map of `before` and, beside it, `after` (same colour scale) as SVG.
///
/// The grid is drawn flat, column along +x and row 0 at the top; `triangles` are the mesh's
/// (vertex indices of the grid); each is filled with the mean colour of its vertices, whose
/// values are the markers' RMS errors blended from the nearest markers.
#[must_use]
pub fn error_map_svg(
    before: &ClothComparison,
    after: Option<&ClothComparison>,
    triangles: &[[u32; 3]],
) -> String {
    let panels: Vec<(&str, &ClothComparison)> = match after {
        Some(a) => vec![("model as given", before), ("with the effect added", a)],
        None => vec![("model as given", before)],
    };
    let scale = nice_ceiling(before.markers.iter().map(|m| m.rms).fold(0.0, f64::max));
    let (nx, nz) = (before.nx.max(2), before.nz.max(2));
    let panel_w = (WIDTH - PAD * (panels.len() as f64 + 1.0)) / panels.len() as f64;
    let cell = (panel_w / (nx - 1) as f64).min(MAX_PANEL / (nz - 1) as f64);
    let (map_w, map_h) = (cell * (nx - 1) as f64, cell * (nz - 1) as f64);
    let height = TITLE + map_h + 2.0 * PAD + BAR;
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height:.0}" viewBox="0 0 {WIDTH} {height:.0}" font-family="sans-serif" font-size="13">"#
    );
    let _ = write!(
        s,
        r##"<rect width="100%" height="100%" fill="#ffffff"/><text x="{PAD}" y="22" font-size="16" fill="#212529">RMS marker error per vertex (mm)</text>"##
    );
    for (p, (label, c)) in panels.iter().enumerate() {
        let left = PAD + p as f64 * (panel_w + PAD) + (panel_w - map_w) / 2.0;
        let top = TITLE + PAD;
        let xy = |v: u32| {
            let v = v as usize;
            (left + (v % nx) as f64 * cell, top + (v / nx) as f64 * cell)
        };
        let _ = write!(
            s,
            r##"<text x="{left:.1}" y="{:.1}" fill="#646a73">{label}: {} RMS</text>"##,
            top - 8.0,
            super::mm(c.rms)
        );
        let weights = vertex_weights(c);
        let rms: Vec<f64> = c.markers.iter().map(|m| m.rms).collect();
        let values = interpolate(&weights, &rms);
        s.push_str("<g stroke-width=\"0.6\">");
        for tri in triangles {
            if tri.iter().any(|&v| v as usize >= values.len()) {
                continue;
            }
            let mean = tri.iter().map(|&v| values[v as usize]).sum::<f64>() / 3.0;
            let colour = hex(error_colour(mean / scale));
            let [a, b, d] = tri.map(xy);
            let _ = write!(
                s,
                r#"<polygon points="{:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" fill="{colour}" stroke="{colour}"/>"#,
                a.0, a.1, b.0, b.1, d.0, d.1
            );
        }
        s.push_str("</g>");
        for m in &c.markers {
            let (x, y) = xy(m.id);
            let _ = write!(
                s,
                r##"<circle cx="{x:.1}" cy="{y:.1}" r="3.2" fill="{}" stroke="#212529" stroke-width="0.8"><title>m{} (row {}, col {}): {}</title></circle>"##,
                hex(error_colour(m.rms / scale)),
                m.id,
                m.row,
                m.col,
                super::mm(m.rms)
            );
        }
        for &pin in &c.pins {
            let (x, y) = xy(pin);
            let _ = write!(
                s,
                r##"<rect x="{:.1}" y="{:.1}" width="8" height="8" fill="#000000"><title>pin {pin}</title></rect>"##,
                x - 4.0,
                y - 4.0
            );
        }
        for m in c.worst_markers(LABELLED) {
            let (x, y) = xy(m.id);
            let _ = write!(
                s,
                r##"<text x="{:.1}" y="{:.1}" font-size="11" fill="#212529" stroke="#ffffff" stroke-width="2.5" paint-order="stroke">m{}</text>"##,
                x + 5.0,
                y - 5.0,
                m.id
            );
        }
    }
    // The colour bar.
    let bar_top = TITLE + PAD + map_h + PAD;
    let bar_w = WIDTH - 2.0 * PAD - 200.0;
    let steps = 60;
    for k in 0..steps {
        let f = k as f64 / steps as f64;
        let _ = write!(
            s,
            r#"<rect x="{:.1}" y="{bar_top:.1}" width="{:.2}" height="14" fill="{}"/>"#,
            PAD + f * bar_w,
            bar_w / steps as f64 + 0.5,
            hex(error_colour(f + 0.5 / steps as f64))
        );
    }
    for k in 0..=5 {
        let f = f64::from(k) / 5.0;
        let _ = write!(
            s,
            r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" fill="#646a73">{}</text>"##,
            PAD + f * bar_w,
            bar_top + 30.0,
            format_number(f * scale * 1e3)
        );
    }
    let _ = write!(
        s,
        r##"<text x="{:.1}" y="{:.1}" fill="#646a73">mm RMS (noise floor {})</text>"##,
        PAD + bar_w + 12.0,
        bar_top + 12.0,
        super::mm(before.noise_floor)
    );
    s.push_str("</svg>");
    s
}

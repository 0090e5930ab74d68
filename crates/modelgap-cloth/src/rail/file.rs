//! Rails in scene files: `[[rails]]` (a rail named once, its motion) and `[[pins.attach]]`
//! (a set of vertices riding a rail), read with the line of every bad field and written
//! back.
//!
//! ```toml
//! [[rails]]
//! name = "top"
//! origin = [0.0, 0.0, 0.0]      # optional, m: the point the rotation turns about
//! translation = ["0.03 * sin(2 * pi * 0.4 * t)", "0", "0"]   # m: expressions of t (s)
//! # translation = [[0.0, 0.0, 0.0, 0.0], [1.0, 0.1, 0.0, 0.0]]  # or rows [t, x, y, z]
//! rotation = ["0", "0", "0.1 * sin(t)"]   # optional, rad, axis x angle: the same forms
//!
//! [[pins.attach]]               # any number: vertices that ride a rail
//! rail = "top"
//! rows = [0]                    # whole rows (row 0 is vertices 0 .. nx - 1)
//! cols = [0]                    # whole columns
//! vertices = [30, 31]           # single vertices, row * nx + col
//! regions = [[0, 0, 3, 1]]      # rectangles [col0, row0, col1, row1], inclusive
//! border = false                # every vertex on the grid's edge
//! ```
//!
//! Every attached vertex is pinned; a vertex may ride one rail and is pinned once in all.

use std::fmt::Write as _;

use serde::Deserialize;
use toml::{Spanned, Value};

use super::{Motion, Rail, TimeExpr};
use crate::error::{ClothError, Result};
use crate::kinematic::PinPath;

/// `[[rails]]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RailFile {
    name: Spanned<String>,
    origin: Option<Spanned<[f64; 3]>>,
    translation: Option<Spanned<Value>>,
    rotation: Option<Spanned<Value>>,
}

/// `[[pins.attach]]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct AttachFile {
    rail: Spanned<String>,
    vertices: Option<Spanned<Vec<i64>>>,
    rows: Option<Spanned<Vec<i64>>>,
    cols: Option<Spanned<Vec<i64>>>,
    regions: Option<Spanned<Vec<Vec<i64>>>>,
    #[serde(default)]
    border: bool,
}

/// A set of vertices of an `nx × nz` grid: single vertices, whole rows and columns,
/// rectangles and the border.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct VertexSet {
    /// Single vertices, `row * nx + col`.
    pub vertices: Vec<u32>,
    /// Whole rows.
    pub rows: Vec<u32>,
    /// Whole columns.
    pub cols: Vec<u32>,
    /// Rectangles `[col0, row0, col1, row1]`, inclusive.
    pub regions: Vec<[u32; 4]>,
    /// Every vertex on the grid's edge.
    pub border: bool,
}

impl VertexSet {
    /// Whole row `row`.
    #[must_use]
    pub fn row(row: u32) -> Self {
        Self {
            rows: vec![row],
            ..Self::default()
        }
    }

    /// The vertices of the set on an `nx × nz` grid, sorted, each once; entries past the
    /// grid are left out (a scene file's are refused when it is read).
    #[must_use]
    pub fn resolve(&self, nx: usize, nz: usize) -> Vec<u32> {
        let n = nx * nz;
        let idx = |col: usize, row: usize| (row * nx + col) as u32;
        let mut out: Vec<u32> = self
            .vertices
            .iter()
            .copied()
            .filter(|&v| (v as usize) < n)
            .collect();
        for &row in self.rows.iter().filter(|&&r| (r as usize) < nz) {
            out.extend((0..nx).map(|col| idx(col, row as usize)));
        }
        for &col in self.cols.iter().filter(|&&c| (c as usize) < nx) {
            out.extend((0..nz).map(|row| idx(col as usize, row)));
        }
        for &[c0, r0, c1, r1] in &self.regions {
            for row in r0 as usize..=(r1 as usize).min(nz.saturating_sub(1)) {
                for col in c0 as usize..=(c1 as usize).min(nx.saturating_sub(1)) {
                    out.push(idx(col, row));
                }
            }
        }
        if self.border {
            for col in 0..nx {
                out.push(idx(col, 0));
                out.push(idx(col, nz - 1));
            }
            for row in 0..nz {
                out.push(idx(0, row));
                out.push(idx(nx - 1, row));
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The same set on a resized grid: rows, columns and corners at the same relative
    /// place (the nearest), single vertices through `map`.
    #[must_use]
    pub fn resized(
        &self,
        (ox, oz): (usize, usize),
        (nx, nz): (usize, usize),
        map: impl Fn(u32) -> u32,
    ) -> Self {
        let scale = |i: u32, n_old: usize, n_new: usize| {
            ((f64::from(i)) * (n_new - 1) as f64 / (n_old.max(2) - 1) as f64).round() as u32
        };
        Self {
            vertices: self.vertices.iter().map(|&v| map(v)).collect(),
            rows: self.rows.iter().map(|&r| scale(r, oz, nz)).collect(),
            cols: self.cols.iter().map(|&c| scale(c, ox, nx)).collect(),
            regions: self
                .regions
                .iter()
                .map(|&[c0, r0, c1, r1]| {
                    [
                        scale(c0, ox, nx),
                        scale(r0, oz, nz),
                        scale(c1, ox, nx),
                        scale(r1, oz, nz),
                    ]
                })
                .collect(),
            border: self.border,
        }
    }
}

/// Vertices that ride a rail: a scene's `[[pins.attach]]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RailPins {
    /// The rail's name.
    pub rail: String,
    /// The vertices.
    pub vertices: VertexSet,
}

/// The vertex-set fields of a scene-file entry, as written.
pub(crate) struct VertexSetFields<'a> {
    pub(crate) vertices: Option<&'a Spanned<Vec<i64>>>,
    pub(crate) rows: Option<&'a Spanned<Vec<i64>>>,
    pub(crate) cols: Option<&'a Spanned<Vec<i64>>>,
    pub(crate) regions: Option<&'a Spanned<Vec<Vec<i64>>>>,
    pub(crate) border: bool,
}

/// The 1-based line of byte `offset` of `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Reads scene-file fields with their lines.
pub(crate) struct Reader<'a> {
    pub(crate) text: &'a str,
    pub(crate) label: &'a str,
}

impl Reader<'_> {
    pub(crate) fn error(
        &self,
        span: std::ops::Range<usize>,
        field: String,
        message: impl Into<String>,
    ) -> ClothError {
        ClothError::SceneAt {
            scene: self.label.to_owned(),
            line: line_of(self.text, span.start),
            field,
            message: message.into(),
        }
    }

    /// The rails of `[[rails]]`, their motions checked finite at every step time `k dt`
    /// of the run.
    pub(crate) fn rails(&self, rails: &[RailFile], times: &[f64]) -> Result<Vec<Rail>> {
        let mut out: Vec<Rail> = Vec::with_capacity(rails.len());
        for (k, r) in rails.iter().enumerate() {
            let name = r.name.get_ref();
            let field = format!("rails[{k}].name");
            if name.trim().is_empty() || name.trim() != name {
                return Err(self.error(
                    r.name.span(),
                    field,
                    format!("expected a name without surrounding spaces, found \"{name}\""),
                ));
            }
            if out.iter().any(|o| &o.name == name) {
                return Err(self.error(
                    r.name.span(),
                    field,
                    format!("expected each rail named once, found \"{name}\" again"),
                ));
            }
            let origin = match &r.origin {
                Some(o) if o.get_ref().iter().all(|v| v.is_finite()) => (*o.get_ref()).into(),
                Some(o) => {
                    return Err(self.error(
                        o.span(),
                        format!("rails[{k}].origin"),
                        format!("expected finite coordinates (m), found {:?}", o.get_ref()),
                    ));
                }
                None => nalgebra::Vector3::zeros(),
            };
            let motion = |value: &Option<Spanned<Value>>, what: &str| -> Result<Option<Motion>> {
                let Some(v) = value else { return Ok(None) };
                let field = format!("rails[{k}].{what}");
                let m = self.motion(v, &field)?;
                if let Some(&t) = times
                    .iter()
                    .find(|&&t| !m.at(t).iter().all(|c| c.is_finite()))
                {
                    return Err(self.error(
                        v.span(),
                        field,
                        format!(
                            "expected finite values at every step, found {:?} at t = {t} s",
                            m.at(t).as_slice()
                        ),
                    ));
                }
                Ok(Some(m))
            };
            out.push(Rail {
                name: name.clone(),
                origin,
                translation: motion(&r.translation, "translation")?.unwrap_or_else(Motion::zero),
                rotation: motion(&r.rotation, "rotation")?,
            });
        }
        Ok(out)
    }

    /// Three expressions (or numbers), or rows `[t, x, y, z]`.
    fn motion(&self, value: &Spanned<Value>, field: &str) -> Result<Motion> {
        let span = value.span();
        let shape = "three expressions of t ([\"0.1 * t\", \"0\", \"0\"]) or rows [t, x, y, z]";
        let Value::Array(items) = value.get_ref() else {
            return Err(self.error(span, field.to_owned(), format!("expected {shape}")));
        };
        let is_row = |v: &Value| matches!(v, Value::Array(_));
        if items.len() == 3 && !items.iter().any(is_row) {
            let mut exprs = Vec::with_capacity(3);
            for (axis, item) in items.iter().enumerate() {
                let field = format!("{field}[{axis}]");
                let e = match item {
                    Value::String(s) => TimeExpr::parse(s).map_err(|e| {
                        self.error(span.clone(), field.clone(), format!("in \"{s}\" at {e}"))
                    })?,
                    Value::Float(v) => TimeExpr::constant(*v),
                    Value::Integer(v) => TimeExpr::constant(*v as f64),
                    other => {
                        return Err(self.error(
                            span,
                            field,
                            format!("expected an expression of t or a number, found {other}"),
                        ));
                    }
                };
                exprs.push(e);
            }
            let [x, y, z]: [TimeExpr; 3] = exprs.try_into().unwrap_or_else(|_| unreachable!());
            return Ok(Motion::Expressions(Box::new([x, y, z])));
        }
        if items.is_empty() || !items.iter().all(is_row) {
            return Err(self.error(span, field.to_owned(), format!("expected {shape}")));
        }
        let mut rows = Vec::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            let Value::Array(row) = item else {
                unreachable!("checked above")
            };
            let numbers: Vec<f64> = row
                .iter()
                .filter_map(|v| match v {
                    Value::Float(f) => Some(*f),
                    Value::Integer(n) => Some(*n as f64),
                    _ => None,
                })
                .collect();
            if numbers.len() != 4 || row.len() != 4 {
                return Err(self.error(
                    span,
                    format!("{field}[{i}]"),
                    format!("expected a row [t, x, y, z] of 4 numbers, found {item}"),
                ));
            }
            rows.push([numbers[0], numbers[1], numbers[2], numbers[3]]);
        }
        PinPath::from_rows(&rows)
            .map(Motion::Samples)
            .map_err(|e| match e {
                ClothError::BadPinPath { index, message } => {
                    self.error(span, format!("{field}[{index}]"), message)
                }
                other => self.error(span, field.to_owned(), other.to_string()),
            })
    }

    /// The vertex set of an entry `at` (`pins.attach[0]`, `materials[1]`) on an `nx × nz`
    /// grid: every vertex, row, column and rectangle checked on the grid, an error naming
    /// its line and field.
    pub(crate) fn vertex_set(
        &self,
        at: &str,
        fields: VertexSetFields<'_>,
        (nx, nz): (usize, usize),
    ) -> Result<VertexSet> {
        let n = nx * nz;
        let grid = format!("the {nx} x {nz} grid");
        let list = |v: Option<&Spanned<Vec<i64>>>, what: &str, below: usize, unit: &str| {
            let Some(v) = v else { return Ok(Vec::new()) };
            let mut out = Vec::with_capacity(v.get_ref().len());
            for (i, &x) in v.get_ref().iter().enumerate() {
                if x < 0 || x as u64 >= below as u64 {
                    return Err(self.error(
                        v.span(),
                        format!("{at}.{what}[{i}]"),
                        format!("expected {unit} of {grid} (0 to {}), found {x}", below - 1),
                    ));
                }
                out.push(x as u32);
            }
            Ok(out)
        };
        let mut set = VertexSet {
            vertices: list(fields.vertices, "vertices", n, "a vertex")?,
            rows: list(fields.rows, "rows", nz, "a row")?,
            cols: list(fields.cols, "cols", nx, "a column")?,
            regions: Vec::new(),
            border: fields.border,
        };
        if let Some(regions) = fields.regions {
            for (i, r) in regions.get_ref().iter().enumerate() {
                let ok = r.len() == 4
                    && r[0] >= 0
                    && r[1] >= 0
                    && r[0] <= r[2]
                    && r[1] <= r[3]
                    && (r[2] as u64) < nx as u64
                    && (r[3] as u64) < nz as u64;
                if !ok {
                    return Err(self.error(
                        regions.span(),
                        format!("{at}.regions[{i}]"),
                        format!(
                            "expected [col0, row0, col1, row1] with 0 <= col0 <= col1 < {nx} \
                             and 0 <= row0 <= row1 < {nz}, found {r:?}"
                        ),
                    ));
                }
                set.regions
                    .push([r[0] as u32, r[1] as u32, r[2] as u32, r[3] as u32]);
            }
        }
        Ok(set)
    }

    /// The attachments of `[[pins.attach]]` on an `nx × nz` grid: each with its vertices
    /// (resolved, checked on the grid) and the field that names it.
    pub(crate) fn attachments(
        &self,
        attach: &[AttachFile],
        rails: &[Rail],
        (nx, nz): (usize, usize),
    ) -> Result<Vec<(RailPins, Vec<u32>, String)>> {
        let mut out = Vec::with_capacity(attach.len());
        for (k, a) in attach.iter().enumerate() {
            let at = format!("pins.attach[{k}]");
            let name = a.rail.get_ref();
            if !rails.iter().any(|r| &r.name == name) {
                let known: Vec<&str> = rails.iter().map(|r| r.name.as_str()).collect();
                return Err(self.error(
                    a.rail.span(),
                    format!("{at}.rail"),
                    format!(
                        "expected the name of a rail of [[rails]] ({}), found \"{name}\"",
                        if known.is_empty() {
                            "the scene names none".to_owned()
                        } else {
                            format!("known: {}", known.join(", "))
                        }
                    ),
                ));
            }
            let set = self.vertex_set(
                &at,
                VertexSetFields {
                    vertices: a.vertices.as_ref(),
                    rows: a.rows.as_ref(),
                    cols: a.cols.as_ref(),
                    regions: a.regions.as_ref(),
                    border: a.border,
                },
                (nx, nz),
            )?;
            let vertices = set.resolve(nx, nz);
            if vertices.is_empty() {
                return Err(self.error(
                    a.rail.span(),
                    at,
                    "expected vertices, rows, cols, regions or border = true, found no vertex",
                ));
            }
            out.push((
                RailPins {
                    rail: name.clone(),
                    vertices: set,
                },
                vertices,
                at,
            ));
        }
        Ok(out)
    }
}

/// A motion as a scene file writes it.
fn motion_text(m: &Motion) -> String {
    let num = |v: f64| format!("{v:?}");
    match m {
        Motion::Expressions(e) => {
            let quoted: Vec<String> = e
                .iter()
                .map(|x| serde_json::to_string(x.text()).unwrap_or_else(|_| "\"0\"".into()))
                .collect();
            format!("[{}]", quoted.join(", "))
        }
        Motion::Samples(path) => {
            let rows: Vec<String> = path
                .t()
                .iter()
                .zip(path.points())
                .map(|(t, p)| format!("[{}, {}, {}, {}]", num(*t), num(p.x), num(p.y), num(p.z)))
                .collect();
            format!("[{}]", rows.join(", "))
        }
    }
}

/// Writes `[[rails]]` entries.
pub(crate) fn write_rails(out: &mut String, rails: &[Rail]) {
    let num = |v: f64| format!("{v:?}");
    for r in rails {
        // Writing to a String cannot fail.
        let _ = writeln!(out, "\n[[rails]]");
        let _ = writeln!(
            out,
            "name = {}",
            serde_json::to_string(&r.name).unwrap_or_default()
        );
        if r.origin != nalgebra::Vector3::zeros() {
            let o = r.origin;
            let _ = writeln!(
                out,
                "origin = [{}, {}, {}]  # m",
                num(o.x),
                num(o.y),
                num(o.z)
            );
        }
        if !r.translation.is_zero() {
            let _ = writeln!(out, "translation = {}  # m", motion_text(&r.translation));
        }
        if let Some(rot) = &r.rotation {
            let _ = writeln!(out, "rotation = {}  # rad, axis x angle", motion_text(rot));
        }
    }
}

/// Writes `[[pins.attach]]` entries.
pub(crate) fn write_attachments(out: &mut String, pins: &[RailPins]) {
    for p in pins {
        let _ = writeln!(out, "\n[[pins.attach]]");
        let _ = writeln!(
            out,
            "rail = {}",
            serde_json::to_string(&p.rail).unwrap_or_default()
        );
        write_vertex_set(out, &p.vertices);
    }
}

/// Writes the fields of a vertex set (those that are set).
pub(crate) fn write_vertex_set(out: &mut String, s: &VertexSet) {
    let list = |v: &[u32]| {
        let items: Vec<String> = v.iter().map(u32::to_string).collect();
        format!("[{}]", items.join(", "))
    };
    if !s.vertices.is_empty() {
        let _ = writeln!(out, "vertices = {}", list(&s.vertices));
    }
    if !s.rows.is_empty() {
        let _ = writeln!(out, "rows = {}", list(&s.rows));
    }
    if !s.cols.is_empty() {
        let _ = writeln!(out, "cols = {}", list(&s.cols));
    }
    if !s.regions.is_empty() {
        let r: Vec<String> = s.regions.iter().map(|r| list(r)).collect();
        let _ = writeln!(out, "regions = [{}]", r.join(", "));
    }
    if s.border {
        let _ = writeln!(out, "border = true");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertex_sets_resolve_on_the_grid() {
        let set = VertexSet {
            vertices: vec![12, 0],
            rows: vec![0],
            cols: vec![3],
            regions: vec![[1, 1, 2, 2]],
            border: false,
        };
        assert_eq!(
            set.resolve(4, 4),
            vec![0, 1, 2, 3, 5, 6, 7, 9, 10, 11, 12, 15]
        );
        let border = VertexSet {
            border: true,
            ..VertexSet::default()
        };
        assert_eq!(border.resolve(3, 3), vec![0, 1, 2, 3, 5, 6, 7, 8]);
        let resized = VertexSet::row(2).resized((3, 3), (5, 5), |v| v);
        assert_eq!(resized.rows, vec![4]);
    }

    #[test]
    fn lines_count_from_one() {
        assert_eq!(line_of("a\nb\nc", 0), 1);
        assert_eq!(line_of("a\nb\nc", 2), 2);
        assert_eq!(line_of("a\nb\nc", 4), 3);
    }
}

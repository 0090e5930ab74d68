//! Materials per region: stretch compliance (one value, or warp and weft),
//! quadratic bending rigidity and velocity damping, for the whole cloth and
//! for named vertex sets of its grid.
//!
//! The cloth's own material is in `[cloth]` (`compliance`, `warp_compliance`,
//! `weft_compliance`, `bending_rigidity`, `damping`); each `[[materials]]`
//! entry names a region (vertices, rows, columns, rectangles or the border, as
//! `[[pins.attach]]`) and sets any of the same fields there; later entries
//! win where regions overlap, and a field an entry leaves out keeps the value
//! underneath.
//!
//! ```toml
//! [[materials]]
//! name = "hem"                # unique; candidates name it (compliance@hem)
//! rows = [20, 21, 22, 23]     # and/or vertices, cols, regions, border
//! compliance = 0.002          # m/N, warp and weft
//! warp_compliance = 0.003     # m/N, links along a row (optional, overrides compliance)
//! weft_compliance = 0.001     # m/N, links along a column
//! bending_rigidity = 1e-4     # N m (crate::bending)
//! damping = 0.1               # 1/s
//! ```
//!
//! Values live on vertices; a link takes the mean of its two ends' values in
//! its direction (a row link the warp compliance, a column link the weft, a
//! diagonal link — shear — the mean of both), so a link across a region's edge
//! is half in each. A vertex's bending rigidity is that of the curvature at
//! it ([`crate::bending`]); its damping acts on its own particle.

use serde::Deserialize;
use toml::Spanned;

use crate::error::Result;
use crate::rail::file::{Reader, VertexSet, VertexSetFields};

/// Material values; `None` leaves the value underneath (the cloth's, or an
/// earlier region's).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Material {
    /// Stretch compliance of links in both directions (m/N).
    pub compliance: Option<f64>,
    /// Compliance of links along a row (warp, the grid's x), over `compliance` (m/N).
    pub warp_compliance: Option<f64>,
    /// Compliance of links along a column (weft, the grid's z), over `compliance` (m/N).
    pub weft_compliance: Option<f64>,
    /// Quadratic bending rigidity `B` (N·m).
    pub bending_rigidity: Option<f64>,
    /// Velocity damping rate (1/s).
    pub damping: Option<f64>,
}

impl Material {
    /// Whether the material sets warp or weft apart.
    #[must_use]
    pub fn is_anisotropic(&self) -> bool {
        self.warp_compliance.is_some() || self.weft_compliance.is_some()
    }
}

/// A named region of the grid with its material: a `[[materials]]` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialRegion {
    /// Name, unique in the scene.
    pub name: String,
    /// Its vertices.
    pub vertices: VertexSet,
    /// What it sets.
    pub material: Material,
}

/// Every vertex's material values, the regions laid over the cloth's own.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexMaterials {
    /// Warp compliance (m/N).
    pub warp: Vec<f64>,
    /// Weft compliance (m/N).
    pub weft: Vec<f64>,
    /// Bending rigidity (N·m).
    pub bending: Vec<f64>,
    /// Damping rate (1/s).
    pub damping: Vec<f64>,
    nx: usize,
}

impl VertexMaterials {
    /// The values of an `nx × nz` grid: `base` everywhere (its unset fields
    /// 0), then each region's set fields on its vertices, in order.
    #[must_use]
    pub fn resolve(base: &Material, regions: &[MaterialRegion], nx: usize, nz: usize) -> Self {
        let n = nx * nz;
        let c = base.compliance.unwrap_or(0.0);
        let mut out = Self {
            warp: vec![base.warp_compliance.unwrap_or(c); n],
            weft: vec![base.weft_compliance.unwrap_or(c); n],
            bending: vec![base.bending_rigidity.unwrap_or(0.0); n],
            damping: vec![base.damping.unwrap_or(0.0); n],
            nx,
        };
        for r in regions {
            let m = &r.material;
            for v in r.vertices.resolve(nx, nz) {
                let v = v as usize;
                if let Some(c) = m.compliance {
                    out.warp[v] = c;
                    out.weft[v] = c;
                }
                if let Some(c) = m.warp_compliance {
                    out.warp[v] = c;
                }
                if let Some(c) = m.weft_compliance {
                    out.weft[v] = c;
                }
                if let Some(b) = m.bending_rigidity {
                    out.bending[v] = b;
                }
                if let Some(d) = m.damping {
                    out.damping[v] = d;
                }
            }
        }
        out
    }

    /// The compliance of the link between grid vertices `a` and `b` (m/N):
    /// the mean of its ends' warp values for a link along a row, weft for a
    /// link along a column, both for any other (a diagonal).
    #[must_use]
    pub fn link_compliance(&self, a: u32, b: u32) -> f64 {
        let (a, b) = (a as usize, b as usize);
        let nx = self.nx.max(1);
        let warp = 0.5 * (self.warp[a] + self.warp[b]);
        let weft = 0.5 * (self.weft[a] + self.weft[b]);
        if a / nx == b / nx {
            warp
        } else if a % nx == b % nx {
            weft
        } else {
            0.5 * (warp + weft)
        }
    }

    /// Whether any link is compliant.
    #[must_use]
    pub fn any_compliance(&self) -> bool {
        self.warp.iter().chain(&self.weft).any(|&c| c > 0.0)
    }

    /// Whether any vertex bends stiffly.
    #[must_use]
    pub fn any_bending(&self) -> bool {
        self.bending.iter().any(|&b| b > 0.0)
    }

    /// The damping rate when it is the same on every vertex.
    #[must_use]
    pub fn uniform_damping(&self) -> Option<f64> {
        let first = *self.damping.first()?;
        self.damping.iter().all(|&d| d == first).then_some(first)
    }
}

/// `[[materials]]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MaterialFile {
    name: Spanned<String>,
    vertices: Option<Spanned<Vec<i64>>>,
    rows: Option<Spanned<Vec<i64>>>,
    cols: Option<Spanned<Vec<i64>>>,
    regions: Option<Spanned<Vec<Vec<i64>>>>,
    #[serde(default)]
    border: bool,
    compliance: Option<Spanned<f64>>,
    warp_compliance: Option<Spanned<f64>>,
    weft_compliance: Option<Spanned<f64>>,
    bending_rigidity: Option<Spanned<f64>>,
    damping: Option<Spanned<f64>>,
}

impl Reader<'_> {
    /// A material value as written: non-negative and finite, or an error
    /// naming its line and `field`.
    pub(crate) fn non_negative(
        &self,
        value: Option<&Spanned<f64>>,
        field: &str,
        unit: &str,
    ) -> Result<Option<f64>> {
        match value {
            Some(s) if !(*s.get_ref() >= 0.0 && s.get_ref().is_finite()) => Err(self.error(
                s.span(),
                field.to_owned(),
                format!(
                    "expected a non-negative, finite value ({unit}), found {}",
                    s.get_ref()
                ),
            )),
            Some(s) => Ok(Some(*s.get_ref())),
            None => Ok(None),
        }
    }

    /// The regions of `[[materials]]` on an `nx × nz` grid: names unique and
    /// not empty, vertex sets on the grid and not empty, every value
    /// non-negative and finite; an error names the line and the field.
    pub(crate) fn materials(
        &self,
        files: &[MaterialFile],
        (nx, nz): (usize, usize),
    ) -> Result<Vec<MaterialRegion>> {
        let mut out: Vec<MaterialRegion> = Vec::with_capacity(files.len());
        for (k, f) in files.iter().enumerate() {
            let at = format!("materials[{k}]");
            let name = f.name.get_ref();
            if name.trim().is_empty() || name.trim() != name || name.contains('@') {
                return Err(self.error(
                    f.name.span(),
                    format!("{at}.name"),
                    format!("expected a name without spaces around it or '@', found \"{name}\""),
                ));
            }
            if out.iter().any(|r| &r.name == name) {
                return Err(self.error(
                    f.name.span(),
                    format!("{at}.name"),
                    format!("expected each material region named once, found \"{name}\" again"),
                ));
            }
            let vertices = self.vertex_set(
                &at,
                VertexSetFields {
                    vertices: f.vertices.as_ref(),
                    rows: f.rows.as_ref(),
                    cols: f.cols.as_ref(),
                    regions: f.regions.as_ref(),
                    border: f.border,
                },
                (nx, nz),
            )?;
            if vertices.resolve(nx, nz).is_empty() {
                return Err(self.error(
                    f.name.span(),
                    at,
                    "expected vertices, rows, cols, regions or border = true, found no vertex",
                ));
            }
            let value = |v: &Option<Spanned<f64>>, field: &str, unit: &str| {
                self.non_negative(v.as_ref(), &format!("{at}.{field}"), unit)
            };
            let material = Material {
                compliance: value(&f.compliance, "compliance", "m/N")?,
                warp_compliance: value(&f.warp_compliance, "warp_compliance", "m/N")?,
                weft_compliance: value(&f.weft_compliance, "weft_compliance", "m/N")?,
                bending_rigidity: value(&f.bending_rigidity, "bending_rigidity", "N m")?,
                damping: value(&f.damping, "damping", "1/s")?,
            };
            out.push(MaterialRegion {
                name: name.clone(),
                vertices,
                material,
            });
        }
        Ok(out)
    }
}

/// Writes `[[materials]]` entries (the fields that are set).
pub(crate) fn write_materials(out: &mut String, regions: &[MaterialRegion]) {
    use std::fmt::Write as _;
    for r in regions {
        let _ = writeln!(out, "\n[[materials]]");
        let _ = writeln!(
            out,
            "name = {}",
            serde_json::to_string(&r.name).unwrap_or_default()
        );
        crate::rail::file::write_vertex_set(out, &r.vertices);
        let m = &r.material;
        for (field, value, unit) in [
            ("compliance", m.compliance, "m/N"),
            ("warp_compliance", m.warp_compliance, "m/N"),
            ("weft_compliance", m.weft_compliance, "m/N"),
            ("bending_rigidity", m.bending_rigidity, "N m"),
            ("damping", m.damping, "1/s"),
        ] {
            if let Some(v) = value {
                let _ = writeln!(out, "{field} = {v:?}  # {unit}");
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_lay_over_the_cloth_and_links_take_their_direction() {
        let base = Material {
            compliance: Some(1.0),
            weft_compliance: Some(2.0),
            bending_rigidity: Some(0.5),
            ..Material::default()
        };
        let regions = vec![
            MaterialRegion {
                name: "right".into(),
                vertices: VertexSet {
                    cols: vec![2],
                    ..VertexSet::default()
                },
                material: Material {
                    compliance: Some(3.0),
                    damping: Some(0.1),
                    ..Material::default()
                },
            },
            MaterialRegion {
                name: "corner".into(),
                vertices: VertexSet {
                    vertices: vec![8],
                    ..VertexSet::default()
                },
                material: Material {
                    warp_compliance: Some(5.0),
                    ..Material::default()
                },
            },
        ];
        let m = VertexMaterials::resolve(&base, &regions, 3, 3);
        assert_eq!(m.warp, vec![1.0, 1.0, 3.0, 1.0, 1.0, 3.0, 1.0, 1.0, 5.0]);
        assert_eq!(m.weft, vec![2.0, 2.0, 3.0, 2.0, 2.0, 3.0, 2.0, 2.0, 3.0]);
        assert_eq!(m.bending, vec![0.5; 9]);
        assert_eq!(m.uniform_damping(), None);
        // Row link 0-1: warp; column link 0-3: weft; across the region's edge: the mean.
        assert_eq!(m.link_compliance(0, 1), 1.0);
        assert_eq!(m.link_compliance(0, 3), 2.0);
        assert_eq!(m.link_compliance(1, 2), 2.0);
        assert_eq!(m.link_compliance(7, 8), 3.0);
        // A diagonal: the mean of warp and weft.
        assert_eq!(m.link_compliance(0, 4), 1.5);
    }
}

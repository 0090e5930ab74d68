//! Quadratic bending: the isometric bending model of Bergou, Wardetzky, Harmon,
//! Zorin & Grinspun (2006), integrated implicitly.
//!
//! For a surface that bends without stretching, the Laplace–Beltrami operator
//! is that of its rest state, and the Laplacian of the position is the mean
//! curvature normal: `Δx = (κ₁ + κ₂) n`. The plate bending energy of a
//! developable surface (Poisson ratio 0, `κ₁ κ₂ = 0`) is then
//! `E = ½ B ∫ |Δx|² dA`, **quadratic in the positions with a constant
//! Hessian**: with the cotangent Laplacian `L` of the rest mesh and the
//! barycentric area `Aᵢ` of each interior vertex,
//!
//! ```text
//! E = ½ Σᵢ Bᵢ |Σⱼ wᵢⱼ xⱼ|²,   wᵢⱼ = Lᵢⱼ / √Aᵢ,
//! Lᵢⱼ = ½ (cot αᵢⱼ + cot βᵢⱼ) (j a neighbour),   Lᵢᵢ = −Σⱼ Lᵢⱼ,
//! ```
//!
//! summed over the interior vertices `i` (a boundary vertex's Laplacian is not
//! a curvature: it is not zero on the flat rest state). `B` (N·m) is the
//! flexural rigidity; a cylinder of radius `R` stores `½ B / R²` per unit
//! area (tested). The energy is zero on the flat rest state and on every
//! rigid motion of it, and it has a real stiffness about the flat state,
//! unlike springs that only push folded vertex pairs apart
//! ([`crate::forces::BendPair`]). This is the vertex form of the model: on a
//! grid of right triangles its energy does not depend on the direction of the
//! fold (the cotangent Laplacian is exact for quadratics there), whereas the
//! edge-hinge form stores three times more energy in a fold across the
//! triangles' diagonals than along them.
//!
//! # Implicit integration
//!
//! The step holds every force constant over the step (see [`crate::forces`]),
//! so a stiff bending force taken at the start of the step would need
//! `B h² / (m d⁴) ≪ 1`. Instead the bending force of a step is taken where the
//! step ends, as backward Euler does: with `a` the acceleration over the step,
//!
//! ```text
//! F_b = −H (x + h v + h² a),   M a = M g + F + F_b   (dynamic vertices)
//! ⇔  (M + h² H) a = M g + F − H (x + h v)
//! ```
//!
//! one sparse symmetric positive definite solve per step (three right-hand
//! sides) with a Cholesky factor made once for the step size. A bending mode
//! of frequency `ω` then changes by a factor whose size stays below 1 for any
//! `ω h` (for `s = ω² h² / (1 + ω² h²) < 1` the step's amplification has
//! determinant `1 − s/2` and trace `2 − 3s/2`), so any stiffness is stable:
//! what bounds `B` is physics, not the step. Pinned vertices move
//! kinematically: their `a` is zero and their `x + h v` is where their motion
//! takes them.
//!
//! # Example
//!
//! ```
//! use modelgap_cloth::bending::QuadraticBending;
//! use modelgap_cloth::{BuildMesh as _, GridCloth};
//! use nalgebra::Vector3;
//!
//! let mesh = GridCloth::new(11, 11, 0.1).build_mesh()?;
//! let mut bending = QuadraticBending::new(&mesh.positions, &mesh.triangles);
//! bending.set_uniform_stiffness(0.01); // N m
//! // Flat: no energy. Rolled on a cylinder of radius 2 m: ½ B / R² per m².
//! assert!(bending.energy(&mesh.positions).abs() < 1e-15);
//! let r = 2.0;
//! let rolled: Vec<Vector3<f64>> = mesh
//!     .positions
//!     .iter()
//!     .map(|p| Vector3::new(r * (p.x / r).sin(), r * (1.0 - (p.x / r).cos()), p.z))
//!     .collect();
//! let interior = 81.0 * 0.1 * 0.1; // m²: 9 x 9 interior vertices, 0.01 m² each
//! let expected = 0.5 * 0.01 / (r * r) * interior;
//! assert!((bending.energy(&rolled) / expected - 1.0).abs() < 0.01);
//! # Ok::<(), modelgap_cloth::ClothError>(())
//! ```

use faer::Side;
use faer::linalg::solvers::SolveCore as _;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::Vector3;

use crate::error::{ClothError, Result};

/// Weights smaller than this fraction of the largest in their stencil are
/// dropped (the cotangent of a right angle, rounded).
const WEIGHT_CUTOFF: f64 = 1e-12;

/// The quadratic bending energy of a mesh: one stencil (an interior vertex and
/// its neighbours, with weights) per interior vertex, and a stiffness per
/// stencil (see the [module docs](self)).
#[derive(Clone, Debug, Default)]
pub struct QuadraticBending {
    /// The interior vertex of each stencil.
    centres: Vec<u32>,
    /// Stencil `s` spans `start[s]..start[s + 1]` of `vertices` and `weights`.
    start: Vec<usize>,
    vertices: Vec<u32>,
    /// `Lᵢⱼ / √Aᵢ` (1/m).
    weights: Vec<f64>,
    /// Flexural rigidity `B` of each stencil (N·m).
    stiffness: Vec<f64>,
}

impl QuadraticBending {
    /// The stencils of a mesh at rest (`rest`: one position per vertex;
    /// `triangles`: vertex indices). A vertex is interior when every edge
    /// around it is shared by two triangles; triangles of zero area and
    /// indices past `rest` are skipped. Every stiffness starts at 0.
    #[must_use]
    pub fn new(rest: &[Vector3<f64>], triangles: &[[u32; 3]]) -> Self {
        let n = rest.len();
        let ok = |t: &[u32; 3]| t.iter().all(|&v| (v as usize) < n);
        // Per vertex: its neighbours with their cotangent weights, its area.
        let mut neighbours: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
        let mut area = vec![0.0; n];
        // Edges with the number of triangles on them.
        let mut edges: Vec<(u32, u32)> = Vec::with_capacity(3 * triangles.len());
        for t in triangles.iter().filter(|t| ok(t)) {
            let p = t.map(|v| rest[v as usize]);
            let twice = (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
            if twice == 0.0 {
                continue;
            }
            for k in 0..3 {
                let (i, j, o) = (k, (k + 1) % 3, (k + 2) % 3);
                // The angle at `o` faces edge i–j.
                let (a, b) = (p[i] - p[o], p[j] - p[o]);
                let cot = a.dot(&b) / a.cross(&b).norm();
                let (vi, vj) = (t[i], t[j]);
                add(&mut neighbours[vi as usize], vj, 0.5 * cot);
                add(&mut neighbours[vj as usize], vi, 0.5 * cot);
                edges.push((vi.min(vj), vi.max(vj)));
                area[t[k] as usize] += twice / 6.0;
            }
        }
        edges.sort_unstable();
        let mut boundary = vec![false; n];
        let mut k = 0;
        while k < edges.len() {
            let mut m = k + 1;
            while m < edges.len() && edges[m] == edges[k] {
                m += 1;
            }
            if m - k != 2 {
                boundary[edges[k].0 as usize] = true;
                boundary[edges[k].1 as usize] = true;
            }
            k = m;
        }
        let mut out = Self {
            start: vec![0],
            ..Self::default()
        };
        for i in 0..n {
            if boundary[i] || neighbours[i].is_empty() || area[i] <= 0.0 {
                continue;
            }
            let scale = 1.0 / area[i].sqrt();
            let largest = neighbours[i].iter().fold(0.0_f64, |m, w| m.max(w.1.abs()));
            let mut diagonal = 0.0;
            for &(j, w) in &neighbours[i] {
                diagonal -= w;
                if w.abs() > WEIGHT_CUTOFF * largest {
                    out.vertices.push(j);
                    out.weights.push(w * scale);
                }
            }
            out.vertices.push(i as u32);
            out.weights.push(diagonal * scale);
            out.centres.push(i as u32);
            out.start.push(out.vertices.len());
        }
        out.stiffness = vec![0.0; out.centres.len()];
        out
    }

    /// Number of stencils (interior vertices).
    #[must_use]
    pub fn len(&self) -> usize {
        self.centres.len()
    }

    /// Whether the mesh has no interior vertex.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.centres.is_empty()
    }

    /// The same stiffness `B` (N·m) everywhere.
    pub fn set_uniform_stiffness(&mut self, b: f64) {
        self.stiffness.fill(b);
    }

    /// The stiffness of each stencil from a per-vertex stiffness (N·m, one per
    /// vertex: the stencil's centre's). Vertices past the slice get 0.
    pub fn set_vertex_stiffness(&mut self, per_vertex: &[f64]) {
        for (b, &c) in self.stiffness.iter_mut().zip(&self.centres) {
            *b = per_vertex.get(c as usize).copied().unwrap_or(0.0);
        }
    }

    /// Whether every stiffness is zero.
    #[must_use]
    pub fn is_off(&self) -> bool {
        self.stiffness.iter().all(|&b| b == 0.0)
    }

    fn stencils(&self) -> impl Iterator<Item = (f64, &[u32], &[f64])> + '_ {
        (0..self.centres.len()).map(|s| {
            let r = self.start[s]..self.start[s + 1];
            (
                self.stiffness[s],
                &self.vertices[r.clone()],
                &self.weights[r],
            )
        })
    }

    /// The bending energy of positions `x` (J).
    #[must_use]
    pub fn energy(&self, x: &[Vector3<f64>]) -> f64 {
        self.stencils()
            .map(|(b, vs, ws)| {
                let lap: Vector3<f64> = vs.iter().zip(ws).map(|(&v, w)| x[v as usize] * *w).sum();
                0.5 * b * lap.norm_squared()
            })
            .sum()
    }

    /// Adds `−H x` to `out` (one per vertex): the bending forces at `x` (N).
    pub fn add_forces(&self, x: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        for (b, vs, ws) in self.stencils() {
            if b == 0.0 {
                continue;
            }
            let lap: Vector3<f64> = vs.iter().zip(ws).map(|(&v, w)| x[v as usize] * *w).sum();
            for (&v, w) in vs.iter().zip(ws) {
                out[v as usize] -= lap * (b * w);
            }
        }
    }
}

/// Adds `w` to `j`'s entry of a neighbour list.
fn add(list: &mut Vec<(u32, f64)>, j: u32, w: f64) {
    match list.iter_mut().find(|e| e.0 == j) {
        Some(e) => e.1 += w,
        None => list.push((j, w)),
    }
}

/// [`QuadraticBending`] integrated implicitly (see the [module docs](self)):
/// the factor of `M + h² H` over the dynamic vertices, made for a step size
/// and kept.
#[derive(Debug)]
pub struct ImplicitBending {
    bending: QuadraticBending,
    /// Mass of each vertex (kg); 0 for a pinned one.
    masses: Vec<f64>,
    /// The row of each dynamic vertex in the system.
    row: Vec<Option<usize>>,
    n_dynamic: usize,
    factor: Option<(f64, faer::sparse::linalg::solvers::Llt<usize, f64>)>,
    rhs: faer::Mat<f64>,
    ahead: Vec<Vector3<f64>>,
    force: Vec<Vector3<f64>>,
}

impl ImplicitBending {
    /// The implicit step of `bending` for vertices of masses `masses` (kg, 0
    /// for pinned vertices).
    #[must_use]
    pub fn new(bending: QuadraticBending, masses: &[f64]) -> Self {
        let mut row = vec![None; masses.len()];
        let mut n_dynamic = 0;
        for (r, &m) in row.iter_mut().zip(masses) {
            if m > 0.0 {
                *r = Some(n_dynamic);
                n_dynamic += 1;
            }
        }
        Self {
            bending,
            masses: masses.to_vec(),
            row,
            n_dynamic,
            factor: None,
            rhs: faer::Mat::zeros(n_dynamic, 3),
            ahead: vec![Vector3::zeros(); masses.len()],
            force: vec![Vector3::zeros(); masses.len()],
        }
    }

    /// The bending energy.
    #[must_use]
    pub fn bending(&self) -> &QuadraticBending {
        &self.bending
    }

    /// Factors `M + h² H` over the dynamic vertices.
    fn factor(&self, h: f64) -> Result<faer::sparse::linalg::solvers::Llt<usize, f64>> {
        let n = self.n_dynamic;
        let mut triplets: Vec<Triplet<usize, usize, f64>> = Vec::new();
        for (i, r) in self.row.iter().enumerate() {
            if let Some(r) = *r {
                triplets.push(Triplet::new(r, r, self.masses[i]));
            }
        }
        let h2 = h * h;
        for (b, vs, ws) in self.bending.stencils() {
            if b == 0.0 {
                continue;
            }
            for (&va, wa) in vs.iter().zip(ws) {
                let Some(ra) = self.row[va as usize] else {
                    continue;
                };
                for (&vb, wb) in vs.iter().zip(ws) {
                    if let Some(rb) = self.row[vb as usize]
                        && rb >= ra
                    {
                        triplets.push(Triplet::new(rb, ra, h2 * b * wa * wb));
                    }
                }
            }
        }
        // M is positive and H positive semi-definite: only a non-finite
        // stiffness makes this fail.
        let failed = || ClothError::BadParameter {
            name: "bending stiffness",
            expected: "non-negative and finite (N m)",
            value: self.bending.stiffness.iter().copied().fold(0.0, f64::max),
        };
        let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
            .map_err(|_| failed())?;
        matrix.sp_cholesky(Side::Lower).map_err(|_| failed())
    }

    /// Adds to `forces` (N, one per vertex, holding the step's other external
    /// forces) the bending force of a step of `h` s from positions `x` and
    /// velocities `v` under gravity `g`: `−H (x + h v + h² a)` (see the
    /// [module docs](self)). Pinned vertices get none.
    ///
    /// # Errors
    /// [`ClothError::BadParameter`] when `M + h² H` cannot be factored (a
    /// non-finite stiffness).
    pub fn add_step_forces(
        &mut self,
        h: f64,
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        g: &Vector3<f64>,
        forces: &mut [Vector3<f64>],
    ) -> Result<()> {
        if self.bending.is_off() || self.n_dynamic == 0 {
            return Ok(());
        }
        if self.factor.as_ref().is_none_or(|(fh, _)| *fh != h) {
            self.factor = Some((h, self.factor(h)?));
        }
        for ((a, x), v) in self.ahead.iter_mut().zip(x).zip(v) {
            *a = x + h * v;
        }
        self.force.fill(Vector3::zeros());
        self.bending.add_forces(&self.ahead, &mut self.force);
        for (i, r) in self.row.iter().enumerate() {
            if let Some(r) = *r {
                let rhs = self.masses[i] * g + forces[i] + self.force[i];
                for k in 0..3 {
                    self.rhs[(r, k)] = rhs[k];
                }
            }
        }
        let Some((_, llt)) = &self.factor else {
            unreachable!("factored above")
        };
        llt.solve_in_place_with_conj(faer::Conj::No, self.rhs.as_mut());
        // F_b = M a − M g − F on the dynamic vertices.
        for (i, r) in self.row.iter().enumerate() {
            if let Some(r) = *r {
                let a = Vector3::new(self.rhs[(r, 0)], self.rhs[(r, 1)], self.rhs[(r, 2)]);
                forces[i] = self.masses[i] * (a - g);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{BuildMesh as _, GridCloth};

    fn grid(n: usize, d: f64) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
        let mesh = GridCloth::new(n, n, d).build_mesh().unwrap();
        (mesh.positions, mesh.triangles)
    }

    /// Energy per unit interior area of the grid bent with height `f(u, v)`
    /// over the flat grid (small slopes), over `½ B κ²`.
    fn ratio(f: impl Fn(f64, f64) -> f64, kappa: f64) -> f64 {
        let (x, t) = grid(21, 0.05);
        let mut b = QuadraticBending::new(&x, &t);
        b.set_uniform_stiffness(2.0);
        let bent: Vec<Vector3<f64>> = x
            .iter()
            .map(|p| Vector3::new(p.x, f(p.x, p.z), p.z))
            .collect();
        let interior = (19.0 * 0.05_f64).powi(2);
        b.energy(&bent) / (0.5 * 2.0 * kappa * kappa * interior)
    }

    #[test]
    fn a_fold_in_any_direction_stores_half_b_kappa_squared() {
        let k = 1e-3;
        for (name, r) in [
            ("along x", ratio(|u, _| 0.5 * k * u * u, k)),
            ("along z", ratio(|_, v| 0.5 * k * v * v, k)),
            ("diagonal", ratio(|u, v| 0.25 * k * (u + v) * (u + v), k)),
            (
                "anti-diagonal",
                ratio(|u, v| 0.25 * k * (u - v) * (u - v), k),
            ),
        ] {
            assert!((r - 1.0).abs() < 1e-6, "{name}: {r}");
        }
    }

    #[test]
    fn flat_and_rigid_motions_store_nothing_and_forces_conserve_momentum() {
        let (x, t) = grid(6, 0.1);
        let mut b = QuadraticBending::new(&x, &t);
        assert_eq!(b.len(), 16);
        b.set_uniform_stiffness(1.0);
        let rot = nalgebra::Rotation3::new(Vector3::new(0.3, -0.2, 0.5));
        let moved: Vec<_> = x
            .iter()
            .map(|p| rot * p + Vector3::new(1.0, 2.0, 3.0))
            .collect();
        assert!(b.energy(&x).abs() < 1e-20);
        assert!(b.energy(&moved).abs() < 1e-20);
        let mut bumped = x.clone();
        bumped[14].y += 0.01;
        let mut f = vec![Vector3::zeros(); x.len()];
        b.add_forces(&bumped, &mut f);
        let total: Vector3<f64> = f.iter().sum();
        assert!(total.norm() < 1e-12, "{total:?}");
        // The bumped vertex is pushed back.
        assert!(f[14].y < 0.0);
        // Energy is ½ xᵀ H x: its derivative along the bump is the force.
        let e = b.energy(&bumped);
        approx::assert_relative_eq!(2.0 * e, -f[14].y * 0.01, max_relative = 1e-9);
    }

    /// Far stiffer than an explicit step could hold (B h² / (m d⁴) = 1e4): the
    /// implicit step stays bounded and brings a bumped sheet back flat.
    #[test]
    fn a_very_stiff_sheet_is_stable_and_settles_flat() {
        let (x, t) = grid(8, 0.1);
        let mut b = QuadraticBending::new(&x, &t);
        let (m, h) = (1e-3, 0.01);
        b.set_uniform_stiffness(1e4 * m * 0.1_f64.powi(4) / (h * h));
        let masses = vec![m; x.len()];
        let mut implicit = ImplicitBending::new(b, &masses);
        let mut pos = x.clone();
        pos[27].y += 0.02;
        let mut vel = vec![Vector3::zeros(); x.len()];
        let g = Vector3::zeros();
        for _ in 0..200 {
            let mut f = vec![Vector3::zeros(); x.len()];
            implicit.add_step_forces(h, &pos, &vel, &g, &mut f).unwrap();
            for ((p, v), f) in pos.iter_mut().zip(&mut vel).zip(&f) {
                let a = f / m;
                *p += h * *v + 0.5 * h * h * a;
                *v += h * a;
            }
            let e = implicit.bending().energy(&pos);
            assert!(e.is_finite() && e < 1e3, "{e}");
        }
        let e = implicit.bending().energy(&pos);
        assert!(e < 1e-6, "{e}");
    }
}

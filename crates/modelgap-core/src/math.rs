//! The one place where modelgap fixes its linear-algebra types: nalgebra, `f64`.
//!
//! Geometry uses [`Vector3`] and [`Point3`]; state-space models and Jacobians use
//! [`DMatrix`] and [`DVector`]. Changing the scalar type is one line per alias.

/// A 3-vector of `f64` (a displacement, velocity or force).
pub type Vector3 = nalgebra::Vector3<f64>;

/// A point in 3-D space, `f64` coordinates (m).
pub type Point3 = nalgebra::Point3<f64>;

/// A dynamically sized matrix of `f64`.
pub type DMatrix = nalgebra::DMatrix<f64>;

/// A dynamically sized column vector of `f64`.
pub type DVector = nalgebra::DVector<f64>;

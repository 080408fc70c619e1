//! Fixed-size aliases used throughout the crate. All are stack values; nothing here allocates.

use nalgebra::{SMatrix, SVector};

/// A 3-vector (m, m/s, rad/s, …): joint centres, link vectors, angular velocities.
pub type Vec3 = SVector<f64, 3>;
/// A 6-vector: pose χ = [x, y, z, α, β, γ] (m, rad), a twist v_E = [Ė; ω], or the joint vector θ (rad).
pub type Vec6 = SVector<f64, 6>;
/// A 3 × 3 matrix: rotations R (eq. 3.2), the Euler-rate Jacobian J_e (eq. 3.22), inertia tensors.
pub type Mat3 = SMatrix<f64, 3, 3>;
/// A 6 × 6 matrix: J_a2, J_ad, J_θ, J', M̃, C̃ …
pub type Mat6 = SMatrix<f64, 6, 6>;
/// A 3 × 6 matrix: one leg's translational or rotational velocity Jacobian block (eq. 3.32, 3.37).
pub type Mat3x6 = SMatrix<f64, 3, 6>;
/// A 6 × 6 per-leg body Jacobian (eq. 3.33, 3.40).
pub type LegJacobian = SMatrix<f64, 6, 6>;
/// Number of legs (serial branches) of a 6-RSS robot.
pub const LEGS: usize = 6;

//! The one pose mean of the project: mean position, and the rotation whose quaternion maximises
//! Σ (q · q_k)² (the eigenvector of Σ q_k q_kᵀ with the largest eigenvalue). It is sign-safe (q and −q
//! are the same rotation), has no trouble at α, γ = ±π, and equals the mean of the Euler angles to first
//! order for the small scatter of a dwell.

use nalgebra::{Matrix4, Quaternion, SymmetricEigen, UnitQuaternion};
use rss6_core::{isometry_to_pose, pose_to_isometry, Vec6};

/// Running mean of poses [x, y, z, α, β, γ] (m, rad), see the module docs.
#[derive(Debug, Clone, Default)]
pub struct PoseMean {
    sum_position: nalgebra::Vector3<f64>,
    scatter: Matrix4<f64>,
    n: u32,
}

impl PoseMean {
    /// Adds one pose (ignored if not finite).
    pub fn add(&mut self, pose: &Vec6) {
        if !pose.iter().all(|v| v.is_finite()) {
            return;
        }
        let iso = pose_to_isometry(pose);
        let q = iso.rotation.quaternion().coords;
        self.scatter += q * q.transpose();
        self.sum_position += iso.translation.vector;
        self.n += 1;
    }

    /// Number of poses added.
    pub fn count(&self) -> u32 {
        self.n
    }

    /// The mean pose, or `None` if no pose was added.
    pub fn mean(&self) -> Option<Vec6> {
        if self.n == 0 {
            return None;
        }
        let eig = SymmetricEigen::new(self.scatter);
        let (mut best, mut k) = (f64::NEG_INFINITY, 0);
        for (i, &l) in eig.eigenvalues.iter().enumerate() {
            if l > best {
                best = l;
                k = i;
            }
        }
        let v = eig.eigenvectors.column(k);
        let q = UnitQuaternion::from_quaternion(Quaternion::new(v[3], v[0], v[1], v[2]));
        let p = self.sum_position / f64::from(self.n);
        let iso = nalgebra::Isometry3::from_parts(nalgebra::Translation3::from(p), q);
        Some(isometry_to_pose(&iso))
    }
}

/// Mean of poses (see [`PoseMean`]); `None` for no finite pose.
pub fn mean_pose<'a>(poses: impl IntoIterator<Item = &'a Vec6>) -> Option<Vec6> {
    let mut m = PoseMean::default();
    for p in poses {
        m.add(p);
    }
    m.mean()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn mean_of_identical_poses_is_the_pose_even_at_pi() {
        let p = Vec6::new(
            0.1,
            -0.2,
            0.3,
            std::f64::consts::PI - 1e-9,
            0.2,
            -std::f64::consts::PI + 1e-9,
        );
        let m = mean_pose([p, p, p].iter()).unwrap();
        let back = isometry_to_pose(&pose_to_isometry(&p));
        // Compare rotations, not angle values (±π wrap).
        let (a, b) = (pose_to_isometry(&m), pose_to_isometry(&back));
        assert!((a.rotation.angle_to(&b.rotation)) < 1e-9);
        assert!((m.fixed_rows::<3>(0) - p.fixed_rows::<3>(0)).norm() < 1e-15);
    }

    #[test]
    fn symmetric_scatter_averages_out() {
        let c = Vec6::new(0.0, 0.0, 0.1, 0.02, -0.01, 0.3);
        let d = 1e-4;
        let mut poses = Vec::new();
        for k in 3..6 {
            let mut a = c;
            a[k] += d;
            let mut b = c;
            b[k] -= d;
            poses.push(a);
            poses.push(b);
        }
        let m = mean_pose(poses.iter()).unwrap();
        // Second-order accurate: the error is O(d²).
        assert!((m - c).amax() < 10.0 * d * d, "{:?}", m - c);
    }
}

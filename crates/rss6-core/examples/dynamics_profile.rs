//! Calls the dynamics hot paths in a loop, for instruction-count profiling
//! (`valgrind --tool=callgrind target/release/examples/dynamics_profile`) independent of machine load.
#![allow(clippy::unwrap_used)]
use rss6_core::*;
use std::hint::black_box;

fn main() {
    let kp = KinematicParams::nominal();
    let dp = DynamicParams::nominal();
    let p = Vec6::new(0.012, -0.015, 0.128, 0.03, -0.04, 0.02);
    let pd = Vec6::new(0.1, -0.2, 0.05, 0.3, 0.1, -0.2);
    let pdd = Vec6::new(1.0, 0.5, -0.3, -2.0, 1.0, 0.4);
    let which = std::env::args().nth(1).unwrap_or_else(|| "id".into());
    let n: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    // "*_load": the same calls with a 2 kg offset load (`*_with_env`).
    let env = Environment::default().with_load(PlatformLoad::new(
        2.0,
        Vec3::new(0.05, 0.02, 0.03),
        Mat3::identity() * 2e-3,
    ));
    let s = ModelState {
        pose: p,
        pose_dot: pd,
    };
    let mut sink = 0.0;
    for _ in 0..n {
        sink += match which.as_str() {
            "geom" => {
                LegGeometry::at_pose(black_box(&kp), black_box(&p))
                    .unwrap()
                    .t[0][0]
            }
            "mm" => mass_matrix(black_box(&kp), &dp, black_box(&p)).unwrap()[(0, 0)],
            "fd" => forward_dynamics(black_box(&kp), &dp, black_box(&p), &pd, &pdd).unwrap()[0],
            "reg" => regressor(black_box(&kp), black_box(&p), &pd, &pdd).unwrap()[(0, 0)],
            "terms" => {
                dynamics_terms(black_box(&kp), &dp, black_box(&p), &pd)
                    .unwrap()
                    .m[(0, 0)]
            }
            "legs" => leg_jacobians(black_box(&kp), black_box(&p), &pd).unwrap()[0].j_a[(0, 0)],
            "rk4" => {
                rk4_step(black_box(&kp), &dp, black_box(&s), &pdd, 1e-3)
                    .unwrap()
                    .pose[0]
            }
            "id_load" => {
                inverse_dynamics_with_env(black_box(&kp), &dp, black_box(&p), &pd, &pdd, &env)
                    .unwrap()[0]
            }
            "fd_load" => {
                forward_dynamics_with_env(black_box(&kp), &dp, black_box(&p), &pd, &pdd, &env)
                    .unwrap()[0]
            }
            "mm_load" => {
                mass_matrix_with_env(black_box(&kp), &dp, black_box(&p), &env).unwrap()[(0, 0)]
            }
            "terms_load" => {
                dynamics_terms_with_env(black_box(&kp), &dp, black_box(&p), &pd, &env)
                    .unwrap()
                    .m[(0, 0)]
            }
            "rk4_load" => {
                rk4_step_with_env(black_box(&kp), &dp, black_box(&s), &pdd, 1e-3, &env)
                    .unwrap()
                    .pose[0]
            }
            _ => inverse_dynamics(black_box(&kp), &dp, black_box(&p), &pd, &pdd).unwrap()[0],
        };
    }
    println!("{which}: {sink}");
}

//! The usage example of docs/dynamics.md, kept compiling and true.
#![allow(clippy::unwrap_used)]
use rss6_core::*;

#[test]
fn docs_example_holds() -> Result<()> {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let pose = home_pose();
    let (pd, pdd) = (Vec6::zeros(), Vec6::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0));
    let tau = inverse_dynamics(&kp, &dp, &pose, &pd, &pdd)?; // N·m per joint
    let acc = forward_dynamics(&kp, &dp, &pose, &pd, &tau)?; // == pdd
    assert!((acc - pdd).amax() < 1e-10);
    let s1 = rk4_step(&kp, &dp, &ModelState { pose, pose_dot: pd }, &tau, 1e-3)?;
    // constant acceleration 1 m/s² upward for 1 ms
    assert!(
        (s1.pose[2] - (pose[2] + 0.5e-6)).abs() < 1e-10,
        "{}",
        s1.pose[2]
    );
    let xi = nalgebra::SVector::<f64, 64>::from_column_slice(&dp.to_vector());
    let gamma = regressor(&kp, &pose, &pd, &pdd)?; // gamma * xi == tau
    assert!((gamma * xi - tau).amax() < 1e-12 * tau.amax());
    // lifting costs more than holding
    let hold = inverse_dynamics(&kp, &dp, &pose, &pd, &Vec6::zeros())?;
    assert!(tau.iter().zip(hold.iter()).all(|(t, h)| t.abs() > h.abs()));
    Ok(())
}

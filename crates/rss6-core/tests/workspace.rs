//! The documented singularity-free box (module docs of `workspace.rs`, docs/kinematics.md).
use rss6_core::*;

#[test]
fn explore() {
    let kp = KinematicParams::nominal();
    for n in [3u32, 5, 7] {
        let r = scan_box(&kp, &PoseBox::documented(), n, &BoxLimits::documented()).unwrap();
        println!("{n}: {r:?} maxdeg {}", r.max_abs_theta.to_degrees());
    }
    let h = singularity_check(&kp, &home_pose()).unwrap();
    println!("{h:?}");
}

//! TEMPORARY stand-in for rss6_core::dynamics_terms until branch `dyn` is merged.
#![allow(missing_docs, unreachable_pub, dead_code)]
use rss6_core::{jacobian_ad, twist_jacobian, DynamicParams, KinematicParams, Mat6, Vec6};
pub struct DynamicsTerms {
    pub m: Mat6,
    pub c: Mat6,
    pub g: Vec6,
    pub f: Vec6,
    pub j_ad: Mat6,
    pub j_s: Mat6,
    pub j_theta: Mat6,
}
pub fn dynamics_terms(
    kp: &KinematicParams,
    _dp: &DynamicParams,
    pose: &Vec6,
    _pd: &Vec6,
) -> rss6_core::Result<DynamicsTerms> {
    let j_ad = jacobian_ad(kp, pose)?;
    let j_s = twist_jacobian(pose);
    Ok(DynamicsTerms {
        m: Mat6::identity(),
        c: Mat6::zeros(),
        g: Vec6::zeros(),
        f: Vec6::zeros(),
        j_ad,
        j_s,
        j_theta: j_ad * j_s,
    })
}

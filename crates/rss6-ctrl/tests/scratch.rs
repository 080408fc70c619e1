#![allow(clippy::unwrap_used, dead_code, clippy::needless_range_loop)]
mod common;
use common::*;
use rss6_core::*;
use rss6_ctrl::*;
fn late(s: &Stats) -> (f64, f64) {
    let v: Vec<_> = s.trace.iter().filter(|(t, _)| *t > 2.0).collect();
    let p = (v.iter().map(|(_, e)| e.fixed_rows::<3>(0).norm_squared()).sum::<f64>() / v.len() as f64).sqrt();
    let a = (v.iter().map(|(_, e)| e.fixed_rows::<3>(3).norm_squared()).sum::<f64>() / v.len() as f64).sqrt();
    (p, a)
}
#[test]
fn scratch() {
    let traj = Sinusoid::experiment1();
    let qps: Vec<f64> = std::env::var("QP").map(|s| s.split(',').map(|x| x.parse().unwrap()).collect()).unwrap_or(vec![0.1]);
    let qas: Vec<f64> = std::env::var("QA").map(|s| s.split(',').map(|x| x.parse().unwrap()).collect()).unwrap_or(vec![10.0]);
    let kps: Vec<f64> = std::env::var("KPA").map(|s| s.split(',').map(|x| x.parse().unwrap()).collect()).unwrap_or(vec![2.5]);
    let kpp: Vec<f64> = std::env::var("KPP").map(|s| s.split(',').map(|x| x.parse().unwrap()).collect()).unwrap_or(vec![250.0]);
    let lams: Vec<f64> = std::env::var("LAM").map(|s| s.split(',').map(|x| x.parse().unwrap()).collect()).unwrap_or(vec![6.0]);
    let secs: f64 = std::env::var("SECS").map(|s| s.parse().unwrap()).unwrap_or(10.0);
    let which = match std::env::var("W").as_deref() { Ok("kcsc") => Which::Kcsc, Ok("kjsc") => Which::Kjsc, _ => Which::Dsmc };
    for &qp in &qps { for &qa in &qas { for &ka in &kps { for &kpt in &kpp { for &lam in &lams {
        let nn = std::env::var("NONOISE").is_ok(); let kpt_true = if nn { KinematicParams::nominal() } else { KinematicParams::perturbed(&table_4_2_errors(42)) }; let cam = std::env::var("NOCAM").is_err(); let mut setup = Setup::new(kpt_true, Noise { camera: !nn && cam, potentiometer: !nn }, secs, 1);
        setup.config.kalman.q_jerk = Vec6::new(qp, qp, qp, qa, qa, qa);
        setup.dsmc.kp = Vec6::new(kpt, kpt, kpt, ka, ka, ka);
        setup.dsmc.ki = setup.dsmc.kp * 2.0;
        setup.dsmc.lambda = Vec6::repeat(lam);  if let Ok(k) = std::env::var("KI") { let k: f64 = k.parse().unwrap(); setup.dsmc.ki = setup.dsmc.kp * k; }
        let s = run_scheme(which, &traj, &setup);
        let (lp, la) = late(&s);
        let r = |a: &[f64;6], b: &[f64;6], i: usize| (a[i]/b[i]).sqrt();
        println!("qp={qp:e} qa={qa:e} kpa={ka} kpp={kpt} lam={lam}: pos {:.3} ang {:.3} | late pos {:.3} ang {:.3} | kf x {:.2}/{:.2} a {:.2}/{:.2} {:?}", s.pos_rmse()*1e3, s.ang_rmse()*1e3, lp*1e3, la*1e3, r(&s.est_sq,&s.cam_sq,0), r(&s.vel_err_sq,&s.vel_sq,0), r(&s.est_sq,&s.cam_sq,3), r(&s.vel_err_sq,&s.vel_sq,3), s.first_fault);
    }}}}}
}

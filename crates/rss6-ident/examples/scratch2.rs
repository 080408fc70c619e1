use rss6_core::*;
use rss6_ident::*;
fn ratio(kp: &KinematicParams, th: &Vec6) -> (f64, Vec6, f64) {
    let p = fk(kp, th, &home_pose(), &FkOptions::default()).unwrap().pose;
    let g = LegGeometry::from_pose_and_theta(kp, &p, th);
    let a1 = g.j_a1();
    let a2 = g.j_a2();
    let j = a2.try_inverse().unwrap() * Mat6::from_diagonal(&a1);
    (j.norm_squared().powi(3) / j.determinant().abs(), a1, a2.determinant())
}
fn main() {
    let kp = KinematicParams::nominal();
    println!("home {:?}", ratio(&kp, &Vec6::zeros()));
    for s in [0.3, 0.5, 0.55, 0.6] {
        let mut worst = (0.0, Vec6::zeros());
        for v in 0..64u32 {
            let th = Vec6::from_fn(|i, _| if v & (1 << i) != 0 { s } else { -s });
            let r = std::panic::catch_unwind(|| ratio(&kp, &th));
            match r { Ok((r, a1, d)) => { if r > worst.0 { worst = (r, a1) }; let _ = d; }, Err(_) => println!("fk fail at {v}") }
        }
        println!("s {s}: worst ratio {:e} a1 {:?}", worst.0, worst.1.as_slice());
    }
    for c in [1e4, 1e5, 1e6, 1e9, f64::INFINITY] {
        for margin in [1e-3, 1e-6] {
        let s = stroke_with(&kp, &StrokeOptions { homeomorphism_c: c, singular_margin: margin, ..Default::default() });
        println!("C {c:e} margin {margin:e}: stroke {:?}", s.map(|s| (s.0.to_degrees(), s.1.to_degrees())));
        }
    }
}

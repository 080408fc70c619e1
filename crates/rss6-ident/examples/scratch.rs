use rand::SeedableRng;
use rss6_ident::*;
use rss6_core::{KinematicParams, Vec6};
fn main() {
    let nominal = KinematicParams::nominal();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let truth = TrueRobot::draw(&nominal, &mut rng);
    let mut src = AnalyticRobot::new(truth, nominal, NoiseModel::default(), 7);
    let stroke = (-0.5, 0.5);
    let mut thetas = vec![Vec6::zeros()];
    thetas.extend(test_configurations(30, 99, stroke));
    let data = collect(&mut src, &thetas, 2.0).unwrap();
    let opts = CalibrationOptions::default();
    let t0 = std::time::Instant::now();
    let r = rpba(&data, &nominal, &opts).unwrap();
    println!("rpba {:?} iters {} rank {} cost {:?}", t0.elapsed(), r.iterations, r.rank, r.cost_history);
    println!("dropped {:?}", r.dropped);
    println!("sv tail {:?}", &r.singular_values[50..]);
    let e = relative_pose_errors(&r.params, &r.target_in_effector, &truth, &nominal, 100, 5, stroke).unwrap();
    println!("rpba rms {:?}", e.rms);
    let u = relative_pose_errors(&nominal, &NOMINAL_TARGET_IN_EFFECTOR.into(), &truth, &nominal, 100, 5, stroke).unwrap();
    println!("uncal rms {:?}", u.rms);
    let guess = perturb_external(&truth.sensor_in_base, &mut rng);
    let t0 = std::time::Instant::now();
    let ri = implicit(&data, &nominal, &guess, &opts).unwrap();
    println!("impl {:?} iters {} rank {} cost {:?}", t0.elapsed(), ri.iterations, ri.rank, ri.cost_history);
    let e = relative_pose_errors(&ri.params, &ri.target_in_effector, &truth, &nominal, 100, 5, stroke).unwrap();
    println!("impl rms {:?}", e.rms);
}

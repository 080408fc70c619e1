//! Hidden effects: deviations of the "real" robot from the analytic model, each off by default and
//! switched on by name with parameters (the raw material of the discrepancy workflow).
//!
//! An effect is a value implementing [`Effect`]; it edits an [`EffectSetup`], the small set of hooks the
//! simulator reads (gravity, payload, extra friction, camera latency, gear backlash, potentiometer
//! offset drift). To add one:
//! write a struct implementing [`Effect`], add a field to [`EffectSetup`] if no existing hook fits,
//! and register its constructor in [`REGISTRY`]. The simulator's outputs (readings, logs, `Debug`)
//! never mention effects; only [`crate::Truth`] lists them.
//!
//! | name | parameters (SI) | physics |
//! |---|---|---|
//! | `joint_friction` | `coulomb` (N·m), `viscous` (N·m·s/rad), optional `joint` (0–5, all if absent) | extra f_c sign(θ̇) + f_v θ̇ at the revolute joints |
//! | `backlash` | `width` (rad), optional `stiffness` (N·m/rad), `damping` (N·m·s/rad), `rotor_inertia` (kg·m²) | dead band between drive (potentiometer side) and wrench |
//! | `camera_latency` | `latency` (s) | extra delay of every CMM frame |
//! | `payload` | `mass` (kg), `x`, `y`, `z` (m, COM in ΣE), optional `inertia` (kg·m², about its COM) | load rigidly fixed to the platform |
//! | `base_tilt` | `roll`, `pitch` (rad) | the base is tilted: gravity = R_x(roll)·R_y(pitch)ᵀ·[0, 0, −9.81] in the base frame |
//! | `joint_offset_drift` | `rate` (rad/s), optional `joint` (0–5, all if absent) | the potentiometer offset drifts: Δθ_i(t) = Δθ_i + rate·t (eq. 4.2), t the simulated time since the robot was built (a reset does not rewind it); plant and twin alike |

use crate::error::{Result, SimError};
use rss6_core::{Environment, Mat3, PlatformLoad, Vec3, LEGS};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Debug;

/// Standard gravity magnitude (m/s²).
pub const G0: f64 = 9.81;

/// A load fixed to the platform: point-like mass with an isotropic inertia about its own COM.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Payload {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the end-effector frame ΣE (m).
    pub com: Vec3,
    /// Isotropic moment of inertia about its own centre of mass (kg·m²).
    pub inertia: f64,
}

impl Payload {
    /// The payload as the analytic model's load: mass, centre of mass in ΣE and the isotropic
    /// inertia as a 3 × 3 tensor about its centre of mass.
    pub fn as_load(&self) -> PlatformLoad {
        PlatformLoad::new(self.mass, self.com, Mat3::identity() * self.inertia)
    }
}

/// Gear backlash between the drive (motor rotor, where the potentiometer sits) and the wrench.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Backlash {
    /// Total width of the dead band (rad); the rotor moves ±width/2 without touching the wrench.
    pub width: f64,
    /// Gear mesh stiffness once in contact (N·m/rad).
    pub stiffness: f64,
    /// Gear mesh damping once in contact (N·m·s/rad).
    pub damping: f64,
    /// Rotor inertia reflected to the joint (kg·m²).
    pub rotor_inertia: f64,
}

/// The hooks effects can set. Defaults = no effect.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectSetup {
    /// Gravity in the base frame (m/s²), [0, 0, −9.81] unless tilted.
    pub gravity: Vec3,
    /// Load on the platform.
    pub payload: Option<Payload>,
    /// Extra Coulomb friction per joint (N·m), added to the true `DynamicParams`.
    pub extra_coulomb: [f64; LEGS],
    /// Extra viscous friction per joint (N·m·s/rad), added to the true `DynamicParams`.
    pub extra_viscous: [f64; LEGS],
    /// Extra camera latency (s), added to the configured one.
    pub extra_camera_latency: f64,
    /// Gear backlash, the same on every joint.
    pub backlash: Option<Backlash>,
    /// Drift rate of each potentiometer offset Δθ_i (rad/s).
    pub dtheta_drift: [f64; LEGS],
}

impl Default for EffectSetup {
    fn default() -> Self {
        EffectSetup {
            gravity: Vec3::new(0.0, 0.0, -G0),
            payload: None,
            extra_coulomb: [0.0; LEGS],
            extra_viscous: [0.0; LEGS],
            extra_camera_latency: 0.0,
            backlash: None,
            dtheta_drift: [0.0; LEGS],
        }
    }
}

impl EffectSetup {
    /// The environment the analytic model sees: this gravity and the payload (if any) as a
    /// [`PlatformLoad`] with its full mass, centre-of-mass offset and inertia.
    pub fn environment(&self) -> Environment {
        let env = Environment::with_gravity(self.gravity);
        match self.payload {
            Some(p) => env.with_load(p.as_load()),
            None => env,
        }
    }
}

/// A hidden effect.
pub trait Effect: Debug + Send + Sync {
    /// The registry name.
    fn name(&self) -> &'static str;
    /// Its parameters (for the truth record).
    fn params(&self) -> BTreeMap<String, f64>;
    /// Applies the effect to the simulator's hooks.
    fn apply(&self, setup: &mut EffectSetup);
}

/// An effect request: a registered name and its parameters (SI units). Serialisable, so a run's
/// effects can live in a TOML file next to the parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectSpec {
    /// Registry name, e.g. `"payload"`.
    pub name: String,
    /// Parameters by name.
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
}

impl EffectSpec {
    /// A spec from a name and `(parameter, value)` pairs.
    pub fn new(name: &str, params: &[(&str, f64)]) -> Self {
        EffectSpec {
            name: name.to_string(),
            params: params.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
        }
    }
}

/// Constructor of a registered effect.
pub type EffectConstructor = fn(&BTreeMap<String, f64>) -> Result<Box<dyn Effect>>;

/// The registry: name → constructor.
pub const REGISTRY: &[(&str, EffectConstructor)] = &[
    ("joint_friction", JointFriction::from_params),
    ("backlash", BacklashEffect::from_params),
    ("camera_latency", CameraLatency::from_params),
    ("payload", PayloadEffect::from_params),
    ("base_tilt", BaseTilt::from_params),
    ("joint_offset_drift", JointOffsetDrift::from_params),
];

/// Builds an effect from its spec. Errors: unknown name, missing/unknown/out-of-range parameter.
pub fn make_effect(spec: &EffectSpec) -> Result<Box<dyn Effect>> {
    for (name, ctor) in REGISTRY {
        if *name == spec.name {
            return ctor(&spec.params);
        }
    }
    Err(SimError::UnknownEffect {
        name: spec.name.clone(),
        known: REGISTRY
            .iter()
            .map(|(n, _)| *n)
            .collect::<Vec<_>>()
            .join(", "),
    })
}

/// Builds every effect and folds them into one [`EffectSetup`]. A name may appear only once.
pub fn build_effects(specs: &[EffectSpec]) -> Result<(Vec<Box<dyn Effect>>, EffectSetup)> {
    let mut setup = EffectSetup::default();
    let mut effects: Vec<Box<dyn Effect>> = Vec::with_capacity(specs.len());
    for spec in specs {
        if effects.iter().any(|e| e.name() == spec.name) {
            return Err(param_err(&spec.name, "effect given twice"));
        }
        let e = make_effect(spec)?;
        e.apply(&mut setup);
        effects.push(e);
    }
    Ok((effects, setup))
}

fn param_err(effect: &str, message: &str) -> SimError {
    SimError::EffectParameter {
        effect: effect.to_string(),
        message: message.to_string(),
    }
}

/// Reads parameters by name, rejecting unknown ones.
struct Params<'a> {
    effect: &'static str,
    map: &'a BTreeMap<String, f64>,
}

impl<'a> Params<'a> {
    fn new(effect: &'static str, map: &'a BTreeMap<String, f64>, known: &[&str]) -> Result<Self> {
        for (k, v) in map {
            if !known.contains(&k.as_str()) {
                return Err(param_err(
                    effect,
                    &format!("unknown parameter `{k}` (known: {})", known.join(", ")),
                ));
            }
            if !v.is_finite() {
                return Err(param_err(effect, &format!("parameter `{k}` is not finite")));
            }
        }
        Ok(Params { effect, map })
    }
    fn required(&self, k: &str) -> Result<f64> {
        self.map
            .get(k)
            .copied()
            .ok_or_else(|| param_err(self.effect, &format!("missing parameter `{k}`")))
    }
    fn optional(&self, k: &str, default: f64) -> f64 {
        self.map.get(k).copied().unwrap_or(default)
    }
    fn non_negative(&self, k: &str, v: f64) -> Result<f64> {
        if v < 0.0 {
            Err(param_err(
                self.effect,
                &format!("`{k}` must be >= 0, got {v}"),
            ))
        } else {
            Ok(v)
        }
    }
}

/// Extra Coulomb + viscous joint friction (eq. 3.48) on one or all joints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointFriction {
    /// f_c (N·m).
    pub coulomb: f64,
    /// f_v (N·m·s/rad).
    pub viscous: f64,
    /// The joint (0–5), or all when `None`.
    pub joint: Option<usize>,
}

impl JointFriction {
    fn from_params(m: &BTreeMap<String, f64>) -> Result<Box<dyn Effect>> {
        let p = Params::new("joint_friction", m, &["coulomb", "viscous", "joint"])?;
        let coulomb = p.non_negative("coulomb", p.optional("coulomb", 0.0))?;
        let viscous = p.non_negative("viscous", p.optional("viscous", 0.0))?;
        let joint = match m.get("joint") {
            None => None,
            Some(&j) if j >= 0.0 && j < LEGS as f64 && j.fract() == 0.0 => Some(j as usize),
            Some(j) => return Err(param_err("joint_friction", &format!("bad joint index {j}"))),
        };
        Ok(Box::new(JointFriction {
            coulomb,
            viscous,
            joint,
        }))
    }
}

impl Effect for JointFriction {
    fn name(&self) -> &'static str {
        "joint_friction"
    }
    fn params(&self) -> BTreeMap<String, f64> {
        let mut m = BTreeMap::from([
            ("coulomb".to_string(), self.coulomb),
            ("viscous".to_string(), self.viscous),
        ]);
        if let Some(j) = self.joint {
            m.insert("joint".to_string(), j as f64);
        }
        m
    }
    fn apply(&self, s: &mut EffectSetup) {
        for i in 0..LEGS {
            if self.joint.is_none_or(|j| j == i) {
                s.extra_coulomb[i] += self.coulomb;
                s.extra_viscous[i] += self.viscous;
            }
        }
    }
}

/// Gear backlash (see [`Backlash`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BacklashEffect(pub Backlash);

impl BacklashEffect {
    fn from_params(m: &BTreeMap<String, f64>) -> Result<Box<dyn Effect>> {
        let p = Params::new(
            "backlash",
            m,
            &["width", "stiffness", "damping", "rotor_inertia"],
        )?;
        let b = Backlash {
            width: p.non_negative("width", p.required("width")?)?,
            stiffness: p.non_negative("stiffness", p.optional("stiffness", 5000.0))?,
            damping: p.non_negative("damping", p.optional("damping", 4.0))?,
            rotor_inertia: p.non_negative("rotor_inertia", p.optional("rotor_inertia", 0.01))?,
        };
        if b.rotor_inertia <= 0.0 || b.stiffness <= 0.0 {
            return Err(param_err(
                "backlash",
                "stiffness and rotor_inertia must be > 0",
            ));
        }
        Ok(Box::new(BacklashEffect(b)))
    }
}

impl Effect for BacklashEffect {
    fn name(&self) -> &'static str {
        "backlash"
    }
    fn params(&self) -> BTreeMap<String, f64> {
        BTreeMap::from([
            ("width".to_string(), self.0.width),
            ("stiffness".to_string(), self.0.stiffness),
            ("damping".to_string(), self.0.damping),
            ("rotor_inertia".to_string(), self.0.rotor_inertia),
        ])
    }
    fn apply(&self, s: &mut EffectSetup) {
        s.backlash = Some(self.0);
    }
}

/// Extra camera latency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraLatency {
    /// Extra delay (s).
    pub latency: f64,
}

impl CameraLatency {
    fn from_params(m: &BTreeMap<String, f64>) -> Result<Box<dyn Effect>> {
        let p = Params::new("camera_latency", m, &["latency"])?;
        Ok(Box::new(CameraLatency {
            latency: p.non_negative("latency", p.required("latency")?)?,
        }))
    }
}

impl Effect for CameraLatency {
    fn name(&self) -> &'static str {
        "camera_latency"
    }
    fn params(&self) -> BTreeMap<String, f64> {
        BTreeMap::from([("latency".to_string(), self.latency)])
    }
    fn apply(&self, s: &mut EffectSetup) {
        s.extra_camera_latency += self.latency;
    }
}

/// A payload on the platform (see [`Payload`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PayloadEffect(pub Payload);

impl PayloadEffect {
    fn from_params(m: &BTreeMap<String, f64>) -> Result<Box<dyn Effect>> {
        let p = Params::new("payload", m, &["mass", "x", "y", "z", "inertia"])?;
        let mass = p.required("mass")?;
        if mass <= 0.0 {
            return Err(param_err("payload", "mass must be > 0"));
        }
        Ok(Box::new(PayloadEffect(Payload {
            mass,
            com: Vec3::new(
                p.optional("x", 0.0),
                p.optional("y", 0.0),
                p.optional("z", 0.0),
            ),
            inertia: p.non_negative("inertia", p.optional("inertia", 0.0))?,
        })))
    }
}

impl Effect for PayloadEffect {
    fn name(&self) -> &'static str {
        "payload"
    }
    fn params(&self) -> BTreeMap<String, f64> {
        BTreeMap::from([
            ("mass".to_string(), self.0.mass),
            ("x".to_string(), self.0.com[0]),
            ("y".to_string(), self.0.com[1]),
            ("z".to_string(), self.0.com[2]),
            ("inertia".to_string(), self.0.inertia),
        ])
    }
    fn apply(&self, s: &mut EffectSetup) {
        s.payload = Some(self.0);
    }
}

/// A tilted base: gravity no longer along −z of the base frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseTilt {
    /// Rotation of the base about the world x axis (rad).
    pub roll: f64,
    /// Rotation of the base about the world y axis (rad).
    pub pitch: f64,
}

impl BaseTilt {
    fn from_params(m: &BTreeMap<String, f64>) -> Result<Box<dyn Effect>> {
        let p = Params::new("base_tilt", m, &["roll", "pitch"])?;
        Ok(Box::new(BaseTilt {
            roll: p.optional("roll", 0.0),
            pitch: p.optional("pitch", 0.0),
        }))
    }

    /// Gravity in the tilted base frame: R_baseᵀ·[0, 0, −g] with R_base = R_x(roll)·R_y(pitch).
    pub fn gravity(&self) -> Vec3 {
        let r = rss6_core::rotation(self.roll, self.pitch, 0.0);
        r.transpose() * Vec3::new(0.0, 0.0, -G0)
    }
}

impl Effect for BaseTilt {
    fn name(&self) -> &'static str {
        "base_tilt"
    }
    fn params(&self) -> BTreeMap<String, f64> {
        BTreeMap::from([
            ("roll".to_string(), self.roll),
            ("pitch".to_string(), self.pitch),
        ])
    }
    fn apply(&self, s: &mut EffectSetup) {
        s.gravity = self.gravity();
    }
}

/// The potentiometer offset Δθ_i drifts linearly in time (temperature, wear): the reading of a joint
/// held still changes by −rate·t/η_i, and a drive that tracks the reading moves the joint by rate·t.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointOffsetDrift {
    /// dΔθ/dt (rad/s), either sign.
    pub rate: f64,
    /// The joint (0–5), or all when `None`.
    pub joint: Option<usize>,
}

impl JointOffsetDrift {
    fn from_params(m: &BTreeMap<String, f64>) -> Result<Box<dyn Effect>> {
        let p = Params::new("joint_offset_drift", m, &["rate", "joint"])?;
        let rate = p.required("rate")?;
        let joint = match m.get("joint") {
            None => None,
            Some(&j) if j >= 0.0 && j < LEGS as f64 && j.fract() == 0.0 => Some(j as usize),
            Some(j) => {
                return Err(param_err(
                    "joint_offset_drift",
                    &format!("bad joint index {j}"),
                ))
            }
        };
        Ok(Box::new(JointOffsetDrift { rate, joint }))
    }
}

impl Effect for JointOffsetDrift {
    fn name(&self) -> &'static str {
        "joint_offset_drift"
    }
    fn params(&self) -> BTreeMap<String, f64> {
        let mut m = BTreeMap::from([("rate".to_string(), self.rate)]);
        if let Some(j) = self.joint {
            m.insert("joint".to_string(), j as f64);
        }
        m
    }
    fn apply(&self, s: &mut EffectSetup) {
        for i in 0..LEGS {
            if self.joint.is_none_or(|j| j == i) {
                s.dtheta_drift[i] += self.rate;
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn unknown_names_and_parameters_are_rejected() {
        let e = make_effect(&EffectSpec::new("warp_drive", &[])).unwrap_err();
        assert!(e.to_string().contains("payload"), "{e}");
        let e = make_effect(&EffectSpec::new("payload", &[("mas", 1.0)])).unwrap_err();
        assert!(e.to_string().contains("unknown parameter `mas`"), "{e}");
        let e = make_effect(&EffectSpec::new("payload", &[("x", 0.1)])).unwrap_err();
        assert!(e.to_string().contains("missing parameter `mass`"), "{e}");
        let dup = [
            EffectSpec::new("base_tilt", &[]),
            EffectSpec::new("base_tilt", &[]),
        ];
        assert!(build_effects(&dup).is_err());
    }

    #[test]
    fn setup_defaults_are_no_effect_and_tilt_keeps_magnitude() {
        let (_, s) = build_effects(&[]).unwrap();
        assert_eq!(s, EffectSetup::default());
        let (_, s) = build_effects(&[EffectSpec::new("base_tilt", &[("roll", 0.1)])]).unwrap();
        assert!((s.gravity.norm() - G0).abs() < 1e-12);
        assert!(
            (s.gravity[1] - (-G0 * 0.1f64.sin())).abs() < 1e-12,
            "{:?}",
            s.gravity
        );
    }
}

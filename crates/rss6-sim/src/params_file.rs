//! Parameter files: TOML (serde) with the `to_dict` keys of docs/architecture.md, SI units. Unknown keys and
//! wrong shapes are errors ([`SimError::ParamFile`], naming the file and the parser's message).
//!
//! Kinematics: `base_joints` (6×3 B_i), `platform_joints` (6×3 A'_i in ΣE), `wrench_lengths`,
//! `link_lengths`, `theta0`, `eta`, `dtheta` (6 each). Dynamics: `platform = {mass, inertia[3]}`,
//! `wrenches = {mass[6], inertia[6][3]}`, `links` (same), `coulomb[6]`, `viscous[6]`. PID: `lp`, `li`,
//! `ld`.

use crate::error::{Result, SimError};
use rss6_core::{Body, DynamicParams, KinematicParams, Vec3, LEGS};
use rss6_ctrl::PidGains;
use serde::{de::DeserializeOwned, Deserialize, Deserializer, Serialize};

/// Deserialises a fixed-size array, rejecting too many elements as well as too few (serde's own
/// array impl ignores extra elements in some formats).
fn exact<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> std::result::Result<[T; N], D::Error> {
    let v: Vec<T> = Vec::deserialize(d)?;
    let n = v.len();
    v.try_into().map_err(|_| {
        serde::de::Error::invalid_length(n, &format!("an array of {N} elements").as_str())
    })
}

/// [`exact`] for N × 3 arrays of points.
fn exact_points<'de, D: Deserializer<'de>, const N: usize>(
    d: D,
) -> std::result::Result<[[f64; 3]; N], D::Error> {
    #[derive(Deserialize)]
    struct P(#[serde(deserialize_with = "exact")] [f64; 3]);
    let v: Vec<P> = Vec::deserialize(d)?;
    let n = v.len();
    let pts: Vec<[f64; 3]> = v.into_iter().map(|p| p.0).collect();
    pts.try_into().map_err(|_| {
        serde::de::Error::invalid_length(n, &format!("an array of {N} points").as_str())
    })
}
use std::path::Path;

/// Kinematic parameter file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KinematicParamsFile {
    /// B_i (m).
    #[serde(deserialize_with = "exact_points")]
    pub base_joints: [[f64; 3]; LEGS],
    /// A'_i in ΣE (m).
    #[serde(deserialize_with = "exact_points")]
    pub platform_joints: [[f64; 3]; LEGS],
    /// l_TB,i (m).
    #[serde(deserialize_with = "exact")]
    pub wrench_lengths: [f64; LEGS],
    /// l_AT,i (m).
    #[serde(deserialize_with = "exact")]
    pub link_lengths: [f64; LEGS],
    /// θ0_i (rad).
    #[serde(deserialize_with = "exact")]
    pub theta0: [f64; LEGS],
    /// η_i (rad/bit).
    #[serde(deserialize_with = "exact")]
    pub eta: [f64; LEGS],
    /// Δθ_i (rad).
    #[serde(deserialize_with = "exact")]
    pub dtheta: [f64; LEGS],
}

impl From<&KinematicParams> for KinematicParamsFile {
    fn from(k: &KinematicParams) -> Self {
        let v3 = |v: &[Vec3; LEGS]| v.map(|x| [x[0], x[1], x[2]]);
        KinematicParamsFile {
            base_joints: v3(&k.base_joints),
            platform_joints: v3(&k.platform_joints),
            wrench_lengths: k.wrench_lengths,
            link_lengths: k.link_lengths,
            theta0: k.theta0,
            eta: k.eta,
            dtheta: k.dtheta,
        }
    }
}

impl From<&KinematicParamsFile> for KinematicParams {
    fn from(f: &KinematicParamsFile) -> Self {
        KinematicParams {
            base_joints: f.base_joints.map(Vec3::from),
            platform_joints: f.platform_joints.map(Vec3::from),
            wrench_lengths: f.wrench_lengths,
            link_lengths: f.link_lengths,
            theta0: f.theta0,
            eta: f.eta,
            dtheta: f.dtheta,
        }
    }
}

/// The platform in a dynamic parameter file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyFile {
    /// Mass (kg).
    pub mass: f64,
    /// Principal moments (kg·m²).
    #[serde(deserialize_with = "exact")]
    pub inertia: [f64; 3],
}

/// Six bodies of one kind in a dynamic parameter file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodiesFile {
    /// Masses (kg).
    #[serde(deserialize_with = "exact")]
    pub mass: [f64; LEGS],
    /// Principal moments (kg·m²).
    #[serde(deserialize_with = "exact_points")]
    pub inertia: [[f64; 3]; LEGS],
}

/// Dynamic parameter file (Table 5.1 layout).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicParamsFile {
    /// The platform.
    pub platform: BodyFile,
    /// The wrenches.
    pub wrenches: BodiesFile,
    /// The links.
    pub links: BodiesFile,
    /// f_c,i (N·m).
    #[serde(deserialize_with = "exact")]
    pub coulomb: [f64; LEGS],
    /// f_v,i (N·m·s/rad).
    #[serde(deserialize_with = "exact")]
    pub viscous: [f64; LEGS],
}

impl From<&DynamicParams> for DynamicParamsFile {
    fn from(d: &DynamicParams) -> Self {
        let bodies = |b: &[Body; LEGS]| BodiesFile {
            mass: b.map(|x| x.mass),
            inertia: b.map(|x| [x.inertia[0], x.inertia[1], x.inertia[2]]),
        };
        let pi = d.platform.inertia;
        DynamicParamsFile {
            platform: BodyFile {
                mass: d.platform.mass,
                inertia: [pi[0], pi[1], pi[2]],
            },
            wrenches: bodies(&d.wrenches),
            links: bodies(&d.links),
            coulomb: d.coulomb,
            viscous: d.viscous,
        }
    }
}

impl From<&DynamicParamsFile> for DynamicParams {
    fn from(f: &DynamicParamsFile) -> Self {
        let bodies = |b: &BodiesFile| -> [Body; LEGS] {
            core::array::from_fn(|i| {
                Body::new(b.mass[i], b.inertia[i][0], b.inertia[i][1], b.inertia[i][2])
            })
        };
        let p = &f.platform;
        DynamicParams {
            platform: Body::new(p.mass, p.inertia[0], p.inertia[1], p.inertia[2]),
            wrenches: bodies(&f.wrenches),
            links: bodies(&f.links),
            coulomb: f.coulomb,
            viscous: f.viscous,
        }
    }
}

/// PID gains file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PidGainsFile {
    /// l_p (N·m/rad).
    pub lp: f64,
    /// l_i (N·m/(rad·s)).
    pub li: f64,
    /// l_d (N·m·s/rad).
    pub ld: f64,
}

fn write<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = toml::to_string(value).map_err(|e| SimError::ParamFile {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    std::fs::write(path, text).map_err(|source| SimError::Io {
        path: path.display().to_string(),
        source,
    })
}

fn read<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|source| SimError::Io {
        path: path.display().to_string(),
        source,
    })?;
    toml::from_str(&text).map_err(|e| SimError::ParamFile {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}

fn invalid(path: &Path, e: rss6_core::CoreError) -> SimError {
    SimError::ParamFile {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Writes kinematic parameters to a TOML file.
pub fn save_kinematic_params(path: &Path, kp: &KinematicParams) -> Result<()> {
    write(path, &KinematicParamsFile::from(kp))
}

/// Reads and validates kinematic parameters from a TOML file.
pub fn load_kinematic_params(path: &Path) -> Result<KinematicParams> {
    let kp = KinematicParams::from(&read::<KinematicParamsFile>(path)?);
    kp.validate().map_err(|e| invalid(path, e))?;
    Ok(kp)
}

/// Writes dynamic parameters to a TOML file.
pub fn save_dynamic_params(path: &Path, dp: &DynamicParams) -> Result<()> {
    write(path, &DynamicParamsFile::from(dp))
}

/// Reads and validates dynamic parameters from a TOML file.
pub fn load_dynamic_params(path: &Path) -> Result<DynamicParams> {
    let dp = DynamicParams::from(&read::<DynamicParamsFile>(path)?);
    dp.validate().map_err(|e| invalid(path, e))?;
    Ok(dp)
}

/// Writes PID gains to a TOML file.
pub fn save_pid_gains(path: &Path, g: &PidGains) -> Result<()> {
    write(
        path,
        &PidGainsFile {
            lp: g.lp,
            li: g.li,
            ld: g.ld,
        },
    )
}

/// Reads PID gains from a TOML file (finite, ≥ 0).
pub fn load_pid_gains(path: &Path) -> Result<PidGains> {
    let f: PidGainsFile = read(path)?;
    if ![f.lp, f.li, f.ld]
        .iter()
        .all(|g| g.is_finite() && *g >= 0.0)
    {
        return Err(SimError::ParamFile {
            path: path.display().to_string(),
            message: "PID gains must be finite and >= 0".into(),
        });
    }
    Ok(PidGains {
        lp: f.lp,
        li: f.li,
        ld: f.ld,
    })
}

/// The plant's truth record as a file (written only when asked for, see [`save_truth`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TruthFile {
    /// True kinematics.
    pub kinematics: KinematicParamsFile,
    /// True dynamics.
    pub dynamics: DynamicParamsFile,
    /// True PID gains.
    pub pid: PidGainsFile,
    /// ᴼχ_C (m, rad).
    #[serde(deserialize_with = "exact")]
    pub sensor_in_base: [f64; 6],
    /// ᴱχ_t (m, rad).
    #[serde(deserialize_with = "exact")]
    pub target_in_effector: [f64; 6],
    /// Hidden effects that were on.
    #[serde(default)]
    pub effects: Vec<crate::effects::EffectSpec>,
}

impl From<&crate::sim::Truth> for TruthFile {
    fn from(t: &crate::sim::Truth) -> Self {
        let six = |v: &rss6_core::Vec6| core::array::from_fn(|i| v[i]);
        TruthFile {
            kinematics: (&t.kinematics).into(),
            dynamics: (&t.dynamics).into(),
            pid: PidGainsFile {
                lp: t.pid.lp,
                li: t.pid.li,
                ld: t.pid.ld,
            },
            sensor_in_base: six(&t.sensor_in_base),
            target_in_effector: six(&t.target_in_effector),
            effects: t.effects.clone(),
        }
    }
}

impl From<&TruthFile> for crate::sim::Truth {
    fn from(f: &TruthFile) -> Self {
        crate::sim::Truth {
            kinematics: (&f.kinematics).into(),
            dynamics: (&f.dynamics).into(),
            pid: PidGains {
                lp: f.pid.lp,
                li: f.pid.li,
                ld: f.pid.ld,
            },
            sensor_in_base: f.sensor_in_base.into(),
            target_in_effector: f.target_in_effector.into(),
            effects: f.effects.clone(),
        }
    }
}

/// Writes the truth record of a run (kinematics, dynamics, PID, ᴼχ_C, ᴱχ_t, effects) to TOML.
pub fn save_truth(path: &Path, truth: &crate::sim::Truth) -> Result<()> {
    write(path, &TruthFile::from(truth))
}

/// Reads a truth record written by [`save_truth`].
pub fn load_truth(path: &Path) -> Result<crate::sim::Truth> {
    Ok((&read::<TruthFile>(path)?).into())
}

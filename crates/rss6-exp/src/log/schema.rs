//! Streams, schemas and message encodings of the log format.

use rss6_core::{isometry_to_pose, pose_to_isometry, Vec6};
use serde::{Deserialize, Serialize};

/// Pose streams (`foxglove.FrameTransform`): (name, parent frame, child frame).
pub const POSE_STREAMS: [(&str, &str, &str); 5] = [
    ("true_pose", "base", "effector_true"),
    ("camera_pose", "base", "effector_camera"),
    ("desired_pose", "base", "effector_desired"),
    ("estimate_pose", "base", "effector_estimate"),
    ("sensor_pose", "sensor", "target"),
];

/// Six-vector streams (`rss6.JointVector`): (name, unit).
pub const VECTOR_STREAMS: [(&str, &str); 4] = [
    ("theta_cmd", "rad"),
    ("theta", "rad"),
    ("kappa", "bit"),
    ("torque", "N*m"),
];

/// The kind of a stream name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamKind {
    /// A pose stream: index into [`POSE_STREAMS`].
    Pose(usize),
    /// A six-vector stream: index into [`VECTOR_STREAMS`].
    Vector(usize),
    /// The calibration dwell means.
    Dwell,
}

impl StreamKind {
    /// The kind of `name`, or `None` for an unknown stream.
    pub fn of(name: &str) -> Option<Self> {
        if name == "dwell" {
            return Some(StreamKind::Dwell);
        }
        if let Some(i) = POSE_STREAMS.iter().position(|(n, _, _)| *n == name) {
            return Some(StreamKind::Pose(i));
        }
        VECTOR_STREAMS
            .iter()
            .position(|(n, _)| *n == name)
            .map(StreamKind::Vector)
    }
}

pub(crate) const FRAME_TRANSFORM_SCHEMA: &str = r#"{"title":"foxglove.FrameTransform","description":"A transform between two reference frames in 3D space","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"parent_frame_id":{"type":"string"},"child_frame_id":{"type":"string"},"translation":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}},"rotation":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},"w":{"type":"number"}}}}}"#;

pub(crate) const VECTOR_SCHEMA: &str = r#"{"title":"rss6.JointVector","description":"One value per leg (1..6) at a time stamp","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"unit":{"type":"string"},"values":{"type":"array","items":{"type":"number"},"minItems":6,"maxItems":6}}}"#;

pub(crate) const DWELL_SCHEMA: &str = r#"{"title":"rss6.Dwell","description":"Means over one calibration dwell at rest","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"index":{"type":"integer"},"window":{"type":"array","items":{"type":"number"},"description":"first and last tick time (s)"},"theta_cmd":{"type":"array","items":{"type":"number"},"description":"rad, drive convention"},"kappa":{"type":"array","items":{"type":"number"},"description":"mean potentiometer readings (bit)"},"sensor_pose":{"type":["array","null"],"items":{"type":"number"},"description":"mean target pose in the sensor frame [x,y,z,alpha,beta,gamma] (m, rad)"},"kappa_samples":{"type":"integer"},"camera_frames":{"type":"integer"},"kappa_std":{"type":["array","null"],"items":{"type":"number"},"description":"sample standard deviation of each potentiometer over the dwell (bit)"},"sensor_pose_std":{"type":["array","null"],"items":{"type":"number"},"description":"sample standard deviation of each sensor pose component over the dwell (m, rad)"},"sensor_pose_cov":{"type":["array","null"],"items":{"type":"array","items":{"type":"number"}},"description":"sample covariance (6 x 6) of one frame's sensor pose components over the dwell (m^2, m rad, rad^2)"},"fault":{"type":["object","null"],"description":"the collection check the configuration failed: kind unreached (joint, error_bits, tolerance_bits) or moving (channel, scatter, tolerance); null if it passed or was not checked"}}}"#;

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub(crate) struct Stamp {
    pub(crate) sec: u64,
    pub(crate) nsec: u64,
}

impl Stamp {
    pub(crate) fn from_ns(ns: u64) -> Self {
        Stamp {
            sec: ns / 1_000_000_000,
            nsec: ns % 1_000_000_000,
        }
    }
    pub(crate) fn ns(&self) -> u64 {
        self.sec
            .saturating_mul(1_000_000_000)
            .saturating_add(self.nsec)
    }
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub(crate) struct Xyz {
    pub(crate) x: f64,
    pub(crate) y: f64,
    pub(crate) z: f64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub(crate) struct Quat {
    pub(crate) x: f64,
    pub(crate) y: f64,
    pub(crate) z: f64,
    pub(crate) w: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct FrameTransform<'a> {
    pub(crate) timestamp: Stamp,
    pub(crate) parent_frame_id: &'a str,
    pub(crate) child_frame_id: &'a str,
    pub(crate) translation: Xyz,
    pub(crate) rotation: Quat,
}

impl FrameTransform<'_> {
    pub(crate) fn pose(&self) -> Vec6 {
        let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            self.rotation.w,
            self.rotation.x,
            self.rotation.y,
            self.rotation.z,
        ));
        let tr =
            nalgebra::Translation3::new(self.translation.x, self.translation.y, self.translation.z);
        isometry_to_pose(&nalgebra::Isometry3::from_parts(tr, q))
    }
}

pub(crate) fn frame_transform<'a>(
    ns: u64,
    parent: &'a str,
    child: &'a str,
    pose: &Vec6,
) -> FrameTransform<'a> {
    let iso = pose_to_isometry(pose);
    let q = iso.rotation.quaternion();
    let t = iso.translation.vector;
    FrameTransform {
        timestamp: Stamp::from_ns(ns),
        parent_frame_id: parent,
        child_frame_id: child,
        translation: Xyz {
            x: t[0],
            y: t[1],
            z: t[2],
        },
        rotation: Quat {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct JointVector<'a> {
    pub(crate) timestamp: Stamp,
    #[serde(borrow)]
    pub(crate) unit: std::borrow::Cow<'a, str>,
    pub(crate) values: [f64; 6],
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct DwellMessage {
    pub(crate) timestamp: Stamp,
    pub(crate) index: usize,
    pub(crate) window: [f64; 2],
    pub(crate) theta_cmd: [f64; 6],
    pub(crate) kappa: [f64; 6],
    pub(crate) sensor_pose: Option<[f64; 6]>,
    pub(crate) kappa_samples: u32,
    pub(crate) camera_frames: u32,
    #[serde(default)]
    pub(crate) kappa_std: Option<[f64; 6]>,
    #[serde(default)]
    pub(crate) sensor_pose_std: Option<[f64; 6]>,
    #[serde(default)]
    pub(crate) sensor_pose_cov: Option<[[f64; 6]; 6]>,
    #[serde(default)]
    pub(crate) fault: Option<crate::dwell::DwellFault>,
}

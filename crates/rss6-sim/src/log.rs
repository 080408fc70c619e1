//! MCAP run logs. One file per run; platform poses as `foxglove.FrameTransform` (jsonschema + json)
//! so Foxglove shows them; joint readings, commands and torques on their own JSON channels.
//!
//! Messages are written into compressed chunks. A run that is killed (no `finish`) leaves every
//! finished chunk on disk: [`read_log`] returns the messages up to the last complete chunk and
//! says that the file is incomplete.
//!
//! Topics ([`TOPICS`]): `/plant/true_pose` (ΣE in the base frame, the simulator's truth),
//! `/cmm/pose` (ᶜχ_t, target in the sensor frame, only when a frame arrived), `/joints/readings`
//! (κ, bit), `/joints/commands` (θ_cmd, rad, nominal convention), `/joints/torques` (τ, N·m).
//! Nothing in a log says which hidden effects are on.

use crate::error::{Result, SimError};
use mcap::records::MessageHeader;
use mcap::{WriteOptions, Writer};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use rss6_core::{isometry_to_pose, pose_to_isometry, Vec6};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

/// Topic names, in the order true pose, camera pose, readings, commands, torques.
pub const TOPICS: [&str; 5] = [
    "/plant/true_pose",
    "/cmm/pose",
    "/joints/readings",
    "/joints/commands",
    "/joints/torques",
];

const FRAME_TRANSFORM_SCHEMA: &str = r#"{
  "title": "foxglove.FrameTransform",
  "description": "A transform between two reference frames in 3D space",
  "type": "object",
  "properties": {
    "timestamp": {"type": "object", "properties": {"sec": {"type": "integer", "minimum": 0}, "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}}},
    "parent_frame_id": {"type": "string"},
    "child_frame_id": {"type": "string"},
    "translation": {"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}},
    "rotation": {"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}, "w": {"type": "number"}}}
  }
}"#;

fn joint_schema(title: &str, field: &str, unit: &str) -> String {
    json!({
        "title": title,
        "type": "object",
        "properties": {
            "time": {"type": "number", "description": "simulated time (s)"},
            field: {"type": "array", "items": {"type": "number"}, "minItems": 6, "maxItems": 6,
                    "description": unit}
        }
    })
    .to_string()
}

/// Everything logged at one joint-loop tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TickRecord {
    /// Simulated time (s).
    pub time: f64,
    /// Joint command θ_cmd (rad, nominal convention).
    pub theta_cmd: Vec6,
    /// Potentiometer readings κ (bit).
    pub kappa: Vec6,
    /// PID torques τ (N·m).
    pub torque: Vec6,
    /// True platform pose χ (m, rad).
    pub true_pose: Vec6,
    /// ᶜχ_t when a CMM frame arrived on this tick.
    pub camera: Option<Vec6>,
}

/// Writes a run to an MCAP file.
pub struct McapLogger<W: Write + Seek> {
    writer: Writer<W>,
    channels: [u16; 5],
    sequence: u32,
}

impl<W: Write + Seek> std::fmt::Debug for McapLogger<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("McapLogger")
            .field("messages", &self.sequence)
            .finish_non_exhaustive()
    }
}

impl McapLogger<BufWriter<File>> {
    /// Creates (truncates) `path` and writes the header, schemas and channels.
    pub fn create(path: &Path) -> Result<Self> {
        let file = File::create(path).map_err(|source| SimError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::new(BufWriter::new(file), DEFAULT_CHUNK_SIZE)
    }
}

/// Default uncompressed chunk size (bytes): ≈ 0.2 s of a 1 kHz run, bounding what a crash loses.
pub const DEFAULT_CHUNK_SIZE: u64 = 64 * 1024;

impl<W: Write + Seek> McapLogger<W> {
    /// A logger on any seekable writer with the given chunk size (bytes).
    pub fn new(w: W, chunk_size: u64) -> Result<Self> {
        let mut writer = WriteOptions::new()
            .chunk_size(Some(chunk_size))
            .profile("")
            .library("rss6-sim")
            .create(w)?;
        let ft = writer.add_schema(
            "foxglove.FrameTransform",
            "jsonschema",
            FRAME_TRANSFORM_SCHEMA.as_bytes(),
        )?;
        let s_read = writer.add_schema(
            "rss6.JointReadings",
            "jsonschema",
            joint_schema(
                "rss6.JointReadings",
                "kappa",
                "potentiometer readings (bit)",
            )
            .as_bytes(),
        )?;
        let s_cmd = writer.add_schema(
            "rss6.JointCommands",
            "jsonschema",
            joint_schema("rss6.JointCommands", "theta_cmd", "joint commands (rad)").as_bytes(),
        )?;
        let s_tau = writer.add_schema(
            "rss6.JointTorques",
            "jsonschema",
            joint_schema("rss6.JointTorques", "tau", "joint torques (N m)").as_bytes(),
        )?;
        let meta = BTreeMap::new();
        let channels = [
            writer.add_channel(ft, TOPICS[0], "json", &meta)?,
            writer.add_channel(ft, TOPICS[1], "json", &meta)?,
            writer.add_channel(s_read, TOPICS[2], "json", &meta)?,
            writer.add_channel(s_cmd, TOPICS[3], "json", &meta)?,
            writer.add_channel(s_tau, TOPICS[4], "json", &meta)?,
        ];
        Ok(McapLogger {
            writer,
            channels,
            sequence: 0,
        })
    }

    fn put(&mut self, k: usize, time: f64, data: &serde_json::Value) -> Result<()> {
        let log_time = (time.max(0.0) * 1e9).round() as u64;
        let header = MessageHeader {
            channel_id: self.channels[k],
            sequence: self.sequence,
            log_time,
            publish_time: log_time,
        };
        self.sequence = self.sequence.wrapping_add(1);
        let bytes = serde_json::to_vec(data).map_err(|e| SimError::Mcap(e.to_string()))?;
        self.writer.write_to_known_channel(&header, &bytes)?;
        Ok(())
    }

    /// Logs one tick.
    pub fn log(&mut self, r: &TickRecord) -> Result<()> {
        self.put(
            0,
            r.time,
            &frame_transform(r.time, "base", "effector", &r.true_pose),
        )?;
        if let Some(c) = r.camera {
            self.put(1, r.time, &frame_transform(r.time, "sensor", "target", &c))?;
        }
        self.put(
            2,
            r.time,
            &json!({"time": r.time, "kappa": r.kappa.as_slice()}),
        )?;
        self.put(
            3,
            r.time,
            &json!({"time": r.time, "theta_cmd": r.theta_cmd.as_slice()}),
        )?;
        self.put(
            4,
            r.time,
            &json!({"time": r.time, "tau": r.torque.as_slice()}),
        )?;
        Ok(())
    }

    /// Writes the summary and footer and flushes. Without it the file still holds every finished
    /// chunk.
    pub fn finish(mut self) -> Result<()> {
        self.writer.finish()?;
        Ok(())
    }

    /// Flushes finished chunks to the underlying writer (what a crash would leave behind).
    pub fn flush(&mut self) -> Result<()> {
        self.writer.flush()?;
        Ok(())
    }
}

fn frame_transform(time: f64, parent: &str, child: &str, pose: &Vec6) -> serde_json::Value {
    let iso = pose_to_isometry(pose);
    let q = iso.rotation.quaternion();
    let t = iso.translation.vector;
    let ns = (time.max(0.0) * 1e9).round() as u64;
    json!({
        "timestamp": {"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000},
        "parent_frame_id": parent,
        "child_frame_id": child,
        "translation": {"x": t[0], "y": t[1], "z": t[2]},
        "rotation": {"x": q.i, "y": q.j, "z": q.k, "w": q.w},
    })
}

#[derive(Deserialize, Serialize)]
struct Xyz {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Deserialize, Serialize)]
struct Quat {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Deserialize)]
struct Ft {
    translation: Xyz,
    rotation: Quat,
}

#[derive(Deserialize)]
struct Joint {
    time: f64,
    #[serde(alias = "kappa", alias = "theta_cmd", alias = "tau")]
    values: [f64; 6],
}

/// A run read back from MCAP: one series per topic, as (time s, value) pairs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunLog {
    /// True platform poses χ.
    pub true_pose: Vec<(f64, Vec6)>,
    /// CMM poses ᶜχ_t.
    pub camera: Vec<(f64, Vec6)>,
    /// Potentiometer readings κ (bit).
    pub readings: Vec<(f64, Vec6)>,
    /// Joint commands θ_cmd (rad).
    pub commands: Vec<(f64, Vec6)>,
    /// Joint torques τ (N·m).
    pub torques: Vec<(f64, Vec6)>,
    /// False if the file ended early (killed run, truncated copy): everything up to the last
    /// complete chunk was read.
    pub complete: bool,
}

fn parse_err(topic: &str, e: serde_json::Error) -> SimError {
    SimError::Mcap(format!("bad message on {topic}: {e}"))
}

/// Reads an MCAP run log, tolerating a missing end (see [`RunLog::complete`]).
pub fn read_log(path: &Path) -> Result<RunLog> {
    let buf = std::fs::read(path).map_err(|source| SimError::Io {
        path: path.display().to_string(),
        source,
    })?;
    read_log_bytes(&buf)
}

/// [`read_log`] on bytes in memory.
pub fn read_log_bytes(buf: &[u8]) -> Result<RunLog> {
    let mut log = RunLog::default();
    let stream =
        mcap::MessageStream::new_with_options(buf, mcap::read::Options::IgnoreEndMagic.into())?;
    let mut ended_cleanly = true;
    for m in stream {
        let m = match m {
            Ok(m) => m,
            Err(_) => {
                ended_cleanly = false;
                break;
            }
        };
        let topic = m.channel.topic.as_str();
        let t = m.log_time as f64 * 1e-9;
        match topic {
            "/plant/true_pose" | "/cmm/pose" => {
                let ft: Ft = serde_json::from_slice(&m.data).map_err(|e| parse_err(topic, e))?;
                let q = UnitQuaternion::from_quaternion(Quaternion::new(
                    ft.rotation.w,
                    ft.rotation.x,
                    ft.rotation.y,
                    ft.rotation.z,
                ));
                let tr = Translation3::new(ft.translation.x, ft.translation.y, ft.translation.z);
                let pose = isometry_to_pose(&Isometry3::from_parts(tr, q));
                if topic == TOPICS[0] {
                    log.true_pose.push((t, pose));
                } else {
                    log.camera.push((t, pose));
                }
            }
            "/joints/readings" | "/joints/commands" | "/joints/torques" => {
                let j: Joint = serde_json::from_slice(&m.data).map_err(|e| parse_err(topic, e))?;
                let v = (j.time, Vec6::from(j.values));
                match topic {
                    "/joints/readings" => log.readings.push(v),
                    "/joints/commands" => log.commands.push(v),
                    _ => log.torques.push(v),
                }
            }
            _ => {}
        }
    }
    log.complete = ended_cleanly && buf.ends_with(mcap::MAGIC) && mcap::read::footer(buf).is_ok();
    Ok(log)
}

//! The chunked, crash-safe writer and the observer that logs a run with it.

use super::schema::{
    frame_transform, DwellMessage, JointVector, Stamp, StreamKind, DWELL_SCHEMA,
    FRAME_TRANSFORM_SCHEMA, POSE_STREAMS, VECTOR_SCHEMA, VECTOR_STREAMS,
};
use crate::dwell::ConfigurationData;
use crate::error::{ExpError, Result};
use crate::observer::{Flow, Observer, Progress};
use crate::record::Record;
use mcap::records::{MessageHeader, Metadata};
use mcap::{WriteOptions, Writer};
use rss6_core::Vec6;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Default uncompressed chunk size (bytes). Runners also finish the chunk at every progress segment.
pub const DEFAULT_CHUNK_SIZE: u64 = 256 * 1024;

/// Writes one run to an MCAP file as it goes. Every finished chunk is on its way to the disk; a
/// process killed mid-run leaves a file readable up to its last finished chunk ([`super::read_log`]).
pub struct LogWriter {
    writer: Option<Writer<BufWriter<File>>>,
    path: PathBuf,
    schemas: [u16; 3],
    channels: BTreeMap<&'static str, u16>,
    sequence: u32,
    messages: u64,
    t0: f64,
    last_ns: u64,
    buf: Vec<u8>,
}

impl std::fmt::Debug for LogWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LogWriter")
            .field("path", &self.path)
            .field("messages", &self.messages)
            .finish_non_exhaustive()
    }
}

fn io_err(path: &Path, source: std::io::Error) -> ExpError {
    ExpError::Io {
        path: path.display().to_string(),
        source,
    }
}

impl LogWriter {
    /// Creates (truncates) `path` with ZSTD chunks of about `chunk_size` bytes (uncompressed), chunk
    /// and data CRCs, and writes the header and schemas; `t0` (s) is added to every time stamp.
    pub fn create(path: &Path, chunk_size: u64, t0: f64) -> Result<Self> {
        if chunk_size == 0 || !t0.is_finite() {
            return Err(ExpError::InvalidInput(format!(
                "chunk_size must be > 0 bytes and t0 finite, got {chunk_size} and {t0}"
            )));
        }
        let file = File::create(path).map_err(|e| io_err(path, e))?;
        let mut writer = WriteOptions::new()
            .chunk_size(Some(chunk_size))
            .profile("")
            .library("rss6")
            .create(BufWriter::new(file))?;
        let schemas = [
            writer.add_schema(
                "foxglove.FrameTransform",
                "jsonschema",
                FRAME_TRANSFORM_SCHEMA.as_bytes(),
            )?,
            writer.add_schema("rss6.JointVector", "jsonschema", VECTOR_SCHEMA.as_bytes())?,
            writer.add_schema("rss6.Dwell", "jsonschema", DWELL_SCHEMA.as_bytes())?,
        ];
        let mut w = LogWriter {
            writer: Some(writer),
            path: path.to_path_buf(),
            schemas,
            channels: BTreeMap::new(),
            sequence: 0,
            messages: 0,
            t0,
            last_ns: 0,
            buf: Vec::with_capacity(256),
        };
        w.flush(false)?;
        Ok(w)
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Messages written so far.
    pub fn messages(&self) -> u64 {
        self.messages
    }

    /// `true` once [`Self::finish`] ran.
    pub fn is_finished(&self) -> bool {
        self.writer.is_none()
    }

    fn writer(&mut self) -> Result<&mut Writer<BufWriter<File>>> {
        match self.writer.as_mut() {
            Some(w) => Ok(w),
            None => Err(ExpError::Mcap(format!(
                "{}: the log is already finished",
                self.path.display()
            ))),
        }
    }

    fn channel(&mut self, name: &str) -> Result<(u16, StreamKind)> {
        let kind = StreamKind::of(name).ok_or_else(|| {
            let known: Vec<&str> = POSE_STREAMS
                .iter()
                .map(|s| s.0)
                .chain(VECTOR_STREAMS.iter().map(|s| s.0))
                .chain(["dwell"])
                .collect();
            ExpError::InvalidInput(format!(
                "unknown stream '{name}' (known: {})",
                known.join(", ")
            ))
        })?;
        let key: &'static str = match kind {
            StreamKind::Pose(i) => POSE_STREAMS[i].0,
            StreamKind::Vector(i) => VECTOR_STREAMS[i].0,
            StreamKind::Dwell => "dwell",
        };
        if let Some(&id) = self.channels.get(key) {
            return Ok((id, kind));
        }
        let schema = match kind {
            StreamKind::Pose(_) => self.schemas[0],
            StreamKind::Vector(_) => self.schemas[1],
            StreamKind::Dwell => self.schemas[2],
        };
        let topic = format!("/rss6/{key}");
        let id = self
            .writer()?
            .add_channel(schema, &topic, "json", &BTreeMap::new())?;
        self.channels.insert(key, id);
        Ok((id, kind))
    }

    fn stamp(&self, t: f64) -> Result<u64> {
        let s = self.t0 + t;
        if !(s.is_finite() && s >= 0.0) {
            return Err(ExpError::InvalidInput(format!(
                "log times must be finite and >= 0 s, got {s}"
            )));
        }
        Ok((s * 1e9).round() as u64)
    }

    fn put(&mut self, channel: u16, ns: u64) -> Result<()> {
        let header = MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: ns,
            publish_time: ns,
        };
        self.sequence = self.sequence.wrapping_add(1);
        let data = std::mem::take(&mut self.buf);
        let r = self.writer()?.write_to_known_channel(&header, &data);
        self.buf = data;
        r?;
        self.messages += 1;
        self.last_ns = self.last_ns.max(ns);
        Ok(())
    }

    /// Appends one sample of stream `name` at time `t` (s): a pose [x, y, z, α, β, γ] (m, rad) or a
    /// six-vector, by the stream's kind.
    pub fn write(&mut self, name: &str, t: f64, value: &Vec6) -> Result<()> {
        let (ch, kind) = self.channel(name)?;
        let ns = self.stamp(t)?;
        self.buf.clear();
        let enc = match kind {
            StreamKind::Pose(i) => {
                let (_, parent, child) = POSE_STREAMS[i];
                serde_json::to_writer(&mut self.buf, &frame_transform(ns, parent, child, value))
            }
            StreamKind::Vector(i) => serde_json::to_writer(
                &mut self.buf,
                &JointVector {
                    timestamp: Stamp::from_ns(ns),
                    unit: VECTOR_STREAMS[i].1.into(),
                    values: (*value).into(),
                },
            ),
            StreamKind::Dwell => {
                return Err(ExpError::InvalidInput(
                    "the dwell stream is written by write_dwell".into(),
                ))
            }
        };
        enc.map_err(|e| ExpError::Mcap(e.to_string()))?;
        self.put(ch, ns)
    }

    /// Appends the means of a finished calibration dwell.
    pub fn write_dwell(
        &mut self,
        index: usize,
        window: [f64; 2],
        data: &ConfigurationData,
    ) -> Result<()> {
        let (ch, _) = self.channel("dwell")?;
        let ns = self.stamp(window[1].max(0.0))?;
        self.buf.clear();
        serde_json::to_writer(
            &mut self.buf,
            &DwellMessage {
                timestamp: Stamp::from_ns(ns),
                index,
                window,
                theta_cmd: data.theta_cmd,
                kappa: data.kappa,
                sensor_pose: data.sensor_pose,
                kappa_samples: data.kappa_samples,
                camera_frames: data.camera_frames,
                kappa_std: data.kappa_std,
                sensor_pose_std: data.sensor_pose_std,
                sensor_pose_cov: data.sensor_pose_cov,
                fault: data.fault.clone(),
            },
        )
        .map_err(|e| ExpError::Mcap(e.to_string()))?;
        self.put(ch, ns)
    }

    /// Appends a metadata record `name` (string pairs) after finishing the chunk in progress, so it
    /// follows every sample written before it; then flushes.
    pub fn add_metadata(&mut self, name: &str, pairs: &BTreeMap<String, String>) -> Result<()> {
        let md = Metadata {
            name: name.to_string(),
            metadata: pairs.clone(),
        };
        self.writer()?.write_metadata(&md)?;
        self.flush(false)
    }

    /// Finishes the chunk in progress and hands everything to the OS; with `sync`, also to the disk.
    pub fn flush(&mut self, sync: bool) -> Result<()> {
        let path = self.path.clone();
        let w = self.writer()?;
        w.flush()?;
        if sync {
            // The writer owns the file: reopen to sync (same inode).
            File::open(&path)
                .and_then(|f| f.sync_all())
                .map_err(|e| io_err(&path, e))?;
        }
        Ok(())
    }

    /// Writes the summary and footer. With `status`, a metadata record `rss6 {status: …}` first.
    pub fn finish(&mut self, status: Option<&str>) -> Result<()> {
        if let Some(s) = status {
            let mut m = BTreeMap::new();
            m.insert("status".to_string(), s.to_string());
            self.add_metadata("rss6", &m)?;
        }
        let mut w = match self.writer.take() {
            Some(w) => w,
            None => return Ok(()),
        };
        w.finish()?;
        Ok(())
    }
}

/// An [`Observer`] that logs every record of a run with a [`LogWriter`] and finishes a chunk at
/// every progress segment. A write error stops the run; [`LogObserver::error`] holds it.
#[derive(Debug)]
pub struct LogObserver {
    /// The writer.
    pub writer: LogWriter,
    error: Option<ExpError>,
}

impl LogObserver {
    /// Logs to `writer`.
    pub fn new(writer: LogWriter) -> Self {
        LogObserver {
            writer,
            error: None,
        }
    }

    /// The first write error, if any (the run was stopped by it).
    pub fn error(&self) -> Option<&ExpError> {
        self.error.as_ref()
    }

    /// Takes the first write error.
    pub fn take_error(&mut self) -> Option<ExpError> {
        self.error.take()
    }

    fn log(&mut self, r: &Record) -> Result<()> {
        let w = &mut self.writer;
        let t = r.t;
        if let Some(s) = &r.truth {
            w.write("true_pose", t, &s.pose)?;
            w.write("theta", t, &s.theta)?;
        }
        if let Some(reference) = &r.reference {
            w.write("desired_pose", t, &reference.pose)?;
        }
        if let Some(z) = &r.sensor_pose {
            w.write("sensor_pose", t, z)?;
        }
        if let Some(c) = &r.camera {
            w.write("camera_pose", t, c)?;
        }
        if let Some(e) = &r.estimate {
            w.write("estimate_pose", t, &e.pose)?;
        }
        w.write("kappa", t, &r.kappa)?;
        w.write("theta_cmd", t, &r.theta_cmd)?;
        if let Some(tau) = &r.torque {
            w.write("torque", t, tau)?;
        }
        Ok(())
    }

    fn check(&mut self, r: Result<()>) -> Flow {
        match r {
            Ok(()) => Flow::Continue,
            Err(e) => {
                if self.error.is_none() {
                    self.error = Some(e);
                }
                Flow::Stop
            }
        }
    }
}

impl Observer for LogObserver {
    fn record(&mut self, record: &Record) -> Flow {
        if self.error.is_some() {
            return Flow::Stop;
        }
        let r = self.log(record);
        self.check(r)
    }

    fn progress(&mut self, _progress: &Progress) -> Flow {
        if self.error.is_some() {
            return Flow::Stop;
        }
        let r = self.writer.flush(false);
        self.check(r)
    }

    fn dwell(&mut self, index: usize, window: [f64; 2], data: &ConfigurationData) -> Flow {
        if self.error.is_some() {
            return Flow::Stop;
        }
        let r = self
            .writer
            .write_dwell(index, window, data)
            .and_then(|()| self.writer.flush(false));
        self.check(r)
    }
}

//! Reading a log back: the framing is checked first (so a file cut mid-run is told apart from a
//! damaged one), then every whole record is decoded.

use super::schema::{DwellMessage, FrameTransform, JointVector, StreamKind};
use crate::dwell::ConfigurationData;
use mcap::records::Record as McapRecord;
use rss6_core::Vec6;
use std::collections::BTreeMap;
use std::path::Path;

/// A finished calibration dwell read from a log.
#[derive(Debug, Clone, PartialEq)]
pub struct LogDwell {
    /// Configuration index (order of visit; 0 = initial).
    pub index: usize,
    /// First and last tick time of the dwell (s).
    pub window: [f64; 2],
    /// The dwell's means, as the collector returned them.
    pub data: ConfigurationData,
}

/// A run read back from a log.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunLog {
    /// Samples per stream name: (times s, values), in log-time order.
    pub streams: BTreeMap<String, (Vec<f64>, Vec<Vec6>)>,
    /// Finished calibration dwells, in file order.
    pub dwells: Vec<LogDwell>,
    /// The `rss6` metadata records merged in file order.
    pub metadata: BTreeMap<String, String>,
    /// Every metadata record (name, pairs) in file order.
    pub records: Vec<(String, BTreeMap<String, String>)>,
    /// The file ends with its footer: the writer finished.
    pub complete: bool,
    /// File size (bytes).
    pub size: usize,
    /// Bytes that are whole records.
    pub readable: usize,
    /// Whole chunk records.
    pub chunks: usize,
    /// Messages decoded.
    pub messages: usize,
}

/// Why a log cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LogError {
    /// The file could not be read.
    #[error("cannot read {path}: {why}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        why: String,
    },
    /// Not an MCAP file, or its content is damaged (bad magic, checksum, undecodable message).
    #[error("{path}: not a readable MCAP log: {why} (at byte {offset})")]
    Corrupt {
        /// The file.
        path: String,
        /// Byte offset of the damage.
        offset: usize,
        /// What is wrong.
        why: String,
    },
    /// The file ends before anything usable (empty, or cut inside its header).
    #[error("{path}: truncated MCAP log: {why}")]
    Truncated {
        /// The file.
        path: String,
        /// What is there.
        why: String,
    },
}

const MAGIC: &[u8] = b"\x89MCAP0\r\n";
const OP_FOOTER: u8 = 0x02;
const OP_CHUNK: u8 = 0x06;
const OP_DATA_END: u8 = 0x0F;

/// (bytes up to the end of the last whole record, ends with footer + magic, whole chunks).
fn scan(path: &str, data: &[u8]) -> Result<(usize, bool, usize), LogError> {
    let n = data.len();
    let truncated = |why: &str| LogError::Truncated {
        path: path.to_string(),
        why: why.to_string(),
    };
    if n == 0 {
        return Err(truncated(
            "the file is empty: its writer stopped before writing",
        ));
    }
    if n < MAGIC.len() || !data.starts_with(MAGIC) {
        if MAGIC.starts_with(data) {
            return Err(truncated("the file ends inside its start magic"));
        }
        return Err(LogError::Corrupt {
            path: path.to_string(),
            offset: 0,
            why: "bad magic: not an MCAP file".into(),
        });
    }
    let (mut pos, mut chunks) = (MAGIC.len(), 0);
    while pos < n {
        let Some(head) = data.get(pos..pos + 9) else {
            return Ok((pos, false, chunks));
        };
        let op = head[0];
        let mut len = [0u8; 8];
        len.copy_from_slice(&head[1..9]);
        let length = u64::from_le_bytes(len);
        if op == 0 {
            return Err(LogError::Corrupt {
                path: path.to_string(),
                offset: pos,
                why: "record with opcode 0x00".into(),
            });
        }
        let end = match usize::try_from(length)
            .ok()
            .and_then(|l| (pos + 9).checked_add(l))
        {
            Some(e) if e <= n => e,
            _ => return Ok((pos, false, chunks)),
        };
        if op == OP_CHUNK {
            chunks += 1;
        }
        if op == OP_DATA_END {
            // The data-section CRC covers every byte before this record (0: not computed). The
            // chunk CRCs cover the chunks; this catches damage in the records between them
            // (message indexes, metadata).
            if let Some(b) = data.get(pos + 9..pos + 13) {
                let saved = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                if saved != 0 && crc32fast::hash(&data[..pos]) != saved {
                    return Err(LogError::Corrupt {
                        path: path.to_string(),
                        offset: pos,
                        why: "data-section CRC mismatch".into(),
                    });
                }
            }
        }
        pos = end;
        if op == OP_FOOTER {
            let tail = &data[pos..];
            if tail == MAGIC {
                return Ok((pos, true, chunks));
            }
            if MAGIC.starts_with(tail) {
                return Ok((pos, false, chunks));
            }
            return Err(LogError::Corrupt {
                path: path.to_string(),
                offset: pos,
                why: "the footer is not followed by the end magic".into(),
            });
        }
    }
    Ok((pos, false, chunks))
}

/// Reads a log written by [`super::LogWriter`]. A file cut mid-run (no footer) is read up to its
/// last whole record and reported by `complete == false`; damage is [`LogError::Corrupt`].
pub fn read_log(path: &Path) -> Result<RunLog, LogError> {
    let p = path.display().to_string();
    let data = std::fs::read(path).map_err(|e| LogError::Io {
        path: p.clone(),
        why: e.to_string(),
    })?;
    read_log_bytes(&p, &data)
}

/// [`read_log`] on bytes in memory (`path` names them in errors).
pub fn read_log_bytes(path: &str, data: &[u8]) -> Result<RunLog, LogError> {
    let (readable, complete, chunks) = scan(path, data)?;
    let corrupt = |why: String| LogError::Corrupt {
        path: path.to_string(),
        offset: readable,
        why,
    };
    let body = if complete { data } else { &data[..readable] };
    let options = mcap::read::Options::IgnoreEndMagic | mcap::read::Options::ValidateChunkCrcs;
    let reader = mcap::read::ChunkFlattener::new_with_options(body, options)
        .map_err(|e| corrupt(e.to_string()))?;
    let mut log = RunLog {
        complete,
        size: data.len(),
        readable,
        chunks,
        ..RunLog::default()
    };
    let mut topics: BTreeMap<u16, String> = BTreeMap::new();
    let mut header = false;
    let mut acc: BTreeMap<String, Vec<(u64, Vec6)>> = BTreeMap::new();
    for rec in reader {
        let rec = rec.map_err(|e| corrupt(e.to_string()))?;
        header = true;
        match rec {
            McapRecord::Channel(c) => {
                topics.insert(c.id, c.topic.clone());
            }
            McapRecord::Metadata(m) => {
                if m.name == "rss6" {
                    log.metadata.extend(m.metadata.clone());
                }
                log.records.push((m.name, m.metadata));
            }
            McapRecord::Message { header, data } => {
                let topic = topics.get(&header.channel_id).ok_or_else(|| {
                    corrupt(format!("message on unknown channel {}", header.channel_id))
                })?;
                log.messages += 1;
                let Some(name) = topic.strip_prefix("/rss6/") else {
                    continue;
                };
                let bad = |e: serde_json::Error| {
                    corrupt(format!(
                        "bad message on {topic} at log time {} ns: {e}",
                        header.log_time
                    ))
                };
                match StreamKind::of(name) {
                    Some(StreamKind::Pose(_)) => {
                        let ft: FrameTransform<'_> = serde_json::from_slice(&data).map_err(bad)?;
                        acc.entry(name.to_string())
                            .or_default()
                            .push((ft.timestamp.ns(), ft.pose()));
                    }
                    Some(StreamKind::Vector(_)) => {
                        let v: JointVector<'_> = serde_json::from_slice(&data).map_err(bad)?;
                        acc.entry(name.to_string())
                            .or_default()
                            .push((v.timestamp.ns(), Vec6::from(v.values)));
                    }
                    Some(StreamKind::Dwell) => {
                        let d: DwellMessage = serde_json::from_slice(&data).map_err(bad)?;
                        log.dwells.push(LogDwell {
                            index: d.index,
                            window: d.window,
                            data: ConfigurationData {
                                theta_cmd: d.theta_cmd,
                                kappa: d.kappa,
                                sensor_pose: d.sensor_pose,
                                kappa_samples: d.kappa_samples,
                                camera_frames: d.camera_frames,
                                kappa_std: d.kappa_std,
                                sensor_pose_std: d.sensor_pose_std,
                                sensor_pose_cov: d.sensor_pose_cov,
                                fault: d.fault,
                            },
                        });
                    }
                    None => {}
                }
            }
            _ => {}
        }
    }
    if !header {
        return Err(LogError::Truncated {
            path: path.to_string(),
            why: "it ends before its header record".into(),
        });
    }
    for (name, mut samples) in acc {
        samples.sort_by_key(|s| s.0);
        let t = samples.iter().map(|s| s.0 as f64 * 1e-9).collect();
        let v = samples.into_iter().map(|s| s.1).collect();
        log.streams.insert(name, (t, v));
    }
    Ok(log)
}

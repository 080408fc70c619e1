//! The one MCAP format: round trip, a file cut mid-run, a damaged file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use rss6_core::Vec6;
use rss6_exp::dwell::ConfigurationData;
use rss6_exp::log::{read_log, read_log_bytes, LogError, LogWriter};
use std::collections::BTreeMap;

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("rss6-exp-log-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn pose(k: usize) -> Vec6 {
    let s = k as f64 * 1e-3;
    Vec6::new(
        0.01 * s.sin(),
        -0.02 * s,
        0.115 + s * 1e-3,
        0.3 * s.cos(),
        -0.2 * s,
        3.1 - s,
    )
}

/// (offset, length) of every whole chunk record (opcode 0x06) of an MCAP file.
fn chunks(data: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut pos = 8;
    while pos + 9 <= data.len() {
        let len = u64::from_le_bytes(data[pos + 1..pos + 9].try_into().unwrap()) as usize;
        if pos + 9 + len > data.len() {
            break;
        }
        if data[pos] == 0x06 {
            out.push((pos, 9 + len));
        }
        pos += 9 + len;
    }
    out
}

#[test]
fn a_run_reads_back_as_written() {
    let path = tmp("round_trip.mcap");
    let mut w = LogWriter::create(&path, 4096, 0.0).unwrap();
    let mut md = BTreeMap::new();
    md.insert("controller".to_string(), "DSMC".to_string());
    w.add_metadata("rss6", &md).unwrap();
    for k in 0..500 {
        let t = k as f64 * 1e-3;
        w.write("true_pose", t, &pose(k)).unwrap();
        w.write("kappa", t, &Vec6::repeat(k as f64 + 0.25)).unwrap();
        if k % 33 == 0 {
            w.write("sensor_pose", t, &pose(k + 7)).unwrap();
        }
    }
    let data = ConfigurationData {
        theta_cmd: [0.1, -0.2, 0.3, 0.0, 0.05, -0.1],
        kappa: [1.5, 2.5, 3.5, 4.5, 5.5, 6.5],
        sensor_pose: Some([0.1, 0.2, 2.0, 0.1, -0.2, 0.3]),
        kappa_samples: 1000,
        camera_frames: 60,
        kappa_std: Some([0.22, 0.21, 0.23, 0.2, 0.24, 0.25]),
        sensor_pose_std: Some([9e-6, 1e-5, 1.1e-5, 4e-4, 5e-4, 4.5e-4]),
        sensor_pose_cov: Some(core::array::from_fn(|r| {
            core::array::from_fn(|c| 1e-9 * (1.0 + r as f64) * (1.0 + c as f64) + 0.5)
        })),
        fault: Some(rss6_exp::dwell::DwellFault::Unreached {
            joint: 2,
            error_bits: -453.25,
            tolerance_bits: 2.0,
        }),
    };
    w.write_dwell(3, [0.1, 0.499], &data).unwrap();
    assert!(w.write("no_such_stream", 0.0, &Vec6::zeros()).is_err());
    w.finish(Some("finished")).unwrap();
    let log = read_log(&path).unwrap();
    assert!(log.complete);
    assert_eq!(log.metadata.get("controller").unwrap(), "DSMC");
    assert_eq!(log.metadata.get("status").unwrap(), "finished");
    let (t, v) = &log.streams["true_pose"];
    assert_eq!(t.len(), 500);
    let worst = (0..500)
        .map(|k| (v[k] - pose(k)).amax())
        .fold(0.0, f64::max);
    // Poses travel as translation + unit quaternion: exact up to the conversion's rounding.
    assert!(worst < 1e-12, "{worst}");
    let (_, kappa) = &log.streams["kappa"];
    assert_eq!(kappa[123], Vec6::repeat(123.25));
    assert_eq!(log.streams["sensor_pose"].0.len(), 16);
    assert_eq!(log.dwells.len(), 1);
    assert_eq!(log.dwells[0].index, 3);
    assert_eq!(log.dwells[0].data, data);
}

#[test]
fn a_run_cut_mid_way_keeps_its_finished_chunks() {
    let path = tmp("cut.mcap");
    let mut w = LogWriter::create(&path, 1 << 20, 0.0).unwrap();
    for k in 0..300 {
        w.write("kappa", k as f64 * 1e-3, &Vec6::repeat(k as f64))
            .unwrap();
    }
    w.flush(false).unwrap(); // the first 300 samples are a finished chunk
    for k in 300..400 {
        w.write("kappa", k as f64 * 1e-3, &Vec6::repeat(k as f64))
            .unwrap();
    }
    // Killed here: no flush, no footer. What the OS has is the file now.
    let bytes = std::fs::read(&path).unwrap();
    let log = read_log_bytes("cut.mcap", &bytes).unwrap();
    assert!(!log.complete);
    assert_eq!(log.streams["kappa"].0.len(), 300);
    // Any cut inside the chunk after it also gives the first chunk back.
    w.flush(false).unwrap();
    let longer = std::fs::read(&path).unwrap();
    // The writer streams a chunk into the file as it fills (its length is written when it is finished),
    // so the killed file above ended inside the second chunk. Cut the finished file inside it too.
    let (second, len) = chunks(&longer).last().copied().unwrap();
    assert!(
        second >= 8 + 300,
        "the last chunk holds the last 100 samples"
    );
    for cut in [second + 5, second + len / 2, second + len - 1] {
        let log = read_log_bytes("cut.mcap", &longer[..cut]).unwrap();
        assert!(!log.complete);
        assert_eq!(log.streams["kappa"].0.len(), 300, "cut at {cut}");
    }
    drop(w);
}

#[test]
fn damage_is_told_apart_from_truncation() {
    let path = tmp("damaged.mcap");
    let mut w = LogWriter::create(&path, 1 << 20, 0.0).unwrap();
    for k in 0..200 {
        w.write("theta_cmd", k as f64 * 1e-3, &Vec6::repeat(0.5))
            .unwrap();
    }
    w.finish(None).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    assert!(read_log_bytes("ok", &bytes).unwrap().complete);
    // Flip a byte in the middle of the (compressed) chunk: its CRC no longer matches.
    let (start, len) = *chunks(&bytes).last().unwrap();
    bytes[start + len - 4] ^= 0x5a;
    assert!(matches!(
        read_log_bytes("damaged", &bytes),
        Err(LogError::Corrupt { .. })
    ));
    assert!(matches!(
        read_log_bytes("empty", &[]),
        Err(LogError::Truncated { .. })
    ));
    assert!(matches!(
        read_log_bytes("text", b"hello, world, not mcap"),
        Err(LogError::Corrupt { .. })
    ));
}

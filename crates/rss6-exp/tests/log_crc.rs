//! The reader checks the data-section CRC: damage outside the chunks (a message index, a metadata
//! record) is reported as corruption, not read as if it were fine.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use rss6_core::Vec6;
use rss6_exp::log::{read_log_bytes, LogError, LogWriter};

fn records(data: &[u8]) -> Vec<(u8, usize, usize)> {
    let (mut out, mut pos) = (Vec::new(), 8);
    while pos + 9 <= data.len() {
        let len = u64::from_le_bytes(data[pos + 1..pos + 9].try_into().unwrap()) as usize;
        out.push((data[pos], pos, len));
        pos += 9 + len;
    }
    out
}

#[test]
fn a_flipped_byte_in_a_message_index_is_corruption() {
    let path = std::env::temp_dir().join(format!("rss6-exp-crc-{}.mcap", std::process::id()));
    let mut w = LogWriter::create(&path, 4 * 1024, 0.0).unwrap();
    for k in 0..2000 {
        let v = Vec6::from_fn(|i, _| (k * 6 + i) as f64 * 1e-3);
        w.write("torque", k as f64 * 1e-3, &v).unwrap();
    }
    w.finish(Some("finished")).unwrap();
    let data = std::fs::read(&path).unwrap();
    std::fs::remove_file(&path).ok();
    let good = read_log_bytes("good", &data).unwrap();
    assert!(good.complete && good.messages == 2000 && good.chunks > 5);

    let &(_, at, len) = records(&data)
        .iter()
        .filter(|r| r.0 == 0x07)
        .nth(2)
        .expect("message index records");
    let mut bad = data.clone();
    bad[at + 9 + len / 2] ^= 0xFF;
    match read_log_bytes("bad", &bad) {
        Err(LogError::Corrupt { why, .. }) => assert!(why.contains("CRC"), "{why}"),
        other => panic!("expected a corrupt log, got {other:?}"),
    }
}

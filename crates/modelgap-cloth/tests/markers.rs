//! Marker recordings: CSV and MCAP round trips, and typed errors for damaged files.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use std::io::Cursor;

use modelgap_cloth::ClothError;
use modelgap_cloth::markers::{
    MarkerRecording, read_markers_csv, read_markers_csv_path, read_markers_mcap, read_markers_path,
    write_markers_csv, write_markers_mcap, write_markers_path,
};
use modelgap_core::io::mcap::McapCompression;
use modelgap_core::{CoreError, Location};

/// Frames at k / 100 s (whole nanoseconds, so MCAP's time round-trips bit for bit) with
/// awkward coordinates (thirds, tiny and huge values, negative zero).
fn recording(n_frames: u32) -> MarkerRecording {
    let ids = vec![0, 29, 450, 899];
    let t = (0..n_frames).map(|k| f64::from(k) / 100.0).collect();
    let positions = (0..n_frames)
        .map(|k| {
            let k = f64::from(k);
            ids.iter()
                .map(|&id| {
                    let i = f64::from(id);
                    [
                        i / 3.0 + (k * 0.37).sin(),
                        -1e-300 * k - 0.0,
                        1e12 * (i + k).cos() / 7.0,
                    ]
                })
                .collect()
        })
        .collect();
    MarkerRecording::new(t, ids, positions).unwrap()
}

fn bits(rec: &MarkerRecording) -> Vec<u64> {
    rec.t()
        .iter()
        .copied()
        .chain(rec.positions().iter().flatten().flatten().copied())
        .map(f64::to_bits)
        .collect()
}

fn csv_text(rec: &MarkerRecording) -> String {
    let mut out = Vec::new();
    write_markers_csv(rec, &mut out).unwrap();
    String::from_utf8(out).unwrap()
}

fn mcap_bytes(rec: &MarkerRecording, compression: McapCompression) -> Vec<u8> {
    let mut out = Cursor::new(Vec::new());
    write_markers_mcap(rec, &mut out, compression).unwrap();
    out.into_inner()
}

#[test]
fn csv_round_trip_is_bit_identical() {
    let rec = recording(50);
    let text = csv_text(&rec);
    assert!(text.starts_with("t,id,x,y,z\n"));
    assert_eq!(text.lines().count(), 1 + 50 * 4);
    let back = read_markers_csv(text.as_bytes()).unwrap();
    assert_eq!(back.ids(), rec.ids());
    assert_eq!(bits(&back), bits(&rec));
}

#[test]
fn mcap_round_trip_is_bit_identical_for_every_compression() {
    let rec = recording(50);
    for compression in [
        McapCompression::None,
        McapCompression::Zstd,
        McapCompression::Lz4,
    ] {
        let back = read_markers_mcap(&mcap_bytes(&rec, compression)).unwrap();
        assert_eq!(back.ids(), rec.ids(), "{compression:?}");
        assert_eq!(bits(&back), bits(&rec), "{compression:?}");
    }
}

#[test]
fn path_functions_pick_the_format_and_name_the_file() {
    let dir = std::env::temp_dir().join(format!("modelgap-cloth-markers-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rec = recording(10);
    for name in ["m.csv", "m.mcap"] {
        let path = dir.join(name);
        write_markers_path(&rec, &path).unwrap();
        assert_eq!(read_markers_path(&path).unwrap(), rec, "{name}");
    }
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "t,id,x,y,z\n0,1,2,3,oops\n").unwrap();
    let e = read_markers_csv_path(&bad).unwrap_err();
    let text = e.to_string();
    assert!(
        text.starts_with("expected a number for `z` at line 2, found `oops` in ")
            && text.ends_with("bad.csv"),
        "{text}"
    );
    assert!(write_markers_path(&rec, &dir.join("m.txt")).is_err());
    // Parquet holds signals (read only): markers are neither written nor read there.
    let parquet = dir.join("m.parquet");
    let e = write_markers_path(&rec, &parquet).unwrap_err();
    assert!(
        matches!(e, ClothError::Core(CoreError::FormatNotSupported { .. })),
        "{e}"
    );
    assert!(!parquet.exists());
    std::fs::write(&parquet, b"PAR1").unwrap();
    let e = read_markers_path(&parquet).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("cannot read markers from parquet"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn csv_errors_name_line_and_field() {
    type Check = fn(&ClothError) -> bool;
    let cases: [(&str, Check); 9] = [
        ("", |e| matches!(e, ClothError::MarkerHeader { .. })),
        ("t,x,y,z\n", |e| {
            matches!(e, ClothError::MarkerHeader { .. })
        }),
        ("# only a header\nt,id,x,y,z\n", |e| {
            matches!(e, ClothError::NoMarkerFrames { .. })
        }),
        (
            "t,id,x,y,z\n0,1,2,3\n",
            |e| matches!(e, ClothError::MarkerField { at: Location::Line(2), field, .. } if field == "row"),
        ),
        (
            "t,id,x,y,z\n0,1,2,3,4\n0,-1,2,3,4\n",
            |e| matches!(e, ClothError::MarkerField { at: Location::Line(3), field, .. } if field == "id"),
        ),
        (
            "t,id,x,y,z\n0,1,2,3,4\n0,1,2,3,4\n",
            |e| matches!(e, ClothError::MarkerField { at: Location::Line(3), field, .. } if field == "id"),
        ),
        (
            "t,id,x,y,z\n0,1,2,3,4\n\n0.1,1,inf,3,4\n",
            |e| matches!(e, ClothError::MarkerField { at: Location::Line(4), field, .. } if field == "x"),
        ),
        ("t,id,x,y,z\n0.2,1,2,3,4\n0.1,1,2,3,4\n", |e| {
            matches!(
                e,
                ClothError::MarkerTime {
                    at: Location::Line(3),
                    ..
                }
            )
        }),
        // The second frame lacks id 2.
        ("t,id,x,y,z\n0,1,0,0,0\n0,2,0,0,0\n0.1,1,0,0,0\n", |e| {
            matches!(e, ClothError::MarkerField { at: Location::Line(4), field, found, .. }
                if field == "id" && found.contains("id 2 missing"))
        }),
    ];
    for (text, check) in cases {
        let e = read_markers_csv(text.as_bytes()).unwrap_err();
        assert!(check(&e), "{text:?}: {e}");
        assert!(!e.to_string().ends_with('.'), "{e}");
    }
}

#[test]
fn truncated_or_damaged_mcap_is_a_typed_error() {
    let rec = recording(40);
    let bytes = mcap_bytes(&rec, McapCompression::Zstd);
    for cut in [0, 3, 8, bytes.len() / 2, bytes.len() - 1] {
        let e = read_markers_mcap(&bytes[..cut]).unwrap_err();
        assert!(
            matches!(e, ClothError::Core(CoreError::McapCorrupt { .. })),
            "cut {cut}: {e}"
        );
    }
    for pos in 0..bytes.len() {
        let mut damaged = bytes.clone();
        damaged[pos] ^= 0xff;
        // Never a panic; a flip in a field reading does not check leaves the data intact.
        if let Ok(back) = read_markers_mcap(&damaged) {
            assert_eq!(back, rec, "flip at {pos}");
        }
    }
    let e = read_markers_mcap(b"garbage").unwrap_err();
    assert!(matches!(e, ClothError::Core(CoreError::McapCorrupt { .. })));
}

#[test]
fn mcap_messages_of_the_wrong_shape_name_message_and_field() {
    use modelgap_core::io::mcap::McapWriter;
    let write = |messages: &[serde_json::Value]| {
        let mut w = McapWriter::new(Cursor::new(Vec::new()), McapCompression::None).unwrap();
        let c = modelgap_cloth::markers::add_markers_channel(&mut w).unwrap();
        for (k, m) in messages.iter().enumerate() {
            w.write_json(c, k as f64 * 0.01, m).unwrap();
        }
        w.finish().unwrap().into_inner()
    };
    let good = serde_json::json!({ "ids": [1, 2], "positions": [0, 0, 0, 1, 1, 1] });
    type Check = fn(&ClothError) -> bool;
    let cases: [(serde_json::Value, Check); 5] = [
        (
            serde_json::json!({ "ids": [1, 2] }),
            |e| matches!(e, ClothError::MarkerField { at: Location::Message(1), field, .. } if field == "positions"),
        ),
        (
            serde_json::json!({ "ids": [1, 2], "positions": [0, 0, 0, 1, 1] }),
            |e| matches!(e, ClothError::MarkerField { at: Location::Message(1), field, .. } if field == "positions"),
        ),
        (
            serde_json::json!({ "ids": [1, 2.5], "positions": [0, 0, 0, 1, 1, 1] }),
            |e| matches!(e, ClothError::MarkerField { field, .. } if field == "ids[1]"),
        ),
        (
            serde_json::json!({ "ids": [1, 2], "positions": [0, 0, 0, 1, null, 1] }),
            |e| matches!(e, ClothError::MarkerField { field, .. } if field == "positions[4]"),
        ),
        (
            serde_json::json!({ "ids": [1, 3], "positions": [0, 0, 0, 1, 1, 1] }),
            |e| matches!(e, ClothError::MarkerField { at: Location::Message(1), field, .. } if field == "id"),
        ),
    ];
    for (second, check) in cases {
        let e = read_markers_mcap(&write(&[good.clone(), second.clone()])).unwrap_err();
        assert!(check(&e), "{second}: {e}");
    }
    let e = read_markers_mcap(&{
        let mut w = McapWriter::new(Cursor::new(Vec::new()), McapCompression::None).unwrap();
        let c = w
            .add_json_channel("/other", "X", &serde_json::json!({}))
            .unwrap();
        w.write_json(c, 0.0, &good).unwrap();
        w.finish().unwrap().into_inner()
    })
    .unwrap_err();
    assert!(matches!(
        e,
        ClothError::Core(CoreError::TopicNotFound { .. })
    ));
}

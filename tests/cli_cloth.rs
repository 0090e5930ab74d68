//! End-to-end tests of `modelgap cloth`: runs written as CSV and MCAP and read back, the
//! bench's JSON, and the exit code for an unknown scene.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use std::path::PathBuf;
use std::process::{Command, Output};

use modelgap::cloth::markers::{read_markers_csv_path, read_markers_mcap_path};
use modelgap::io::mcap::read_topic_messages;

fn modelgap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_modelgap"))
        .args(args)
        .output()
        .expect("the modelgap binary runs")
}

fn ok(args: &[&str]) -> String {
    let out = modelgap(args);
    assert!(
        out.status.success(),
        "modelgap {args:?} failed with {:?}\nstdout:\n{}\nstderr:\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A fresh directory for one test, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("modelgap-cli-cloth-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }

    fn path(&self, name: &str) -> String {
        self.0.join(name).to_string_lossy().into_owned()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn run_two_corners_writes_csv_and_mcap_that_read_back() {
    let dir = TempDir::new("run");
    let csv = dir.path("run.csv");
    let text = ok(&[
        "cloth",
        "run",
        "--scene",
        "two-corners",
        "--duration",
        "0.2",
        "--out",
        &csv,
    ]);
    assert!(text.contains("20 steps"), "{text}");
    assert!(
        text.contains("worst stretch") && text.contains("x real time"),
        "{text}"
    );
    let rec = read_markers_csv_path(csv.as_ref()).unwrap();
    // 20 steps of 0.01 s: the start and one frame per step, every vertex.
    assert_eq!((rec.n_frames(), rec.n_markers()), (21, 900));
    assert_eq!(rec.ids()[29], 29);
    // The pinned corners stay put.
    assert_eq!(rec.track(29).unwrap()[20], [1.0, 0.0, 0.0]);

    let mcap = dir.path("run.mcap");
    ok(&[
        "cloth",
        "run",
        "--scene",
        "two-corners",
        "--duration",
        "0.2",
        "--rate",
        "50",
        "--markers",
        "0,29,435",
        "--out",
        &mcap,
    ]);
    let rec = read_markers_mcap_path(mcap.as_ref()).unwrap();
    assert_eq!((rec.n_frames(), rec.n_markers()), (11, 3));
    assert_eq!(rec.ids(), &[0, 29, 435]);
    assert!(rec.track(435).unwrap()[10][1] < 0.0, "the middle falls");

    let bytes = std::fs::read(&mcap).unwrap();
    let updates = read_topic_messages(&bytes, "/cloth").unwrap();
    assert_eq!(updates.len(), 11);
    let update: serde_json::Value = serde_json::from_slice(&updates[1].data).unwrap();
    let entity = &update["entities"][0];
    assert_eq!(entity["frame_id"], "world");
    assert!(update["deletions"].as_array().unwrap().is_empty());
    for key in [
        "arrows",
        "cubes",
        "spheres",
        "cylinders",
        "lines",
        "triangles",
        "texts",
        "models",
        "metadata",
    ] {
        assert!(entity[key].is_array(), "{key}");
    }
    let triangles = &entity["triangles"][0];
    assert_eq!(triangles["points"].as_array().unwrap().len(), 900);
    // 29 x 29 cells, two triangles each, three indices per triangle.
    assert_eq!(
        triangles["indices"].as_array().unwrap().len(),
        29 * 29 * 2 * 3
    );
    assert_eq!(
        entity["lines"][0]["indices"].as_array().unwrap().len(),
        2 * 1740
    );
    let tf = read_topic_messages(&bytes, "/tf").unwrap();
    let tf: serde_json::Value = serde_json::from_slice(&tf[0].data).unwrap();
    assert_eq!(tf["parent_frame_id"], "world");
}

#[test]
fn bench_json_has_every_field() {
    let out = ok(&[
        "cloth",
        "bench",
        "--scene",
        "corner",
        "--nx",
        "10",
        "--nz",
        "10",
        "--duration",
        "0.1",
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in [
        "scene",
        "particles",
        "constraints",
        "steps",
        "max_stretch",
        "mean_iterations",
        "max_iterations",
        "wall_s",
        "x_real_time",
        "threads",
    ] {
        assert!(!json[key].is_null(), "{key} missing in {json}");
    }
    assert_eq!(json["particles"], 100);
    assert_eq!(json["constraints"], 180);
    assert_eq!(json["steps"], 10);
    assert_eq!(json["threads"], 1);
}

/// `cloth bench --json` on a 10 x 10 corner with extra arguments, parsed.
fn bench_json(extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "cloth",
        "bench",
        "--scene",
        "corner",
        "--nx",
        "10",
        "--nz",
        "10",
        "--duration",
        "0.1",
        "--json",
    ];
    args.extend_from_slice(extra);
    serde_json::from_str(&ok(&args)).unwrap()
}

#[test]
fn bench_threads_run_the_coloured_sweep_with_the_same_result() {
    // Issue 4: the coloured sweep gives the same bits for any number of threads.
    let gs = ["--method", "gauss-seidel", "--tolerance", "1e-3"];
    let one = bench_json(&[&["--threads", "1"][..], &gs].concat());
    let two = bench_json(&[&["--threads", "2"][..], &gs].concat());
    assert_eq!(
        (one["threads"].as_u64(), two["threads"].as_u64()),
        (Some(1), Some(2))
    );
    for json in [&one, &two] {
        assert_eq!(json["sweep"], "coloured", "{json}");
        assert_eq!(json["method"], "gauss-seidel", "{json}");
        assert_eq!(json["stretch_tolerance"], 1e-3, "{json}");
    }
    for key in [
        "max_stretch",
        "mean_iterations",
        "max_iterations",
        "unconverged_steps",
    ] {
        assert_eq!(one[key], two[key], "{key}: {one} vs {two}");
    }
    let serial = bench_json(&[
        "--method",
        "gauss-seidel",
        "--threads",
        "2",
        "--sweep",
        "serial",
        "--max-iterations",
        "7",
    ]);
    assert_eq!(serial["sweep"], "serial");
    assert!(serial["max_iterations"].as_u64().unwrap() <= 7, "{serial}");
    assert_eq!(bench_json(&[])["sweep"], "none", "Newton is the default");
    assert_eq!(bench_json(&["--method", "gauss-seidel"])["sweep"], "serial");
}

#[test]
fn bench_rejects_zero_threads_and_a_bad_tolerance() {
    for extra in [
        ["--threads", "0"],
        ["--tolerance", "-1"],
        ["--max-iterations", "0"],
    ] {
        let mut args = vec!["cloth", "bench", "--scene", "corner"];
        args.extend_from_slice(&extra);
        let out = modelgap(&args);
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
    }
}

#[test]
fn unknown_scene_exits_with_2_naming_the_built_ins() {
    let dir = TempDir::new("bad");
    let out = modelgap(&[
        "cloth",
        "run",
        "--scene",
        "nope",
        "--out",
        &dir.path("x.csv"),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("corner, two-corners, drape"), "{stderr}");
    let out = modelgap(&["cloth", "bench", "--scene", "nope"]);
    assert_eq!(out.status.code(), Some(2));
}

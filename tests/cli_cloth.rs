//! End-to-end tests of `modelgap cloth`: runs written as CSV and MCAP and read back, the
//! bench's JSON, the exit code for an unknown scene, and the hard edges of issue 11 (limits,
//! bounds, duplicate pins, OBJ indices and marker ids named where they are).

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
    // One frame convention: entities in the simulation's frame, unrotated; /tf rotates.
    assert_eq!(entity["frame_id"], "cloth");
    assert_eq!(
        entity["triangles"][0]["pose"]["orientation"],
        serde_json::json!({ "x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0 })
    );
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
    assert_eq!(tf["child_frame_id"], "cloth");
    // Every message validates, complete, against its schema (Foxglove's published ones).
    let checked =
        modelgap::io::mcap::check_messages(&bytes, modelgap::io::json_schema::Strictness::Complete)
            .unwrap();
    assert_eq!(checked.len(), 3, "{checked:?}");
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
        "cpu_s",
        "x_real_time_cpu",
        "wall_ms_per_step",
        "cpu_ms_per_step",
        "threads",
    ] {
        assert!(!json[key].is_null(), "{key} missing in {json}");
    }
    // CPU and wall time of the same run: both positive, per step consistent.
    let (cpu, wall) = (
        json["cpu_s"].as_f64().unwrap(),
        json["wall_s"].as_f64().unwrap(),
    );
    assert!(cpu >= 0.0 && wall > 0.0, "{json}");
    let per_step = json["cpu_ms_per_step"].as_f64().unwrap();
    approx::assert_relative_eq!(per_step, 1e3 * cpu / 10.0, max_relative = 1e-9);
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

/// Runs modelgap and returns its standard error, asserting exit code 2 (bad input), that
/// nothing panicked or aborted, and that `out` (when given) was not written.
fn bad_input(args: &[&str], out: Option<&str>) -> String {
    let output = modelgap(args);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(
        output.status.code(),
        Some(2),
        "modelgap {args:?}\nstderr:\n{stderr}"
    );
    if let Some(out) = out {
        assert!(!std::path::Path::new(out).exists(), "{out} was written");
    }
    stderr
}

/// A 3 x 3 scene file in `dir` pinned at vertex 0, with `extra` top-level lines and
/// `cloth` lines in `[cloth]`, and `tail` after it.
fn small_scene(dir: &TempDir, name: &str, extra: &str, cloth: &str, tail: &str) -> String {
    let path = dir.path(name);
    std::fs::write(
        &path,
        format!(
            "name = 'small'\nduration = 0.02\ndt = 0.01\n{extra}\n[cloth]\nnx = 3\nnz = 3\n\
             size = 1.0\n{cloth}\n{tail}\n"
        ),
    )
    .unwrap();
    path
}

/// Issue 11: sizes without limits aborted the process (SIGABRT) while allocating.
#[test]
fn run_and_bench_refuse_sizes_past_their_limits_before_allocating() {
    let dir = TempDir::new("limits");
    let out = dir.path("out.csv");
    let wide = small_scene(&dir, "wide.toml", "", "pins = [0]", "");
    let text = std::fs::read_to_string(&wide)
        .unwrap()
        .replace("nx = 3", "nx = 100000")
        .replace("nz = 3", "nz = 100000");
    std::fs::write(&wide, text).unwrap();
    let err = bad_input(
        &["cloth", "run", "--scene", &wide, "--out", &out],
        Some(&out),
    );
    assert!(
        err.contains(
            "expected at most 1000000 particles (`max_particles`), found a 100000 x \
                      100000 grid of 10000000000 particles"
        ) && err.contains("--max-particles"),
        "{err}"
    );
    let absurd = small_scene(&dir, "absurd.toml", "", "", "");
    let text = std::fs::read_to_string(&absurd)
        .unwrap()
        .replace("nx = 3", "nx = 99999999999");
    std::fs::write(&absurd, text).unwrap();
    let err = bad_input(
        &["cloth", "run", "--scene", &absurd, "--out", &out],
        Some(&out),
    );
    assert!(err.contains("99999999999 x 3 grid"), "{err}");
    let err = bad_input(
        &[
            "cloth", "bench", "--scene", "corner", "--nx", "50000", "--nz", "50000",
        ],
        None,
    );
    assert!(
        err.contains("--nx 50000 --nz 50000") && err.contains("2500000000 particles"),
        "{err}"
    );
    let tiny_dt = small_scene(&dir, "dt.toml", "", "pins = [0]", "");
    let text = std::fs::read_to_string(&tiny_dt)
        .unwrap()
        .replace("dt = 0.01", "dt = 1e-9");
    std::fs::write(&tiny_dt, text).unwrap();
    let err = bad_input(
        &["cloth", "run", "--scene", &tiny_dt, "--out", &out],
        Some(&out),
    );
    assert!(
        err.contains(
            "expected at most 10000000 steps (`max_steps`), found 2e7 (duration 0.02 s \
                      / dt 1e-9 s)"
        ) && err.contains("--max-steps"),
        "{err}"
    );
    // The limits are options: lowered here, so a small run meets them.
    let small = small_scene(&dir, "small.toml", "", "pins = [0]", "");
    let err = bad_input(
        &[
            "cloth",
            "run",
            "--scene",
            &small,
            "--max-particles",
            "8",
            "--out",
            &out,
        ],
        Some(&out),
    );
    assert!(err.contains("expected at most 8 particles"), "{err}");
    let err = bad_input(
        &["cloth", "bench", "--scene", &small, "--max-steps", "1"],
        None,
    );
    assert!(err.contains("expected at most 1 steps"), "{err}");
    let err = bad_input(
        &[
            "cloth",
            "run",
            "--scene",
            "corner",
            "--max-frame-mib",
            "1",
            "--out",
            &out,
        ],
        Some(&out),
    );
    assert!(
        err.contains("(`max_frame_bytes`), found 302 frames x 1800 positions")
            && err.contains("--max-frame-mib"),
        "{err}"
    );
    ok(&[
        "cloth",
        "run",
        "--scene",
        &small,
        "--max-particles",
        "9",
        "--max-steps",
        "2",
        "--out",
        &out,
    ]);
}

/// Issue 11: gravity -1e200 printed "worst stretch inf", exited 0 and wrote -2e201;
/// gravity 1e15 took 110 s for 5 steps.
#[test]
fn run_refuses_gravity_past_its_bound_naming_the_field() {
    let dir = TempDir::new("gravity");
    let out = dir.path("out.csv");
    for (g, found) in [
        ("-1e200", "found [0, -1e200, 0] (magnitude 1e200 m/s^2)"),
        ("-1e15", "found [0, -1e15, 0] (magnitude 1e15 m/s^2)"),
        ("nan", "found [0, NaN, 0]"),
    ] {
        let scene = small_scene(
            &dir,
            "g.toml",
            &format!("gravity = [0.0, {g}, 0.0]"),
            "pins = [0]",
            "",
        );
        let err = bad_input(
            &["cloth", "run", "--scene", &scene, "--out", &out],
            Some(&out),
        );
        assert!(
            err.contains("g.toml': gravity must be finite and at most 1000 m/s^2 in magnitude")
                && err.contains(found),
            "{err}"
        );
    }
}

/// Issue 11: a vertex pinned twice was accepted silently; other fields name themselves.
#[test]
fn run_refuses_duplicate_pins_and_bad_fields_naming_them() {
    let dir = TempDir::new("fields");
    let out = dir.path("out.csv");
    let twice = small_scene(&dir, "twice.toml", "", "pins = [0, 2, 0]", "");
    let err = bad_input(
        &["cloth", "run", "--scene", &twice, "--out", &out],
        Some(&out),
    );
    assert!(
        err.contains(
            "vertex 0 is pinned twice, by cloth.pins[0] and by cloth.pins[2]; expected each \
             vertex pinned once"
        ),
        "{err}"
    );
    let moving = small_scene(
        &dir,
        "moving.toml",
        "",
        "pins = [2]",
        "[[pins.paths]]\nvertex = 2\npath = [[0.0, 1.0, 0.0, 0.0]]",
    );
    let err = bad_input(
        &["cloth", "run", "--scene", &moving, "--out", &out],
        Some(&out),
    );
    assert!(
        err.contains("by cloth.pins[0] and by pins.paths[0].vertex"),
        "{err}"
    );
    for (cloth, message) in [
        (
            "pins = [9]",
            "cloth.pins[0] must be a vertex of the 3 x 3 grid (below 9), found 9",
        ),
        (
            "particle_mass = -1.0",
            "cloth.particle_mass must be positive and finite, found -1",
        ),
        (
            "origin = [0.0, inf, 0.0]",
            "cloth.origin must be finite coordinates",
        ),
    ] {
        let scene = small_scene(&dir, "field.toml", "", cloth, "");
        let err = bad_input(
            &["cloth", "run", "--scene", &scene, "--out", &out],
            Some(&out),
        );
        assert!(err.contains(message), "{cloth}: {err}");
    }
    let err = bad_input(
        &[
            "cloth",
            "run",
            "--scene",
            "corner",
            "--markers",
            "0,950",
            "--out",
            &out,
        ],
        Some(&out),
    );
    assert!(
        err.contains(
            "--markers: expected vertex ids of scene corner (30 x 30 grid, 0 to 899), \
                      found 950"
        ),
        "{err}"
    );
}

/// Issue 11: an OBJ face index out of range had no line, and -9 was reported as "vertex 9".
#[test]
fn obj_face_index_out_of_range_names_line_index_and_file() {
    let dir = TempDir::new("obj");
    let out = dir.path("out.csv");
    std::fs::write(
        dir.path("table.obj"),
        "# a table\nv 0 -1 0\nv 1 -1 0\nv 1 -1 1\nf 1 2 3\nf 1 3 -9\n",
    )
    .unwrap();
    let scene = small_scene(
        &dir,
        "obj.toml",
        "",
        "pins = [0]",
        "[[colliders]]\nshape = \"trimesh\"\nobj = \"table.obj\"",
    );
    let err = bad_input(
        &["cloth", "run", "--scene", &scene, "--out", &out],
        Some(&out),
    );
    assert!(
        err.contains(
            "colliders[0]: OBJ line 6: expected a face vertex index from 1 to 3 or from -3 to \
             -1 (3 vertices defined so far), found -9 in "
        ) && err.contains("table.obj"),
        "{err}"
    );
    // Negative indices within range are OBJ's relative indices, and work.
    std::fs::write(
        dir.path("table.obj"),
        "v 0 -1 0\nv 1 -1 0\nv 1 -1 1\nf -3 -2 -1\n",
    )
    .unwrap();
    ok(&["cloth", "run", "--scene", &scene, "--out", &out]);
}

/// Issue 11: a bad marker id 4000 on line 7 was reported as another id on a later line.
#[test]
fn a_marker_id_outside_the_grid_is_named_at_its_own_line() {
    let dir = TempDir::new("ids");
    let scene = small_scene(&dir, "small.toml", "", "pins = [0]", "");
    let run = dir.path("run.csv");
    ok(&["cloth", "run", "--scene", &scene, "--out", &run]);
    let text = std::fs::read_to_string(&run).unwrap();
    let bad: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i + 1 == 7 {
                let cells: Vec<&str> = l.split(',').collect();
                format!("{},4000,{}", cells[0], cells[2..].join(","))
            } else {
                l.to_owned()
            }
        })
        .collect();
    let data = dir.path("bad.csv");
    std::fs::write(&data, bad.join("\n") + "\n").unwrap();
    let err = bad_input(&["compare", "--model", &scene, "--data", &data], None);
    assert!(
        err.contains("for scene small (3 x 3 grid)")
            && err.contains(
                "expected a vertex of the mesh (0 to 8) for `id` at line 7, found marker id 4000 in "
            )
            && err.contains("bad.csv"),
        "{err}"
    );
}

#[test]
fn a_run_killed_mid_way_leaves_the_earlier_file_whole() {
    // Issue 11: SIGKILL during `cloth run` left a 94-byte MCAP stub over a good 1.68 MB file.
    let dir = TempDir::new("killed");
    let out = dir.path("run.mcap");
    ok(&[
        "cloth",
        "run",
        "--scene",
        "corner",
        "--duration",
        "0.05",
        "--out",
        &out,
    ]);
    let before = std::fs::read(&out).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_modelgap"))
        .args([
            "cloth",
            "run",
            "--scene",
            "drape",
            "--duration",
            "30",
            "--out",
            &out,
        ])
        .spawn()
        .unwrap();
    // Not a timing assertion: the 30 s run takes far longer than this in any profile.
    std::thread::sleep(std::time::Duration::from_millis(500));
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert!(!status.success());
    assert_eq!(
        std::fs::read(&out).unwrap(),
        before,
        "the earlier file changed"
    );
}

/// Issue 15, item 5: a stretch tolerance the solver cannot reach (1e-9 on a curtain held by
/// every other top-row vertex, inextensible: straight row segments under load) is reported
/// once with the level reached, by `cloth run`, `cloth bench --json` and `compare`, and the
/// runs finish (it ran the 1000-iteration cap on every step before).
#[test]
fn an_unreachable_tolerance_is_a_warning_and_the_run_finishes() {
    let dir = TempDir::new("stagnation");
    let curtain = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/data/curtain.toml"),
    )
    .unwrap()
    .replace("stretch_tolerance = 1e-4", "stretch_tolerance = 1e-9")
    .replace(
        "rows = [0]",
        "vertices = [0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22]",
    )
    .replace("duration = 3.0", "duration = 0.3");
    let scene = dir.path("alternate.toml");
    std::fs::write(&scene, curtain).unwrap();
    let run = dir.path("run.csv");
    let text = ok(&["cloth", "run", "--scene", &scene, "--out", &run]);
    assert!(
        text.contains("warning: stretch tolerance 1.0e-9 cannot be reached"),
        "{text}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&ok(&["cloth", "bench", "--scene", &scene, "--json"])).unwrap();
    let warning = json["warning"].as_str().unwrap();
    assert!(warning.contains("cannot be reached"), "{json}");
    // Iterations: the first step stops on the stall window, the others at the level held.
    assert!(json["mean_iterations"].as_f64().unwrap() < 10.0, "{json}");
    let out = modelgap(&["compare", "--model", &scene, "--data", &run]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("note: the cloth solver: stretch tolerance 1.0e-9 cannot be reached"),
        "{stderr}"
    );
    // Without the tolerance, no warning.
    let json: serde_json::Value = serde_json::from_str(&ok(&[
        "cloth",
        "bench",
        "--scene",
        &scene,
        "--tolerance",
        "1e-4",
        "--json",
    ]))
    .unwrap();
    assert!(json["warning"].is_null(), "{json}");
}

/// Issue 15, item 7: `--noise all=SIGMA` sets every marker coordinate's floor at once (a
/// `NAME=SIGMA` beside it overrides its output), and compare states 3-D and per-coordinate
/// RMS.
#[test]
fn noise_all_sets_every_marker_coordinate_and_rms_is_given_both_ways() {
    let root = env!("CARGO_MANIFEST_DIR");
    let scene = format!("{root}/examples/data/cloth_scene.toml");
    let data = format!("{root}/examples/data/cloth_hidden_effect.csv");
    let json = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["compare", "--model", &scene, "--data", &data, "--json"];
        args.extend_from_slice(extra);
        serde_json::from_str(&ok(&args)).unwrap()
    };
    let all = json(&["--noise", "all=0.002"]);
    let per_coordinate = all["noise_floor_per_coordinate"].as_f64().unwrap();
    assert!((per_coordinate - 0.002).abs() < 1e-12, "{per_coordinate}");
    let floor_3d = all["noise_floor"].as_f64().unwrap();
    assert!((floor_3d - 0.002 * 3f64.sqrt()).abs() < 1e-12, "{floor_3d}");
    let rms = all["rms"].as_f64().unwrap();
    let rms_pc = all["rms_per_coordinate"].as_f64().unwrap();
    assert!((rms_pc - rms / 3f64.sqrt()).abs() < 1e-12);
    // Every marker's floor is the given one, in 3-D.
    for m in all["markers"].as_array().unwrap() {
        let f = m["noise_floor"].as_f64().unwrap();
        assert!((f - 0.002 * 3f64.sqrt()).abs() < 1e-12, "{m}");
    }
    // m0.x overrides `all` for its coordinate, before or after it.
    for order in [
        ["--noise", "m0.x=0.01", "--noise", "all=0.002"],
        ["--noise", "all=0.002", "--noise", "m0.x=0.01"],
    ] {
        let mixed = json(&order);
        let m0 = mixed["markers"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["id"] == 0)
            .unwrap();
        let expected = (0.01f64.powi(2) + 2.0 * 0.002f64.powi(2)).sqrt();
        assert!(
            (m0["noise_floor"].as_f64().unwrap() - expected).abs() < 1e-12,
            "{m0}"
        );
    }
    let text = ok(&["compare", "--model", &scene, "--data", &data]);
    assert!(
        text.contains("marker error RMS 64.56 mm 3-D (37.27 mm per coordinate)"),
        "{text}"
    );
    assert!(text.contains("per marker (3-D RMS, mm)"), "{text}");
}

/// A scene on the second-order step: `cloth bench` counts the steps it took again as the
/// paper's impulse step (`first_order_steps`), and says so in its text (the two-corners
/// cloth's taut row does not converge as BDF2 at its first steps).
#[test]
fn bench_counts_the_bdf2_steps_taken_again_first_order() {
    let dir = TempDir::new("bdf2");
    let path = dir.path("two-corners-bdf2.toml");
    let scene = modelgap::cloth::scenes::two_corners()
        .resized(12, 12)
        .unwrap();
    let toml =
        scene
            .to_toml()
            .unwrap()
            .replacen("gravity =", "integrator = \"bdf2\"\ngravity =", 1);
    std::fs::write(&path, toml).unwrap();
    let args = ["cloth", "bench", "--scene", &path, "--duration", "0.3"];
    let json: serde_json::Value =
        serde_json::from_str(&ok(&[&args[..], &["--json"]].concat())).unwrap();
    let first_order = json["first_order_steps"].as_u64().unwrap();
    assert!((1..30).contains(&first_order), "{json}");
    let out = ok(&args);
    assert!(
        out.contains(&format!(
            "{first_order} of 30 steps did not converge as BDF2 and were taken as the paper's \
             impulse step"
        )),
        "{out}"
    );
}

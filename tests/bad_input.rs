//! The bad-input suite (issue 11): one case per class of bad input — CSV and MCAP recordings,
//! model TOML, scene TOML, OBJ meshes, marker recordings and command-line options — each run
//! through the `modelgap` binary, asserting the exit code (2: the input is at fault) and
//! that the message says what and where (the file, line, field, element or option). A new
//! class is one more entry in [`cases`].

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed setup should stop the test

use std::path::PathBuf;
use std::process::Command;

use modelgap::io::mcap::{McapCompression, McapWriter, number_object_schema};
use serde_json::json;

/// One class of bad input.
struct Case {
    /// The class, named for the failure.
    class: &'static str,
    /// Files written into the case's folder first: name and content.
    files: Vec<(&'static str, Vec<u8>)>,
    /// The arguments; `{d}` stands for the case's folder.
    args: Vec<String>,
    /// The exit code expected.
    code: i32,
    /// What standard error must say (each piece, case-sensitive).
    says: Vec<String>,
}

fn case(
    class: &'static str,
    files: Vec<(&'static str, Vec<u8>)>,
    args: &str,
    code: i32,
    says: &[&str],
) -> Case {
    Case {
        class,
        files,
        args: args.split_whitespace().map(str::to_owned).collect(),
        code,
        says: says.iter().map(|s| (*s).to_owned()).collect(),
    }
}

fn text(name: &'static str, body: &str) -> (&'static str, Vec<u8>) {
    (name, body.as_bytes().to_vec())
}

/// A good recording for the DC motor: 40 samples of V, i and omega.
fn good_csv() -> String {
    let mut s = String::from("t,V,i,omega\n");
    for k in 0..40 {
        let t = f64::from(k) * 1e-3;
        s.push_str(&format!("{t},12,{},{}\n", 2.0 - t, 10.0 * t));
    }
    s
}

/// `good_csv` with line `line` (1 = the header) replaced.
fn csv_with_line(line: usize, replacement: &str) -> String {
    good_csv()
        .lines()
        .enumerate()
        .map(|(i, l)| if i + 1 == line { replacement } else { l })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

/// The DC motor's model file with `from` replaced by `to`.
fn motor_with(from: &str, to: &str) -> String {
    let src = include_str!("../crates/modelgap-bond/models/dc-motor.toml");
    assert!(src.contains(from), "the motor file has no `{from}`");
    src.replacen(from, to, 1)
}

/// A small scene (the drape, 6 × 6) with `from` replaced by `to`.
fn scene_with(from: &str, to: &str) -> String {
    let src = modelgap::cloth::scenes::drape()
        .resized(6, 6)
        .unwrap()
        .to_toml()
        .unwrap();
    assert!(src.contains(from), "the scene has no `{from}`:\n{src}");
    src.replacen(from, to, 1)
}

/// A 3 × 3 sheet as OBJ, with `extra` lines appended.
fn obj(extra: &str) -> String {
    let mut s = String::from("# sheet\n");
    for j in 0..3 {
        for i in 0..3 {
            s.push_str(&format!(
                "v {} 0 {}\n",
                f64::from(i) * 0.1,
                f64::from(j) * 0.1
            ));
        }
    }
    s.push_str("f 1 2 5 4\nf 2 3 6 5\nf 4 5 8 7\nf 5 6 9 8\n");
    s.push_str(extra);
    s
}

/// Markers of the 6 × 6 drape: ids 0, 7 and 35 over 5 frames, with `edit` applied.
fn markers(edit: impl Fn(String) -> String) -> String {
    let mut s = String::from("t,id,x,y,z\n");
    for k in 0..5 {
        let t = f64::from(k) * 0.01;
        for id in [0, 7, 35] {
            s.push_str(&format!("{t},{id},0.1,0.2,0.3\n"));
        }
    }
    edit(s)
}

/// An MCAP file of signals where `messages` are the JSON objects, one per 1 ms.
fn mcap(topic: &str, messages: &[serde_json::Value]) -> Vec<u8> {
    let mut w = McapWriter::new(std::io::Cursor::new(Vec::new()), McapCompression::Zstd).unwrap();
    let schema = number_object_schema("Signals", &["V", "i", "omega"]);
    let ch = w.add_json_channel(topic, "Signals", &schema).unwrap();
    for (k, m) in messages.iter().enumerate() {
        w.write_json(ch, k as f64 * 1e-3, m).unwrap();
    }
    w.finish().unwrap().into_inner()
}

fn good_messages() -> Vec<serde_json::Value> {
    (0..40)
        .map(|k| json!({"V": 12.0, "i": 1.0, "omega": f64::from(k)}))
        .collect()
}

fn cases() -> Vec<Case> {
    let good = || text("run.csv", &good_csv());
    let loop_args = |cmd: &str| format!("{cmd} --model dc-motor --data {{d}}/run.csv");
    let mut v = vec![
        // --- CSV recordings -------------------------------------------------------------
        case(
            "csv: empty file",
            vec![text("run.csv", "")],
            &loop_args("compare"),
            2,
            &["no header line", "run.csv"],
        ),
        case(
            "csv: header without t",
            vec![text("run.csv", &csv_with_line(1, "when,V,i,omega"))],
            &loop_args("compare"),
            2,
            &["missing column `t`", "line 1", "run.csv"],
        ),
        case(
            "csv: duplicate column",
            vec![text("run.csv", &csv_with_line(1, "t,V,i,i"))],
            &loop_args("compare"),
            2,
            &["duplicate signal `i`", "run.csv"],
        ),
        case(
            "csv: empty column name",
            vec![text("run.csv", &csv_with_line(1, "t,V,,omega"))],
            &loop_args("compare"),
            2,
            &["invalid signal name", "run.csv"],
        ),
        case(
            "csv: a cell that is not a number",
            vec![text("run.csv", &csv_with_line(5, "0.003,12,abc,1"))],
            &loop_args("compare"),
            2,
            &["`abc`", "line 5", "column `i`", "run.csv"],
        ),
        case(
            "csv: NaN",
            vec![text("run.csv", &csv_with_line(6, "0.004,12,NaN,1"))],
            &loop_args("compare"),
            2,
            &["not finite", "line 6", "`i`", "run.csv"],
        ),
        case(
            "csv: infinity",
            vec![text("run.csv", &csv_with_line(6, "0.004,12,1,inf"))],
            &loop_args("compare"),
            2,
            &["not finite", "line 6", "`omega`", "run.csv"],
        ),
        case(
            "csv: time goes back",
            vec![text("run.csv", &csv_with_line(7, "0.001,12,1,1"))],
            &loop_args("compare"),
            2,
            &["not strictly increasing", "line 7", "run.csv"],
        ),
        case(
            "csv: repeated time",
            vec![text("run.csv", &csv_with_line(7, "0.004,12,1,1"))],
            &loop_args("compare"),
            2,
            &["not strictly increasing", "line 7"],
        ),
        case(
            "csv: short row",
            vec![text("run.csv", &csv_with_line(8, "0.006,12,1"))],
            &loop_args("compare"),
            2,
            &["line 8 has 3 cells, expected 4", "run.csv"],
        ),
        case(
            "csv: long row",
            vec![text("run.csv", &csv_with_line(8, "0.006,12,1,1,1"))],
            &loop_args("compare"),
            2,
            &["line 8 has 5 cells, expected 4"],
        ),
        case(
            "csv: header only",
            vec![text("run.csv", "t,V,i,omega\n")],
            &loop_args("compare"),
            2,
            &["no samples", "run.csv"],
        ),
        case(
            "csv: not utf-8",
            vec![("run.csv", {
                let mut b = good_csv().into_bytes();
                b.extend_from_slice(b"0.5,12,\xff\xfe,1\n");
                b
            })],
            &loop_args("compare"),
            2,
            &["not valid utf-8", "line 42"],
        ),
        case(
            "csv: a value beyond the range of squares",
            vec![text("run.csv", &csv_with_line(9, "0.007,12,1.7e308,1"))],
            &loop_args("compare"),
            2,
            &["line 9", "`i`", "run.csv"],
        ),
        case(
            "csv: no signal the model measures",
            vec![text("run.csv", "t,x\n0,1\n0.001,2\n")],
            &loop_args("compare"),
            2,
            &["none of the outputs", "i, omega", "run.csv"],
        ),
        case(
            "csv: one sample, floor unknown",
            vec![text("run.csv", "t,V,i,omega\n0,12,1,1\n")],
            &loop_args("compare"),
            2,
            &["1 sample", "noise floor", "--noise"],
        ),
        // --- MCAP recordings -------------------------------------------------------------
        case(
            "mcap: not an mcap file",
            vec![text("run.mcap", "this is text")],
            "compare --model dc-motor --data {d}/run.mcap",
            2,
            &["mcap", "run.mcap"],
        ),
        case(
            "mcap: truncated",
            vec![("run.mcap", {
                let b = mcap("/signals", &good_messages());
                b[..b.len() / 2].to_vec()
            })],
            "compare --model dc-motor --data {d}/run.mcap",
            2,
            &["truncated or corrupt", "run.mcap"],
        ),
        case(
            "mcap: no /signals topic",
            vec![("run.mcap", mcap("/other", &good_messages()))],
            "compare --model dc-motor --data {d}/run.mcap",
            2,
            &["no messages on topic `/signals`", "/other"],
        ),
        case(
            "mcap: a message lacks a field",
            vec![("run.mcap", {
                let mut m = good_messages();
                m[3] = json!({"V": 12.0, "i": 1.0});
                mcap("/signals", &m)
            })],
            "compare --model dc-motor --data {d}/run.mcap",
            2,
            &["message 3", "lacks field `omega`"],
        ),
        case(
            "mcap: a message has an extra field",
            vec![("run.mcap", {
                let mut m = good_messages();
                m[4] = json!({"V": 12.0, "i": 1.0, "omega": 1.0, "x": 2.0});
                mcap("/signals", &m)
            })],
            "compare --model dc-motor --data {d}/run.mcap",
            2,
            &["message 4", "field `x`"],
        ),
        case(
            "mcap: a field that is not a number",
            vec![("run.mcap", {
                let mut m = good_messages();
                m[5] = json!({"V": 12.0, "i": "one", "omega": 1.0});
                mcap("/signals", &m)
            })],
            "compare --model dc-motor --data {d}/run.mcap",
            2,
            &["field `i` of message 5", "not a finite number"],
        ),
        case(
            "mcap: a message that is not an object",
            vec![("run.mcap", {
                let mut m = good_messages();
                m[2] = json!([1, 2, 3]);
                mcap("/signals", &m)
            })],
            "compare --model dc-motor --data {d}/run.mcap",
            2,
            &["message 2", "not a flat json object"],
        ),
        // --- the data file itself ---------------------------------------------------------
        case(
            "data: missing file",
            vec![],
            "compare --model dc-motor --data {d}/nowhere.csv",
            2,
            &["nowhere.csv", "not found"],
        ),
        case(
            "data: a directory",
            vec![text("sub/x", "")],
            "compare --model dc-motor --data {d}/sub",
            2,
            &["is a directory", "sub"],
        ),
        case(
            "data: unknown extension",
            vec![text("run.txt", &good_csv())],
            "compare --model dc-motor --data {d}/run.txt",
            2,
            &["extension `txt`", "csv", "mcap"],
        ),
        // --- model files ----------------------------------------------------------------
        case(
            "model: toml syntax",
            vec![
                good(),
                text(
                    "m.toml",
                    &motor_with("name = \"dc-motor\"", "name = dc-motor\""),
                ),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["line 6", "m.toml"],
        ),
        case(
            "model: unknown element kind",
            vec![
                good(),
                text("m.toml", &motor_with("kind = \"Se\"", "kind = \"Sx\"")),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["Sx", "m.toml"],
        ),
        case(
            "model: a bond to an unknown element",
            vec![
                good(),
                text("m.toml", &motor_with("to = \"R\"", "to = \"Rx\"")),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["unknown element 'Rx'"],
        ),
        case(
            "model: an element defined twice",
            vec![
                good(),
                text(
                    "m.toml",
                    &motor_with("name = \"tau_L\"\nkind", "name = \"V\"\nkind"),
                ),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["'V'", "twice"],
        ),
        case(
            "model: a law naming an unknown variable",
            vec![
                good(),
                text(
                    "m.toml",
                    &motor_with("parameter = \"R\"", "effort = \"Rz * f\""),
                ),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["element 'R'", "Rz"],
        ),
        case(
            "model: a law that does not parse",
            vec![
                good(),
                text(
                    "m.toml",
                    &motor_with("parameter = \"R\"", "effort = \"R * * f\""),
                ),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["R * * f"],
        ),
        case(
            "model: a law not finite at the start",
            vec![
                good(),
                text(
                    "m.toml",
                    &motor_with("parameter = \"R\"", "effort = \"f / 0\""),
                ),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["element R", "`f/0`", "NaN at the start"],
        ),
        case(
            "model: the square root of a negative number",
            vec![
                good(),
                text(
                    "m.toml",
                    &motor_with("parameter = \"R\"", "effort = \"sqrt(-1) * f\""),
                ),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["element R", "`sqrt(-1)*f`"],
        ),
        case(
            "model: a parameter that is not finite",
            vec![
                good(),
                text("m.toml", &motor_with("value = 1.0,", "value = nan,")),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["R", "finite"],
        ),
        case(
            "model: a negative inductance",
            vec![
                good(),
                text("m.toml", &motor_with("value = 5e-3,", "value = -5e-3,")),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["L", "positive", "-0.005"],
        ),
        case(
            "model: an output of an unknown element",
            vec![
                good(),
                text("m.toml", &motor_with("flow = \"1e\"", "flow = \"2e\"")),
            ],
            "compare --model {d}/m.toml --data {d}/run.csv",
            2,
            &["2e"],
        ),
        case(
            "model: a missing file",
            vec![good()],
            "compare --model {d}/nothing.toml --data {d}/run.csv",
            2,
            &["nothing.toml"],
        ),
        case(
            "model: a directory",
            vec![good(), text("models/x", "")],
            "compare --model {d}/models --data {d}/run.csv",
            2,
            &["is a directory", "models"],
        ),
        case(
            "model: unknown built-in",
            vec![good()],
            "compare --model dc-motr --data {d}/run.csv",
            2,
            &["dc-motr", "dc-motor", "buck-motor"],
        ),
        // --- parameters and loop options ----------------------------------------------------
        case(
            "--set: unknown parameter",
            vec![good()],
            &(loop_args("compare") + " --set Rx=1"),
            2,
            &["Rx", "known: J, L, R"],
        ),
        case(
            "--set: zero inductance",
            vec![good()],
            &(loop_args("compare") + " --set L=0"),
            2,
            &["L", "positive", "found 0"],
        ),
        case(
            "--set: negative inertia",
            vec![good()],
            &(loop_args("explain") + " --set J=-1"),
            2,
            &["J", "positive", "-1"],
        ),
        case(
            "--set: a value too large to simulate",
            vec![good()],
            &(loop_args("compare") + " --set k=1e300"),
            2,
            &["k"],
        ),
        case(
            "--set: no value",
            vec![good()],
            &(loop_args("compare") + " --set L"),
            2,
            &["--set", "NAME=VALUE"],
        ),
        case(
            "--noise: negative",
            vec![good()],
            &(loop_args("compare") + " --noise i=-1"),
            2,
            &["noise floor of `i` must be positive"],
        ),
        case(
            "--noise: an output the model lacks",
            vec![good()],
            &(loop_args("compare") + " --noise x=1"),
            2,
            &["no output `x`"],
        ),
        case(
            "--band-sigmas: zero",
            vec![good()],
            &(loop_args("compare") + " --band-sigmas 0"),
            2,
            &["--band-sigmas", "positive"],
        ),
        case(
            "--band-fraction: negative",
            vec![good()],
            &(loop_args("compare") + " --band-fraction -0.02"),
            2,
            &["--band-fraction", "-0.02"],
        ),
        case(
            "--effect: rank past the menu",
            vec![good()],
            &(loop_args("fix") + " --out {d}/o.toml --effect 99"),
            2,
            &["--effect 99", "ranked 1 to"],
        ),
        case(
            "--effect: unknown id",
            vec![good()],
            &(loop_args("fix") + " --out {d}/o.toml --effect friction"),
            2,
            &["--effect friction", "coulomb@1m"],
        ),
        case(
            "--out: a directory",
            vec![good(), text("outdir/x", "")],
            &(loop_args("fix") + " --out {d}/outdir"),
            2,
            &["--out", "is a directory"],
        ),
        case(
            "--out: the input model",
            vec![good(), text("m.toml", &motor_with("", ""))],
            "fix --model {d}/m.toml --data {d}/run.csv --out {d}/m.toml",
            2,
            &["--out", "input model"],
        ),
        // --- bond simulate ------------------------------------------------------------------
        case(
            "simulate: negative duration",
            vec![],
            "bond simulate --model dc-motor --duration -1 --out {d}/o.csv",
            2,
            &["--duration", "-1"],
        ),
        case(
            "simulate: zero rate",
            vec![],
            "bond simulate --model dc-motor --rate 0 --out {d}/o.csv",
            2,
            &["--rate", "0"],
        ),
        case(
            "simulate: PWM at a terahertz",
            vec![],
            "bond simulate --model buck-motor --input m=pwm:0.5@1e12 --out {d}/o.csv",
            2,
            &["limit", "--max-events"],
        ),
        case(
            "simulate: too many samples",
            vec![],
            "bond simulate --model dc-motor --duration 1e6 --rate 1e6 --out {d}/o.csv",
            2,
            &["limit", "--max-samples"],
        ),
        case(
            "simulate: a drive that does not parse",
            vec![],
            "bond simulate --model dc-motor --input V=pwm:abc --out {d}/o.csv",
            2,
            &["--input", "pwm"],
        ),
        case(
            "simulate: an input the model lacks",
            vec![],
            "bond simulate --model dc-motor --input W=3 --out {d}/o.csv",
            2,
            &["W"],
        ),
        case(
            "simulate: a fault that does not parse",
            vec![],
            "bond simulate --model dc-motor --fault R=1.2 --out {d}/o.csv",
            2,
            &["--fault", "NAME=VALUE@TIME"],
        ),
        case(
            "simulate: unknown output extension",
            vec![],
            "bond simulate --model dc-motor --out {d}/o.json",
            2,
            &["extension `json`"],
        ),
        case(
            "simulate: inputs file is a directory",
            vec![text("ins/x", "")],
            "bond simulate --model dc-motor --inputs {d}/ins --out {d}/o.csv",
            2,
            &["is a directory"],
        ),
        // --- scene files ---------------------------------------------------------------------
        case(
            "scene: toml syntax",
            vec![text("s.toml", &scene_with("[cloth]", "[cloth"))],
            "cloth run --scene {d}/s.toml --out {d}/o.csv",
            2,
            &["s.toml"],
        ),
        case(
            "scene: a grid too large",
            vec![text("s.toml", &scene_with("nx = 6", "nx = 99999999999"))],
            "cloth run --scene {d}/s.toml --out {d}/o.csv",
            2,
            &["limit", "--max-particles"],
        ),
        case(
            "scene: a 1-wide grid",
            vec![text("s.toml", &scene_with("nx = 6", "nx = 1"))],
            "cloth run --scene {d}/s.toml --out {d}/o.csv",
            2,
            &["2 x 2", "1 x 6"],
        ),
        case(
            "scene: zero time step",
            vec![text("s.toml", &scene_with("dt = 0.01", "dt = 0.0"))],
            "cloth run --scene {d}/s.toml --out {d}/o.csv",
            2,
            &["dt", "0"],
        ),
        case(
            "scene: a time step that makes too many steps",
            vec![text("s.toml", &scene_with("dt = 0.01", "dt = 1e-9"))],
            "cloth run --scene {d}/s.toml --out {d}/o.csv",
            2,
            &["steps", "--max-steps"],
        ),
        case(
            "scene: gravity beyond physics",
            vec![text(
                "s.toml",
                &scene_with(
                    "gravity = [0.0, -9.81, 0.0]",
                    "gravity = [0.0, -1e200, 0.0]",
                ),
            )],
            "cloth run --scene {d}/s.toml --out {d}/o.csv",
            2,
            &["gravity", "1e200"],
        ),
        case(
            "scene: negative friction",
            vec![text(
                "s.toml",
                &scene_with("friction = 0.3", "friction = -0.3"),
            )],
            "cloth run --scene {d}/s.toml --out {d}/o.csv",
            2,
            &["friction", "-0.3"],
        ),
        case(
            "scene: a pin past the mesh",
            vec![text("s.toml", &scene_with("pins = [", "pins = [400, "))],
            "cloth run --scene {d}/s.toml --out {d}/o.csv",
            2,
            &["400", "36"],
        ),
        case(
            "scene: a vertex pinned twice",
            vec![text("s.toml", &scene_with("pins = [", "pins = [0, 0, "))],
            "cloth run --scene {d}/s.toml --out {d}/o.csv",
            2,
            &["vertex 0", "twice"],
        ),
        case(
            "scene: unknown scene name",
            vec![],
            "cloth run --scene cornr --out {d}/o.csv",
            2,
            &["cornr", "corner"],
        ),
        // --- marker recordings -----------------------------------------------------------------
        case(
            "markers: a bad header",
            vec![
                text("s.toml", &scene_with("", "")),
                text(
                    "m.csv",
                    &markers(|s| s.replacen("t,id,x,y,z", "t,x,y,z", 1)),
                ),
            ],
            "compare --model {d}/s.toml --data {d}/m.csv",
            2,
            &["header `t,id,x,y,z`", "m.csv"],
        ),
        case(
            "markers: an id past the mesh",
            vec![
                text("s.toml", &scene_with("", "")),
                text("m.csv", &markers(|s| s.replacen("0,35,", "0,4000,", 1))),
            ],
            "compare --model {d}/s.toml --data {d}/m.csv",
            2,
            &["4000", "line 4", "m.csv"],
        ),
        case(
            "markers: an id that is not a whole number",
            vec![
                text("s.toml", &scene_with("", "")),
                text("m.csv", &markers(|s| s.replacen("0,7,", "0,7.5,", 1))),
            ],
            "compare --model {d}/s.toml --data {d}/m.csv",
            2,
            &["7.5", "line 3"],
        ),
        case(
            "markers: a frame without a marker",
            vec![
                text("s.toml", &scene_with("", "")),
                text(
                    "m.csv",
                    &markers(|s| {
                        let mut l: Vec<&str> = s.lines().collect();
                        l.remove(6);
                        l.join("\n") + "\n"
                    }),
                ),
            ],
            "compare --model {d}/s.toml --data {d}/m.csv",
            2,
            &["id", "missing"],
        ),
        case(
            "markers: a coordinate that is not finite",
            vec![
                text("s.toml", &scene_with("", "")),
                text(
                    "m.csv",
                    &markers(|s| s.replacen("0.1,0.2,0.3", "0.1,NaN,0.3", 1)),
                ),
            ],
            "compare --model {d}/s.toml --data {d}/m.csv",
            2,
            &["line 2"],
        ),
        // --- cloth options ---------------------------------------------------------------------
        case(
            "cloth bench: a grid too large",
            vec![],
            "cloth bench --scene corner --nx 50000 --nz 50000",
            2,
            &["limit", "--max-particles"],
        ),
        case(
            "cloth run: negative duration",
            vec![],
            "cloth run --scene corner --duration -1 --out {d}/o.csv",
            2,
            &["--duration", "-1"],
        ),
        case(
            "cloth run: zero tolerance",
            vec![],
            "cloth run --scene corner --tolerance 0 --out {d}/o.csv",
            2,
            &["--tolerance"],
        ),
        case(
            "cloth run: markers that do not parse",
            vec![],
            "cloth run --scene corner --markers 1,x --out {d}/o.csv",
            2,
            &["--markers", "x"],
        ),
    ];
    // The same recording classes through explain must fail the same way (one case each way is
    // enough to show the path is shared).
    v.push(case(
        "explain: a cell that is not a number",
        vec![text("run.csv", &csv_with_line(5, "0.003,12,abc,1"))],
        &loop_args("explain"),
        2,
        &["`abc`", "line 5", "column `i`"],
    ));
    v
}

/// OBJ meshes enter through the library and Python (`ClothMesh::from_obj`), not scene
/// files: each class of bad OBJ gets a typed error naming the line.
#[test]
fn every_class_of_bad_obj_gets_a_typed_error_naming_the_line() {
    use modelgap::cloth::{ClothError, ClothMesh};
    let read = |text: &str| {
        ClothMesh::from_obj(text.as_bytes(), 0.01)
            .map(|_| ())
            .unwrap_err()
    };
    let cases: [(&str, String, &[&str]); 6] = [
        (
            "a face index past the vertices",
            obj("f 1 2 12\n"),
            &["OBJ line 15", "12"],
        ),
        (
            "a negative index past the start",
            obj("f -1 -2 -9\nf 1 2 -20\n"),
            &["OBJ line 16", "-20"],
        ),
        ("index 0", obj("f 0 1 2\n"), &["OBJ line 15", "0"]),
        (
            "a vertex with two coordinates",
            obj("v 1 2\n"),
            &["OBJ line 15"],
        ),
        (
            "a coordinate that is not a number",
            obj("v 1 x 2\n"),
            &["OBJ line 15", "x"],
        ),
        ("no faces", "v 0 0 0\nv 1 0 0\n".to_owned(), &["empty"]),
    ];
    for (class, text, says) in cases {
        let e = read(&text);
        let message = e.to_string();
        assert!(
            says.iter().all(|s| message.contains(s)),
            "{class}: {message} lacks {says:?}"
        );
        assert!(
            matches!(
                e,
                ClothError::Obj { .. } | ClothError::ObjIndex { .. } | ClothError::EmptyMesh { .. }
            ),
            "{class}: {e:?}"
        );
    }
}

#[test]
fn every_class_of_bad_input_gets_a_typed_message_that_says_what_and_where() {
    let root = std::env::temp_dir().join(format!("modelgap-bad-input-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let all = cases();
    let mut failures = Vec::new();
    for (k, c) in all.iter().enumerate() {
        let dir: PathBuf = root.join(format!("case{k}"));
        std::fs::create_dir_all(&dir).unwrap();
        for (name, content) in &c.files {
            let path = dir.join(name);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, content).unwrap();
        }
        let d = dir.to_string_lossy();
        let args: Vec<String> = c.args.iter().map(|a| a.replace("{d}", &d)).collect();
        let out = Command::new(env!("CARGO_BIN_EXE_modelgap"))
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let missing: Vec<&String> = c
            .says
            .iter()
            .filter(|s| !stderr.contains(s.as_str()))
            .collect();
        if out.status.code() != Some(c.code) || !missing.is_empty() {
            failures.push(format!(
                "{}: exit {:?} (expected {}), missing {missing:?}\n  stderr: {}",
                c.class,
                out.status.code(),
                c.code,
                stderr.trim().replace('\n', "\n          ")
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&root);
    assert!(all.len() >= 60, "{} classes", all.len());
    assert!(
        failures.is_empty(),
        "{} of {} classes failed:\n{}",
        failures.len(),
        all.len(),
        failures.join("\n")
    );
}

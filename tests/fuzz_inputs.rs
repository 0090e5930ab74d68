//! Seeded mutation fuzzing of every input format (issue 11): a few hundred mutated copies
//! of the bundled files — recordings (CSV, MCAP), model TOML, scene TOML, OBJ meshes and
//! marker recordings (CSV, MCAP) — go through the readers and, when they read, a short
//! simulation. Nothing may panic, and nothing that returns `Ok` may carry a non-finite
//! number. The normal run mutates each file a few hundred times;
//! `cargo test --release --test fuzz_inputs -- --ignored` runs 50× more.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed setup should stop the test

use std::panic::{AssertUnwindSafe, catch_unwind};

use modelgap::bond::simulate::{Inputs, SimOptions, simulate, time_grid};
use modelgap::bond::{BondModel, file::read_model};
use modelgap::cloth::markers::{read_markers_csv, read_markers_mcap, write_markers_mcap};
use modelgap::cloth::{ClothMesh, Scene};
use modelgap::io::mcap::{DEFAULT_SIGNAL_TOPIC, McapCompression};
use modelgap::io::{csv, mcap};
use modelgap::{CompareOptions, Recording, compare};

/// A small seeded generator (xorshift64*): the same mutations on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that break parsers and simulations alike.
const NASTY: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "1e-320",
    "NaN",
    "inf",
    "-inf",
    "99999999999",
    "18446744073709551616",
    "-9",
    "0.0000001",
    "",
    "\"",
    "[",
    "1,2",
    "x",
    "é",
    "1e30",
    "-1e30",
];

/// One mutation of a text: a byte changed, a line deleted, duplicated or swapped, a number
/// replaced by a nasty value, a cut, or bytes inserted (not always UTF-8).
fn mutate_text(text: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut out = text.to_vec();
    let lines: Vec<&[u8]> = text.split(|b| *b == b'\n').collect();
    match rng.below(7) {
        0 if !out.is_empty() => {
            let i = rng.below(out.len());
            let pool = b" ,.-=[]{}\"#e0123456789abcxyz\n\t";
            out[i] = pool[rng.below(pool.len())];
        }
        1 if lines.len() > 1 => {
            let k = rng.below(lines.len());
            let kept: Vec<&[u8]> = lines
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, l)| *l)
                .collect();
            out = kept.join(&b'\n');
        }
        2 if lines.len() > 1 => {
            let k = rng.below(lines.len());
            let mut v = lines.clone();
            v.insert(k, lines[k]);
            out = v.join(&b'\n');
        }
        3 if lines.len() > 2 => {
            let (a, b) = (rng.below(lines.len()), rng.below(lines.len()));
            let mut v = lines.clone();
            v.swap(a, b);
            out = v.join(&b'\n');
        }
        4 => {
            // Replace the k-th number-like token.
            let s = String::from_utf8_lossy(text).into_owned();
            let starts: Vec<usize> = s
                .char_indices()
                .filter(|(i, c)| {
                    c.is_ascii_digit() && (*i == 0 || !s.as_bytes()[i - 1].is_ascii_alphanumeric())
                })
                .map(|(i, _)| i)
                .collect();
            if let Some(&start) = starts.get(rng.below(starts.len())) {
                let end = s[start..]
                    .find(|c: char| {
                        !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '+')
                    })
                    .map_or(s.len(), |e| start + e);
                let nasty = NASTY[rng.below(NASTY.len())];
                out = format!("{}{nasty}{}", &s[..start], &s[end..]).into_bytes();
            }
        }
        5 if !out.is_empty() => out.truncate(rng.below(out.len())),
        _ => {
            let i = rng.below(out.len() + 1);
            let junk: Vec<u8> = (0..1 + rng.below(6)).map(|_| rng.next() as u8).collect();
            out.splice(i..i, junk);
        }
    }
    out
}

/// One mutation of binary data: bytes flipped, cut or inserted.
fn mutate_bytes(bytes: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut out = bytes.to_vec();
    match rng.below(3) {
        0 => {
            for _ in 0..1 + rng.below(4) {
                let i = rng.below(out.len());
                out[i] ^= 1 << rng.below(8);
            }
        }
        1 => out.truncate(rng.below(out.len())),
        _ => {
            let i = rng.below(out.len());
            let junk: Vec<u8> = (0..1 + rng.below(16)).map(|_| rng.next() as u8).collect();
            out.splice(i..i, junk);
        }
    }
    out
}

/// Runs `f` and fails the test, naming `what` and the input, when it panics.
fn no_panic(what: &str, input: &[u8], f: impl FnOnce()) {
    if catch_unwind(AssertUnwindSafe(f)).is_err() {
        panic!(
            "{what} panicked on this input:\n{}",
            String::from_utf8_lossy(&input[..input.len().min(2000)])
        );
    }
}

fn first_lines(text: &str, n: usize) -> String {
    text.lines().take(n).collect::<Vec<_>>().join("\n") + "\n"
}

fn check_recording(rec: &Recording, input: &[u8]) {
    for s in rec.signals() {
        assert!(
            s.values.iter().all(|v| v.is_finite()),
            "a recording read with a non-finite value:\n{}",
            String::from_utf8_lossy(input)
        );
    }
    let motor = BondModel::new(modelgap::bond::library::dc_motor());
    if let Ok(c) = compare(&motor, rec, &CompareOptions::default()) {
        for o in &c.outputs {
            assert!(
                o.stats.rms.is_finite() && o.noise_floor.is_finite() && o.stats.max_abs.is_finite(),
                "compare returned non-finite numbers for {}: {:?}\n{}",
                o.name,
                o.stats,
                String::from_utf8_lossy(&input[..input.len().min(2000)])
            );
        }
    }
}

fn fuzz_recordings(rounds: usize, seed: u64) {
    let csv_text = first_lines(
        include_str!("../examples/data/motor_hidden_effect.csv"),
        300,
    );
    let fault = include_str!("../examples/data/dc_motor_r_fault.csv");
    let base = csv::read_signals(csv_text.as_bytes()).unwrap();
    let mcap_bytes = mcap::write_signals(
        &base,
        std::io::Cursor::new(Vec::new()),
        DEFAULT_SIGNAL_TOPIC,
        McapCompression::Zstd,
    )
    .unwrap()
    .into_inner();
    let mut rng = Rng(seed);
    for k in 0..rounds {
        let src: &str = if k % 2 == 0 { &csv_text } else { fault };
        let text = mutate_text(src.as_bytes(), &mut rng);
        no_panic("the CSV reader or compare", &text, || {
            if let Ok(rec) = csv::read_signals(text.as_slice()) {
                check_recording(&rec, &text);
            }
        });
        let bytes = mutate_bytes(&mcap_bytes, &mut rng);
        no_panic("the MCAP reader or compare", &bytes, || {
            if let Ok(rec) = mcap::read_signals(&bytes, DEFAULT_SIGNAL_TOPIC) {
                check_recording(&rec, &bytes);
            }
        });
    }
}

fn fuzz_models(rounds: usize, seed: u64) {
    let sources = [
        include_str!("../crates/modelgap-bond/models/dc-motor.toml"),
        include_str!("../crates/modelgap-bond/models/buck-motor.toml"),
    ];
    let mut rng = Rng(seed);
    for k in 0..rounds {
        let text = mutate_text(sources[k % 2].as_bytes(), &mut rng);
        no_panic("the model reader or a simulation", &text, || {
            let Ok(src) = std::str::from_utf8(&text) else {
                return;
            };
            let Ok(graph) = read_model(src) else {
                return;
            };
            if let Ok(run) = simulate(
                &graph,
                &Inputs::new(),
                &time_grid(0.02, 1000.0),
                &SimOptions::default(),
            ) {
                for (name, y) in run.output_names.iter().zip(&run.outputs) {
                    assert!(
                        y.iter().all(|v| v.is_finite()),
                        "a simulation returned a non-finite {name}:\n{src}"
                    );
                }
            }
        });
    }
}

fn fuzz_scenes(rounds: usize, seed: u64) {
    // The bundled swing (pins on paths) and a small drape (a ball with friction), so that
    // mutations reach every kind of field, not only the paths' thousands of numbers.
    let swing = include_str!("../examples/data/cloth_scene.toml").to_owned();
    let drape = modelgap::cloth::scenes::drape()
        .resized(8, 8)
        .unwrap()
        .to_toml()
        .unwrap();
    let sources = [swing, drape];
    let mut rng = Rng(seed);
    let mut stepped = 0;
    for k in 0..rounds {
        let text = mutate_text(sources[k % 2].as_bytes(), &mut rng);
        no_panic("the scene reader or a step", &text, || {
            let Ok(src) = std::str::from_utf8(&text) else {
                return;
            };
            let Ok(scene) = Scene::from_toml(src, "fuzzed.toml") else {
                return;
            };
            let Ok((mut world, cloth)) = scene.build() else {
                return;
            };
            // Large meshes are legal but slow to step here; the readers and builders ran.
            if world.positions(cloth).len() > 5000 {
                return;
            }
            stepped += 1;
            for _ in 0..3 {
                match world.step(scene.dt) {
                    Ok(report) => assert!(
                        report.max_stretch.is_finite()
                            && world
                                .positions(cloth)
                                .iter()
                                .all(|p| p.iter().all(|v| v.is_finite())),
                        "a step returned Ok with non-finite numbers:\n{src}"
                    ),
                    Err(_) => return,
                }
            }
        });
    }
    // Most mutations must still read, or the steps above test nothing.
    assert!(
        stepped > rounds / 6,
        "only {stepped} of {rounds} mutated scenes stepped"
    );
}

/// A small OBJ: a 4 × 4 grid of quads, with a comment, normals and texture coordinates.
fn obj_text() -> String {
    let mut s = String::from("# a 4 x 4 sheet\no sheet\n");
    for j in 0..4 {
        for i in 0..4 {
            s.push_str(&format!(
                "v {} 0 {}\nvt {} {}\n",
                i as f64 * 0.1,
                j as f64 * 0.1,
                i,
                j
            ));
        }
    }
    s.push_str("vn 0 1 0\n");
    for j in 0..3 {
        for i in 0..3 {
            let a = j * 4 + i + 1;
            s.push_str(&format!(
                "f {a}/{a}/1 {}/{}/1 {}/{}/1 {}/{}/1\n",
                a + 1,
                a + 1,
                a + 5,
                a + 5,
                a + 4,
                a + 4
            ));
        }
    }
    s
}

fn fuzz_meshes_and_markers(rounds: usize, seed: u64) {
    let obj = obj_text();
    let all = read_markers_csv(include_str!("../examples/data/cloth_hidden_effect.csv").as_bytes())
        .unwrap();
    let (t, ids, positions) = all.into_parts();
    let markers =
        modelgap::cloth::MarkerRecording::new(t[..20].to_vec(), ids, positions[..20].to_vec())
            .unwrap();
    let mut markers_csv = Vec::new();
    modelgap::cloth::markers::write_markers_csv(&markers, &mut markers_csv).unwrap();
    let markers_csv = String::from_utf8(markers_csv).unwrap();
    let markers_mcap = write_markers_mcap(
        &markers,
        std::io::Cursor::new(Vec::new()),
        McapCompression::Zstd,
    )
    .unwrap()
    .into_inner();
    let mut rng = Rng(seed);
    for _ in 0..rounds {
        let text = mutate_text(obj.as_bytes(), &mut rng);
        no_panic("the OBJ reader", &text, || {
            if let Ok(mesh) = ClothMesh::from_obj(text.as_slice(), 0.01) {
                assert!(
                    mesh.positions
                        .iter()
                        .all(|p| p.iter().all(|v| v.is_finite())),
                    "an OBJ read with non-finite vertices"
                );
            }
        });
        let text = mutate_text(markers_csv.as_bytes(), &mut rng);
        no_panic("the marker CSV reader", &text, || {
            let _ = read_markers_csv(text.as_slice());
        });
        let bytes = mutate_bytes(&markers_mcap, &mut rng);
        no_panic("the marker MCAP reader", &bytes, || {
            let _ = read_markers_mcap(&bytes);
        });
    }
}

#[test]
fn mutated_recordings_never_panic_or_return_non_finite_numbers() {
    fuzz_recordings(300, 11);
}

#[test]
fn mutated_model_files_never_panic_or_simulate_to_non_finite_numbers() {
    fuzz_models(300, 12);
}

#[test]
fn mutated_scene_files_never_panic_or_step_to_non_finite_numbers() {
    fuzz_scenes(300, 13);
}

#[test]
fn mutated_meshes_and_marker_recordings_never_panic() {
    fuzz_meshes_and_markers(300, 14);
}

#[test]
#[ignore = "long: 50× the mutations of the normal run"]
fn long_fuzz_of_every_format() {
    for seed in 0..50 {
        fuzz_recordings(300, 100 + seed);
        fuzz_models(300, 200 + seed);
        fuzz_scenes(300, 300 + seed);
        fuzz_meshes_and_markers(300, 400 + seed);
    }
}

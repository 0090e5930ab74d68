//! Writes the cloth recording and scene that `modelgap demo` tells its cloth story on: the
//! `drag` case of `modelgap::cloth::hidden` on a 7 × 7 swing scene — a 1 m cloth hanging
//! from clips on every other vertex of its top row, which swing 0.1 m back and forth at
//! 1 Hz — with air drag (C_d = 0.8) that the scene does not have; 9 markers (every third
//! vertex), 2 s at 100 Hz, 1 mm of Gaussian noise per coordinate (seed 1), simulated at half
//! the model's step with a 100× tighter stretch tolerance. The cloth is small so that the
//! demo's explain (hundreds of simulations) stays quick.
//!
//! Run with `cargo run --example make_cloth_demo_data` (writes
//! `examples/data/cloth_hidden_effect.csv` and the nominal scene
//! `examples/data/cloth_scene.toml`), or
//! `cargo run --example make_cloth_demo_data -- CASE OUT.csv SCENE.toml` for another case of
//! `modelgap::cloth::hidden::cases(7, 7)` (`drag`, `compliance`, `point-mass`, `nothing`).
//!
//! Marker positions are written with 6 decimals (1 µm, a thousandth of the noise), so the
//! file stays small. `modelgap demo` embeds both files at compile time; a unit test in
//! `src/cli/demo.rs` checks they are still what this example writes.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;
use modelgap::cloth::hidden::{RecordingOptions, cases, record};
use modelgap::cloth::model::recording_to_markers;

/// Vertices per side of the demo cloth.
const GRID: usize = 7;

/// Decimals of the marker positions (m) in the file.
const DECIMALS: usize = 6;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (name, csv_path, scene_path) = match args.as_slice() {
        [] => (
            "drag".to_owned(),
            PathBuf::from("examples/data/cloth_hidden_effect.csv"),
            PathBuf::from("examples/data/cloth_scene.toml"),
        ),
        [name, csv, scene] => (name.clone(), PathBuf::from(csv), PathBuf::from(scene)),
        _ => anyhow::bail!("usage: make_cloth_demo_data [CASE OUT.csv SCENE.toml]"),
    };
    let all = cases(GRID, GRID);
    let case = all.iter().find(|c| c.name == name).with_context(|| {
        format!(
            "no cloth case `{name}`; the cases are {}",
            all.iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })?;
    let rec = record(case, &RecordingOptions::default())
        .with_context(|| format!("recording case {name}"))?;
    let markers = recording_to_markers(&rec)?;
    let mut text = format!(
        "# modelgap cloth demo recording: case `{name}` of modelgap::cloth::hidden on a {GRID} x \
         {GRID} swing scene,\n# made by `cargo run --example make_cloth_demo_data`; positions in m\n\
         t,id,x,y,z\n"
    );
    for (t, frame) in markers.t().iter().zip(markers.positions()) {
        for (id, p) in markers.ids().iter().zip(frame) {
            let _ = writeln!(
                text,
                "{t:.2},{id},{:.DECIMALS$},{:.DECIMALS$},{:.DECIMALS$}",
                p[0], p[1], p[2]
            );
        }
    }
    std::fs::write(&csv_path, &text).with_context(|| format!("writing {}", csv_path.display()))?;
    let scene = case.scene.to_toml()?;
    std::fs::write(&scene_path, &scene)
        .with_context(|| format!("writing {}", scene_path.display()))?;
    println!(
        "wrote {} ({} frames of {} markers, {} bytes) and {} ({} bytes); hidden: {}",
        csv_path.display(),
        markers.n_frames(),
        markers.n_markers(),
        text.len(),
        scene_path.display(),
        scene.len(),
        case.hidden
            .iter()
            .map(|h| format!("{} = {:?}", h.id, h.values))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

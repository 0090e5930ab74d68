//! Benchmark of the measurement loop (issue 3): explaining a 4 s, 1 kHz DC-motor
//! recording with a hidden effect against the full candidate menu.
#![allow(clippy::unwrap_used)] // benches: setup failures should abort

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use modelgap::bond::hidden::{RecordingOptions, cases, record};
use modelgap::bond::{BondModel, library};
use modelgap::{ExplainOptions, explain};

/// The same allocator as the `modelgap` binary (see src/main.rs).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn explain_benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("explain");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for name in ["load", "nothing", "fault"] {
        let case = cases().into_iter().find(|c| c.name == name).unwrap();
        let rec = record(&case, &RecordingOptions::default()).unwrap();
        let model = BondModel::new(library::builtin(&case.model).unwrap());
        let opts = ExplainOptions::default();
        group.bench_function(format!("dc_motor_4s_1khz/{name}"), |b| {
            b.iter(|| black_box(explain(&model, black_box(&rec), &opts).unwrap()));
        });
    }
    group.finish();
}

criterion_group!(benches, explain_benches);
criterion_main!(benches);

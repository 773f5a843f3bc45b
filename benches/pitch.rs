//! Tents pitched per second, without solving, on a 128 x 128 structured mesh.
//!
//! Run: `cargo bench --bench pitch`. Criterion reports the median time per run and the
//! throughput in tents per second.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};

use sdg_engine::pitch_to_end;
use sdg_mesh::{Diagonal, Front, Pitcher, Rectangle};

fn pitch_128(c: &mut Criterion) {
    let mesh = Rectangle {
        width: 1.0,
        height: 1.0,
        nx: 128,
        ny: 128,
        diagonal: Diagonal::Alternate,
        interfaces: Vec::new(),
        sides: Vec::new(),
        perturb: 0.1,
        seed: 1,
    }
    .build()
    .expect("valid rectangle");
    // About ten tents per vertex.
    let pitcher = Pitcher::new(&mesh, 1.0, 0.9, 10.0 * 0.9 * 0.5 / 128.0).expect("valid pitcher");
    let run = || {
        let front = Front::flat(mesh.vertices().len(), 0.0);
        pitch_to_end(&mesh, &pitcher, &front, |_, _| {}).expect("reaches the end")
    };
    let tents = run();
    let mut group = c.benchmark_group("pitch");
    group.throughput(Throughput::Elements(tents));
    group.bench_function("128x128", |b| b.iter(run));
    group.finish();
}

criterion_group!(benches, pitch_128);
criterion_main!(benches);

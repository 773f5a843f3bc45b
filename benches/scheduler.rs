//! Scheduler overhead per tent: the full claim / pitch / record / release / offer cycle with no
//! patch solve, on a 128 x 128 mesh, in both modes on one thread.
//!
//! Run: `cargo bench --bench scheduler`. Compare the time per tent with a patch solve
//! (`cargo bench --bench patch`).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};

use sdg_mesh::{Diagonal, Front, Pitcher, Rectangle};
use sdg_scheduler::{Events, Fixed, Lease, Options, VertexId, Work};

struct PitchOnly<'a> {
    pitcher: &'a Pitcher,
}

impl<'a> Work<'a> for PitchOnly<'a> {
    type State = Fixed<'a>;
    type Scratch = ();
    type Outcome = ();
    type Error = ();

    fn tent(
        &self,
        lease: &mut Lease<'_, Fixed<'a>>,
        _: &mut (),
        v: VertexId,
        _: &Events<'a, Fixed<'a>>,
    ) -> Result<(f64, ()), ()> {
        let state = *lease.state();
        let tent = self.pitcher.pitch(state.mesh, state.front, v).ok_or(())?;
        Ok((tent.t_new, ()))
    }

    fn record(
        &'a self,
        _: &Fixed<'a>,
        _: VertexId,
        (): (),
        _: &Events<'a, Fixed<'a>>,
    ) -> Result<(), ()> {
        Ok(())
    }
}

fn schedule(c: &mut Criterion) {
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
    let pitcher = Pitcher::new(&mesh, 1.0, 0.9, 10.0 * 0.9 * 0.5 / 128.0).expect("valid pitcher");
    let mut group = c.benchmark_group("schedule");
    group.sample_size(20);
    for deterministic in [false, true] {
        let run = || {
            let front = Front::flat(mesh.vertices().len(), 0.0);
            let work = PitchOnly { pitcher: &pitcher };
            let options = Options {
                threads: 1,
                deterministic,
            };
            let mut state = Fixed {
                mesh: &mesh,
                front: &front,
            };
            sdg_scheduler::run(&mut state, pitcher.t_end(), &work, vec![()], &options)
                .expect("reaches the end")
                .tents
        };
        group.throughput(Throughput::Elements(run()));
        let name = if deterministic {
            "deterministic"
        } else {
            "asynchronous"
        };
        group.bench_function(name, |b| b.iter(run));
    }
    group.finish();
}

criterion_group!(benches, schedule);
criterion_main!(benches);

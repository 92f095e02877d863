//! The mission's step cost: the shipped default mission (`scenarios/mission.toml`: a
//! UR5-class arm on a differential drive crossing nav2's depot map, a crate appearing at
//! t = 5 s and a D* Lite re-plan, then the reach) run by `mission::run`, timed over its
//! closed loop only (`WallTimes::simulation_s`: the control steps with their law, torques,
//! monitors, records and RK4 step; the planning before the loop and the re-plan inside it
//! are excluded). Throughput is reported per control step (`MissionResult::steps`).
//!
//! Run: `cargo bench -p moma --bench mission_step --locked`.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn bench_mission_step(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/mission.toml");
    let mission = moma::mission::load(&path).expect("the default mission loads");
    let first = moma::mission::run(&mission).expect("the default mission runs");
    assert!(first.reached, "the default mission reaches its goal");
    let mut g = c.benchmark_group("mission/default_depot");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    g.throughput(Throughput::Elements(first.steps as u64));
    g.bench_function("closed_loop_per_control_step", |b| {
        b.iter_custom(|iters| {
            let mut loop_time = 0.0;
            for _ in 0..iters {
                let r = moma::mission::run(black_box(&mission)).unwrap();
                loop_time += r.wall.simulation_s;
                black_box(r.steps);
            }
            Duration::from_secs_f64(loop_time)
        });
    });
    g.finish();
}

criterion_group!(benches, bench_mission_step);
criterion_main!(benches);

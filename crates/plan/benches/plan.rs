//! The cost of `flexprr plan`'s pipeline (docs/performance.md, "Motion planning"): the
//! shipped pick-and-place plan (coupled model, ZVD) with and without its flexible check.

use criterion::{Criterion, criterion_group, criterion_main};
use flexprr_plan::{Options, plan_scene};
use flexprr_scene::Scene;

fn bench(c: &mut Criterion) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs/plan_pick_and_place.toml");
    let scene = Scene::load(&path).unwrap();
    let mut group = c.benchmark_group("plan");
    group.sample_size(10);
    group.bench_function("pick_and_place_zvd_coupled_with_flexible_check", |b| {
        b.iter(|| plan_scene(&scene, Options::default(), &mut |_| {}).unwrap())
    });
    group.bench_function("pick_and_place_zvd_coupled_plan_only", |b| {
        b.iter(|| {
            plan_scene(
                &scene,
                Options {
                    flexible_check: false,
                },
                &mut |_| {},
            )
            .unwrap()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

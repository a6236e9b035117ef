//! Criterion benchmarks of the planner on the paper's machine (docs/performance.md,
//! "Motion planning"): raw TOPP-RA on 1000 grid intervals (sampling the path form, writing
//! the rows, backward and forward passes), the checked plan (plus the dense check at ten
//! points per interval, refinement and tightening), and phase-plane integration for scale;
//! the orientation searches (best constant phi, phi free along the path, the buckling margin
//! of a timed motion).

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};

#[path = "../tests/common/mod.rs"]
mod common;
use flexprr_kinematics::Path;
use flexprr_planning::{
    Boundary, Buckling, Efficiency, MotorSpeed, MotorTorque, PhiObjective, PhiSearch, Planner,
    Schedule, Settings, SliderForce, SliderSpeed,
};

fn planning(c: &mut Criterion) {
    let machine = common::machine();
    let segment = common::pick_and_place();
    let circle = common::circle();
    let settings = Settings {
        convergence: false,
        ..Settings::default()
    };
    let periodic = Settings {
        boundary: Boundary::Periodic,
        ..settings
    };
    let speed_force = |path, settings| {
        Planner::new(&machine, path, settings)
            .constraint(SliderSpeed::new(1.0).unwrap())
            .constraint(SliderForce::new(400.0).unwrap())
    };
    let motor_buckling = |path, settings| {
        Planner::new(&machine, path, settings)
            .constraint(MotorTorque::new(common::motor(), Efficiency::PowerFlow).unwrap())
            .constraint(MotorSpeed::new(&common::motor()))
            .constraint(Buckling::new(&machine, 0.5).unwrap())
    };
    let cases = [
        (
            "pick_and_place_speed_force",
            speed_force(&segment, settings),
        ),
        (
            "circle_periodic_speed_force",
            speed_force(&circle, periodic),
        ),
        (
            "pick_and_place_motor_buckling",
            motor_buckling(&segment, settings),
        ),
    ];
    let mut group = c.benchmark_group("topp_ra_1000");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(3));
    for (name, planner) in &cases {
        group.bench_function(*name, |b| {
            b.iter(|| black_box(planner.solve_uniform(1000).unwrap().duration))
        });
    }
    group.finish();
    let mut group = c.benchmark_group("checked_plan_1000");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(4));
    for (name, planner) in &cases {
        group.bench_function(*name, |b| {
            b.iter(|| black_box(planner.plan().unwrap().duration))
        });
    }
    group.finish();
    let mut group = c.benchmark_group("phase_plane_20000");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(4));
    let (name, planner) = &cases[0];
    group.bench_function(*name, |b| {
        b.iter(|| black_box(planner.phase_plane(20_000).unwrap().duration))
    });
    group.finish();
}

fn orientation(c: &mut Criterion) {
    let machine = common::machine();
    let segment = common::pick_and_place();
    let circle = common::circle();
    let planner = Planner::new(&machine, &segment, Settings::default())
        .constraint(SliderSpeed::new(1.0).unwrap())
        .constraint(SliderForce::new(400.0).unwrap());
    let range = (-180f64.to_radians(), 180f64.to_radians());
    let fastest = PhiSearch::new(range.0, range.1, PhiObjective::MinTime).unwrap();
    let schedule = Schedule::revolution(circle.length(), 20.0);
    let margin =
        PhiSearch::new(range.0, range.1, PhiObjective::MaxMargin(schedule.clone())).unwrap();
    let on_circle = Planner::new(&machine, &circle, Settings::default());
    let mut group = c.benchmark_group("orientation");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    group.bench_function("compression_paper_circle_1000_samples", |b| {
        b.iter(|| black_box(on_circle.compression(&schedule, 1000).unwrap().ratio))
    });
    group.bench_function("best_constant_pick_and_place_min_time", |b| {
        b.iter(|| black_box(planner.best_constant_phi(&fastest).unwrap().value))
    });
    group.bench_function("best_constant_paper_circle_max_margin", |b| {
        b.iter(|| black_box(on_circle.best_constant_phi(&margin).unwrap().value))
    });
    let constant = planner.best_constant_phi(&fastest).unwrap();
    group.bench_function("free_pick_and_place_min_time", |b| {
        b.iter(|| black_box(planner.free_phi(&fastest, &constant).unwrap().value))
    });
    group.finish();
}

criterion_group!(benches, planning, orientation);
criterion_main!(benches);

use flexprr_kinematics::{CirclePath, Path, Pose, SegmentPath};
use flexprr_planning::*;
use std::time::Instant;

fn main() {
    let machine =
        flexprr_dynamics::paper::machine(3, flexprr_dynamics::paper::YOUNGS_MODULUS).unwrap();
    let circle =
        CirclePath::new([-0.05, 0.0], 0.05, std::f64::consts::FRAC_PI_4, 0.0, false).unwrap();
    for boundary in [Boundary::Periodic, Boundary::RestToRest] {
        let settings = Settings {
            boundary,
            ..Settings::default()
        };
        let planner = Planner::new(&machine, &circle, settings)
            .constraint(SliderSpeed::new(1.0).unwrap())
            .constraint(SliderForce::new(400.0).unwrap());
        if boundary == Boundary::Periodic {
            let cs = planner.constant_speed().unwrap();
            println!(
                "constant speed: f = {} Hz binding {} {} at {}",
                cs.frequency, cs.constraint, cs.label, cs.at
            );
        }
        let t = Instant::now();
        let plan = planner.plan().unwrap();
        println!(
            "{boundary:?}: duration {} ({:?}), grid {}, rounds {}, tightened {}, max usage {}, conv {:?}",
            plan.duration,
            t.elapsed(),
            plan.grid_points,
            plan.refinements,
            plan.tightened_points,
            plan.check.max_usage,
            plan.convergence
        );
        for u in &plan.check.constraints {
            println!(
                "   {} {} usage {} at s {}",
                u.constraint, u.label, u.usage, u.s
            );
        }
        println!(
            "   binding {:?}",
            plan.binding
                .iter()
                .map(|b| (b.from, b.to, b.constraint.clone()))
                .collect::<Vec<_>>()
        );
        let t = Instant::now();
        let pp = planner.phase_plane(20000).unwrap();
        println!(
            "   phase plane {} ({:?}) switches {:?}",
            pp.duration,
            t.elapsed(),
            pp.switch_points.len()
        );
    }
    let seg = SegmentPath::new(
        Pose::new(-0.08, -0.03, 30f64.to_radians()),
        Pose::new(-0.02, 0.033, 30f64.to_radians()),
    )
    .unwrap();
    let planner = Planner::new(&machine, &seg, Settings::default())
        .constraint(SliderSpeed::new(1.0).unwrap())
        .constraint(SliderForce::new(400.0).unwrap());
    let t = Instant::now();
    let plan = planner.plan().unwrap();
    println!(
        "p&p: duration {} ({:?}), grid {}, rounds {}, tightened {}, max usage {}, conv {:?}",
        plan.duration,
        t.elapsed(),
        plan.grid_points,
        plan.refinements,
        plan.tightened_points,
        plan.check.max_usage,
        plan.convergence
    );
    for u in &plan.check.constraints {
        println!(
            "   {} {} usage {} at s {}",
            u.constraint, u.label, u.usage, u.s
        );
    }
    let pp = planner.phase_plane(20000).unwrap();
    println!(
        "   phase plane {} switches {:?}",
        pp.duration, pp.switch_points
    );
    let t = Instant::now();
    let sol = planner.solve_uniform(1000).unwrap();
    println!("   raw 1000: {} in {:?}", sol.duration, t.elapsed());
}

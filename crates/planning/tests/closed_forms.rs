//! Minimum times against closed forms: the constant-speed circle by scaling one evaluation of
//! the Circle trajectory (kinematics and dynamics crates, no path form), a platform-speed
//! limit on the circle, and straight moves of one slider whose map from the path is linear.

mod common;

use flexprr_dynamics::inverse_dynamics;
use flexprr_kinematics::{Circle, Path, Pose, SegmentPath, Trajectory};
use flexprr_planning::{
    Boundary, Constraint, PathSample, Planner, PlatformSpeed, Row, Settings, SliderForce,
    SliderSpeed,
};

/// Largest slider speed and drive force of the paper's circle at `f1` (Hz), by sampling the
/// time-parameterised trajectory through the closed-form IK and the rigid inverse dynamics.
fn peaks_at(f1: f64) -> (f64, f64) {
    let machine = common::machine();
    let circle = Circle::paper(f1).unwrap();
    let n = 20_000;
    let (mut v, mut f) = (0.0f64, 0.0f64);
    for k in 0..n {
        let t = k as f64 / (n as f64 * f1);
        let state = machine
            .geometry
            .inverse_kinematics(&circle.motion(t))
            .unwrap();
        let reactions = inverse_dynamics(&machine, &state, None, t).unwrap();
        for i in 0..3 {
            v = v.max(state.legs[i].rho_dot.abs());
            f = f.max(reactions.driving_force[i].abs());
        }
    }
    (v, f)
}

#[test]
fn constant_speed_circle_matches_the_scaling_of_one_evaluation() {
    let machine = common::machine();
    let path = common::circle();
    let f1 = 20.0;
    let (v1, force1) = peaks_at(f1);
    // planning.md: 8.3 m/s and up to 663 N at 20 Hz.
    assert!((v1 - 8.3).abs() < 0.05, "{v1}");
    assert!((force1 - 663.0).abs() < 1.0, "{force1}");
    for (v, force) in [(1.0, 400.0), (10.0, 400.0), (3.0, 60.0)] {
        let expected = (f1 * v / v1).min(f1 * (force / force1).sqrt());
        let planner = Planner::new(
            &machine,
            &path,
            Settings {
                boundary: Boundary::Periodic,
                ..Settings::default()
            },
        )
        .constraint(SliderSpeed::new(v).unwrap())
        .constraint(SliderForce::new(force).unwrap());
        let fastest = planner.constant_speed().unwrap();
        // The sampled peaks are themselves within (pi/20000)^2 relative of the true peaks.
        assert!(
            (fastest.frequency - expected).abs() <= 1e-6 * expected,
            "v {v}, F {force}: {} vs {expected}",
            fastest.frequency
        );
        let binds_speed = f1 * v / v1 < f1 * (force / force1).sqrt();
        let name = if binds_speed {
            "slider_speed"
        } else {
            "slider_force"
        };
        assert_eq!(fastest.constraint, name);
        // The time-optimal periodic re-timing is at least as fast as constant speed.
        let plan = planner.plan().unwrap();
        assert!(plan.check.max_usage <= 1.0 + 1e-9);
        assert!(
            plan.duration <= 1.0 / fastest.frequency,
            "{} vs {}",
            plan.duration,
            1.0 / fastest.frequency
        );
    }
}

#[test]
fn periodic_circle_under_a_platform_speed_limit_is_the_constant_speed_revolution() {
    let machine = common::machine();
    let path = common::circle();
    let v = 0.7;
    let planner = Planner::new(
        &machine,
        &path,
        Settings {
            boundary: Boundary::Periodic,
            ..Settings::default()
        },
    )
    .constraint(PlatformSpeed::new(v).unwrap());
    let exact = path.length() / v;
    let plan = planner.plan().unwrap();
    assert!(
        (plan.duration - exact).abs() <= 1e-12 * exact,
        "{} vs {exact}",
        plan.duration
    );
    assert!((plan.frequency().unwrap() - v / path.length()).abs() <= 1e-12);
    let fastest = planner.constant_speed().unwrap();
    assert!((fastest.frequency * exact - 1.0).abs() <= 1e-12);
    // The phase plane agrees.
    let pp = planner.phase_plane(2000).unwrap();
    assert!((pp.duration - exact).abs() <= 1e-12 * exact);
}

/// `|rho_1'| <= v` and `|rho_1''| <= a` on slider 1 only.
#[derive(Debug)]
struct FirstSlider {
    speed: f64,
    acceleration: f64,
}

impl Constraint for FirstSlider {
    fn name(&self) -> &str {
        "first_slider"
    }
    fn unit(&self) -> &str {
        "m/s, m/s^2"
    }
    fn count(&self) -> usize {
        2
    }
    fn label(&self, row: usize) -> String {
        ["speed", "acceleration"][row].into()
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        let leg = &sample.legs[0];
        rows[0] = Row {
            sqrt_x: leg.d1.abs(),
            upper: self.speed,
            ..Row::INACTIVE
        };
        rows[1] = Row::symmetric(leg.d1, leg.d2, 0.0, self.acceleration);
    }
}

#[test]
fn a_move_along_a_guide_is_a_trapezoid_or_a_triangle_of_that_slider() {
    // Along guide 1's direction at constant phi, C_1 moves parallel to the guide: the closure
    // gives rho_1(s) = rho_1(0) + s exactly (rho_1' = 1, rho_1'' = 0), so slider 1 follows a
    // trapezoid (or a triangle) of its own speed.
    let machine = common::machine();
    let u = machine.geometry.legs[0].guide.direction.into_inner();
    let start = Pose::new(-0.03, -0.04, 0.3);
    let length = 0.06;
    let end = Pose::new(start.x + length * u.x, start.y + length * u.y, start.phi);
    let path = SegmentPath::new(start, end).unwrap();
    let a = 30.0;
    for v in [0.5, 5.0] {
        let planner = Planner::new(&machine, &path, Settings::default()).constraint(FirstSlider {
            speed: v,
            acceleration: a,
        });
        let exact = if v * v / a < length {
            length / v + v / a
        } else {
            2.0 * (length / a).sqrt()
        };
        let plan = planner.plan().unwrap();
        // The grid resolves the switch points to one interval.
        let interval = length / 1000.0;
        assert!(
            plan.duration >= exact * (1.0 - 1e-12),
            "{} vs {exact}",
            plan.duration
        );
        assert!(
            plan.duration - exact <= 4.0 * interval / v.min((a * length).sqrt()),
            "{} vs {exact}",
            plan.duration
        );
        let pp = planner.phase_plane(20_000).unwrap();
        assert!(
            (pp.duration - exact).abs() <= 1e-5 * exact,
            "{} vs {exact}",
            pp.duration
        );
        // The slider really moves by the path parameter.
        let sample = planner.sampler().sample(&path, 0.5 * length).unwrap();
        assert!((sample.legs[0].d1 - 1.0).abs() <= 1e-12 && sample.legs[0].d2.abs() <= 1e-9);
    }
}

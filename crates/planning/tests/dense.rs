//! A planned motion, run as a trajectory and checked at ten times the grid's resolution in
//! time through the layers below (closed-form inverse kinematics, rigid inverse dynamics,
//! the actuator's own torque model, the joint-reaction axial force and Euler's load), keeps
//! every limit to 0.1 %. None of this goes through the planner's path form.

mod common;

use common::recheck::{Limits, recheck, ten_times_finer, trajectory_of};
use flexprr_kinematics::Path;
use flexprr_planning::{
    Boundary, Buckling, Efficiency, MotorSpeed, MotorTorque, Planner, RmsLimit, Settings,
    SliderAcceleration, SliderForce, SliderSpeed, shaping,
};

#[test]
fn slider_limits_hold_between_grid_points() {
    let machine = common::machine();
    let circle = common::circle();
    let segment = common::pick_and_place();
    let cases: [(&dyn Path, Boundary); 3] = [
        (&segment, Boundary::RestToRest),
        (&circle, Boundary::RestToRest),
        (&circle, Boundary::Periodic),
    ];
    for (path, boundary) in cases {
        let limits = Limits {
            speed: Some(1.5),
            acceleration: Some(250.0),
            force: Some(150.0),
            ..Limits::default()
        };
        let plan = Planner::new(
            &machine,
            path,
            Settings {
                boundary,
                ..Settings::default()
            },
        )
        .constraint(SliderSpeed::new(1.5).unwrap())
        .constraint(SliderAcceleration::new(250.0).unwrap())
        .constraint(SliderForce::new(150.0).unwrap())
        .plan()
        .unwrap();
        let worst = ten_times_finer(&machine, &plan, path, &limits);
        // Time-optimal: some limit is reached.
        assert!(worst > 0.99, "{worst}");
    }
}

#[test]
fn motor_and_buckling_limits_hold_between_grid_points() {
    let machine = common::machine();
    let segment = common::pick_and_place();
    let circle = common::circle();
    for path in [&segment as &dyn Path, &circle] {
        let limits = Limits {
            motor: Some(common::motor()),
            buckling: Some(0.3),
            ..Limits::default()
        };
        let planner = Planner::new(&machine, path, Settings::default())
            .constraint(MotorTorque::new(common::motor(), Efficiency::Symmetric).unwrap())
            .constraint(MotorSpeed::new(&common::motor()))
            .constraint(Buckling::new(&machine, 0.3).unwrap());
        let plan = planner.plan().unwrap();
        let worst = ten_times_finer(&machine, &plan, path, &limits);
        assert!(worst > 0.99, "{worst}");
        // The buckling constraint's critical load is Euler's for the sine-mode link.
        let buckling = Buckling::new(&machine, 0.3).unwrap();
        let euler = flexprr_testkit::paper::euler_load();
        for p in buckling.critical_loads() {
            assert!((p - euler).abs() <= 1e-9 * euler, "{p} vs {euler}");
        }
    }
}

#[test]
fn an_rms_limit_lowers_the_peak_torque_until_it_holds() {
    let machine = common::machine();
    let segment = common::pick_and_place();
    let mut motor = common::motor();
    motor.ratings.continuous_torque = 0.3;
    let torque = MotorTorque::new(motor, Efficiency::Symmetric).unwrap();
    let base = Planner::new(&machine, &segment, Settings::default())
        .constraint(torque)
        .constraint(MotorSpeed::new(&motor));
    let fastest = base.plan().unwrap();
    let planner = base.rms(RmsLimit {
        motor: torque,
        continuous_torque: 0.3,
        dwell: 0.05,
    });
    let plan = planner.plan().unwrap();
    let rms = plan.rms_torque.unwrap();
    println!(
        "peak factor {}, rms {rms:?}, {} s vs {} s unconstrained",
        plan.peak_torque_factor, plan.duration, fastest.duration
    );
    assert!(plan.peak_torque_factor < 1.0);
    assert!(plan.duration > fastest.duration);
    // Independently: the RMS of the actuator's own torque over the move and the dwell.
    let trajectory = trajectory_of(&plan, &segment);
    let cycle = plan.duration + 0.05;
    let limits = Limits {
        motor: Some(motor),
        rms: Some(0.3),
        ..Limits::default()
    };
    let (worst, what) = recheck(
        &machine,
        &trajectory,
        (0.0, cycle),
        20 * plan.grid_points,
        &limits,
    );
    assert!(worst <= 1.001, "{what}: {worst}");
    // The RMS torque is at its limit within the bisection's resolution (0.1 % of the peak
    // factor).
    let largest = rms.iter().fold(0.0f64, |a, b| a.max(*b));
    assert!((0.3 * 0.99..=0.3).contains(&largest), "{largest}");
}

#[test]
fn a_jerk_limit_is_met_by_smoothing() {
    let machine = common::machine();
    let segment = common::pick_and_place();
    let jerk = 2.0e4;
    let plan = Planner::new(&machine, &segment, Settings::default())
        .constraint(SliderSpeed::new(1.0).unwrap())
        .constraint(SliderForce::new(200.0).unwrap())
        .jerk(jerk)
        .plan()
        .unwrap();
    println!(
        "smoothing {} s, tightening {}, duration {} vs {}",
        plan.smoothing, plan.tightening, plan.duration, plan.optimal_duration
    );
    assert!(plan.smoothing > 0.0);
    let limits = Limits {
        speed: Some(1.0),
        force: Some(200.0),
        jerk: Some(jerk),
        ..Limits::default()
    };
    ten_times_finer(&machine, &plan, &segment, &limits);
}

#[test]
fn a_shaped_plan_keeps_its_limits_and_costs_its_shaper() {
    let machine = common::machine();
    let segment = common::pick_and_place();
    let impulses = shaping::design(
        shaping::Shaper::Zvd,
        shaping::Mode {
            frequency: 90.0,
            damping: 0.02,
        },
    )
    .unwrap();
    let planner = Planner::new(&machine, &segment, Settings::default())
        .constraint(SliderSpeed::new(1.0).unwrap())
        .constraint(SliderForce::new(400.0).unwrap());
    let unshaped = planner.plan().unwrap();
    let plan = planner.shaper(impulses.clone()).plan().unwrap();
    let extra = shaping::duration(&impulses);
    println!(
        "shaped {} = {} + {extra} (tightening {})",
        plan.duration, plan.optimal_duration, plan.tightening
    );
    assert!((plan.duration - (plan.optimal_duration + extra)).abs() <= 1e-12);
    assert!(plan.optimal_duration >= unshaped.duration * (1.0 - 1e-12));
    let limits = Limits {
        speed: Some(1.0),
        force: Some(400.0),
        ..Limits::default()
    };
    ten_times_finer(&machine, &plan, &segment, &limits);
}

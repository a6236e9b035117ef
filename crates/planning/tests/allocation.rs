//! The path form and the constraints' rows, evaluated at every grid and check point, allocate
//! nothing (the solver's own loops are checked in its unit tests).

mod common;

use flexprr_control::{MotorBallScrew, MotorRatings};
use flexprr_dynamics::JointReactionAxialForce;
use flexprr_planning::{
    Buckling, Constraint, Efficiency, MotorSpeed, MotorTorque, Row, Sampler, SliderAcceleration,
    SliderForce, SliderSpeed,
};
use flexprr_testkit::alloc::{CountingAllocator, count_allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn sampling_and_rows_allocate_nothing() {
    let machine = common::machine();
    let path = common::circle();
    let sampler = Sampler::new(&machine, Some(&JointReactionAxialForce));
    let motor = MotorBallScrew {
        rotor_inertia: 1e-5,
        lead: 0.01,
        efficiency: 0.9,
        ratings: MotorRatings {
            peak_torque: 1.0,
            continuous_torque: 0.5,
            max_speed: 100.0,
        },
        viscous_friction: 1e-4,
        coulomb_friction: 0.01,
        coulomb_smoothing: 0.01,
        drive: None,
        friction_feedforward: false,
        screw: None,
        lugre: None,
    };
    let constraints: Vec<Box<dyn Constraint>> = vec![
        Box::new(SliderSpeed::new(1.0).unwrap()),
        Box::new(SliderAcceleration::new(100.0).unwrap()),
        Box::new(SliderForce::new(400.0).unwrap()),
        Box::new(MotorTorque::new(motor, Efficiency::PowerFlow).unwrap()),
        Box::new(MotorSpeed::new(&motor)),
        Box::new(Buckling::new(&machine, 0.5).unwrap()),
    ];
    let mut rows = vec![Row::INACTIVE; 32];
    let ((), allocations) = count_allocations(|| {
        for k in 0..100 {
            let sample = sampler.sample(&path, 0.003 * k as f64).unwrap();
            for c in &constraints {
                c.rows(&sample, &mut rows[..c.count()]);
            }
        }
    });
    assert_eq!(allocations, 0);
}

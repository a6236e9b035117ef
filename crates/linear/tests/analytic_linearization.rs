//! The linearisation's analytic path (`A = [0 I; -M^-1 K  -M^-1 C]` from the nonlinear
//! model's co-rotational tangents, crates/dynamics/src/nonlinear/tangent.rs) against central
//! differences of the right-hand side with Richardson extrapolation
//! (`linearize_with(.., Derivatives::Differences)`), at rest where the model says its form
//! is exact, and the differences kept where it is not (actuated sliders, a moving
//! platform).

use std::sync::Arc;

use flexprr_control::{Actuator, IdealForce, Pid};
use flexprr_dynamics::{
    Actuation, LinearHints, NonlinearOptions, NonlinearSystem, SceneModel, paper,
};
use flexprr_kinematics::{Circle, Line, Pose, Trajectory};
use flexprr_linear::{Derivatives, Input, Output, linearize, linearize_with, modes};
use nalgebra::{Point2, Vector3};

fn nonlinear(trajectory: Arc<dyn Trajectory + Send + Sync>, elements: usize) -> NonlinearSystem {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let options = NonlinearOptions {
        elements,
        ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
    };
    let mut model = NonlinearSystem::new(machine, trajectory, options).unwrap();
    model.start_at(0.0).unwrap();
    model
}

fn at_rest(pose: Pose) -> Arc<dyn Trajectory + Send + Sync> {
    Arc::new(Line::new(pose, Vector3::zeros(), 0.0).unwrap())
}

#[test]
fn the_tangents_are_the_derivatives_at_rest() {
    let inputs = [
        Input::SliderForce(1),
        Input::PointForce { link: 0, xi: 0.3 },
    ];
    let outputs = [
        Output::Deflection { link: 0, xi: 0.5 },
        Output::Acceleration { link: 2, xi: 0.4 },
    ];
    for (pose, elements) in [
        (Pose::new(0.0, 0.0, 45f64.to_radians()), 8),
        (Pose::new(-0.08, 0.03, 30f64.to_radians()), 16),
    ] {
        let mut model = nonlinear(at_rest(pose), elements);
        let y = SceneModel::initial_state(&model);
        let analytic = linearize(&mut model, 0.0, &y, &inputs, &outputs).unwrap();
        let differences = linearize_with(
            &mut model,
            0.0,
            &y,
            &inputs,
            &outputs,
            Derivatives::Differences,
        )
        .unwrap();
        assert_eq!(analytic.derivatives, Derivatives::Analytic);
        assert_eq!(differences.derivatives, Derivatives::Differences);
        // Entry by entry, relative to the largest entry of each row of A.
        let n = analytic.a.nrows();
        let mut worst = 0.0_f64;
        for i in 0..n {
            let scale = (0..n).fold(0.0_f64, |m, j| m.max(differences.a[(i, j)].abs()));
            for j in 0..n {
                let d = (analytic.a[(i, j)] - differences.a[(i, j)]).abs();
                worst = worst.max(if scale > 0.0 { d / scale } else { d });
            }
        }
        let (fa, fd) = (modes(&analytic).unwrap(), modes(&differences).unwrap());
        let frequency = fa
            .iter()
            .zip(&fd)
            .take(12)
            .map(|(a, d)| (a.frequency_hz - d.frequency_hz).abs() / d.frequency_hz)
            .fold(0.0, f64::max);
        let outputs_c = (0..analytic.c.nrows())
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| (analytic.c[(i, j)] - differences.c[(i, j)]).abs())
            .fold(0.0, f64::max)
            / (0..analytic.c.nrows())
                .flat_map(|i| (0..n).map(move |j| (i, j)))
                .map(|(i, j)| differences.c[(i, j)].abs())
                .fold(0.0, f64::max);
        println!(
            "{elements} elements: A analytic against differences {worst:.1e} (row-relative), \
             lowest 12 frequencies {frequency:.1e}, C (with an acceleration row) {outputs_c:.1e}"
        );
        assert!(worst < 1e-6, "{worst}");
        assert!(frequency < 1e-8, "{frequency}");
        assert!(outputs_c < 1e-6, "{outputs_c}");
    }
}

#[test]
fn differences_where_the_form_is_not_exact() {
    // Actuated sliders: the tangents difference the control law.
    let force: Arc<dyn Actuator> = Arc::new(IdealForce);
    let actuation = Actuation {
        controller: Arc::new(Pid::pd(2.0e5, 400.0, true, 0.0).unwrap()),
        actuators: [force.clone(), force.clone(), force],
    };
    let mut servo = nonlinear(at_rest(Pose::new(0.0, 0.0, 45f64.to_radians())), 8)
        .with_actuation(actuation, 0.0)
        .unwrap();
    let y = SceneModel::initial_state(&servo);
    assert!(!servo.exact_mechanical_form(0.0, &y));
    let lin = linearize(&mut servo, 0.0, &y, &[], &[]).unwrap();
    assert_eq!(lin.derivatives, Derivatives::Differences);
    // A moving platform: centripetal and damping terms are left out of the tangents.
    let circle: Arc<dyn Trajectory + Send + Sync> = Arc::new(
        Circle::new(Point2::new(-0.05, 0.0), 0.05, 20.0, 45f64.to_radians(), 0.0).unwrap(),
    );
    let mut moving = nonlinear(circle, 8);
    let y = SceneModel::initial_state(&moving);
    assert!(!moving.exact_mechanical_form(0.0, &y));
    let lin = linearize(&mut moving, 0.0, &y, &[], &[]).unwrap();
    assert_eq!(lin.derivatives, Derivatives::Differences);
}

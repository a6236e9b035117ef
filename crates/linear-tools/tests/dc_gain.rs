//! A property of the servo's linear model at rest, over generated poses and gains: the static
//! gain of the closed loop from the slider forces to the sliders is `I / kp`. At rest with no
//! external load on the platform, a 3-DOF body held by three links, the links carry no force
//! in equilibrium (three link forces balancing nothing are zero away from a singular pose), so
//! each slider holds its own force with its own position gain, whatever the pose, the links'
//! flexibility or the machine's inertia; and from the references to the sliders it is `I`.

use faer::Mat;
use faer::linalg::solvers::Solve;
use flexprr_kinematics::Pose;
use flexprr_linear::{Input, Linearization, Output, linearize};
use flexprr_linear_tools::linear::{OperatingPoint, operating_point};
use flexprr_scene::Scene;
use proptest::prelude::*;

fn servo(kp: f64) -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/servo_f20.toml");
    let text = std::fs::read_to_string(path)
        .unwrap()
        .replace("kp = 2e5 ", &format!("kp = {kp:e} "));
    assert!(text.contains(&format!("kp = {kp:e}")));
    Scene::from_text("servo.toml", "servo", &text).unwrap()
}

/// `D - C A^-1 B`, the static gain.
fn dc_gain(lin: &Linearization) -> Mat<f64> {
    let x = lin.a.partial_piv_lu().solve(&lin.b);
    &lin.d - &lin.c * &x
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    #[test]
    fn the_static_gain_is_one_over_kp_at_any_pose(
        x in -0.07f64..-0.03,
        y in -0.02f64..0.02,
        phi in 35.0f64..55.0,
        kp in 5e4f64..5e5,
    ) {
        let scene = servo(kp);
        let pose = Pose::new(x, y, phi.to_radians());
        let mut at = operating_point(&scene, OperatingPoint::Rest(pose)).unwrap();
        let mut inputs: Vec<Input> = (0..3).map(Input::SliderForce).collect();
        inputs.extend((0..3).map(Input::Reference));
        let outputs: Vec<Output> = (0..3).map(Output::SliderPosition).collect();
        let lin = linearize(at.model.as_mut(), at.t, &at.state, &inputs, &outputs).unwrap();
        let g = dc_gain(&lin);
        for i in 0..3 {
            for j in 0..3 {
                let force = if i == j { 1.0 / kp } else { 0.0 };
                let reference = if i == j { 1.0 } else { 0.0 };
                prop_assert!((g[(i, j)] - force).abs() <= 1e-6 / kp, "force {i},{j}: {} vs {force}", g[(i, j)]);
                prop_assert!((g[(i, 3 + j)] - reference).abs() <= 1e-6, "reference {i},{j}: {}", g[(i, 3 + j)]);
            }
        }
    }
}

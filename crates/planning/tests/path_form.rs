//! The path form against the layers below at arbitrary path speeds and accelerations: the
//! drive forces and axial forces of the sample's coefficients equal the inverse dynamics of the
//! actual motion (the linear-quadratic structure, exactly), and the slider derivatives in `s`
//! equal differences of the closed-form inverse kinematics.

mod common;

use flexprr_dynamics::{
    AxialForceModel, AxialInput, JointReactionAxialForce, PaperAxialForce, end_forces,
    inverse_dynamics,
};
use flexprr_kinematics::{Path, Pose, SplinePath, WaypointSpline};
use flexprr_planning::Sampler;

#[test]
fn drive_and_axial_forces_are_affine_in_the_path_acceleration_and_squared_speed() {
    let machine = common::machine();
    let circle = common::circle();
    let segment = common::pick_and_place();
    let spline = SplinePath::new(
        &WaypointSpline::new(&[
            (0.0, Pose::new(-0.08, -0.03, 0.5)),
            (0.05, Pose::new(-0.05, 0.02, 0.7)),
            (0.1, Pose::new(-0.02, 0.033, 0.3)),
        ])
        .unwrap(),
    )
    .unwrap();
    let models: [&dyn AxialForceModel; 2] = [&JointReactionAxialForce, &PaperAxialForce];
    for model in models {
        let sampler = Sampler::new(&machine, Some(model));
        for path in [&circle as &dyn Path, &segment, &spline] {
            for k in 1..10 {
                let s = path.length() * k as f64 / 10.0;
                let sample = sampler.sample(path, s).unwrap();
                for (s_dot, s_ddot) in [(0.7, -3.0), (2.0, 40.0), (0.1, 0.0)] {
                    let motion = path.point(s).motion(s_dot, s_ddot);
                    let state = machine.geometry.inverse_kinematics(&motion).unwrap();
                    let reactions = inverse_dynamics(&machine, &state, None, 0.0).unwrap();
                    let x = s_dot * s_dot;
                    for i in 0..3 {
                        let path_form = sample.drive[i].at(s_ddot, x);
                        let direct = reactions.driving_force[i];
                        assert!((path_form - direct).abs() <= 1e-10 * (1.0 + direct.abs()));
                        let leg = &sample.legs[i];
                        assert!((leg.velocity(s_dot) - state.legs[i].rho_dot).abs() <= 1e-12);
                        assert!(
                            (leg.acceleration(s_dot, s_ddot) - state.legs[i].rho_ddot).abs()
                                <= 1e-10 * (1.0 + state.legs[i].rho_ddot.abs())
                        );
                        let load = model.load(&AxialInput {
                            leg: &state.legs[i].kinematics,
                            guide_direction: machine.geometry.legs[i].guide.direction.into_inner(),
                            link: &machine.links[i],
                            reactions: Some(&reactions),
                            index: i,
                        });
                        let (p0, pl) = end_forces(&load, machine.links[i].length());
                        for (end, p) in [p0, pl].iter().enumerate() {
                            let path_form = sample.axial[i][end].at(s_ddot, x);
                            assert!(
                                (path_form - p).abs() <= 1e-10 * (1.0 + p.abs()),
                                "{} {path_form} vs {p}",
                                model.name()
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn slider_derivatives_in_s_match_differences_of_the_inverse_kinematics() {
    let machine = common::machine();
    let sampler = Sampler::new(&machine, None);
    let circle = common::circle();
    let segment = common::pick_and_place();
    for path in [&circle as &dyn Path, &segment] {
        let h = 1e-5 * path.length();
        for k in 1..10 {
            let s = path.length() * k as f64 / 10.0;
            let (before, here, after) = (
                sampler.sample(path, s - h).unwrap(),
                sampler.sample(path, s).unwrap(),
                sampler.sample(path, s + h).unwrap(),
            );
            for i in 0..3 {
                let d1 = (after.legs[i].rho - before.legs[i].rho) / (2.0 * h);
                let d2 = (after.legs[i].d1 - before.legs[i].d1) / (2.0 * h);
                let d3 = (after.legs[i].d2 - before.legs[i].d2) / (2.0 * h);
                let l = &here.legs[i];
                assert!(
                    (l.d1 - d1).abs() <= 1e-7 * (1.0 + d1.abs()),
                    "rho' {} vs {d1}",
                    l.d1
                );
                assert!(
                    (l.d2 - d2).abs() <= 1e-6 * (1.0 + d2.abs()),
                    "rho'' {} vs {d2}",
                    l.d2
                );
                assert!(
                    (l.d3 - d3).abs() <= 1e-5 * (1.0 + d3.abs()),
                    "rho''' {} vs {d3}",
                    l.d3
                );
            }
        }
    }
}

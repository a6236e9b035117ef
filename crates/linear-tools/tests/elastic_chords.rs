//! The coupled model's chords relaxed into the links' axial springs for linear analyses at
//! rest (`LinearHints::chord_compliance`, crates/dynamics/src/coupled/elastic.rs), checked
//! against what does not depend on it:
//! * the mass matrix it gives for the model's own coordinates is the coupled model's: times
//!   the exact input columns of the rigid model's linearisation (unit slider forces, point
//!   forces), it gives back the generalized forces of those loads;
//! * stiff chords (`EA` x 1e8) give back the rigid model's modes;
//! * away from rest the model keeps its rigid chords (and says so);
//! * a point force's static response: the platform moves by the chords' compliance `K_d^-1`
//!   (from `G` and `EA / l`, computed here from the geometry), the sliders not at all.
//!
//! The external eigen-analysis (axially elastic ANCF links) is in `crates/linear/tests/modes_validation.rs`.

use std::sync::Arc;

use flexprr_control::{Actuator, IdealForce, Pid};
use flexprr_dynamics::{
    Actuation, CoupledOptions, CoupledSystem, Machine, ModalDamping, SceneModel, paper,
};
use flexprr_kinematics::{Circle, Line, Pose, Trajectory};
use flexprr_linear::{Axis, Input, Output, linearize, modes};
use nalgebra::{DMatrix, Matrix3, Point2, Vector2, Vector3};

const EA: f64 = paper::YOUNGS_MODULUS * paper::THICKNESS * paper::HEIGHT;

fn machine() -> Arc<Machine> {
    Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap())
}

fn pose() -> Pose {
    Pose::new(-0.07, 0.03, 40f64.to_radians())
}

/// The coupled model at rest at `pose()`, sliders locked or on a PD servo, with `axial`
/// given as the links' `EA` (or rigid chords).
fn coupled(servo: bool, axial: Option<f64>) -> CoupledSystem {
    let rest: Arc<dyn Trajectory + Send + Sync> =
        Arc::new(Line::new(pose(), Vector3::zeros(), 0.0).unwrap());
    let options = CoupledOptions {
        axial_stiffness: axial.map(|k| [k; 3]),
        ..CoupledOptions::full()
    };
    let model = CoupledSystem::new(machine(), rest, ModalDamping::none(), options).unwrap();
    if !servo {
        return model;
    }
    let force: Arc<dyn Actuator> = Arc::new(IdealForce);
    let actuation = Actuation {
        controller: Arc::new(Pid::pd(2.0e5, 400.0, true, 0.0).unwrap()),
        actuators: [force.clone(), force.clone(), force],
    };
    model.with_actuation(actuation, 0.0).unwrap()
}

/// The point forces of the checks: three places on each link.
fn point_forces() -> Vec<Input> {
    (0..3)
        .flat_map(|link| [0.2, 0.5, 0.7].map(|xi| Input::PointForce { link, xi }))
        .collect()
}

/// The chord of link `i` at rest at `pose()` with sliders `rho`: its slider joint `B`,
/// direction `e` (from `B` to the platform joint `C`), normal `n` and `C - p`.
fn chord(
    m: &Machine,
    rho: &[f64; 3],
    i: usize,
) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>, Vector2<f64>) {
    let p = pose();
    let leg = &m.geometry.legs[i];
    let u = leg.guide.direction.into_inner();
    let b = leg.guide.anchor.coords + rho[i] * u;
    let (s, c) = p.phi.sin_cos();
    let a = leg.attachment;
    let r = Vector2::new(c * a.x - s * a.y, s * a.x + c * a.y);
    let joint = Vector2::new(p.x, p.y) + r;
    let e = (joint - b).normalize();
    (b, e, Vector2::new(-e.y, e.x), r)
}

#[test]
fn the_relaxed_mass_is_the_coupled_models_own() {
    let m = machine();
    let mut model = coupled(true, Some(EA));
    let y = model.initial_state();
    let cc = model
        .chord_compliance(0.0, &y)
        .unwrap()
        .expect("at rest with EA");
    let mut rigid = coupled(true, None);
    let mut inputs: Vec<Input> = (0..3).map(Input::SliderForce).collect();
    inputs.extend(point_forces());
    let outputs: Vec<Output> = [Axis::X, Axis::Y, Axis::Phi]
        .into_iter()
        .map(Output::Platform)
        .collect();
    let lin = linearize(&mut rigid, 0.0, &y, &inputs, &outputs).unwrap();
    assert!(!lin.elastic_chords);
    let n = lin.coordinates;
    let modes = m.total_modes();
    assert_eq!(n, modes + 3);
    // dp/drho of the rigid chords, from the model's own platform outputs.
    let p_of_rho = |q: usize, i: usize| lin.c[(q, modes + i)];
    let rho = model.snapshot(0.0, &y).unwrap().sliders.map(|s| s.position);
    let mut worst = 0.0_f64;
    for (col, input) in inputs.iter().enumerate() {
        // Expected generalized forces of the unit load.
        let mut expected = vec![0.0; n];
        match *input {
            Input::SliderForce(i) => expected[modes + i] = 1.0,
            Input::PointForce { link, xi } => {
                let offset = m.mode_offset(link);
                for k in 0..m.links[link].modes() {
                    expected[offset + k] = m.links[link].basis.eval(k, xi)[0];
                }
                let (_, _, normal, r) = chord(&m, &rho, link);
                let joint_normal =
                    Vector3::new(normal.x, normal.y, -r.y * normal.x + r.x * normal.y);
                for i in 0..3 {
                    let u = m.geometry.legs[i].guide.direction.into_inner();
                    let through_platform: f64 =
                        (0..3).map(|q| joint_normal[q] * p_of_rho(q, i)).sum();
                    let own = if i == link {
                        (1.0 - xi) * normal.dot(&u)
                    } else {
                        0.0
                    };
                    expected[modes + i] = own + xi * through_platform;
                }
            }
            _ => unreachable!("only forces are applied here"),
        }
        for row in 0..n {
            let force: f64 = (0..n)
                .map(|k| cc.mass[(row, k)] * lin.b[(n + k, col)])
                .sum();
            let scale = expected.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
            worst = worst.max((force - expected[row]).abs() / scale);
        }
    }
    println!("mass x exact input columns against the loads' generalized forces: {worst:.2e}");
    assert!(worst < 1e-9, "{worst}");
}

/// The frequencies (Hz) of the linear model of `model` at its initial state, below 5 kHz.
fn frequencies(model: &mut dyn SceneModel) -> (Vec<f64>, bool) {
    let y = model.initial_state();
    let lin = linearize(model, 0.0, &y, &[], &[]).unwrap();
    let found = modes(&lin).unwrap();
    (
        found
            .iter()
            .map(|m| m.frequency_hz)
            .filter(|f| *f < 5e3)
            .collect(),
        lin.elastic_chords,
    )
}

#[test]
fn stiff_chords_give_back_the_rigid_model() {
    for servo in [false, true] {
        let (rigid, relaxed_rigid) = frequencies(&mut coupled(servo, None));
        let (stiff, relaxed) = frequencies(&mut coupled(servo, Some(1e8 * EA)));
        let (elastic, _) = frequencies(&mut coupled(servo, Some(EA)));
        assert!(!relaxed_rigid && relaxed);
        assert_eq!(rigid.len(), stiff.len(), "{rigid:?} {stiff:?}");
        let worst = rigid
            .iter()
            .zip(&stiff)
            .map(|(a, b)| (a - b).abs() / a)
            .fold(0.0, f64::max);
        let change = rigid
            .iter()
            .zip(&elastic)
            .map(|(a, b)| (a - b).abs() / a)
            .fold(0.0, f64::max);
        println!(
            "servo {servo}: EA x 1e8 against rigid chords {worst:.1e}; the real EA changes them by {change:.1e}"
        );
        assert!(worst < 1e-7, "{worst}");
        // The real chords do move the modes: the check above is not vacuous.
        assert!(change > 1e-4, "{change}");
    }
}

#[test]
fn away_from_rest_the_chords_stay_rigid() {
    let circle: Arc<dyn Trajectory + Send + Sync> = Arc::new(
        Circle::new(Point2::new(-0.05, 0.0), 0.05, 20.0, 45f64.to_radians(), 0.0).unwrap(),
    );
    let options = CoupledOptions {
        axial_stiffness: Some([EA; 3]),
        ..CoupledOptions::full()
    };
    let mut model = CoupledSystem::new(machine(), circle, ModalDamping::none(), options).unwrap();
    let y = model.initial_state();
    assert!(model.chord_compliance(0.0, &y).unwrap().is_none());
    let lin = linearize(&mut model, 0.0, &y, &[], &[]).unwrap();
    assert!(!lin.elastic_chords);
    assert_eq!(lin.a.nrows(), y.len());
}

#[test]
fn a_point_force_moves_the_platform_by_the_chords_compliance() {
    let m = machine();
    let mut model = coupled(false, Some(EA));
    let y = model.initial_state();
    let rho = model.snapshot(0.0, &y).unwrap().sliders.map(|s| s.position);
    let inputs = point_forces();
    let outputs: Vec<Output> = [Axis::X, Axis::Y, Axis::Phi]
        .into_iter()
        .map(Output::Platform)
        .collect();
    let lin = linearize(&mut model, 0.0, &y, &inputs, &outputs).unwrap();
    assert!(lin.elastic_chords);
    // Static gain -C A^-1 B + D.
    let a = DMatrix::from_fn(lin.a.nrows(), lin.a.ncols(), |i, j| lin.a[(i, j)]);
    let b = DMatrix::from_fn(lin.b.nrows(), lin.b.ncols(), |i, j| lin.b[(i, j)]);
    let c = DMatrix::from_fn(lin.c.nrows(), lin.c.ncols(), |i, j| lin.c[(i, j)]);
    let gain = -(&c * a.lu().solve(&b).unwrap());
    // The chords' stiffness from the geometry: G rows e_i^T dC_i/dp, springs EA / l.
    let mut g = Matrix3::zeros();
    for i in 0..3 {
        let (_, e, _, r) = chord(&m, &rho, i);
        g.set_row(
            i,
            &Vector3::new(e.x, e.y, -r.y * e.x + r.x * e.y).transpose(),
        );
    }
    let k = g.transpose() * (EA / paper::LINK_LENGTH) * g;
    let compliance = k.try_inverse().unwrap();
    let mut worst = 0.0_f64;
    for (col, input) in inputs.iter().enumerate() {
        let Input::PointForce { link, xi } = *input else {
            unreachable!()
        };
        let (_, _, n, r) = chord(&m, &rho, link);
        // The link passes xi of the force to its platform joint, along its normal.
        let wrench = xi * Vector3::new(n.x, n.y, -r.y * n.x + r.x * n.y);
        let expected = compliance * wrench;
        for q in 0..3 {
            let scale = expected.amax();
            worst = worst.max((gain[(q, col)] - expected[q]).abs() / scale);
        }
    }
    println!("static platform compliance against G^T (EA/l) G: {worst:.2e}");
    assert!(worst < 1e-8, "{worst}");
}

#[test]
fn the_scene_key_keeps_the_chords_rigid_and_only_the_coupled_model_takes_it() {
    let base = format!("{}/configs/coupled_f20.toml", WORKSPACE);
    let text = std::fs::read_to_string(&base).unwrap();
    let with = |coupling: &str, chords: &str| {
        text.replace(
            "coupling = \"coupled\"",
            &format!("coupling = \"{coupling}\"\nchords = \"{chords}\""),
        )
    };
    let rigid =
        flexprr_scene::Scene::from_text("rigid.toml", "rigid", &with("coupled", "rigid")).unwrap();
    assert!(rigid.rigid_chords);
    let elastic =
        flexprr_scene::Scene::from_text("elastic.toml", "elastic", &with("coupled", "elastic"))
            .unwrap();
    assert!(!elastic.rigid_chords);
    let count = |scene: &flexprr_scene::Scene| {
        flexprr_linear_tools::machine_modes::machine_modes(
            scene,
            flexprr_linear_tools::linear::OperatingPoint::Rest(pose()),
            3,
            &flexprr_linear::Settings::default(),
        )
        .unwrap()
        .modes
        .len()
    };
    assert_eq!(count(&rigid), 9, "nine bending modes on rigid chords");
    assert_eq!(
        count(&elastic),
        21,
        "and three platform modes and each link's three axial modes on elastic ones"
    );
    let refused =
        flexprr_scene::Scene::from_text("nonlinear.toml", "nonlinear", &with("nonlinear", "rigid"))
            .unwrap_err()
            .to_string();
    println!("{refused}");
    assert!(
        refused.contains("model.chords") && refused.contains("coupled model"),
        "{refused}"
    );
}

/// The workspace root: the tests read its configs and validation data.
const WORKSPACE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

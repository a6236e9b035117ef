//! The actuated coupled model (sliders as degrees of freedom under PD control with the rigid
//! feedforward, docs/control.md) against an independent flexible-multibody model: Exudyn,
//! ANCF cable links, slider bodies on prismatic joints, the same PD law as a spring-damper to
//! a point moving with `rho_ref` plus the feedforward as a load (`validation/exudyn_servo.py`,
//! data in `validation/data/servo_f*.csv`, converged to 0.03 % in mesh and step).
//!
//! Targets of the control issue, over 0-0.2 s at 10 and 20 Hz: mid-point deflections within
//! 2 % and slider errors within 5 % (relative L2 over all links).

use std::sync::Arc;

use flexprr_control::{Actuator, IdealForce, Pid};
use flexprr_dynamics::{
    Actuation, CoupledOptions, CoupledSystem, ModalDamping, NonlinearOptions, NonlinearSystem,
    SceneModel, paper,
};
use flexprr_integrators::{Integrator, Options, Rk45};
use flexprr_kinematics::Trajectory;

/// One external history: columns of the CSV by name.
struct External {
    names: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl External {
    fn load(name: &str) -> External {
        let path = format!("{}/validation/data/{name}.csv", WORKSPACE);
        let (names, rows) = flexprr_testkit::csv::read_numeric(std::path::Path::new(&path));
        External { names, rows }
    }
    fn column(&self, name: &str) -> Vec<f64> {
        let k = self
            .names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("column {name} missing"));
        self.rows.iter().map(|r| r[k]).collect()
    }
}

fn rel_l2(ours: &[Vec<f64>], theirs: &[Vec<f64>]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (a, b) in ours.iter().zip(theirs) {
        for (x, y) in a.iter().zip(b) {
            num += (x - y) * (x - y);
            den += y * y;
        }
    }
    (num / den).sqrt()
}

/// The control of `validation/exudyn_servo.py`: PD `kp = 2e5 N/m`, `kd = 400 N s/m` with
/// the rigid feedforward, ideal force actuators.
fn actuation() -> Actuation {
    let force: Arc<dyn Actuator> = Arc::new(IdealForce);
    Actuation {
        controller: Arc::new(Pid::pd(2.0e5, 400.0, true, 0.0).unwrap()),
        actuators: [force.clone(), force.clone(), force],
    }
}

/// The servo scene of `validation/exudyn_servo.py` with the coupled model: the paper's
/// machine and circle at `f`.
fn servo(f: f64) -> Box<dyn SceneModel> {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let trajectory: Arc<dyn Trajectory + Send + Sync> = Arc::new(paper::trajectory(f).unwrap());
    let actuation = actuation();
    Box::new(
        CoupledSystem::new(
            machine,
            trajectory,
            ModalDamping::none(),
            CoupledOptions::full(),
        )
        .unwrap()
        .with_actuation(actuation, 0.0)
        .unwrap(),
    )
}

/// The same with geometrically nonlinear links of `elements` co-rotational elements.
fn servo_nonlinear(f: f64, elements: usize) -> Box<dyn SceneModel> {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let trajectory: Arc<dyn Trajectory + Send + Sync> = Arc::new(paper::trajectory(f).unwrap());
    let options = NonlinearOptions {
        elements,
        ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
    };
    Box::new(
        NonlinearSystem::new(machine, trajectory, options)
            .unwrap()
            .with_actuation(actuation(), 0.0)
            .unwrap(),
    )
}

fn compare(f: u32, mut system: Box<dyn SceneModel>) -> (f64, f64) {
    let external = External::load(&format!("servo_f{f}"));
    let t = external.column("t_s");
    let y0 = system.initial_state();
    let solution = Rk45::new(Options::default().rtol(1e-9).atol(1e-12))
        .solve(system.as_mut(), 0.0, &y0, &t)
        .expect("solves");
    // Mid-point deflections, and the slider errors rho_ref - rho with rho_ref from the
    // commanded inverse kinematics.
    let (mut w, mut e) = (vec![Vec::new(); 3], vec![Vec::new(); 3]);
    for (k, &tk) in t.iter().enumerate() {
        let snapshot = system.snapshot(tk, solution.y(k)).expect("snapshot");
        let rigid = system
            .machine()
            .geometry
            .inverse_kinematics_unchecked(&snapshot.nominal)
            .expect("commanded inverse kinematics");
        for i in 0..3 {
            let deflection = system.deflection(tk, i, 0.5, solution.y(k)).expect("w");
            w[i].push(deflection);
            e[i].push(rigid.legs[i].rho - snapshot.sliders[i].position);
        }
    }
    let w_ext: Vec<Vec<f64>> = (1..=3)
        .map(|i| external.column(&format!("w_mid_{i}_m")))
        .collect();
    let e_ext: Vec<Vec<f64>> = (1..=3)
        .map(|i| external.column(&format!("slider_error_{i}_m")))
        .collect();
    (rel_l2(&w, &w_ext), rel_l2(&e, &e_ext))
}

#[test]
fn servo_model_matches_external_at_20_hz() {
    let (w, e) = compare(20, servo(20.0));
    println!(
        "20 Hz: mid-point deflections {:.2} %, slider errors {:.2} %",
        100.0 * w,
        100.0 * e
    );
    assert!(w < 0.02, "deflections {w}");
    assert!(e < 0.05, "slider errors {e}");
}

#[test]
fn servo_model_matches_external_at_10_hz() {
    let (w, e) = compare(10, servo(10.0));
    println!(
        "10 Hz: mid-point deflections {:.2} %, slider errors {:.2} %",
        100.0 * w,
        100.0 * e
    );
    assert!(w < 0.02, "deflections {w}");
    assert!(e < 0.05, "slider errors {e}");
}

#[test]
fn nonlinear_servo_model_matches_external_at_20_hz() {
    let (w, e) = compare(20, servo_nonlinear(20.0, 16));
    println!(
        "nonlinear, 16 elements, 20 Hz: mid-point deflections {:.2} %, slider errors {:.2} %",
        100.0 * w,
        100.0 * e
    );
    assert!(w < 0.02, "deflections {w}");
    assert!(e < 0.05, "slider errors {e}");
}

/// The workspace root: the tests read its configs and validation data.
const WORKSPACE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

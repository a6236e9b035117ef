//! The coupled model against an independent flexible-multibody model (Exudyn: ANCF cable links,
//! axially elastic, sliders driven along their inverse-kinematics path, free rigid platform
//! pinned to the links; `validation/` in this repository, data in `validation/data/`).
//!
//! Checks, over 0-0.2 s at 10 and 20 Hz: relative L2 error of the mid-point deflections (all
//! links together), relative RMS error of the platform deviation from the nominal path and of
//! the axial forces at both ends; and that the consistent KED model, compared the same way,
//! stays near the figures of model.md section 8 (so the comparison is set up alike).

use std::sync::Arc;

use flexprr_dynamics::{
    CoupledOptions, CoupledSystem, Formulation, ModalDamping, ModalSystem, paper,
};
use flexprr_integrators::{Integrator, Options, Rk45};

/// One external history: columns of the CSV by name.
struct External {
    names: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl External {
    fn load(frequency: u32) -> External {
        let path = format!("{}/validation/data/coupled_f{frequency}.csv", WORKSPACE);
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
    let mut num = 0.0;
    let mut den = 0.0;
    for (a, b) in ours.iter().zip(theirs) {
        for (x, y) in a.iter().zip(b) {
            num += (x - y) * (x - y);
            den += y * y;
        }
    }
    (num / den).sqrt()
}

/// Relative errors against the external model (all over 0-0.2 s unless said otherwise).
struct Comparison {
    /// Mid-point deflections, all links together: coupled model.
    w_coupled: f64,
    /// The same for the consistent KED model.
    w_ked: f64,
    /// Platform deviation `dx, dy, dphi` (with the quasi-static axial stretch).
    pose: [f64; 3],
    /// Axial force at B, per link.
    force_b: [f64; 3],
    /// Axial force at C, per link.
    force_c: [f64; 3],
    /// Axial forces at both ends of all links after the external model's axial start-up
    /// ringing (~1.9 kHz, damped in its model) has died out, t >= 20 ms.
    force_settled: f64,
}

/// First sample at or after 20 ms.
const SETTLED: usize = 80;

fn compare(frequency: u32) -> Comparison {
    let ext = External::load(frequency);
    let times = ext.column("t_s");
    assert_eq!(times.len(), 801, "0-0.2 s every 2.5e-4 s");
    assert!((times[SETTLED] - 0.02).abs() < 1e-9);
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let trajectory = Arc::new(paper::trajectory(f64::from(frequency)).unwrap());
    let opts = Options::default().rtol(1e-8).atol(1e-12);
    let mut coupled = CoupledSystem::new(
        machine.clone(),
        trajectory.clone(),
        ModalDamping::none(),
        CoupledOptions {
            axial_stiffness: Some([paper::YOUNGS_MODULUS * paper::THICKNESS * paper::HEIGHT; 3]),
            ..CoupledOptions::full()
        },
    )
    .unwrap();
    let y0 = coupled.initial_state();
    let sol = Rk45::new(opts.clone())
        .solve(&mut coupled, 0.0, &y0, &times)
        .unwrap();
    let mut ked = ModalSystem::new(
        machine,
        trajectory,
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap();
    let ked_sol = Rk45::new(opts).solve(&mut ked, 0.0, &y0, &times).unwrap();
    let mut w = vec![Vec::new(); 3];
    let mut w_ked = vec![Vec::new(); 3];
    let mut pose = vec![Vec::new(); 3];
    let mut fb = vec![Vec::new(); 3];
    let mut fc = vec![Vec::new(); 3];
    for (k, &t) in times.iter().enumerate() {
        let out = coupled.output(t, sol.y(k)).unwrap();
        let d = out.pose_deviation_with_stretch();
        for i in 0..3 {
            w[i].push(out.midpoint_deflection[i]);
            let range = ked.link_range(i);
            w_ked[i].push(ked.machine().links[i].deflection(&ked_sol.y(k)[range], 0.5));
            pose[i].push(d[i]);
            fb[i].push(out.axial_force_b[i]);
            fc[i].push(out.axial_force_c[i]);
        }
    }
    let ext_w: Vec<Vec<f64>> = (1..=3)
        .map(|i| ext.column(&format!("w_mid_{i}_m")))
        .collect();
    let ext_pose = ["dx_m", "dy_m", "dphi_rad"].map(|c| ext.column(c));
    let ext_b: Vec<Vec<f64>> = (1..=3).map(|i| ext.column(&format!("P_B_{i}_N"))).collect();
    let ext_c: Vec<Vec<f64>> = (1..=3).map(|i| ext.column(&format!("P_C_{i}_N"))).collect();
    let settled =
        |v: &[Vec<f64>]| -> Vec<Vec<f64>> { v.iter().map(|x| x[SETTLED..].to_vec()).collect() };
    let ours_forces: Vec<Vec<f64>> = settled(&fb).into_iter().chain(settled(&fc)).collect();
    let ext_forces: Vec<Vec<f64>> = settled(&ext_b).into_iter().chain(settled(&ext_c)).collect();
    let c = Comparison {
        w_coupled: rel_l2(&w, &ext_w),
        w_ked: rel_l2(&w_ked, &ext_w),
        pose: std::array::from_fn(|i| rel_l2(&pose[i..=i], &ext_pose[i..=i])),
        force_b: std::array::from_fn(|i| rel_l2(&fb[i..=i], &ext_b[i..=i])),
        force_c: std::array::from_fn(|i| rel_l2(&fc[i..=i], &ext_c[i..=i])),
        force_settled: rel_l2(&ours_forces, &ext_forces),
    };
    println!(
        "f = {frequency} Hz: w coupled {:.4}, w KED consistent {:.4}, pose {:.4?}, P_B {:.4?}, P_C {:.4?}, forces after 20 ms {:.4}",
        c.w_coupled, c.w_ked, c.pose, c.force_b, c.force_c, c.force_settled
    );
    c
}

/// The acceptance figures, with the deflection bound tightened to keep regressions
/// visible (the model is at 0.7 % / 1.3 %; the issue asks for 5 % / 10 %).
fn check(c: &Comparison, w_bound: f64, ked_section8: f64) {
    assert!(
        c.w_coupled < w_bound,
        "coupled deflections: {}",
        c.w_coupled
    );
    // The consistent KED model compared the same way lands on model.md section 8's figure.
    assert!(
        (c.w_ked - ked_section8).abs() < 0.03,
        "KED consistent: {} vs section 8's {ked_section8}",
        c.w_ked
    );
    for (name, errors) in [("pose", c.pose), ("P_B", c.force_b), ("P_C", c.force_c)] {
        for (i, e) in errors.iter().enumerate() {
            assert!(*e < 0.15, "{name} component/link {}: {e}", i + 1);
        }
    }
    assert!(
        c.force_settled < 0.03,
        "forces after 20 ms: {}",
        c.force_settled
    );
}

#[test]
fn coupled_model_matches_external_at_10_hz() {
    check(&compare(10), 0.02, 0.09);
}

#[test]
fn coupled_model_matches_external_at_20_hz() {
    check(&compare(20), 0.04, 0.47);
}

/// The workspace root: the tests read its configs and validation data.
const WORKSPACE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

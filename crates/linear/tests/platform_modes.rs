//! The whole locked machine's modes against an exact reference (issue 35, item 3;
//! docs/linear.md, "Validation"): the platform, rigid, on three links that are exact
//! Euler-Bernoulli beams transversely (pinned at both ends) and exact rods axially (fixed at
//! the slider), its natural frequencies found by the Wittrick-Williams algorithm
//! (W. H. Wittrick and F. W. Williams, "A general algorithm for computing natural frequencies
//! of elastic structures", *Q. J. Mech. Appl. Math.* 24(3), 1971, pp. 263-284): the number
//! of natural frequencies below `omega` is `J0(omega) + s{K(omega)}`, with `K` the exact
//! dynamic stiffness of the platform's three coordinates,
//!
//! ```text
//! K(w) = -w^2 diag(m_p, m_p, I_p) + sum_i [k_ax(w) g_i g_i^T + k_tr(w) h_i h_i^T]
//! k_ax = EA beta cot(beta l),                 beta = w sqrt(rho / E)     (rod fixed at B)
//! k_tr = -EI lambda^3 (coth(lambda l) - cot(lambda l)) / 2,  lambda^4 = rho A w^2 / EI
//! ```
//!
//! (`k_tr` the force that moves the platform end of a beam pinned at both ends, without
//! moment, transversely: `-w^2 m / 3` at low frequency, a bar turning about `B`), `g_i`,
//! `h_i` the platform-joint Jacobians' transposes applied to the chord direction and normal,
//! `s{K}` the number of negative eigenvalues of `K`, and `J0` the natural frequencies of the
//! links with both ends held (`beta l = k pi` axially, `lambda l = k pi` in bending).
//!
//! The coupled model with elastic chords (the links' axial inertia distributed in
//! fixed-fixed axial modes) and 8 sine modes per link, and the geometrically nonlinear model
//! with 32 elements per link, against it at four poses: every mode below 4.5 kHz (the nine
//! lowest bending families' first three, the platform's three, the 4th and 5th families).

use std::f64::consts::PI;
use std::sync::Arc;

use flexprr_dynamics::{
    CoupledOptions, CoupledSystem, Machine, ModalDamping, NonlinearOptions, NonlinearSystem,
    SceneModel, paper,
};
use flexprr_kinematics::{Line, PlatformMotion, Pose, Trajectory};
use flexprr_linear::{linearize, modes};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Poses at rest (m, m, deg).
const POSES: [(f64, f64, f64); 4] = [
    (0.0, 0.0, 45.0),
    (-0.05, 0.0, 45.0),
    (-0.1, 0.0, 45.0),
    (-0.05, 0.05, 30.0),
];

/// Modes compared: all below this (Hz).
const UP_TO_HZ: f64 = 4500.0;

fn rest(at: Pose) -> Arc<dyn Trajectory + Send + Sync> {
    Arc::new(Line::new(at, Vector3::zeros(), 0.0).unwrap())
}

/// The section's constants: `EA`, `EI`, `rho A`, `l`.
fn section() -> (f64, f64, f64, f64) {
    let (e, rho, h, t) = (
        paper::YOUNGS_MODULUS,
        paper::DENSITY,
        paper::HEIGHT,
        paper::THICKNESS,
    );
    (
        e * h * t,
        e * h * t.powi(3) / 12.0,
        rho * h * t,
        paper::LINK_LENGTH,
    )
}

/// Each link's `g_i = J_i^T e_i` and `h_i = J_i^T n_i` at `pose`.
fn joints(machine: &Machine, pose: Pose) -> [(Vector3<f64>, Vector3<f64>); 3] {
    let state = machine
        .geometry
        .inverse_kinematics(&PlatformMotion::at_rest(pose))
        .unwrap();
    let (sin, cos) = pose.phi.sin_cos();
    std::array::from_fn(|i| {
        let leg = &machine.geometry.legs[i];
        let u = leg.guide.direction.into_inner();
        let b = leg.guide.anchor.coords + state.legs[i].rho * u;
        let a = leg.attachment;
        let r = nalgebra::Vector2::new(cos * a.x - sin * a.y, sin * a.x + cos * a.y);
        let c = nalgebra::Vector2::new(pose.x, pose.y) + r;
        let e = (c - b).normalize();
        let n = nalgebra::Vector2::new(-e.y, e.x);
        let jt = |v: nalgebra::Vector2<f64>| Vector3::new(v.x, v.y, r.x * v.y - r.y * v.x);
        (jt(e), jt(n))
    })
}

/// The number of natural frequencies of the locked machine below `omega` (rad/s).
fn count_below(machine: &Machine, joints: &[(Vector3<f64>, Vector3<f64>); 3], omega: f64) -> usize {
    let (ea, ei, rho_a, l) = section();
    let beta = omega * (rho_a / ea).sqrt();
    let lambda = (rho_a * omega * omega / ei).powf(0.25);
    let k_ax = ea * beta / (beta * l).tan();
    let (bl, ll) = (beta * l, lambda * l);
    let k_tr = -ei * lambda.powi(3) * (1.0 / ll.tanh() - 1.0 / ll.tan()) / 2.0;
    let w2 = omega * omega;
    let mut k = Matrix3::from_diagonal(&Vector3::new(
        -w2 * machine.platform_mass,
        -w2 * machine.platform_mass,
        -w2 * machine.platform_inertia,
    ));
    for (g, h) in joints {
        k += k_ax * g * g.transpose() + k_tr * h * h.transpose();
    }
    let negative = SymmetricEigen::new(k)
        .eigenvalues
        .iter()
        .filter(|v| **v < 0.0)
        .count();
    let held = 3 * ((bl / PI).floor() as usize + (ll / PI).floor() as usize);
    held + negative
}

/// The exact natural frequencies below `up_to` (Hz), each by bisection on the count.
fn exact_hz(machine: &Machine, pose: Pose, up_to: f64) -> Vec<f64> {
    let joints = joints(machine, pose);
    let top = 2.0 * PI * up_to;
    let total = count_below(machine, &joints, top);
    (1..=total)
        .map(|k| {
            let (mut lo, mut hi) = (1.0, top);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if count_below(machine, &joints, mid) >= k {
                    hi = mid;
                } else {
                    lo = mid;
                }
                if hi - lo < 1e-12 * hi {
                    break;
                }
            }
            0.5 * (lo + hi) / (2.0 * PI)
        })
        .collect()
}

/// The model's modes below `up_to` (Hz).
fn model_hz(model: &mut dyn SceneModel, up_to: f64) -> Vec<f64> {
    let y0 = model.initial_state();
    let lin = linearize(model, 0.0, &y0, &[], &[]).unwrap();
    modes(&lin)
        .unwrap()
        .iter()
        .map(|m| m.frequency_hz)
        .filter(|f| *f < up_to)
        .collect()
}

/// The largest relative difference of `found` from `exact`, mode by mode (both sorted).
fn worst(found: &[f64], exact: &[f64]) -> f64 {
    assert_eq!(found.len(), exact.len(), "{found:?}\n{exact:?}");
    found
        .iter()
        .zip(exact)
        .map(|(f, e)| (f / e - 1.0).abs())
        .fold(0.0, f64::max)
}

#[test]
fn whole_machine_modes_match_the_exact_platform_on_beams_and_rods() {
    let (ea, ..) = section();
    for p in POSES {
        let pose = Pose::new(p.0, p.1, p.2.to_radians());
        // The reference's own check: its lowest family is the pinned-pinned links'.
        let exact = exact_hz(
            &paper::machine(3, paper::YOUNGS_MODULUS).unwrap(),
            pose,
            UP_TO_HZ,
        );
        let fine = Arc::new(paper::machine(8, paper::YOUNGS_MODULUS).unwrap());
        let options = CoupledOptions {
            axial_stiffness: Some([ea; 3]),
            ..CoupledOptions::full()
        };
        let mut coupled =
            CoupledSystem::new(fine, rest(pose), ModalDamping::none(), options).unwrap();
        let coupled_hz = model_hz(&mut coupled, UP_TO_HZ);
        let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
        let nl_options = NonlinearOptions {
            elements: 32,
            ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
        };
        let mut nonlinear = NonlinearSystem::new(machine, rest(pose), nl_options).unwrap();
        nonlinear.start_at(0.0).unwrap();
        let nonlinear_hz = model_hz(&mut nonlinear, UP_TO_HZ);
        let (c, n) = (worst(&coupled_hz, &exact), worst(&nonlinear_hz, &exact));
        println!(
            "pose {p:?}: {} modes below {UP_TO_HZ} Hz, exact {:.2?} Hz; coupled (8 modes, elastic chords) within {:.4} %, nonlinear (32 elements) within {:.4} %",
            exact.len(),
            &exact[9..],
            100.0 * c,
            100.0 * n
        );
        assert!((exact[0] / 116.39 - 1.0).abs() < 1e-3, "{}", exact[0]);
        assert!(c < 5e-4, "coupled: {c}");
        assert!(n < 5e-4, "nonlinear: {n}");
    }
}

/// The shipped basis (3 sine modes per link, the 4th family left out from about 1862 Hz):
/// the modes clear of it (below 1862 / 1.5 Hz, what `flexprr modes` calls complete) within
/// 0.01 % of the exact machine, the platform modes between within 1 % (the 4th and 5th
/// families' dynamics missing), at four poses.
#[test]
fn the_shipped_basis_is_right_clear_of_its_first_missing_family() {
    let (ea, ..) = section();
    let cut = 16.0 * 116.39;
    for p in &POSES {
        let pose = Pose::new(p.0, p.1, p.2.to_radians());
        let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
        let exact = exact_hz(&machine, pose, cut);
        let options = CoupledOptions {
            axial_stiffness: Some([ea; 3]),
            ..CoupledOptions::full()
        };
        let mut coupled =
            CoupledSystem::new(machine, rest(pose), ModalDamping::none(), options).unwrap();
        let found = model_hz(&mut coupled, cut);
        let clear = |f: &&f64| **f < cut / 1.5;
        let (found_clear, exact_clear): (Vec<f64>, Vec<f64>) = (
            found.iter().filter(clear).copied().collect(),
            exact.iter().filter(clear).copied().collect(),
        );
        let w = worst(&found_clear, &exact_clear);
        // Between: each of the model's modes against the nearest exact one.
        let near = found
            .iter()
            .filter(|f| !clear(f))
            .map(|f| {
                exact
                    .iter()
                    .map(|e| (f / e - 1.0).abs())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        println!(
            "pose {p:?}, 3 modes per link: {} modes below {:.0} Hz within {:.5} %, the rest below {cut:.0} Hz within {:.3} %",
            found_clear.len(),
            cut / 1.5,
            100.0 * w,
            100.0 * near
        );
        assert!(w < 1e-4, "{w}");
        assert!(near < 1e-2, "{near}");
    }
}

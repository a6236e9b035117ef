//! Sine basis (the paper's): modal integrals against their closed forms, the paper's
//! frequencies, the exact axially loaded frequencies and an external FE code's values.

use faer::Mat;
use flexprr_beam::{
    AxialLoad, Coupling, FrequencySolver, ModalIntegrals, ModeState, SineBasis, UniformSection,
    frequencies,
};
use std::f64::consts::PI;

/// The paper's link (model.md section 2).
const LENGTH: f64 = 0.2;
const THICKNESS: f64 = 0.002;
const HEIGHT: f64 = 0.03;
const DENSITY: f64 = 2770.0;

fn ei(e: f64) -> f64 {
    e * HEIGHT * THICKNESS.powi(3) / 12.0
}
fn rho_a() -> f64 {
    DENSITY * THICKNESS * HEIGHT
}
fn paper_link(e: f64, r: usize) -> ModalIntegrals {
    let section = UniformSection::rectangle(e, DENSITY, THICKNESS, HEIGHT).unwrap();
    ModalIntegrals::compute(&SineBasis::new(r).unwrap(), &section, LENGTH).unwrap()
}
/// Exact pinned-pinned frequency of mode j (1-based) under uniform axial force P (Hz).
fn exact_frequency(e: f64, j: usize, force: f64) -> f64 {
    let k = j as f64 * PI / LENGTH;
    let omega2 = (ei(e) * k.powi(4) + force * k * k) / rho_a();
    omega2.sqrt() / (2.0 * PI)
}

fn sign(n: usize) -> f64 {
    if n % 2 == 0 { 1.0 } else { -1.0 }
}

/// Closed forms of the sine-mode integrals (derived by hand in docs/beam.md), j, k 1-based.
fn closed_g(n: usize, j: usize, k: usize) -> f64 {
    let (jf, kf) = (j as f64, k as f64);
    let pi2 = PI * PI;
    match (n, j == k) {
        (0, true) => jf * jf * pi2 / 2.0,
        (0, false) => 0.0,
        (1, true) => jf * jf * pi2 / 4.0,
        (1, false) => {
            jf * kf / 2.0
                * (sign(j + k) - 1.0)
                * (1.0 / (jf - kf).powi(2) + 1.0 / (jf + kf).powi(2))
        }
        (2, true) => jf * jf * pi2 / 6.0 + 0.25,
        (2, false) => jf * kf * sign(j + k) * (1.0 / (jf - kf).powi(2) + 1.0 / (jf + kf).powi(2)),
        _ => unreachable!(),
    }
}

fn assert_matrix(name: &str, got: &Mat<f64>, exact: impl Fn(usize, usize) -> f64, tol: f64) {
    let r = got.nrows();
    for j in 0..r {
        for k in 0..r {
            let e = exact(j, k);
            let scale = e.abs().max((exact(j, j) * exact(k, k)).abs().sqrt());
            assert!(
                (got[(j, k)] - e).abs() <= tol * scale,
                "{name}[{j},{k}] (r = {r}): {} vs {e}",
                got[(j, k)]
            );
        }
    }
}

#[test]
fn modal_integrals_match_closed_forms_for_r_up_to_20() {
    let (e, l) = (7.1e10, LENGTH);
    let m = rho_a() * l;
    for r in 1..=20 {
        let mi = paper_link(e, r);
        assert_eq!(mi.r(), r);
        let delta = |j: usize, k: usize| if j == k { 1.0 } else { 0.0 };
        assert_matrix("M", &mi.mass, |j, k| m / 2.0 * delta(j, k), 1e-13);
        assert_matrix(
            "Kf",
            &mi.stiffness,
            |j, k| ei(e) / l.powi(3) * ((j + 1) as f64 * PI).powi(4) / 2.0 * delta(j, k),
            1e-13,
        );
        for n in 0..3 {
            assert_matrix("G", &mi.g[n], |j, k| closed_g(n, j + 1, k + 1), 1e-13);
        }
        for j in 0..r {
            let jn = j + 1;
            let jpi = jn as f64 * PI;
            let int_psi = (1.0 - sign(jn)) / jpi;
            let int_xi_psi = -sign(jn) / jpi;
            let scale = 1.0 / jpi;
            assert!(
                (mi.int_psi[j] - int_psi).abs() <= 1e-13 * scale,
                "int psi {j}"
            );
            assert!(
                (mi.int_xi_psi[j] - int_xi_psi).abs() <= 1e-13 * scale,
                "int xi psi {j}"
            );
            assert!((mi.mass_psi[j] - m * int_psi).abs() <= 1e-13 * m * scale);
            assert!((mi.mass_xi_psi[j] - m * int_xi_psi).abs() <= 1e-13 * m * scale);
        }
        assert!((mi.total_mass - m).abs() < 1e-14 * m);
        // Symmetric matrices.
        for j in 0..r {
            for k in 0..r {
                assert!(
                    (mi.g[1][(j, k)] - mi.g[1][(k, j)]).abs() <= 1e-15 * mi.g[1][(r - 1, r - 1)]
                );
            }
        }
    }
}

#[test]
fn paper_frequencies_at_both_moduli() {
    for (e, expected) in [
        (7.1e10, [114.786, 459.144, 1033.073]),
        (7.3e10, [116.39, 465.57, 1047.52]),
    ] {
        let mi = paper_link(e, 3);
        for coupling in [Coupling::Full, Coupling::Diagonal] {
            let f = frequencies(&mi, &AxialLoad::default(), coupling).unwrap();
            for (j, want) in expected.iter().enumerate() {
                let got = f.modes[j].frequency_hz;
                // Expected values are given to 3 (or 2) decimals.
                let decimals = if e < 7.2e10 { 5e-4 } else { 5e-3 };
                assert!(
                    (got - want).abs() <= decimals,
                    "E = {e}, mode {}: {got}",
                    j + 1
                );
                assert!((got - exact_frequency(e, j + 1, 0.0)).abs() < 1e-10 * got);
            }
            assert_eq!(f.critical_load_factor, None);
            assert!(!f.is_buckled());
        }
    }
}

#[test]
fn uniform_axial_load_matches_exact_frequencies() {
    let e = 7.1e10;
    let p_cr = PI * PI * ei(e) / (LENGTH * LENGTH);
    assert!((p_cr - 350.4).abs() < 0.05, "Euler load {p_cr}");
    let r = 5;
    let mi = paper_link(e, r);
    for coupling in [Coupling::Full, Coupling::Diagonal] {
        for step in 0..=290 {
            let force = p_cr * (-0.9 + 0.01 * step as f64);
            let f = frequencies(&mi, &AxialLoad::uniform(force), coupling).unwrap();
            for j in 1..=r {
                let exact = exact_frequency(e, j, 0.0)
                    * (1.0 + force * LENGTH * LENGTH / ((j * j) as f64 * PI * PI * ei(e))).sqrt();
                let got = f.modes[j - 1].frequency_hz;
                assert!(
                    ((got - exact) / exact).abs() < 1e-10,
                    "{coupling:?} P = {force}, mode {j}: {got} vs {exact}"
                );
            }
            // Compression buckles at lambda = P_cr / |P|.
            match f.critical_load_factor {
                Some(lambda) if force < 0.0 => {
                    assert!((lambda - p_cr / -force).abs() < 1e-9 * lambda, "{lambda}");
                }
                None if force >= 0.0 => {}
                other => panic!("P = {force}: critical factor {other:?}"),
            }
        }
    }
}

#[test]
fn at_the_euler_load_the_first_mode_is_buckled_not_nan() {
    let e = 7.1e10;
    let p_cr = PI * PI * ei(e) / (LENGTH * LENGTH);
    let mi = paper_link(e, 3);
    for coupling in [Coupling::Full, Coupling::Diagonal] {
        let f = frequencies(&mi, &AxialLoad::uniform(-p_cr), coupling).unwrap();
        assert!(f.is_buckled());
        assert_ne!(f.modes[0].state, ModeState::Stable);
        assert!(f.modes[0].frequency_hz.abs() < 1e-12);
        assert!(
            f.modes
                .iter()
                .all(|m| m.frequency_hz.is_finite() && m.omega_squared.is_finite())
        );
        let lambda = f.critical_load_factor.unwrap();
        assert!((lambda - 1.0).abs() < 1e-9);
        assert_eq!(f.modes[1].state, ModeState::Stable);
        // Beyond the Euler load the first mode is buckled with a negative eigenvalue.
        let f = frequencies(&mi, &AxialLoad::uniform(-1.5 * p_cr), coupling).unwrap();
        assert_eq!(f.modes[0].state, ModeState::Buckled);
        assert!(f.lowest_eigenvalue() < 0.0);
        assert!((f.critical_load_factor.unwrap() - 1.0 / 1.5).abs() < 1e-9);
    }
}

#[test]
fn external_fe_values_at_plus_minus_50_newton() {
    // 2D ANCF cable, 32 elements (model.md section 7).
    let mi = paper_link(7.1e10, 3);
    for (force, reference) in [
        (0.0, [114.786, 459.144, 1033.078]),
        (50.0, [122.702, 467.257, 1041.224]),
        (-50.0, [106.282, 450.885, 1024.868]),
    ] {
        let f = frequencies(&mi, &AxialLoad::uniform(force), Coupling::Full).unwrap();
        for (j, want) in reference.iter().enumerate() {
            let got = f.modes[j].frequency_hz;
            assert!(
                ((got - want) / want).abs() < 1e-4,
                "P = {force}, mode {}: {got}",
                j + 1
            );
        }
    }
}

#[test]
fn geometric_stiffness_is_the_integral_of_the_load() {
    // Kp_jk = int_0^l P(x) psi_j'(x) psi_k'(x) dx with d/dx = (1/l) d/dxi, by the closed forms.
    let mi = paper_link(7.1e10, 4);
    let load = AxialLoad {
        p0: -30.0,
        p1: 120.0,
        p2: -800.0,
    };
    let kp = mi.geometric_stiffness(&load);
    let l = LENGTH;
    let scale = (0..4).map(|j| kp[(j, j)].abs()).fold(0.0, f64::max);
    for j in 0..4 {
        for k in 0..4 {
            let exact = load.p0 / l * closed_g(0, j + 1, k + 1)
                + load.p1 * closed_g(1, j + 1, k + 1)
                + load.p2 * l * closed_g(2, j + 1, k + 1);
            assert!((kp[(j, k)] - exact).abs() < 1e-13 * scale, "{j},{k}");
        }
    }
}

#[test]
fn diagonal_variant_is_the_ratio_of_diagonals_and_keeps_basis_order() {
    // A load whose Kp is not diagonal: full and diagonal differ, diagonal is k_jj/m_jj.
    let mi = paper_link(7.3e10, 3);
    let load = AxialLoad {
        p0: 40.0,
        p1: -500.0,
        p2: 0.0,
    };
    let f = frequencies(&mi, &load, Coupling::Diagonal).unwrap();
    let kp = mi.geometric_stiffness(&load);
    for j in 0..3 {
        let w2 = (mi.stiffness[(j, j)] + kp[(j, j)]) / mi.mass[(j, j)];
        assert!((f.modes[j].omega_squared - w2).abs() < 1e-12 * w2);
        assert_eq!(f.modes[j].mode, j + 1);
    }
    // Full eigenvalues interlace: the lowest is at most the smallest Rayleigh quotient.
    let full = frequencies(&mi, &load, Coupling::Full).unwrap();
    assert!(full.modes[0].omega_squared <= f.modes[0].omega_squared * (1.0 + 1e-12));
    // Sum of eigenvalues = trace of M^-1 K (M diagonal here).
    let trace: f64 = f.modes.iter().map(|m| m.omega_squared).sum();
    let sum: f64 = full.modes.iter().map(|m| m.omega_squared).sum();
    assert!((trace - sum).abs() < 1e-10 * trace);
}

#[test]
fn solver_rejects_bad_input() {
    let mi = paper_link(7.1e10, 3);
    let mut solver = FrequencySolver::new(&mi, Coupling::Full).unwrap();
    let mut out = [0.0; 3];
    assert!(
        solver
            .eigenvalues(Mat::<f64>::zeros(2, 2).as_ref(), &mut out)
            .is_err()
    );
    assert!(
        solver
            .eigenvalues(mi.stiffness.as_ref(), &mut [0.0; 2])
            .is_err()
    );
    let mut bad = mi.stiffness.clone();
    bad[(1, 2)] = f64::NAN;
    assert!(solver.eigenvalues(bad.as_ref(), &mut out).is_err());
    assert!(frequencies(&mi, &AxialLoad::uniform(f64::INFINITY), Coupling::Full).is_err());
    assert!(SineBasis::new(0).is_err());
    assert!(UniformSection::rectangle(-1.0, DENSITY, THICKNESS, HEIGHT).is_err());
    let section = UniformSection::new(1.0, 1.0).unwrap();
    assert!(ModalIntegrals::compute(&SineBasis::new(2).unwrap(), &section, 0.0).is_err());
    assert!(ModalIntegrals::compute(&SineBasis::new(2).unwrap(), &section, f64::NAN).is_err());
    let singular = Mat::<f64>::zeros(3, 3);
    assert!(FrequencySolver::from_mass(singular.as_ref(), Coupling::Full).is_err());
}

#[test]
fn public_types_are_thread_safe() {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<FrequencySolver>();
    send_sync::<ModalIntegrals>();
    send_sync::<flexprr_beam::LinkFrequencies>();
    send_sync::<flexprr_beam::BeamError>();
    send_sync::<flexprr_beam::ClassicalBasis>();
    send_sync::<flexprr_beam::HermiteBasis>();
}

//! Classical Euler-Bernoulli eigenfunctions: characteristic roots against textbook values,
//! orthogonality, Rayleigh quotients, boundary conditions at high mode numbers, and a
//! second method (Hermite finite elements with the same ends).

use flexprr_beam::{
    Basis, ClassicalBasis, Coupling, EndCondition, EndConditions, HermiteBasis, ModalIntegrals,
    UniformSection, frequencies,
};

/// Unit beam: EI = 1, rhoA = 1, l = 1, so M = int psi psi and Kf = int psi'' psi''.
fn unit_integrals(basis: &dyn Basis) -> ModalIntegrals {
    ModalIntegrals::compute(basis, &UniformSection::new(1.0, 1.0).unwrap(), 1.0).unwrap()
}

fn all_cases() -> [(EndConditions, &'static str); 4] {
    [
        (EndConditions::CLAMPED_FREE, "clamped-free"),
        (EndConditions::CLAMPED_CLAMPED, "clamped-clamped"),
        (EndConditions::CLAMPED_PINNED, "clamped-pinned"),
        (EndConditions::PINNED_FREE, "pinned-free"),
    ]
}

#[test]
fn first_roots_match_textbook_values() {
    // Blevins, Formulas for Natural Frequency and Mode Shape, table 8-1 (beta l).
    let textbook: [(EndConditions, [f64; 2]); 4] = [
        (EndConditions::CLAMPED_FREE, [1.8751, 4.6941]),
        (EndConditions::CLAMPED_CLAMPED, [4.7300, 7.8532]),
        (EndConditions::CLAMPED_PINNED, [3.9266, 7.0686]),
        (EndConditions::PINNED_FREE, [3.9266, 7.0686]),
    ];
    for (ends, roots) in textbook {
        let basis = ClassicalBasis::new(ends, 3).unwrap();
        let rigid = basis.rigid_modes();
        assert_eq!(rigid, usize::from(ends == EndConditions::PINNED_FREE));
        let betas = basis.wavenumbers();
        for (k, want) in roots.iter().enumerate() {
            let got = betas[rigid + k];
            assert!(
                (got - want).abs() < 1e-4,
                "{}: root {k}: {got} vs {want}",
                ends.name()
            );
        }
    }
}

#[test]
fn higher_roots_approach_their_asymptotes() {
    // beta_n -> (2n - 1) pi / 2 (clamped-free), (2n + 1) pi / 2 (clamped-clamped),
    // (4n + 1) pi / 4 (clamped-pinned, pinned-free): the gap decays like e^{-beta}.
    use std::f64::consts::PI;
    type Asymptote = fn(f64) -> f64;
    let asymptote: [(EndConditions, Asymptote); 4] = [
        (EndConditions::CLAMPED_FREE, |n| (2.0 * n - 1.0) * PI / 2.0),
        (EndConditions::CLAMPED_CLAMPED, |n| {
            (2.0 * n + 1.0) * PI / 2.0
        }),
        (EndConditions::CLAMPED_PINNED, |n| {
            (4.0 * n + 1.0) * PI / 4.0
        }),
        (EndConditions::PINNED_FREE, |n| (4.0 * n + 1.0) * PI / 4.0),
    ];
    for (ends, formula) in asymptote {
        let basis = ClassicalBasis::new(ends, 20).unwrap();
        let rigid = basis.rigid_modes();
        for (k, beta) in basis.wavenumbers().iter().enumerate().skip(rigid) {
            let n = (k - rigid + 1) as f64;
            let expected = formula(n);
            let bound = 4.0 * (-expected).exp() + 1e-13 * expected;
            assert!(
                (beta - expected).abs() < bound,
                "{}: n = {n}: {beta}",
                ends.name()
            );
        }
    }
}

#[test]
fn modes_are_mass_orthonormal_and_diagonalise_the_bending_stiffness_up_to_r_20() {
    for (ends, name) in all_cases() {
        for r in [1, 2, 5, 12, 20] {
            let basis = ClassicalBasis::new(ends, r).unwrap();
            let mi = unit_integrals(&basis);
            let betas = basis.wavenumbers();
            for j in 0..r {
                for k in 0..r {
                    let delta = if j == k { 1.0 } else { 0.0 };
                    assert!(
                        (mi.mass[(j, k)] - delta).abs() < 1e-10,
                        "{name} r = {r}: M[{j},{k}] = {}",
                        mi.mass[(j, k)]
                    );
                    // Kf = diag(beta^4) (eigenfunctions of psi'''' = beta^4 psi).
                    let scale = (betas[j] * betas[k]).powi(2).max(1.0);
                    let want = delta * betas[j].powi(4);
                    assert!(
                        (mi.stiffness[(j, k)] - want).abs() < 1e-10 * scale,
                        "{name} r = {r}: Kf[{j},{k}] = {} vs {want}",
                        mi.stiffness[(j, k)]
                    );
                }
            }
        }
    }
}

#[test]
fn mode_20_satisfies_its_boundary_conditions_without_cancellation() {
    // The textbook form cosh - cos - sigma (sinh - sin) loses all digits at beta ~ 62;
    // the stable form must meet the end conditions to rounding relative to the mode's size.
    for (ends, name) in all_cases() {
        let basis = ClassicalBasis::new(ends, 20).unwrap();
        let j = 19;
        let beta = basis.wavenumbers()[j];
        for (xi, condition) in [(0.0, ends.left), (1.0, ends.right)] {
            let [w, dw, ddw] = basis.eval(j, xi);
            let (w, dw, ddw) = (w, dw / beta, ddw / (beta * beta));
            let residual = match condition {
                EndCondition::Pinned => w.abs().max(ddw.abs()),
                EndCondition::Clamped => w.abs().max(dw.abs()),
                EndCondition::Free => {
                    // Shear by a central difference of psi'' (O(h^2) accurate).
                    let h = 1e-5;
                    let side = if xi > 0.5 { -1.0 } else { 1.0 };
                    let d2 = |x: f64| basis.eval(j, x)[2] / (beta * beta);
                    let shear = side * (d2(xi + side * h) - d2(xi)) / h / beta;
                    assert!(shear.abs() < 1e-3, "{name}: shear {shear}");
                    ddw.abs()
                }
            };
            assert!(
                residual < 1e-12,
                "{name} mode 20 at xi = {xi}: residual {residual}"
            );
        }
        // Bounded by a few units (int psi^2 = 1): no e^{beta} blow-up anywhere.
        for i in 0..=1000 {
            let v = basis.eval(j, i as f64 / 1000.0);
            assert!(
                v[0].abs() < 3.0 && v[2].abs() < 3.0 * beta * beta,
                "{name} {v:?}"
            );
        }
    }
}

#[test]
fn frequencies_agree_with_hermite_finite_elements_with_the_same_ends() {
    // Second method: 48 cubic elements, first 3 elastic modes, agreement 2e-6.
    let section = UniformSection::rectangle(7.1e10, 2770.0, 0.002, 0.03).unwrap();
    for (ends, name) in all_cases() {
        let classical = ClassicalBasis::new(ends, 6).unwrap();
        let fe = HermiteBasis::new(48, ends).unwrap();
        let a = frequencies(
            &ModalIntegrals::compute(&classical, &section, 0.2).unwrap(),
            &Default::default(),
            Coupling::Full,
        )
        .unwrap();
        let b = frequencies(
            &ModalIntegrals::compute(&fe, &section, 0.2).unwrap(),
            &Default::default(),
            Coupling::Full,
        )
        .unwrap();
        let rigid = classical.rigid_modes();
        for j in rigid..rigid + 3 {
            let (fa, fb) = (a.modes[j].frequency_hz, b.modes[j].frequency_hz);
            // Conforming FE is a Rayleigh-Ritz upper bound, within O(h^4).
            assert!(fb >= fa * (1.0 - 1e-12), "{name} mode {j}: {fa} vs {fb}");
            assert!((fb - fa) / fa < 2e-6, "{name} mode {j}: {fa} vs {fb}");
        }
    }
}

#[test]
fn pinned_free_rigid_rotation_is_neutral_unloaded_and_stiffened_by_tension() {
    let section = UniformSection::new(1.0, 1.0).unwrap();
    let mi =
        ModalIntegrals::compute(&ClassicalBasis::pinned_free(3).unwrap(), &section, 1.0).unwrap();
    let f = frequencies(&mi, &Default::default(), Coupling::Full).unwrap();
    assert_eq!(f.modes[0].state, flexprr_beam::ModeState::Neutral);
    assert!(f.modes[0].frequency_hz.abs() < 1e-12);
    // Under tension P the rigid rotation has omega^2 = P int psi'^2 / (l int rhoA psi^2)
    // = 3P / 1 for psi = sqrt(3) xi, coupled weakly to the elastic modes (Full <= Rayleigh).
    let load = flexprr_beam::AxialLoad::uniform(2.0);
    let f = frequencies(&mi, &load, Coupling::Diagonal).unwrap();
    assert!((f.modes[0].omega_squared - 6.0).abs() < 1e-12);
    assert_eq!(f.critical_load_factor, None);
    let f = frequencies(&mi, &load.scaled(-1.0), Coupling::Full).unwrap();
    assert_eq!(f.modes[0].state, flexprr_beam::ModeState::Buckled);
    assert!(f.critical_load_factor.unwrap() < 1e-9);
}

#[test]
fn bad_counts_are_errors() {
    assert!(ClassicalBasis::clamped_free(0).is_err());
    assert!(ClassicalBasis::clamped_free(10_000).is_err());
    assert!(HermiteBasis::pinned_pinned(0).is_err());
    let free_free = EndConditions::new(EndCondition::Free, EndCondition::Free);
    let basis = ClassicalBasis::new(free_free, 4).unwrap();
    assert_eq!(basis.rigid_modes(), 2);
    assert!((basis.wavenumbers()[2] - 4.7300).abs() < 1e-4);
}

#[test]
fn critical_load_factor_makes_the_stiffness_singular() {
    // Law: at lambda_c the lowest eigenvalue crosses zero (stable just below, buckled just
    // above), for a non-uniform load, with and without a rigid-body mode (the latter takes
    // the bisection path, the former the buckling eigenproblem).
    use flexprr_beam::{AxialLoad, ModeState, SineBasis};
    let section = UniformSection::rectangle(7.1e10, 2770.0, 0.002, 0.03).unwrap();
    let sine = SineBasis::new(6).unwrap();
    let cantilever = ClassicalBasis::clamped_free(6).unwrap();
    let pinned_free = ClassicalBasis::pinned_free(6).unwrap();
    let bases: [(&dyn Basis, AxialLoad); 3] = [
        (
            &sine,
            AxialLoad {
                p0: 40.0,
                p1: -900.0,
                p2: 1500.0,
            },
        ),
        (
            &cantilever,
            AxialLoad {
                p0: -20.0,
                p1: -100.0,
                p2: 0.0,
            },
        ),
        (
            &pinned_free,
            AxialLoad {
                p0: 30.0,
                p1: -200.0,
                p2: 0.0,
            },
        ),
    ];
    for (basis, load) in bases {
        let mi = ModalIntegrals::compute(basis, &section, 0.2).unwrap();
        for coupling in [Coupling::Full, Coupling::Diagonal] {
            let f = frequencies(&mi, &load, coupling).unwrap();
            let Some(lambda) = f.critical_load_factor else {
                // Possible for the diagonal model only (here: pinned-free, all kp_jj > 0);
                // then no multiple of the load buckles it.
                assert_eq!(coupling, Coupling::Diagonal, "{}", basis.name());
                for factor in [1e2, 1e4, 1e8] {
                    let g = frequencies(&mi, &load.scaled(factor), coupling).unwrap();
                    assert!(!g.is_buckled(), "{} x{factor}", basis.name());
                }
                continue;
            };
            let below = frequencies(&mi, &load.scaled(lambda * (1.0 - 1e-6)), coupling).unwrap();
            let above = frequencies(&mi, &load.scaled(lambda * (1.0 + 1e-6)), coupling).unwrap();
            assert!(
                !below.is_buckled(),
                "{} {coupling:?}: {below:?}",
                basis.name()
            );
            assert!(
                above.is_buckled(),
                "{} {coupling:?}: {above:?}",
                basis.name()
            );
            let at = frequencies(&mi, &load.scaled(lambda), coupling).unwrap();
            assert!(at.modes.iter().any(|m| m.state != ModeState::Stable));
        }
    }
}

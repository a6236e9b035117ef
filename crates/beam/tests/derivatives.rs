//! Every basis' first and second derivatives against central differences of the function
//! (and of the first derivative), at random points and modes.

use flexprr_beam::{Basis, ClassicalBasis, EndCondition, EndConditions, HermiteBasis, SineBasis};
use proptest::prelude::*;

/// Checks psi' and psi'' at xi by central differences with step h (error O(h^2)).
fn check(basis: &dyn Basis, j: usize, xi: f64, scale: f64) -> Result<(), TestCaseError> {
    let h = 1e-5;
    let [_, d1, d2] = basis.eval(j, xi);
    let (minus, plus) = (basis.eval(j, xi - h), basis.eval(j, xi + h));
    let fd1 = (plus[0] - minus[0]) / (2.0 * h);
    let fd2 = (plus[1] - minus[1]) / (2.0 * h);
    // Relative to the mode's size: |psi'| ~ k, |psi''| ~ k^2 for wavenumber k = scale.
    prop_assert!(
        (d1 - fd1).abs() < 1e-6 * scale.max(1.0),
        "{}: psi' {d1} vs {fd1}",
        basis.name()
    );
    prop_assert!(
        (d2 - fd2).abs() < 1e-6 * (scale * scale).max(1.0),
        "{}: psi'' {d2} vs {fd2}",
        basis.name()
    );
    Ok(())
}

proptest! {
    #[test]
    fn sine_derivatives(j in 0usize..20, xi in 0.001f64..0.999) {
        let basis = SineBasis::new(20).unwrap();
        check(&basis, j, xi, (j + 1) as f64 * std::f64::consts::PI)?;
    }

    #[test]
    fn classical_derivatives(case in 0usize..6, j in 0usize..12, xi in 0.001f64..0.999) {
        use EndCondition::*;
        let ends = [
            (Clamped, Free), (Clamped, Clamped), (Clamped, Pinned),
            (Pinned, Free), (Free, Free), (Free, Pinned),
        ][case];
        let basis = ClassicalBasis::new(EndConditions::new(ends.0, ends.1), 12).unwrap();
        let k = basis.wavenumbers()[j];
        check(&basis, j, xi, k)?;
    }

    #[test]
    fn hermite_derivatives_inside_elements(
        j in 0usize..16, element in 0usize..8, s in 0.01f64..0.99,
    ) {
        let basis = HermiteBasis::pinned_pinned(8).unwrap();
        let xi = (element as f64 + s) / 8.0;
        // Element scale: psi' ~ 1/h for nodal values, psi'' ~ 1/h^2.
        check(&basis, j, xi, 8.0)?;
    }
}

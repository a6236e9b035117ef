//! Gauss-Legendre rules against the laws they must satisfy: exactness up to degree 2n - 1,
//! failure at degree 2n, symmetry, weight sums.

use flexprr_beam::{CompositeRule, GaussLegendre};
use proptest::prelude::*;

/// Legendre polynomial P_n by its explicit sum (independent of the recurrence in the crate):
/// P_n(x) = 2^-n sum_k (-1)^k C(n,k) C(2n-2k, n) x^(n-2k).
fn legendre_explicit(n: usize, x: f64) -> f64 {
    fn binomial(n: usize, k: usize) -> f64 {
        (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
    }
    let mut sum = 0.0;
    for k in 0..=n / 2 {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        sum += sign * binomial(n, k) * binomial(2 * n - 2 * k, n) * x.powi((n - 2 * k) as i32);
    }
    sum / 2f64.powi(n as i32)
}

#[test]
fn monomials_up_to_degree_2n_minus_1_are_exact_on_unit_interval() {
    for n in 1..=40 {
        let rule = GaussLegendre::new(n).unwrap();
        for k in 0..2 * n {
            let got = rule.integrate(0.0, 1.0, |x| x.powi(k as i32));
            let exact = 1.0 / (k as f64 + 1.0);
            assert!(
                ((got - exact) / exact).abs() < 1e-14,
                "n = {n}, degree {k}: {got} vs {exact}"
            );
        }
    }
}

#[test]
fn degree_2n_is_not_exact() {
    // P_n vanishes at every node, so the rule gives 0 for P_n^2, whose integral is 2/(2n+1).
    for n in 1..=30 {
        let rule = GaussLegendre::new(n).unwrap();
        let got = rule.integrate(-1.0, 1.0, |x| legendre_explicit(n, x).powi(2));
        let exact = 2.0 / (2.0 * n as f64 + 1.0);
        assert!(got.abs() < 1e-10 * exact, "n = {n}: {got}");
        // And x^(2n) on [-1, 1]: the error term (Abramowitz & Stegun 25.4.30) is
        // 2^(2n+1) (n!)^4 / ((2n+1) ((2n)!)^3) * (2n)!, far above rounding for small n.
        if n <= 8 {
            let got = rule.integrate(-1.0, 1.0, |x| x.powi(2 * n as i32));
            let exact = 2.0 / (2.0 * n as f64 + 1.0);
            assert!(((got - exact) / exact).abs() > 1e-8, "n = {n}");
        }
    }
}

#[test]
fn nodes_symmetric_and_weights_sum_to_one_on_unit_interval() {
    for n in [1, 2, 3, 7, 20, 64, 257, 1000] {
        let rule = GaussLegendre::new(n).unwrap();
        let (x, w) = (rule.nodes(), rule.weights());
        for i in 0..n {
            assert!((x[i] + x[n - 1 - i]).abs() < 1e-15, "n = {n}");
            assert!((w[i] - w[n - 1 - i]).abs() < 1e-15, "n = {n}");
            assert!(w[i] > 0.0 && x[i].abs() < 1.0);
            if i > 0 {
                assert!(x[i] > x[i - 1]);
            }
        }
        let sum = rule.integrate(0.0, 1.0, |_| 1.0);
        assert!((sum - 1.0).abs() < 1e-14, "n = {n}: {sum}");
    }
}

#[test]
fn bad_point_counts_are_errors() {
    assert!(GaussLegendre::new(0).is_err());
    assert!(GaussLegendre::new(1_000_000).is_err());
    assert!(CompositeRule::new(3, &[f64::NAN]).is_err());
}

#[test]
fn composite_rule_is_exact_on_piecewise_polynomials() {
    // |xi - 0.3|^3 has a jump in its 3rd derivative at 0.3: exact with a panel cut there.
    let f = |x: f64| (x - 0.3).abs().powi(3);
    let exact = (0.3f64.powi(4) + 0.7f64.powi(4)) / 4.0;
    let rule = CompositeRule::new(2, &[0.3, 0.7]).unwrap();
    assert_eq!(rule.panels(), 3);
    assert!((rule.integrate(f) - exact).abs() < 1e-15);
    let sum: f64 = rule.weights().iter().sum();
    assert!((sum - 1.0).abs() < 1e-15);
}

proptest! {
    #[test]
    fn random_polynomials_of_degree_2n_minus_1_are_exact(
        n in 1usize..25,
        coefficients in proptest::collection::vec(-1.0f64..1.0, 50),
        a in -3.0f64..3.0,
        width in 0.1f64..4.0,
    ) {
        let b = a + width;
        let degree = 2 * n - 1;
        let c = &coefficients[..=degree];
        let rule = GaussLegendre::new(n).unwrap();
        let got = rule.integrate(a, b, |x| c.iter().rev().fold(0.0, |acc, ck| acc * x + ck));
        let antiderivative = |x: f64| {
            c.iter().enumerate().map(|(k, ck)| ck * x.powi(k as i32 + 1) / (k as f64 + 1.0)).sum::<f64>()
        };
        let exact = antiderivative(b) - antiderivative(a);
        // Relative to the integral of |terms| (the exact value may itself cancel).
        let magnitude = c.iter().enumerate().map(|(k, ck)| {
            ck.abs() * (b.abs().max(a.abs())).powi(k as i32) * width
        }).sum::<f64>();
        prop_assert!((got - exact).abs() <= 1e-14 * magnitude.max(exact.abs()), "{got} vs {exact}");
    }
}

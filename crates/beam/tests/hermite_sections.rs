//! Hermite finite elements (element matrices against the textbook, convergence order
//! against the exact sine-basis frequencies) and non-uniform sections (closed forms and a
//! second method).

use flexprr_beam::{
    AxialLoad, Coupling, EndCondition, EndConditions, HermiteBasis, ModalIntegrals, SineBasis,
    SteppedSection, TaperedSection, UniformSection, frequencies,
};
use std::f64::consts::PI;

#[test]
fn one_free_element_gives_the_textbook_element_matrices() {
    // Consistent mass rhoA h/420 [...], bending EI/h^3 [...], geometric P/(30 h) [...]
    // (Przemieniecki, Theory of Matrix Structural Analysis, eqs. 5.116, 11.34, 15.44),
    // with rotations scaled by h; here h = l = 1 so DOFs (w0, w0', w1, w1') in xi.
    let free = EndConditions::new(EndCondition::Free, EndCondition::Free);
    let basis = HermiteBasis::new(1, free).unwrap();
    let mi = ModalIntegrals::compute(&basis, &UniformSection::new(1.0, 1.0).unwrap(), 1.0).unwrap();
    let mass = [
        [156.0, 22.0, 54.0, -13.0],
        [22.0, 4.0, 13.0, -3.0],
        [54.0, 13.0, 156.0, -22.0],
        [-13.0, -3.0, -22.0, 4.0],
    ];
    let bending = [
        [12.0, 6.0, -12.0, 6.0],
        [6.0, 4.0, -6.0, 2.0],
        [-12.0, -6.0, 12.0, -6.0],
        [6.0, 2.0, -6.0, 4.0],
    ];
    let geometric = [
        [36.0, 3.0, -36.0, 3.0],
        [3.0, 4.0, -3.0, -1.0],
        [-36.0, -3.0, 36.0, -3.0],
        [3.0, -1.0, -3.0, 4.0],
    ];
    for j in 0..4 {
        for k in 0..4 {
            assert!(
                (mi.mass[(j, k)] - mass[j][k] / 420.0).abs() < 1e-15,
                "M {j}{k}"
            );
            assert!(
                (mi.stiffness[(j, k)] - bending[j][k]).abs() < 1e-13,
                "K {j}{k}"
            );
            assert!(
                (mi.g[0][(j, k)] - geometric[j][k] / 30.0).abs() < 1e-15,
                "G {j}{k}"
            );
        }
    }
    // Exact quadrature order chosen from the degree: cubic shapes -> degree 6 -> 4 points.
    assert_eq!(mi.points_per_panel, 4);
}

/// Relative eigenvalue errors of the first three modes with `n` pinned-pinned elements,
/// against the exact sine-basis eigenvalues (jπ)^4 of a unit beam.
fn eigenvalue_errors(elements: usize) -> [f64; 3] {
    let section = UniformSection::new(1.0, 1.0).unwrap();
    let fe = ModalIntegrals::compute(
        &HermiteBasis::pinned_pinned(elements).unwrap(),
        &section,
        1.0,
    )
    .unwrap();
    let sine = ModalIntegrals::compute(&SineBasis::new(3).unwrap(), &section, 1.0).unwrap();
    let f_fe = frequencies(&fe, &AxialLoad::default(), Coupling::Full).unwrap();
    let f_sine = frequencies(&sine, &AxialLoad::default(), Coupling::Full).unwrap();
    std::array::from_fn(|j| {
        let exact = f_sine.modes[j].omega_squared;
        assert!((exact - ((j + 1) as f64 * PI).powi(4)).abs() < 1e-10 * exact);
        (f_fe.modes[j].omega_squared - exact) / exact
    })
}

#[test]
fn hermite_elements_converge_to_sine_frequencies_at_fourth_order() {
    // Cubic Hermite elements: eigenvalue error O(h^{2(p-1)}) = O(h^4) (Strang & Fix,
    // An Analysis of the Finite Element Method, section 6.3).
    // (At 64 elements and beyond the lowest eigenvalue meets the rounding floor of the
    // reduction to standard form, about eps * lambda_max / lambda_min; see docs/beam.md.)
    let mut previous = eigenvalue_errors(4);
    for elements in [8, 16, 32] {
        let errors = eigenvalue_errors(elements);
        for j in 0..3 {
            assert!(errors[j] > 0.0, "upper bound, mode {}", j + 1);
            let order = (previous[j] / errors[j]).log2();
            eprintln!(
                "n = {elements:2}, mode {}: error {:.3e}, order {order:.3}",
                j + 1,
                errors[j]
            );
            // Pre-asymptotic for mode 3 at 4 -> 8 elements (3.84).
            let tolerance = if elements == 8 { 0.2 } else { 0.05 };
            assert!(
                (order - 4.0).abs() < tolerance,
                "n = {elements}, mode {}: order {order}",
                j + 1
            );
        }
        previous = errors;
    }
    // 32 elements reproduce the first three eigenvalues to 2e-5.
    assert!(previous.iter().all(|e| *e < 2e-5));
}

#[test]
fn stepped_section_matches_closed_forms() {
    // Two halves: (EI1, rhoA1) on [0, 1/2), (EI2, rhoA2) on [1/2, 1]; sine modes.
    // int_0^{1/2} sin(j pi xi) sin(k pi xi) = (1/2)[sin((j-k)pi/2)/((j-k)pi) - sin((j+k)pi/2)/((j+k)pi)].
    let (ei1, ra1, ei2, ra2, l) = (2.0, 3.0, 5.0, 7.0, 0.7);
    let section = SteppedSection::new(vec![
        (0.5, UniformSection::new(ei1, ra1).unwrap()),
        (1.0, UniformSection::new(ei2, ra2).unwrap()),
    ])
    .unwrap();
    let r = 8;
    let mi = ModalIntegrals::compute(&SineBasis::new(r).unwrap(), &section, l).unwrap();
    assert_eq!(mi.panels, 2);
    let half = |j: usize, k: usize| -> f64 {
        let (jf, kf) = (j as f64, k as f64);
        if j == k {
            0.25
        } else {
            0.5 * (((jf - kf) * PI / 2.0).sin() / ((jf - kf) * PI)
                - ((jf + kf) * PI / 2.0).sin() / ((jf + kf) * PI))
        }
    };
    for j in 1..=r {
        for k in 1..=r {
            let (full, first) = (if j == k { 0.5 } else { 0.0 }, half(j, k));
            let mass = l * (ra1 * first + ra2 * (full - first));
            let curv = ((j * k) as f64 * PI * PI).powi(2);
            let stiff = curv * (ei1 * first + ei2 * (full - first)) / l.powi(3);
            let m_scale = l * ra2;
            let k_scale = ((j * j) as f64 * PI * PI) * ((k * k) as f64 * PI * PI) * ei2 / l.powi(3);
            assert!(
                (mi.mass[(j - 1, k - 1)] - mass).abs() < 1e-13 * m_scale,
                "M {j}{k}"
            );
            assert!(
                (mi.stiffness[(j - 1, k - 1)] - stiff).abs() < 1e-13 * k_scale,
                "K {j}{k}"
            );
        }
    }
    assert!((mi.total_mass - l * (ra1 + ra2) / 2.0).abs() < 1e-14);
}

#[test]
fn tapered_section_mass_matches_closed_form_and_frequencies_agree_across_bases() {
    let (e, rho, t0, t1, h, l) = (7.1e10, 2770.0, 0.003, 0.0015, 0.03, 0.2);
    let section = TaperedSection::new(e, rho, t0, t1, h).unwrap();
    let r = 20;
    let sine = ModalIntegrals::compute(&SineBasis::new(r).unwrap(), &section, l).unwrap();
    // M_jk = rho h l int (t0 + (t1 - t0) xi) sin(j pi xi) sin(k pi xi) dxi, with
    // int xi sin sin = (1/2)[((-1)^(j-k) - 1)/((j-k)pi)^2 - ((-1)^(j+k) - 1)/((j+k)pi)^2], 1/4 on the diagonal.
    let dt = t1 - t0;
    for j in 1..=r {
        for k in 1..=r {
            let (jf, kf) = (j as f64, k as f64);
            let (base, slope) = if j == k {
                (0.5, 0.25)
            } else {
                let s = if (j + k) % 2 == 0 { 1.0 } else { -1.0 };
                (
                    0.0,
                    0.5 * ((s - 1.0) / ((jf - kf) * PI).powi(2)
                        - (s - 1.0) / ((jf + kf) * PI).powi(2)),
                )
            };
            let exact = rho * h * l * (t0 * base + dt * slope);
            assert!((sine.mass[(j - 1, k - 1)] - exact).abs() < 1e-13 * rho * h * l * t0);
        }
    }
    assert!((sine.total_mass - rho * h * l * (t0 + t1) / 2.0).abs() < 1e-15);
    // Second method: 64 Hermite elements (exact Gauss order for cubic EI) vs 20 sines.
    let fe =
        ModalIntegrals::compute(&HermiteBasis::pinned_pinned(64).unwrap(), &section, l).unwrap();
    // Highest integrand degree: rhoA psi psi = 1 + 3 + 3 = 7 -> 4 Gauss points per element.
    assert_eq!(fe.points_per_panel, 4);
    let load = AxialLoad {
        p0: -20.0,
        p1: 300.0,
        p2: 0.0,
    };
    let a = frequencies(&sine, &load, Coupling::Full).unwrap();
    let b = frequencies(&fe, &load, Coupling::Full).unwrap();
    for j in 0..3 {
        let (fa, fb) = (a.modes[j].frequency_hz, b.modes[j].frequency_hz);
        assert!(
            ((fa - fb) / fb).abs() < 2e-6,
            "mode {}: {fa} vs {fb}",
            j + 1
        );
    }
}

#[test]
fn bad_sections_are_errors() {
    let u = UniformSection::new(1.0, 1.0).unwrap();
    assert!(SteppedSection::new(vec![]).is_err());
    assert!(SteppedSection::new(vec![(0.5, u)]).is_err());
    assert!(SteppedSection::new(vec![(0.5, u), (0.4, u), (1.0, u)]).is_err());
    assert!(TaperedSection::new(7e10, 2770.0, 0.0, 0.001, 0.03).is_err());
    assert!(UniformSection::new(f64::NAN, 1.0).is_err());
}

//! The co-rotational beam against closed forms:
//! * the element's internal force is the gradient of its strain energy and its tangent the
//!   derivative of the force (central differences), and a rigid motion of any size leaves
//!   it unstrained;
//! * a cantilever under a transverse tip load at large deflection matches the elastica
//!   (Bisshopp & Drucker 1945; Timoshenko & Gere, *Theory of Elastic Stability*, 2nd ed.,
//!   section 2.7) through complete and incomplete elliptic integrals;
//! * a pinned-pinned strut past buckling follows the elastica's post-buckling curve
//!   `P / P_cr = (2 K(k) / pi)^2`, `w_mid / L = k / K(k)`, `chord / L = 2 E(k) / K(k) - 1`
//!   (Timoshenko & Gere, section 2.7);
//! * both converge at second order in the element length.

use flexprr_dynamics::nonlinear::{CorotationalElement, PlanarBeam};
use std::f64::consts::PI;

const L: f64 = 0.2;
const EA: f64 = 4.38e6;
const EI: f64 = 1.46;

// --- elliptic integrals by Carlson's symmetric forms (B. C. Carlson, "Numerical computation
// of real or complex elliptic integrals", Numer. Algorithms 10 (1995) 13-26), duplication
// to convergence ---
fn carlson_rf(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    loop {
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lam = sx * sy + sy * sz + sz * sx;
        x = 0.25 * (x + lam);
        y = 0.25 * (y + lam);
        z = 0.25 * (z + lam);
        let a = (x + y + z) / 3.0;
        let (dx, dy, dz) = (1.0 - x / a, 1.0 - y / a, 1.0 - z / a);
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-4 {
            let e2 = dx * dy - dz * dz;
            let e3 = dx * dy * dz;
            return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0)
                / a.sqrt();
        }
    }
}

fn carlson_rd(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    let mut sum = 0.0;
    let mut factor = 1.0;
    loop {
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lam = sx * sy + sy * sz + sz * sx;
        sum += factor / (sz * (z + lam));
        factor *= 0.25;
        x = 0.25 * (x + lam);
        y = 0.25 * (y + lam);
        z = 0.25 * (z + lam);
        let a = (x + y + 3.0 * z) / 5.0;
        let (dx, dy, dz) = (1.0 - x / a, 1.0 - y / a, 1.0 - z / a);
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-4 {
            let ea = dx * dy;
            let eb = dz * dz;
            let ec = ea - eb;
            let ed = ea - 6.0 * eb;
            let ee = ed + ec + ec;
            let s = 1.0
                + ed * (-3.0 / 14.0 + 9.0 / 88.0 * ed - 4.5 / 26.0 * dz * ee)
                + dz * (ee / 6.0 + dz * (-9.0 / 22.0 * ec + 3.0 / 26.0 * dz * ea));
            return 3.0 * sum + factor * s / (a * a.sqrt());
        }
    }
}

/// Incomplete elliptic integral of the first kind `F(phi, k)`, `0 <= phi <= pi/2`.
fn ellf(phi: f64, k: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    s * carlson_rf(c * c, 1.0 - k * k * s * s, 1.0)
}

/// Incomplete elliptic integral of the second kind `E(phi, k)`.
fn elle(phi: f64, k: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    let q = 1.0 - k * k * s * s;
    s * carlson_rf(c * c, q, 1.0) - k * k * s * s * s * carlson_rd(c * c, q, 1.0) / 3.0
}

#[test]
fn elliptic_integrals_match_known_values() {
    // K(1/sqrt 2) = Gamma(1/4)^2 / (4 sqrt(pi)) = 1.854074677301372; E(1/sqrt 2) = 1.350643881047675.
    let k = std::f64::consts::FRAC_1_SQRT_2;
    assert!((ellf(PI / 2.0, k) - 1.854_074_677_301_372).abs() < 1e-13);
    assert!((elle(PI / 2.0, k) - 1.350_643_881_047_675).abs() < 1e-13);
    // k = 0: F = E = phi.
    assert!((ellf(0.7, 0.0) - 0.7).abs() < 1e-14 && (elle(0.7, 0.0) - 0.7).abs() < 1e-14);
}

fn element() -> CorotationalElement {
    CorotationalElement {
        length: 0.025,
        axial_stiffness: EA,
        bending_stiffness: EI,
    }
}

fn energy(el: &CorotationalElement, q: &[f64; 6]) -> f64 {
    let st = el.state(q);
    let [t1, t2] = st.rotations;
    0.5 * el.axial_stiffness * st.stretch * st.stretch / el.length
        + 2.0 * el.bending_stiffness / el.length * (t1 * t1 + t1 * t2 + t2 * t2)
}

#[test]
fn element_force_is_energy_gradient_and_tangent_its_derivative() {
    let el = element();
    // A strongly rotated (2.3 rad), stretched and bent element; nodal angles wound by 2 pi.
    let b = 2.3_f64;
    let q = [
        0.01,
        -0.02,
        b + 0.05 + 2.0 * PI,
        0.01 + 0.02501 * b.cos() - 0.001 * b.sin(),
        -0.02 + 0.02501 * b.sin() + 0.001 * b.cos(),
        b - 0.03,
    ];
    let (f, _) = el.internal_force(&q);
    let k = el.tangent(&q);
    for j in 0..6 {
        let h = 1e-7;
        let (mut qp, mut qm) = (q, q);
        qp[j] += h;
        qm[j] -= h;
        let grad = (energy(&el, &qp) - energy(&el, &qm)) / (2.0 * h);
        assert!(
            (grad - f[j]).abs() <= 1e-6 * f.iter().map(|v| v.abs()).fold(0.0, f64::max),
            "force {j}: {} vs energy gradient {grad}",
            f[j]
        );
        let (fp, _) = el.internal_force(&qp);
        let (fm, _) = el.internal_force(&qm);
        let scale = k.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
        for i in 0..6 {
            let d = (fp[i] - fm[i]) / (2.0 * h);
            assert!(
                (d - k[i][j]).abs() <= 1e-6 * scale,
                "K[{i}][{j}] = {} vs difference {d}",
                k[i][j]
            );
        }
        // Symmetric (conservative).
        for (i, row) in k.iter().enumerate() {
            assert!((row[j] - k[j][i]).abs() <= 1e-9 * scale);
        }
    }
    // Rigid motion: any translation and rotation of the straight element is strain free.
    for angle in [0.0, 1.0, 3.0, -2.9, 7.5] {
        let (c, s) = (f64::cos(angle), f64::sin(angle));
        let q = [1.0, 2.0, angle, 1.0 + 0.025 * c, 2.0 + 0.025 * s, angle];
        let (f, st) = el.internal_force(&q);
        assert!(f.iter().all(|v| v.abs() < 1e-6), "{angle}: {f:?} {st:?}");
    }
}

/// Cantilever along x clamped at the origin, tip load `p` in -y. Returns the tip
/// `(x, -y, -psi)` of the FE model with `ne` elements.
fn fe_cantilever(ne: usize, p: f64) -> (f64, f64, f64) {
    let beam = PlanarBeam::straight(L, EA, EI, ne).unwrap();
    let tip = 3 * ne;
    let sol = beam
        .solve_static(
            &beam.reference,
            &[(0, 0.0), (1, 0.0), (2, 0.0)],
            &[(tip + 1, -p)],
            20,
        )
        .unwrap();
    let q = &sol.coordinates;
    (q[tip], -q[tip + 1], -q[tip + 2])
}

/// The elastica cantilever with tip angle `theta0`: load `P`, tip `(x, delta)`.
/// `lambda L = K(k) - F(phi1, k)`, `delta = L - 2 (E(k) - E(phi1, k)) / lambda`,
/// `x = sqrt(2 sin theta0) / lambda`, with `k^2 = (1 + sin theta0) / 2`,
/// `sin phi1 = 1 / (k sqrt 2)`, `lambda = sqrt(P / EI)`.
fn elastica_cantilever(theta0: f64) -> (f64, f64, f64) {
    let k = ((1.0 + theta0.sin()) / 2.0).sqrt();
    let phi1 = (1.0 / (k * 2f64.sqrt())).asin();
    let lambda = (ellf(PI / 2.0, k) - ellf(phi1, k)) / L;
    let p = lambda * lambda * EI;
    let delta = L - 2.0 * (elle(PI / 2.0, k) - elle(phi1, k)) / lambda;
    let x = (2.0 * theta0.sin()).sqrt() / lambda;
    (p, x, delta)
}

#[test]
fn cantilever_matches_the_elastica_at_large_deflection() {
    for theta0_deg in [20.0_f64, 50.0, 75.0] {
        let theta0 = theta0_deg.to_radians();
        let (p, x, delta) = elastica_cantilever(theta0);
        let mut errors = Vec::new();
        for ne in [4, 8, 16, 32] {
            let (xf, df, tf) = fe_cantilever(ne, p);
            println!(
                "cantilever {theta0_deg} deg, {ne} elements: tip x {xf:.6} ({x:.6}), deflection {df:.6} ({delta:.6}), angle {tf:.6}"
            );
            // Axial stretch P sin(theta) / EA is below 1e-4 of L here: compare to 2e-4 L.
            let err = ((xf - x).abs().max((df - delta).abs()) / L).max((tf - theta0).abs());
            errors.push(err);
        }
        // Second order in the element length until the stretch floor.
        for w in errors.windows(2) {
            assert!(
                w[1] < w[0] / 3.0 || w[1] < 3e-4,
                "{theta0_deg} deg: {errors:?}"
            );
        }
        assert!(
            errors[3] < 3e-4,
            "{theta0_deg} deg, 32 elements: {errors:?}"
        );
        assert!(delta / L > 0.2, "large deflection: {}", delta / L);
    }
}

/// The elastica of the pinned-pinned strut with end slope `theta0`: `(P / P_cr, w_mid / L,
/// chord / L)`.
fn elastica_strut(theta0: f64) -> (f64, f64, f64) {
    let k = (theta0 / 2.0).sin();
    let (kk, ek) = (ellf(PI / 2.0, k), elle(PI / 2.0, k));
    ((2.0 * kk / PI).powi(2), k / kk, 2.0 * ek / kk - 1.0)
}

/// Pinned-pinned strut with `ne` elements, the chord prescribed: follows the post-buckling
/// path by continuation in the end slope (every 5 degrees, each solution the next guess) and
/// returns `(P, w_mid)` at each of `checkpoints` (degrees, increasing).
fn fe_strut(ne: usize, checkpoints: &[f64]) -> Vec<(f64, f64)> {
    let p_cr = PI * PI * EI / (L * L);
    let beam = PlanarBeam::straight(L, EA, EI, ne).unwrap();
    let tip = 3 * ne;
    // First guess: the buckling mode, a half sine of the 5-degree amplitude.
    let (_, w0, _) = elastica_strut(5f64.to_radians());
    let mut guess = beam.reference.clone();
    for k in 0..=ne {
        let s = k as f64 / ne as f64;
        guess[3 * k] = s * L;
        guess[3 * k + 1] = w0 * L * (PI * s).sin();
        guess[3 * k + 2] = (w0 * PI * (PI * s).cos()).atan();
    }
    let mut out = Vec::new();
    let last = checkpoints.last().copied().unwrap_or(0.0);
    let mut deg = 5.0;
    while deg <= last + 1e-9 {
        let (load, _, chord) = elastica_strut(f64::to_radians(deg));
        // The strut is axially elastic: its length is L (1 - P / EA); the chord scales with it.
        let chord = chord * L * (1.0 - load * p_cr / EA);
        let sol = beam
            .solve_static(
                &guess,
                &[(0, 0.0), (1, 0.0), (tip, chord), (tip + 1, 0.0)],
                &[],
                4,
            )
            .unwrap();
        if checkpoints.iter().any(|c| (c - deg).abs() < 1e-9) {
            // The support's reaction is -(f_int - f_ext) there: it pushes with P.
            out.push((-sol.residual[tip], sol.coordinates[3 * (ne / 2) + 1]));
        }
        guess = sol.coordinates;
        deg += 5.0;
    }
    out
}

#[test]
fn pinned_strut_follows_the_post_buckling_elastica() {
    let p_cr = PI * PI * EI / (L * L);
    let checkpoints = [10.0, 40.0, 90.0, 120.0];
    let runs: Vec<Vec<(f64, f64)>> = [4, 8, 16, 32]
        .iter()
        .map(|ne| fe_strut(*ne, &checkpoints))
        .collect();
    for (c, theta0_deg) in checkpoints.iter().enumerate() {
        let (load, w, _) = elastica_strut(theta0_deg.to_radians());
        let errors: Vec<f64> = runs
            .iter()
            .map(|run| {
                let (p, wm) = run[c];
                ((p / p_cr - load).abs() / load).max((wm.abs() / L - w).abs() / w)
            })
            .collect();
        for e in errors.windows(2) {
            assert!(
                e[1] < e[0] / 3.0 || e[1] < 2e-4,
                "{theta0_deg} deg: {errors:?}"
            );
        }
        assert!(
            errors[3] < 2e-3,
            "{theta0_deg} deg, 32 elements: {errors:?}"
        );
        println!(
            "strut {theta0_deg} deg: P/Pcr {load:.5}, w/L {w:.4}, errors (4, 8, 16, 32 elements) {errors:?}"
        );
    }
}

#[test]
fn bad_input_is_an_error() {
    assert!(PlanarBeam::straight(0.0, EA, EI, 4).is_err());
    assert!(PlanarBeam::straight(L, EA, f64::NAN, 4).is_err());
    assert!(PlanarBeam::straight(L, EA, EI, 0).is_err());
    let beam = PlanarBeam::straight(L, EA, EI, 2).unwrap();
    assert!(beam.solve_static(&[0.0; 3], &[], &[], 1).is_err());
    assert!(
        beam.solve_static(&beam.reference, &[(99, 0.0)], &[], 1)
            .is_err()
    );
    // A free beam under a load has no equilibrium: singular tangent, an error, not a panic.
    assert!(
        beam.solve_static(&beam.reference, &[], &[(4, 1.0)], 1)
            .is_err()
    );
}

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
//! * both converge at second order in the element length with the chord element
//!   ([`LocalStrain::Chord`]) and at fourth order with the shallow-arch local strain
//!   ([`LocalStrain::ShallowArch`]), down to the floor the axial stretch sets (the elastica is
//!   inextensible; the stretch is removed by raising `EA`).

use flexprr_dynamics::nonlinear::{CorotationalElement, LocalStrain, PlanarBeam};
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

fn element(strain: LocalStrain) -> CorotationalElement {
    CorotationalElement {
        length: 0.025,
        axial_stiffness: EA,
        bending_stiffness: EI,
        strain,
    }
}

/// The strain energy written out from the module's formulas (independently of the
/// element's own `strain_energy`).
fn energy(el: &CorotationalElement, q: &[f64; 6]) -> f64 {
    let st = el.state(q);
    let [t1, t2] = st.rotations;
    let bending = 2.0 * el.bending_stiffness / el.length * (t1 * t1 + t1 * t2 + t2 * t2);
    let eps = match el.strain {
        LocalStrain::Chord => st.stretch / el.length,
        LocalStrain::ShallowArch => {
            st.stretch / el.length + (2.0 * t1 * t1 - t1 * t2 + 2.0 * t2 * t2) / 30.0
        }
    };
    0.5 * el.axial_stiffness * el.length * eps * eps + bending
}

#[test]
fn element_force_is_energy_gradient_and_tangent_its_derivative() {
    for strain in [LocalStrain::Chord, LocalStrain::ShallowArch] {
        element_checks(element(strain));
    }
}

fn element_checks(el: CorotationalElement) {
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
        assert!((el.strain_energy(&el.state(&qp)) - energy(&el, &qp)).abs() < 1e-12);
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
fn fe_cantilever(ne: usize, p: f64, strain: LocalStrain, ea: f64) -> (f64, f64, f64) {
    let beam = PlanarBeam::straight(L, ea, EI, ne)
        .unwrap()
        .with_strain(strain);
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

/// Max error over tip x, tip deflection (per length) and tip angle of the FE cantilever at
/// the elastica's tip angles, for 2, 4, 8, 16 and 32 elements.
fn cantilever_errors(theta0_deg: f64, strain: LocalStrain, ea: f64) -> Vec<f64> {
    let theta0 = theta0_deg.to_radians();
    let (p, x, delta) = elastica_cantilever(theta0);
    assert!(delta / L > 0.2, "large deflection: {}", delta / L);
    [2, 4, 8, 16, 32]
        .iter()
        .map(|&ne| {
            let (xf, df, tf) = fe_cantilever(ne, p, strain, ea);
            ((xf - x).abs().max((df - delta).abs()) / L).max((tf - theta0).abs())
        })
        .collect()
}

/// `errors` falls by at least `factor` per halving of the element length until it is below
/// `floor` (a model difference that does not converge away: the axial stretch).
fn assert_order(what: &str, errors: &[f64], factor: f64, floor: f64) {
    println!(
        "{what}: errors (2, 4, 8, 16, 32 elements) {}",
        errors
            .iter()
            .map(|e| format!("{e:.2e}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for w in errors.windows(2) {
        if w[0].is_finite() {
            assert!(w[1] < w[0] / factor || w[1] < floor, "{what}: {errors:?}");
        }
    }
}

#[test]
fn cantilever_matches_the_elastica_at_large_deflection() {
    for theta0_deg in [20.0_f64, 50.0, 75.0] {
        // The chord element: second order (4 per halving; 3 allowed). The stretch P sin(theta)
        // / EA is below 1e-4 of L: compare to 3e-4.
        let chord = cantilever_errors(theta0_deg, LocalStrain::Chord, EA);
        assert_order(&format!("chord, {theta0_deg} deg"), &chord, 3.0, 3e-4);
        assert!(chord[4] < 3e-4, "{theta0_deg} deg, 32 elements: {chord:?}");
        // The shallow-arch element: fourth order (16 per halving; 10 allowed) with the axial
        // stretch removed (EA x 1e4: floor below 1e-8 of L); with the links' EA it reaches the
        // stretch floor (4e-5 at 75 degrees) with 8 elements.
        let stiff = cantilever_errors(theta0_deg, LocalStrain::ShallowArch, 1e4 * EA);
        assert_order(
            &format!("shallow arch (EA x 1e4), {theta0_deg} deg"),
            &stiff,
            10.0,
            1e-8,
        );
        let shallow = cantilever_errors(theta0_deg, LocalStrain::ShallowArch, EA);
        assert_order(
            &format!("shallow arch, {theta0_deg} deg"),
            &shallow,
            10.0,
            5e-5,
        );
        assert!(
            shallow[2] < 5e-5,
            "{theta0_deg} deg, 8 elements: {shallow:?}"
        );
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
/// path by continuation in the end slope (every 2.5 degrees, each solution the next guess) and
/// returns `(P, w_mid)` at each of `checkpoints` (degrees, increasing).
fn fe_strut(ne: usize, checkpoints: &[f64], strain: LocalStrain, ea: f64) -> Vec<(f64, f64)> {
    let p_cr = PI * PI * EI / (L * L);
    let beam = PlanarBeam::straight(L, ea, EI, ne)
        .unwrap()
        .with_strain(strain);
    let tip = 3 * ne;
    // First guess: the buckling mode, a half sine of the 5-degree amplitude on the
    // 5-degree chord.
    let (_, w0, chord0) = elastica_strut(5f64.to_radians());
    let mut guess = beam.reference.clone();
    for k in 0..=ne {
        let s = k as f64 / ne as f64;
        guess[3 * k] = s * L * chord0;
        guess[3 * k + 1] = w0 * L * (PI * s).sin();
        guess[3 * k + 2] = (w0 * PI * (PI * s).cos()).atan();
    }
    let mut out = Vec::new();
    let last = checkpoints.last().copied().unwrap_or(0.0);
    let mut deg = 5.0;
    let mut previous: Option<Vec<f64>> = None;
    while deg <= last + 1e-9 {
        let (load, _, chord) = elastica_strut(f64::to_radians(deg));
        // The strut is axially elastic: its length is L (1 - P / EA); the chord scales with it.
        let chord = chord * L * (1.0 - load * p_cr / ea);
        let sol = beam
            .solve_static(
                &guess,
                &[(0, 0.0), (1, 0.0), (tip, chord), (tip + 1, 0.0)],
                &[],
                1,
            )
            .unwrap();
        if checkpoints.iter().any(|c| (c - deg).abs() < 1e-9) {
            // The support's reaction is -(f_int - f_ext) there: it pushes with P.
            out.push((-sol.residual[tip], sol.coordinates[3 * (ne / 2) + 1]));
        }
        // Secant predictor: the next guess extrapolates the last two solutions.
        let next: Vec<f64> = match &previous {
            Some(p) => sol
                .coordinates
                .iter()
                .zip(p)
                .map(|(a, b): (&f64, &f64)| 2.0 * a - b)
                .collect(),
            None => sol.coordinates.clone(),
        };
        previous = Some(sol.coordinates);
        guess = next;
        deg += 2.5;
    }
    out
}

/// Max relative error of `P` and `w_mid` against the elastica at each checkpoint (degrees),
/// for 2, 4, 8, 16 and 32 elements (2 and 4 only up to 40 degrees: their elements turn by
/// more than half a radian beyond).
fn strut_errors(checkpoints: &[f64], strain: LocalStrain, ea: f64) -> Vec<Vec<f64>> {
    let p_cr = PI * PI * EI / (L * L);
    let coarse = checkpoints.iter().filter(|c| **c <= 40.0).count();
    let runs: Vec<Vec<(f64, f64)>> = [2, 4, 8, 16, 32]
        .iter()
        .map(|&ne| {
            let upto = if ne < 8 { coarse } else { checkpoints.len() };
            fe_strut(ne, &checkpoints[..upto], strain, ea)
        })
        .collect();
    checkpoints
        .iter()
        .enumerate()
        .map(|(c, theta0_deg)| {
            let (load, w, _) = elastica_strut(theta0_deg.to_radians());
            runs.iter()
                .map(|run| {
                    run.get(c).map_or(f64::NAN, |(p, wm)| {
                        ((p / p_cr - load).abs() / load).max((wm.abs() / L - w).abs() / w)
                    })
                })
                .collect()
        })
        .collect()
}

#[test]
fn pinned_strut_follows_the_post_buckling_elastica() {
    let checkpoints = [10.0, 40.0, 90.0, 120.0];
    // The chord element: second order; 32 elements within 0.1 %.
    for (errors, deg) in strut_errors(&checkpoints, LocalStrain::Chord, EA)
        .iter()
        .zip(checkpoints)
    {
        assert_order(&format!("strut, chord, {deg} deg"), errors, 3.0, 2e-4);
        assert!(errors[4] < 2e-3, "{deg} deg, 32 elements: {errors:?}");
    }
    // The shallow-arch element: fourth order to the extensibility floor (about 1e-6 with EA x
    // 100; 8e-5 with the links' EA, which the chord element approaches too).
    for (errors, deg) in strut_errors(&checkpoints, LocalStrain::ShallowArch, 1e2 * EA)
        .iter()
        .zip(checkpoints)
    {
        assert_order(
            &format!("strut, shallow arch (EA x 100), {deg} deg"),
            errors,
            8.0,
            2e-6,
        );
        assert!(errors[2] < 1.5e-4, "{deg} deg, 8 elements: {errors:?}");
    }
    for (errors, deg) in strut_errors(&checkpoints, LocalStrain::ShallowArch, EA)
        .iter()
        .zip(checkpoints)
    {
        assert_order(
            &format!("strut, shallow arch, {deg} deg"),
            errors,
            8.0,
            1.5e-4,
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

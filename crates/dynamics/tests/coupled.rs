//! The coupled model against independent references:
//! * with both couplings off it is the consistent KED model ([`ModalSystem`], whose axial
//!   forces come from the separate rigid inverse dynamics): same right-hand side at random
//!   states, same history;
//! * linearised about `eta = 0` (central differences) it is the consistent KED model's
//!   analytic Jacobian and forcing;
//! * its platform motion closes the loop with the foreshortened chords, and the reported
//!   velocity and acceleration are the time derivatives of the pose along a solution;
//! * at `eta = 0` its axial forces and driving forces are the rigid inverse-dynamics ones;
//! * the three integrators agree on it; the right-hand side allocates nothing; bad input is
//!   an error, not a panic.

use std::sync::Arc;

use faer::Mat;
use flexprr_dynamics::{
    CoupledOptions, CoupledSystem, CouplingModel, DynamicsError, Formulation, ModalDamping,
    ModalSystem, end_forces, inverse_dynamics, paper,
};
use flexprr_integrators::{Abm, Bdf, Integrator, OdeSystem, Options, Rk45};
use flexprr_kinematics::{Line, Pose, Trajectory};
use proptest::prelude::*;

// --- allocation counting on the current thread only (tests run in parallel threads) ---
#[global_allocator]
static GLOBAL: flexprr_testkit::CountingAllocator = flexprr_testkit::CountingAllocator;

fn machine() -> Arc<flexprr_dynamics::Machine> {
    Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap())
}

fn circle(f: f64) -> Arc<dyn Trajectory + Send + Sync> {
    Arc::new(paper::trajectory(f).unwrap())
}

fn coupled(f: f64, options: CoupledOptions) -> CoupledSystem {
    CoupledSystem::new(machine(), circle(f), ModalDamping::none(), options).unwrap()
}

fn ked(f: f64) -> ModalSystem {
    ModalSystem::new(
        machine(),
        circle(f),
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap()
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let den: f64 = b.iter().map(|y| y * y).sum();
    (num / den.max(f64::MIN_POSITIVE)).sqrt()
}

/// A state of the size met at 20 Hz: deflections up to ~3 mm, rates up to ~2 m/s.
fn state_from(seed: &[f64; 18]) -> Vec<f64> {
    seed.iter()
        .enumerate()
        .map(|(k, s)| {
            let mode = (k % 9) % 3 + 1;
            let scale = if k < 9 { 3e-3 } else { 2.0 } / (mode * mode) as f64;
            scale * s
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Both couplings off: the coupled right-hand side is the consistent KED one, whose axial
    /// force comes from `inverse_dynamics` and the joint-reaction model instead of the
    /// platform balance assembled here; undamped and with modal damping.
    #[test]
    fn ked_limit_has_the_consistent_ked_rhs(
        seed in prop::array::uniform18(-1.0f64..1.0),
        t in 0.0f64..0.05,
    ) {
        let y = state_from(&seed);
        let mut c = coupled(20.0, CoupledOptions::ked_limit());
        let mut k = ked(20.0);
        let mut dc = vec![0.0; 18];
        let mut dk = vec![0.0; 18];
        c.rhs(t, &y, &mut dc);
        k.rhs(t, &y, &mut dk);
        prop_assert!(rel_diff(&dc[9..], &dk[9..]) < 1e-11, "{dc:?} vs {dk:?}");
        // Modal damping, one ratio per mode: the coupled model forms its damping matrix itself.
        let damping = ModalDamping { ratios: vec![0.01, 0.02, 0.05] };
        let mut c = CoupledSystem::new(machine(), circle(20.0), damping.clone(), CoupledOptions::ked_limit()).unwrap();
        let mut k = ModalSystem::new(machine(), circle(20.0), Formulation::consistent(), damping).unwrap();
        c.rhs(t, &y, &mut dc);
        k.rhs(t, &y, &mut dk);
        prop_assert!(rel_diff(&dc[9..], &dk[9..]) < 1e-11, "damped: {dc:?} vs {dk:?}");
    }
}

#[test]
fn ked_limit_reproduces_the_consistent_ked_history() {
    let times: Vec<f64> = (1..=40).map(|k| 0.005 * f64::from(k)).collect();
    let opts = Options::default().rtol(1e-9).atol(1e-13);
    let mut c = coupled(20.0, CoupledOptions::ked_limit());
    let mut k = ked(20.0);
    let y0 = c.initial_state();
    let sc = Rk45::new(opts.clone())
        .solve(&mut c, 0.0, &y0, &times)
        .unwrap();
    let sk = Rk45::new(opts).solve(&mut k, 0.0, &y0, &times).unwrap();
    for (n, t) in times.iter().enumerate() {
        let d = rel_diff(&sc.y(n)[..9], &sk.y(n)[..9]);
        assert!(d < 1e-6, "t = {t}: {d}");
    }
}

/// Largest entry of `|J_coupled - J_expected|` and of `|J_expected|` at `eta = 0`, the coupled
/// Jacobian by central differences of its right-hand side, the expected one the KED analytic
/// Jacobian plus `correction` (added to the `eta''` rows), and the relative forcing gap.
fn linearisation_gap(
    f: f64,
    t: f64,
    options: CoupledOptions,
    correction: &Mat<f64>,
) -> (f64, f64, f64) {
    let mut c = coupled(f, options);
    let mut k = ked(f);
    let n = c.dim();
    let y0 = vec![0.0; n];
    let mut fc = vec![0.0; n];
    let mut fk = vec![0.0; n];
    c.rhs(t, &y0, &mut fc);
    k.rhs(t, &y0, &mut fk);
    let forcing = rel_diff(&fc, &fk);
    let mut jk = Mat::<f64>::zeros(n, n);
    k.jacobian(t, &y0, jk.as_mut());
    let (mut plus, mut minus) = (vec![0.0; n], vec![0.0; n]);
    let mut worst: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for col in 0..n {
        let h = if col < n / 2 { 1e-5 } else { 1e-3 };
        let mut y = y0.clone();
        y[col] = h;
        c.rhs(t, &y, &mut plus);
        y[col] = -h;
        c.rhs(t, &y, &mut minus);
        for row in 0..n {
            let d = (plus[row] - minus[row]) / (2.0 * h);
            let extra = if row >= n / 2 && col < n / 2 {
                correction[(row - n / 2, col)]
            } else {
                0.0
            };
            let expected = jk[(row, col)] + extra;
            worst = worst.max((d - expected).abs());
            scale = scale.max(expected.abs());
        }
    }
    (forcing, worst, scale)
}

/// `-M^-1 (dT_i / l) G0` per link, with `dT_i` the change of the tension at `C_i` when the
/// links' elastic inertia for the coupled model's `eta''` at `eta = 0` joins the rigid inverse
/// dynamics (computed by `inverse_dynamics`, independently of the coupled assembly).
fn elastic_tension_correction(f: f64, t: f64) -> Mat<f64> {
    use faer::linalg::solvers::DenseSolveCore;
    let m = machine();
    let traj = circle(f);
    let k = ked(f);
    let mut c = coupled(f, CoupledOptions::ked_limit());
    let eta_dd = c.modal_accelerations(t, &c.initial_state()).unwrap();
    let elastic = k.elastic_inertia(&eta_dd);
    let state = m
        .geometry
        .inverse_kinematics_unchecked(&traj.motion(t))
        .unwrap();
    let rigid = inverse_dynamics(&m, &state, None, t).unwrap();
    let with = inverse_dynamics(&m, &state, Some(&elastic), t).unwrap();
    let mut out = Mat::<f64>::zeros(9, 9);
    for i in 0..3 {
        let e = state.legs[i].e;
        let dt = (with.platform_on_link[i] - rigid.platform_on_link[i]).dot(&e);
        let ints = &m.links[i].integrals;
        let m_inv = ints.mass.llt(faer::Side::Lower).unwrap().inverse();
        let block = &m_inv * &ints.g[0] * (-dt / ints.length);
        let range = k.link_range(i);
        for (a, row) in range.clone().enumerate() {
            for (b, col) in range.clone().enumerate() {
                out[(row, col)] = block[(a, b)];
            }
        }
    }
    out
}

/// Linearised about `eta = 0` with the rigid motion prescribed (no foreshortening in the
/// closure), the coupled model is the consistent KED model term by term: same forcing, and
/// the Jacobian (central differences of the coupled right-hand side) is the KED analytic
/// Jacobian, plus, when the links' elastic inertia enters the joint reactions (which KED's
/// rigid inverse dynamics leaves out), the geometric stiffness of the tension it adds.
#[test]
fn linearisation_with_prescribed_rigid_motion_is_the_consistent_ked_model() {
    let zero = Mat::<f64>::zeros(9, 9);
    for (f, t) in [(10.0, 0.013), (20.0, 0.0371), (30.0, 0.002)] {
        let (forcing, worst, scale) = linearisation_gap(f, t, CoupledOptions::ked_limit(), &zero);
        assert!(forcing < 1e-12, "forcing at f = {f}: {forcing}");
        assert!(worst < 1e-8 * scale, "f = {f}: {worst} vs {scale}");
        let prescribed = CoupledOptions {
            foreshortening: false,
            ..CoupledOptions::full()
        };
        let correction = elastic_tension_correction(f, t);
        let (forcing, worst, scale) = linearisation_gap(f, t, prescribed, &correction);
        assert!(forcing < 1e-12, "forcing at f = {f}: {forcing}");
        // Central differences carry O(h^2) terms of the tension's own eta dependence here.
        assert!(worst < 1e-6 * scale, "f = {f}: {worst} vs {scale}");
        // The correction is real (not zero) but small.
        let size = (0..9)
            .flat_map(|r| (0..9).map(move |c| (r, c)))
            .map(|(r, c)| correction[(r, c)].abs())
            .fold(0.0, f64::max);
        assert!(size > 1e-6 * scale && size < 1e-2 * scale, "{size}");
    }
}

/// With foreshortening on, the linearisation about `eta = 0` also carries the coupling through
/// the chord's acceleration `L'' = -(1/l)(eta'^T G0 eta' + eta^T G0 eta'')`: first order in
/// `eta` because `eta''` is forced, so a deflected link moves the platform and forces the
/// other links. Only that coupling separates it from the prescribed-motion linearisation.
#[test]
fn foreshortening_couples_the_links_at_first_order() {
    let (f, t) = (20.0, 0.0371);
    let on = CoupledOptions {
        elastic_reactions: false,
        ..CoupledOptions::full()
    };
    let zero = Mat::<f64>::zeros(9, 9);
    let (forcing, worst, scale) = linearisation_gap(f, t, on, &zero);
    assert!(forcing < 1e-12);
    assert!(
        worst > 1e-6 * scale && worst < 1e-2 * scale,
        "{worst} vs {scale}"
    );
    // With eta'' = 0 (no forcing: the machine at rest) the coupling vanishes at first order.
    let rest: Arc<dyn Trajectory + Send + Sync> = Arc::new(
        Line::new(
            Pose::new(-0.05, 0.02, std::f64::consts::FRAC_PI_4),
            nalgebra::Vector3::zeros(),
            0.0,
        )
        .unwrap(),
    );
    let mut c = CoupledSystem::new(machine(), rest.clone(), ModalDamping::none(), on).unwrap();
    let mut k = ModalSystem::new(
        machine(),
        rest,
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap();
    let (mut plus, mut minus, mut jk) = (vec![0.0; 18], vec![0.0; 18], Mat::zeros(18, 18));
    k.jacobian(0.0, &[0.0; 18], jk.as_mut());
    // Small steps: the O(h^2) remainder carries omega^2 of the stiffest mode.
    for col in 0..18 {
        let h = if col < 9 { 1e-7 } else { 1e-5 };
        let mut y = vec![0.0; 18];
        y[col] = h;
        c.rhs(0.0, &y, &mut plus);
        y[col] = -h;
        c.rhs(0.0, &y, &mut minus);
        for row in 9..18 {
            let d = (plus[row] - minus[row]) / (2.0 * h);
            assert!(
                (d - jk[(row, col)]).abs() < 1e-6 * 4.4e7,
                "{row} {col}: {d} vs {}",
                jk[(row, col)]
            );
        }
    }
}

/// At `eta = 0` the chord tensions and driving forces are the inverse-dynamics ones with the
/// links' elastic inertia for the coupled model's own `eta''` (model.md section 4 plus
/// [`flexprr_dynamics::ElasticInertia`], computed by the separate 3x3 reduction of `inverse_dynamics`).
#[test]
fn rigid_limit_forces_are_the_inverse_dynamics_forces() {
    let m = machine();
    let traj = circle(20.0);
    let mut c = CoupledSystem::new(
        m.clone(),
        traj.clone(),
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap();
    let k = ked(20.0);
    for t in [0.0, 0.011, 0.023, 0.04] {
        let y0 = c.initial_state();
        let out = c.output(t, &y0).unwrap();
        let elastic = k.elastic_inertia(&c.modal_accelerations(t, &y0).unwrap());
        let state = m
            .geometry
            .inverse_kinematics_unchecked(&traj.motion(t))
            .unwrap();
        let reactions = inverse_dynamics(&m, &state, Some(&elastic), t).unwrap();
        let model = Formulation::consistent().axial.model();
        for i in 0..3 {
            let load = model.load(&flexprr_dynamics::AxialInput {
                leg: &state.legs[i],
                guide_direction: m.geometry.legs[i].guide.direction.into_inner(),
                link: &m.links[i],
                reactions: Some(&reactions),
                index: i,
            });
            let (p_b, p_c) = end_forces(&load, m.links[i].length());
            let scale = p_b.abs().max(p_c.abs()).max(1.0);
            assert!((out.axial_force_b[i] - p_b).abs() < 1e-9 * scale);
            assert!((out.axial_force_c[i] - p_c).abs() < 1e-9 * scale);
            let fa = reactions.driving_force[i];
            assert!((out.driving_force[i] - fa).abs() < 1e-9 * fa.abs().max(1.0));
            assert!(out.pose_deviation().iter().all(|d| d.abs() < 1e-15));
        }
    }
}

/// Along a solution: the pose closes the loop with chords `l - delta`, and the reported
/// velocity and acceleration are central differences of the reported pose and velocity.
#[test]
fn platform_motion_is_consistent_along_a_solution() {
    let m = machine();
    let mut c = coupled(20.0, CoupledOptions::full());
    let h = 2e-6;
    let centres = [0.031, 0.0777, 0.12];
    let mut times = Vec::new();
    for tc in centres {
        times.extend([tc - h, tc, tc + h]);
    }
    let y0 = c.initial_state();
    let sol = Rk45::new(Options::default().rtol(1e-12).atol(1e-15))
        .solve(&mut c, 0.0, &y0, &times)
        .unwrap();
    for (k, tc) in centres.iter().enumerate() {
        let outs: Vec<_> = (0..3)
            .map(|j| c.output(times[3 * k + j], sol.y(3 * k + j)).unwrap())
            .collect();
        let mid = &outs[1];
        // Closure with the foreshortened chords.
        let delta = c.chord_shortening(&sol.y(3 * k + 1)[..9]);
        assert!(delta.iter().any(|d| *d > 1e-7), "deflected: {delta:?}");
        let pose = mid.platform.pose;
        for (i, leg) in m.geometry.legs.iter().enumerate() {
            let rho = m
                .geometry
                .inverse_kinematics_unchecked(&mid.nominal)
                .unwrap()
                .legs[i]
                .rho;
            let b = leg.guide.slider_point(rho);
            let cpt = pose.position() + pose.rotate(&leg.attachment);
            let chord = (cpt - b).norm();
            assert!((chord - (leg.link_length - delta[i])).abs() < 1e-14);
            assert!((chord - mid.chord_length[i]).abs() < 1e-14);
        }
        let q = |o: &flexprr_dynamics::CoupledOutput| o.platform.pose.to_vector();
        let dq = (q(&outs[2]) - q(&outs[0])) / (2.0 * h);
        let dv = (outs[2].platform.velocity - outs[0].platform.velocity) / (2.0 * h);
        let v = mid.platform.velocity;
        let a = mid.platform.acceleration;
        assert!((dq - v).norm() < 1e-6 * v.norm(), "t = {tc}: {dq} vs {v}");
        // The deviation from the nominal acceleration is what foreshortening adds: check it
        // relative to its own size, not only to the total.
        let dev = a - mid.nominal.acceleration;
        assert!(
            (dv - a).norm() < 1e-3 * dev.norm(),
            "t = {tc}: {dv} vs {a} (deviation {dev})"
        );
    }
}

/// The mass matrix of Lagrange's equations is symmetric and positive definite; its
/// configuration-dependent part (the platform and chord inertia seen through the
/// foreshortening) is assembled from independently computed pieces (closure Jacobian, platform
/// balance, link moments), so symmetry is a real check of the derivation. At `eta = 0` it is the
/// modal mass.
#[test]
fn mass_matrix_is_symmetric_positive_definite() {
    let m = machine();
    for (seed, t) in [(0.7, 0.0371), (-0.4, 0.011), (0.9, 0.18)] {
        let mut c = coupled(20.0, CoupledOptions::full());
        let y = state_from(&std::array::from_fn(|k| {
            seed * ((k as f64) * 1.3 + 0.2).sin()
        }));
        let a = c.mass_matrix(t, &y).unwrap();
        let n = 9;
        let size = a.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
        let mut asym: f64 = 0.0;
        let mut coupling: f64 = 0.0;
        for i in 0..n {
            for j in 0..n {
                asym = asym.max((a[i * n + j] - a[j * n + i]).abs());
                let link = i / 3;
                let modal = if link == j / 3 {
                    m.links[link].integrals.mass[(i % 3, j % 3)]
                } else {
                    0.0
                };
                coupling = coupling.max((a[i * n + j] - modal).abs());
            }
        }
        assert!(asym < 1e-12 * size, "asymmetry {asym} of {size}");
        assert!(coupling > 1e-9 * size, "coupling part {coupling}");
        let mat = Mat::from_fn(n, n, |i, j| a[i * n + j]);
        assert!(mat.llt(faer::Side::Lower).is_ok());
        let a0 = c.mass_matrix(t, &[0.0; 18]).unwrap();
        for i in 0..n {
            for j in 0..n {
                let link = i / 3;
                let modal = if link == j / 3 {
                    m.links[link].integrals.mass[(i % 3, j % 3)]
                } else {
                    0.0
                };
                assert!((a0[i * n + j] - modal).abs() <= 1e-15 * size);
            }
        }
    }
}

#[test]
fn three_integrators_agree_on_the_coupled_model() {
    let times = [0.01, 0.02, 0.03];
    let opts = Options::default().rtol(1e-8).atol(1e-12);
    let y0 = vec![0.0; 18];
    let mut reference = coupled(20.0, CoupledOptions::full());
    let r = Rk45::new(Options::default().rtol(1e-11).atol(1e-15))
        .solve(&mut reference, 0.0, &y0, &times)
        .unwrap();
    let mut a = coupled(20.0, CoupledOptions::full());
    let sa = Abm::new(opts.clone())
        .solve(&mut a, 0.0, &y0, &times)
        .unwrap();
    let mut b = coupled(20.0, CoupledOptions::full());
    let sb = Bdf::new(opts.clone())
        .solve(&mut b, 0.0, &y0, &times)
        .unwrap();
    let mut k = coupled(20.0, CoupledOptions::full());
    let sk = Rk45::new(opts).solve(&mut k, 0.0, &y0, &times).unwrap();
    for (n, t) in times.iter().enumerate() {
        for (name, s) in [("abm", &sa), ("bdf", &sb), ("rk45", &sk)] {
            let d = rel_diff(&s.y(n)[..9], &r.y(n)[..9]);
            assert!(d < 1e-4, "{name} at t = {t}: {d}");
        }
    }
    assert!(b.counters().rhs_evaluations > 0);
    assert_eq!(
        a.counters().rhs_evaluations,
        a.counters().acceleration_solves
    );
    assert_eq!(
        a.counters().rhs_evaluations,
        a.counters().forward_kinematics_solves
    );
}

#[test]
fn rhs_allocates_nothing() {
    let mut c = coupled(20.0, CoupledOptions::full());
    let y = state_from(&[0.3; 18]);
    let mut dy = vec![0.0; 18];
    c.rhs(0.01, &y, &mut dy);
    let ((), allocations) = flexprr_testkit::count_allocations(|| {
        for k in 0..100 {
            c.rhs(0.01 + 1e-4 * f64::from(k), &y, &mut dy);
        }
    });
    assert_eq!(allocations, 0);
    assert!(dy.iter().all(|v| v.is_finite()));
}

#[test]
fn bad_input_is_an_error() {
    let bad = CoupledOptions {
        axial_stiffness: Some([1e6, -1.0, 1e6]),
        ..CoupledOptions::full()
    };
    match CoupledSystem::new(machine(), circle(20.0), ModalDamping::none(), bad) {
        Err(DynamicsError::InvalidParameter { quantity, .. }) => {
            assert!(quantity.contains("link 2"), "{quantity}");
        }
        other => panic!("expected InvalidParameter, got {other:?}"),
    }
    assert_eq!(
        "coupled".parse::<CouplingModel>().unwrap(),
        CouplingModel::Coupled
    );
    assert_eq!("ked".parse::<CouplingModel>().unwrap(), CouplingModel::Ked);
    let err = "rigid".parse::<CouplingModel>().unwrap_err();
    assert!(
        matches!(&err, DynamicsError::UnknownCoupling { name } if name == "rigid"),
        "{err}"
    );
    // A path that leaves the workspace: the failure is kept with its time and the right-hand
    // side writes NaN (the integrator then stops).
    let far = Line::new(
        Pose::new(-0.05, 0.0, std::f64::consts::FRAC_PI_4),
        nalgebra::Vector3::new(2.0, 0.0, 0.0),
        0.0,
    )
    .unwrap();
    let mut c = CoupledSystem::new(
        machine(),
        Arc::new(far),
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap();
    let mut dy = vec![0.0; 18];
    c.rhs(0.9, &[0.0; 18], &mut dy);
    assert!(dy.iter().all(|v| v.is_nan()));
    assert!(matches!(
        c.take_failure(),
        Some(DynamicsError::Kinematics { t, .. } | DynamicsError::SingularInverseDynamics { t, .. }) if (t - 0.9).abs() < 1e-15
    ));
    assert!(c.output(0.5, &[0.0; 3]).is_err());
}

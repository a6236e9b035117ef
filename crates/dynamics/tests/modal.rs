//! The modal system (eq. 16 and model.md section 6) against independent checks: its analytic
//! Jacobian against central differences of its own right-hand side, heap allocations counted
//! by a global allocator, the work counters, each switch of [`Formulation`] against the
//! closed-form term it adds (sine-basis integrals in closed form, axial forces from the
//! independent 12-equation inverse dynamics, geometric stiffness by Gauss quadrature), modal
//! damping against `2 zeta omega_j`, and the machine at rest against free pinned-pinned
//! oscillators (closed-form frequencies and responses).

use std::f64::consts::PI;
use std::sync::Arc;

use faer::Mat;
use flexprr_beam::{Basis, GaussLegendre, HermiteBasis, UniformSection};
use flexprr_dynamics::{
    AxialModel, Coupling, DynamicsError, Formulation, LinkModel, Machine, ModalDamping,
    ModalSystem, inverse_dynamics_full, paper,
};
use flexprr_integrators::{Integrator, OdeSystem, Options, Rk45};
use flexprr_kinematics::{PlatformMotion, Pose, Trajectory};

// ---------------------------------------------------------------------------------------
// Allocation counter (per thread, so that tests running in parallel do not disturb each other).

use flexprr_testkit::alloc::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

// ---------------------------------------------------------------------------------------
// Helpers.

/// The platform held still at `pose` (a constant trajectory).
#[derive(Debug, Clone, Copy)]
struct AtRest(Pose);

impl Trajectory for AtRest {
    fn motion(&self, _t: f64) -> PlatformMotion {
        PlatformMotion::at_rest(self.0)
    }
}

/// The centre of the paper's circle: well away from both singularity types.
const REST_POSE: Pose = Pose::new(-0.05, 0.0, PI / 4.0);

fn paper_machine(r: usize) -> Arc<Machine> {
    Arc::new(paper::machine(r, paper::YOUNGS_MODULUS).unwrap())
}

fn circle_system(r: usize, formulation: Formulation, damping: ModalDamping) -> ModalSystem {
    let trajectory = Arc::new(paper::trajectory(20.0).unwrap());
    ModalSystem::new(paper_machine(r), trajectory, formulation, damping).unwrap()
}

/// A deterministic, irregular state: displacements of order 1 mm, rates of order 0.1 m/s.
fn test_state(modes: usize, seed: u64) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    (0..2 * modes)
        .map(|k| {
            if k < modes {
                1e-3 * next()
            } else {
                0.1 * next()
            }
        })
        .collect()
}

fn rhs(sys: &mut ModalSystem, t: f64, y: &[f64]) -> Vec<f64> {
    let mut dy = vec![0.0; y.len()];
    sys.rhs(t, y, &mut dy);
    dy
}

/// Bending stiffness and mass per length of the paper's link (closed form, `I = h t^3 / 12`).
fn paper_section() -> (f64, f64) {
    let ei = paper::YOUNGS_MODULUS * paper::HEIGHT * paper::THICKNESS.powi(3) / 12.0;
    let rho_a = paper::DENSITY * paper::HEIGHT * paper::THICKNESS;
    (ei, rho_a)
}

/// Unloaded pinned-pinned circular frequency of mode `j` (1-based): `(j pi / l)^2 sqrt(EI/rhoA)`
/// (the paper's eq. 23).
fn pinned_omega(j: usize) -> f64 {
    let (ei, rho_a) = paper_section();
    (j as f64 * PI / paper::LINK_LENGTH).powi(2) * (ei / rho_a).sqrt()
}

fn with(f: Formulation, edit: impl FnOnce(&mut Formulation)) -> Formulation {
    let mut f = f;
    edit(&mut f);
    f
}

fn alpha(i: usize) -> f64 {
    paper::ALPHA_DEG[i].to_radians()
}

// ---------------------------------------------------------------------------------------
// Jacobian.

/// Central differences of the right-hand side against the analytic Jacobian, on the paper's
/// machine (sine basis, r = 3 and r = 6) and on Hermite elements (full mass matrix), both
/// formulations, with modal damping. The rhs is affine in `y`, so central differences are
/// exact up to rounding and the tolerance can be tight.
#[test]
fn analytic_jacobian_equals_central_differences() {
    let hermite_machine = {
        let section =
            UniformSection::rectangle(paper::YOUNGS_MODULUS, paper::DENSITY, 0.002, 0.03).unwrap();
        let basis: Arc<dyn Basis> = Arc::new(HermiteBasis::pinned_pinned(3).unwrap());
        let link = LinkModel::new(basis, &section, paper::LINK_LENGTH).unwrap();
        let base = paper::machine(1, paper::YOUNGS_MODULUS).unwrap();
        Arc::new(
            Machine::new(
                base.geometry,
                [link.clone(), link.clone(), link],
                base.slider_mass,
                base.platform_mass,
                base.platform_inertia,
            )
            .unwrap(),
        )
    };
    let machines = [
        ("sine r=3", paper_machine(3)),
        ("sine r=6", paper_machine(6)),
        ("hermite 3 elements", hermite_machine),
    ];
    for (name, machine) in machines {
        for formulation in [Formulation::paper(), Formulation::consistent()] {
            let mut sys = ModalSystem::new(
                machine.clone(),
                Arc::new(paper::trajectory(20.0).unwrap()),
                formulation,
                ModalDamping::uniform(0.03),
            )
            .unwrap();
            let n = sys.dim();
            for (k, t) in [0.0, 0.0131, 0.027, 0.0412].into_iter().enumerate() {
                let y = test_state(sys.modes(), k as u64 + 7);
                let mut jac = Mat::<f64>::zeros(n, n);
                sys.jacobian(t, &y, jac.as_mut());
                let mut yp = y.clone();
                for col in 0..n {
                    let h = 1e-3 * y[col].abs().max(1e-6);
                    yp[col] = y[col] + h;
                    let fp = rhs(&mut sys, t, &yp);
                    yp[col] = y[col] - h;
                    let fm = rhs(&mut sys, t, &yp);
                    yp[col] = y[col];
                    for row in 0..n {
                        let fd = (fp[row] - fm[row]) / (2.0 * h);
                        let row_scale = (0..n).map(|c| jac[(row, c)].abs()).fold(1.0, f64::max);
                        assert!(
                            (fd - jac[(row, col)]).abs() <= 1e-8 * row_scale,
                            "{name}, {formulation}, t = {t}: J[{row}, {col}] analytic {} vs differenced {fd}",
                            jac[(row, col)]
                        );
                    }
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Allocations and counters.

/// The right-hand side and the analytic Jacobian allocate nothing, for every axial model.
#[test]
fn rhs_and_jacobian_allocate_nothing() {
    let none = with(Formulation::paper(), |f| f.axial = AxialModel::None);
    for formulation in [Formulation::paper(), Formulation::consistent(), none] {
        let mut sys = circle_system(3, formulation, ModalDamping::uniform(0.02));
        let n = sys.dim();
        let y = test_state(sys.modes(), 3);
        let mut dy = vec![0.0; n];
        let mut jac = Mat::<f64>::zeros(n, n);
        sys.rhs(0.0, &y, &mut dy);
        sys.jacobian(0.0, &y, jac.as_mut());
        let before = allocations();
        for k in 0..1000 {
            let t = k as f64 * 1e-4;
            sys.rhs(t, &y, &mut dy);
            if k % 100 == 0 {
                sys.jacobian(t, &y, jac.as_mut());
            }
        }
        let used = allocations() - before;
        assert_eq!(used, 0, "{formulation}: {used} allocations in 1000 rhs");
        assert!(dy.iter().all(|v| v.is_finite()));
    }
}

/// Without axial force no rigid inverse dynamics is solved (over a whole integration and
/// Jacobian evaluations), while the paper's axial force solves exactly one per instant.
/// Independent evidence: at the type-II singular home pose the system without axial force
/// still evaluates, whereas with the paper's axial force it reports the singular pose.
#[test]
fn no_axial_force_never_solves_inverse_dynamics() {
    let none = with(Formulation::paper(), |f| f.axial = AxialModel::None);
    let mut sys = circle_system(3, none, ModalDamping::none());
    let y0 = sys.initial_state();
    let mut jac = Mat::<f64>::zeros(sys.dim(), sys.dim());
    Rk45::new(Options::default().rtol(1e-6).atol(1e-10))
        .solve(&mut sys, 0.0, &y0, &[0.05])
        .unwrap();
    sys.jacobian(0.01, &y0, jac.as_mut());
    let c = sys.counters();
    assert!(
        c.rhs_evaluations > 50 && c.jacobian_evaluations == 1,
        "{c:?}"
    );
    assert_eq!(c.inverse_dynamics_solves, 0, "{c:?}");

    let mut sys = circle_system(3, Formulation::paper(), ModalDamping::none());
    let mut dy = vec![0.0; sys.dim()];
    for k in 0..10 {
        sys.rhs(k as f64 * 1e-3, &y0, &mut dy);
    }
    sys.jacobian(0.01, &y0, jac.as_mut());
    let c = sys.counters();
    assert_eq!(c.inverse_dynamics_solves, 11, "{c:?}");

    // The home pose: the link lines meet at the platform centre.
    let home = Arc::new(AtRest(Pose::new(0.0, 0.0, 0.0)));
    let mut sys =
        ModalSystem::new(paper_machine(3), home.clone(), none, ModalDamping::none()).unwrap();
    let y = test_state(9, 1);
    let mut dy = vec![0.0; 18];
    sys.rhs(0.1, &y, &mut dy);
    assert!(dy.iter().all(|v| v.is_finite()) && sys.take_failure().is_none());
    let mut sys = ModalSystem::new(
        paper_machine(3),
        home,
        Formulation::paper(),
        ModalDamping::none(),
    )
    .unwrap();
    sys.rhs(0.1, &y, &mut dy);
    assert!(dy.iter().all(|v| v.is_nan()));
    let failure = sys.take_failure();
    assert!(
        matches!(
            failure,
            Some(DynamicsError::SingularInverseDynamics { t, .. }) if (t - 0.1).abs() < 1e-15
        ),
        "{failure:?}"
    );
}

// ---------------------------------------------------------------------------------------
// Each switch of the formulation, against the closed-form term it adds.

/// Evaluates the acceleration part of the rhs for two formulations at the same `(t, y)`.
fn acceleration_difference(
    a: Formulation,
    b: Formulation,
    damping: ModalDamping,
    t: f64,
    y: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let mut sa = circle_system(3, a, damping.clone());
    let mut sb = circle_system(3, b, damping);
    let n = sa.modes();
    let fa = rhs(&mut sa, t, y);
    let fb = rhs(&mut sb, t, y);
    let scale = fa[n..].iter().map(|v| v.abs()).fold(1.0, f64::max);
    let diff = fa[n..].iter().zip(&fb[n..]).map(|(p, q)| p - q).collect();
    (diff, vec![scale; n])
}

fn assert_close(what: &str, got: &[f64], expected: &[f64], scale: &[f64], tol: f64) {
    for (k, ((g, e), s)) in got.iter().zip(expected).zip(scale).enumerate() {
        assert!(
            (g - e).abs() <= tol * s,
            "{what}: component {k}: {g} vs expected {e} (scale {s})"
        );
    }
}

const TIMES: [f64; 5] = [0.0, 0.0093, 0.0187, 0.031, 0.044];

/// Centrifugal softening on minus off is `b'^2 eta` for every mode (model.md section 6).
#[test]
fn softening_adds_beta_rate_squared_times_eta() {
    let off = with(Formulation::consistent(), |f| {
        f.centrifugal_softening = false
    });
    let mut probe = circle_system(3, Formulation::consistent(), ModalDamping::none());
    for (k, t) in TIMES.into_iter().enumerate() {
        let y = test_state(9, k as u64);
        let (diff, scale) =
            acceleration_difference(Formulation::consistent(), off, ModalDamping::none(), t, &y);
        let legs = probe.instant(t).unwrap().state.legs;
        let expected: Vec<f64> = (0..9)
            .map(|m| legs[m / 3].beta_dot.powi(2) * y[m])
            .collect();
        assert_close("softening", &diff, &expected, &scale, 1e-13);
        assert!(expected.iter().any(|v| v.abs() > 1e-6));
    }
}

/// The paper's `F_fg` on minus off is `rho' b' cos(a - b) M^-1 m int psi`; for sine modes
/// (`m_jj = m/2`, `int sin(j pi xi) = (1 - (-1)^j) / (j pi)`) that is
/// `rho' b' cos(a - b) 2 (1 - (-1)^j) / (j pi)`, angles from the guide and link angles.
#[test]
fn coriolis_forcing_adds_the_closed_form_term() {
    let off = with(Formulation::paper(), |f| f.coriolis_forcing = false);
    let mut probe = circle_system(3, Formulation::paper(), ModalDamping::none());
    for (k, t) in TIMES.into_iter().enumerate() {
        let y = test_state(9, k as u64 + 20);
        let (diff, scale) =
            acceleration_difference(Formulation::paper(), off, ModalDamping::none(), t, &y);
        let legs = probe.instant(t).unwrap().state.legs;
        let expected: Vec<f64> = (0..9)
            .map(|m| {
                let (i, j) = (m / 3, m % 3 + 1);
                let leg = &legs[i];
                let sign = if j % 2 == 1 { 2.0 } else { 0.0 };
                leg.rho_dot * leg.beta_dot * (alpha(i) - leg.beta).cos() * 2.0 * sign
                    / (j as f64 * PI)
            })
            .collect();
        assert_close("F_fg", &diff, &expected, &scale, 1e-13);
        assert!(expected.iter().any(|v| v.abs() > 1.0));
    }
}

/// `Kp_jk = int_0^l P psi_j' psi_k' dx` for sine modes by Gauss quadrature, with
/// `psi_j'(x) = (j pi / l) cos(j pi x / l)`.
fn sine_geometric_stiffness(p: impl Fn(f64) -> f64, l: f64) -> [[f64; 3]; 3] {
    let rule = GaussLegendre::new(24).unwrap();
    let mut kp = [[0.0; 3]; 3];
    for (j, row) in kp.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            let (wj, wk) = ((j + 1) as f64 * PI / l, (k + 1) as f64 * PI / l);
            *v = rule.integrate(0.0, l, |x| p(x) * wj * (wj * x).cos() * wk * (wk * x).cos());
        }
    }
    kp
}

/// Full minus diagonal `Kp` is `-M^-1 (Kp - diag Kp) eta`, `Kp` by quadrature of the load.
#[test]
fn full_geometric_stiffness_adds_the_off_diagonal_coupling() {
    let diagonal = with(Formulation::consistent(), |f| {
        f.geometric_stiffness = Coupling::Diagonal;
    });
    let mut probe = circle_system(3, Formulation::consistent(), ModalDamping::none());
    let m = probe.machine().links[0].mass();
    let l = paper::LINK_LENGTH;
    for (k, t) in TIMES.into_iter().enumerate() {
        let y = test_state(9, k as u64 + 40);
        let (diff, scale) = acceleration_difference(
            Formulation::consistent(),
            diagonal,
            ModalDamping::none(),
            t,
            &y,
        );
        let loads = probe.instant(t).unwrap().loads;
        let mut expected = vec![0.0; 9];
        for i in 0..3 {
            let kp = sine_geometric_stiffness(|x| loads[i].at(x), l);
            for j in 0..3 {
                let coupling: f64 = (0..3)
                    .filter(|&q| q != j)
                    .map(|q| kp[j][q] * y[3 * i + q])
                    .sum();
                expected[3 * i + j] = -coupling / (m / 2.0);
            }
        }
        assert_close("full Kp", &diff, &expected, &scale, 1e-12);
        assert!(expected.iter().any(|v| v.abs() > 1e-3));
    }
}

/// Axial model on minus off is `-M^-1 Kp(P) eta`, with `P(x)` rebuilt from the independent
/// 12-equation inverse dynamics: eq. (12) `(m_s rho'' - F_a) cos(b - a)` (paper, diagonal
/// `Kp`) and `-F_B.e` (joint reaction, full `Kp`), plus the inertia part of eq. (11).
#[test]
fn axial_models_add_the_geometric_stiffness_of_eq_12() {
    let cases = [
        (Formulation::paper(), AxialModel::Paper),
        (Formulation::consistent(), AxialModel::JointReaction),
    ];
    let (_, rho_a) = paper_section();
    let l = paper::LINK_LENGTH;
    for (base, model) in cases {
        let none = with(base, |f| f.axial = AxialModel::None);
        let mut probe = circle_system(3, base, ModalDamping::none());
        let machine = probe.machine().clone();
        let m = machine.links[0].mass();
        for (k, t) in TIMES.into_iter().enumerate() {
            let y = test_state(9, k as u64 + 60);
            let (diff, scale) = acceleration_difference(base, none, ModalDamping::none(), t, &y);
            let state = probe.instant(t).unwrap().state;
            let reactions = inverse_dynamics_full(&machine, &state, t).unwrap();
            let mut expected = vec![0.0; 9];
            for i in 0..3 {
                let leg = &state.legs[i];
                let cos_ba = (leg.beta - alpha(i)).cos();
                let p0 = match model {
                    AxialModel::Paper => {
                        (paper::SLIDER_MASS * leg.rho_ddot - reactions.driving_force[i]) * cos_ba
                    }
                    _ => -reactions.slider_on_link[i].dot(&leg.e),
                };
                let p = |x: f64| {
                    p0 + rho_a * (leg.rho_ddot * cos_ba * x - 0.5 * leg.beta_dot.powi(2) * x * x)
                };
                let kp = sine_geometric_stiffness(p, l);
                for j in 0..3 {
                    let force: f64 = match model {
                        AxialModel::Paper => kp[j][j] * y[3 * i + j],
                        _ => (0..3).map(|q| kp[j][q] * y[3 * i + q]).sum(),
                    };
                    expected[3 * i + j] = -force / (m / 2.0);
                }
            }
            assert_close(&format!("{model:?}"), &diff, &expected, &scale, 1e-10);
            assert!(expected.iter().any(|v| v.abs() > 1.0));
        }
    }
}

/// Modal damping on a sine basis: `-2 zeta_j omega_j eta_j'` exactly (diagonal), with
/// `omega_j` the closed-form pinned-pinned frequency, one ratio for all modes or one per mode.
#[test]
fn modal_damping_on_sine_modes_is_two_zeta_omega() {
    for ratios in [vec![0.02], vec![0.01, 0.05, 0.003]] {
        let damping = ModalDamping {
            ratios: ratios.clone(),
        };
        let zeta = |j: usize| {
            if ratios.len() == 1 {
                ratios[0]
            } else {
                ratios[j]
            }
        };
        for formulation in [Formulation::paper(), Formulation::consistent()] {
            let y = test_state(9, 99);
            let mut damped = circle_system(3, formulation, damping.clone());
            let mut undamped = circle_system(3, formulation, ModalDamping::none());
            let fd = rhs(&mut damped, 0.01, &y);
            let fu = rhs(&mut undamped, 0.01, &y);
            let scale = fu[9..].iter().map(|v| v.abs()).fold(1.0, f64::max);
            for m in 0..9 {
                let j = m % 3;
                let expected = -2.0 * zeta(j) * pinned_omega(j + 1) * y[9 + m];
                let got = fd[9 + m] - fu[9 + m];
                assert!(
                    (got - expected).abs() <= 1e-9 * expected.abs() + 1e-13 * scale,
                    "{formulation}, mode {m}: {got} vs {expected}"
                );
            }
            let mut jac = Mat::<f64>::zeros(18, 18);
            damped.jacobian(0.01, &y, jac.as_mut());
            for a in 0..9 {
                for b in 0..9 {
                    let expected = if a == b {
                        -2.0 * zeta(a % 3) * pinned_omega(a % 3 + 1)
                    } else {
                        0.0
                    };
                    assert!(
                        (jac[(9 + a, 9 + b)] - expected).abs() <= 1e-9 * pinned_omega(3) * 0.05,
                        "damping block ({a}, {b}): {} vs {expected}",
                        jac[(9 + a, 9 + b)]
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Platform at rest: free oscillators.

/// With the platform at rest (a constant trajectory at the centre of the paper's circle)
/// every forcing term and axial force vanishes: the rhs at zero state is zero, each sine mode
/// is a free oscillator `eta'' = -omega_j^2 eta` at the unloaded frequency (eq. 23), and an
/// integration from a displaced mode follows `A cos(omega_j t)`.
#[test]
fn platform_at_rest_gives_free_oscillators_at_unloaded_frequencies() {
    let rest = Arc::new(AtRest(REST_POSE));
    for formulation in [Formulation::paper(), Formulation::consistent()] {
        let mut sys = ModalSystem::new(
            paper_machine(3),
            rest.clone(),
            formulation,
            ModalDamping::none(),
        )
        .unwrap();
        let zero = vec![0.0; 18];
        assert!(rhs(&mut sys, 0.3, &zero).iter().all(|v| v.abs() < 1e-12));
        for m in 0..9 {
            let mut y = vec![0.0; 18];
            y[m] = 1e-3;
            let f = rhs(&mut sys, 0.3, &y);
            let omega2 = pinned_omega(m % 3 + 1).powi(2);
            for (q, v) in f[9..].iter().enumerate() {
                let expected = if q == m { -omega2 * 1e-3 } else { 0.0 };
                assert!(
                    (v - expected).abs() <= 1e-9 * omega2 * 1e-3,
                    "{formulation}: mode {m} -> {q}: {v} vs {expected}"
                );
            }
        }
        // One displaced mode per link (modes 1, 2, 3 of links 1, 2, 3), two periods of mode 1.
        let mut y0 = vec![0.0; 18];
        let amplitude = [1e-3, 2e-4, 5e-5];
        for (i, a) in amplitude.iter().enumerate() {
            y0[3 * i + i] = *a;
        }
        let t_end = 2.0 * std::f64::consts::TAU / pinned_omega(1);
        let t_out: Vec<f64> = (1..=20).map(|k| t_end * k as f64 / 20.0).collect();
        let sol = Rk45::new(Options::default().rtol(1e-10).atol(1e-14))
            .solve(&mut sys, 0.0, &y0, &t_out)
            .unwrap();
        for (k, t) in t_out.iter().enumerate() {
            for (i, a) in amplitude.iter().enumerate() {
                for j in 0..3 {
                    let exact = if i == j {
                        a * (pinned_omega(j + 1) * t).cos()
                    } else {
                        0.0
                    };
                    let got = sol.y(k)[3 * i + j];
                    assert!(
                        (got - exact).abs() <= 1e-7 * a,
                        "{formulation}: t = {t}, link {i} mode {j}: {got} vs {exact}"
                    );
                }
            }
        }
    }
}

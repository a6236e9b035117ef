//! Whole-machine linear models against closed forms (docs/linear.md, "Validation"):
//!
//! * the locked coupled machine at rest: its chords are axially rigid and the sliders fixed,
//!   so the platform cannot move and each link is a pinned-pinned Euler-Bernoulli beam:
//!   `f_k = k^2 pi / (2 l^2) sqrt(EI / rho A)`, each three times (three identical links);
//! * the nonlinear (axially elastic) model's platform modes: a rigid platform on three axial
//!   springs `EA / l` along the chords (derivation in
//!   [`platform_on_axial_springs_hz`]);
//! * the servo modes of a machine with rigid links: `omega^2` the eigenvalues of `kp I`
//!   against the rigid mass matrix in slider coordinates, built from the rigid inverse
//!   dynamics (a separate code, model.md section 4);
//! * the low-frequency limit of a frequency response: the static deflection of a
//!   pinned-pinned beam under a point load, by its three-mode series and in closed form;
//! * the Hessenberg frequency response against a dense complex LU solve of
//!   `(i omega I - A) X = B` (and the eigenvector form, where that is well conditioned).

use std::f64::consts::PI;
use std::sync::Arc;

use flexprr_control::{Actuator, IdealForce, MotorBallScrew, MotorRatings, Pid, Screw};
use flexprr_dynamics::{
    Actuation, CoupledOptions, CoupledSystem, Machine, ModalDamping, NonlinearOptions,
    NonlinearSystem, SceneModel, inverse_dynamics, paper,
};
use flexprr_integrators::{Integrator, Options, Rk45};
use flexprr_kinematics::{Line, PlatformMotion, Pose, Trajectory};
use flexprr_linear::{
    Axis, Input, Output, frequency_response, frequency_response_direct, linearize, modes,
};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Poses at rest inside the workspace (m, m, deg).
const POSES: [(f64, f64, f64); 3] = [(0.0, 0.0, 45.0), (-0.05, 0.02, 40.0), (-0.1, 0.0, 45.0)];

fn pose((x, y, phi): (f64, f64, f64)) -> Pose {
    Pose::new(x, y, phi.to_radians())
}

fn rest(at: Pose) -> Arc<dyn Trajectory + Send + Sync> {
    Arc::new(Line::new(at, Vector3::zeros(), 0.0).unwrap())
}

fn coupled(machine: Arc<Machine>, at: Pose, actuation: Option<Actuation>) -> Box<dyn SceneModel> {
    let c = CoupledSystem::new(
        machine,
        rest(at),
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap();
    match actuation {
        Some(a) => Box::new(c.with_actuation(a, 0.0).unwrap()),
        None => Box::new(c),
    }
}

fn pd(kp: f64, kd: f64) -> Actuation {
    let force: Arc<dyn Actuator> = Arc::new(IdealForce);
    Actuation {
        controller: Arc::new(Pid::pd(kp, kd, false, 0.0).unwrap()),
        actuators: [force.clone(), force.clone(), force],
    }
}

/// `sqrt(EI / rho A)` of the paper's link.
fn beam_speed() -> f64 {
    let ei = paper::YOUNGS_MODULUS * paper::HEIGHT * paper::THICKNESS.powi(3) / 12.0;
    let rho_a = paper::DENSITY * paper::HEIGHT * paper::THICKNESS;
    (ei / rho_a).sqrt()
}

/// The pinned-pinned link's `k`-th natural frequency (Hz).
fn pinned_pinned_hz(k: usize) -> f64 {
    let k = k as f64;
    k * k * PI / (2.0 * paper::LINK_LENGTH.powi(2)) * beam_speed()
}

#[test]
fn locked_coupled_bending_modes_are_the_pinned_pinned_links() {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    for p in POSES {
        let mut model = coupled(machine.clone(), pose(p), None);
        let y0 = model.initial_state();
        let lin = linearize(model.as_mut(), 0.0, &y0, &[], &[]).unwrap();
        let found = modes(&lin).unwrap();
        assert_eq!(found.len(), 9, "{p:?}");
        let mut worst = 0.0_f64;
        for (k, m) in found.iter().enumerate() {
            let exact = pinned_pinned_hz(k / 3 + 1);
            worst = worst.max((m.frequency_hz - exact).abs() / exact);
            assert!(m.damping_ratio.abs() < 1e-6, "{p:?}: {m:?}");
        }
        println!(
            "{p:?}: 9 bending modes within {worst:.1e} of 116.39/465.57/1047.52 Hz ({:.4}, {:.4}, {:.4})",
            pinned_pinned_hz(1),
            pinned_pinned_hz(2),
            pinned_pinned_hz(3)
        );
        assert!(worst < 1e-7, "{p:?}: {worst}");
    }
}

/// For each link at the pose `at`: `G_i` (platform motion to the motion of its joint `C_i`)
/// and the chord's unit vector `u_i` from the slider's pin `B_i` to `C_i`.
fn chords(machine: &Machine, at: Pose) -> Vec<(nalgebra::Matrix2x3<f64>, nalgebra::Vector2<f64>)> {
    let state = machine
        .geometry
        .inverse_kinematics(&PlatformMotion::at_rest(at))
        .unwrap();
    let (sin, cos) = at.phi.sin_cos();
    machine
        .geometry
        .legs
        .iter()
        .enumerate()
        .map(|(i, leg)| {
            let a = leg.attachment;
            let r = nalgebra::Vector2::new(cos * a.x - sin * a.y, sin * a.x + cos * a.y);
            let b = leg.guide.anchor.coords + state.legs[i].rho * leg.guide.direction.into_inner();
            let c = nalgebra::Vector2::new(at.x + r.x, at.y + r.y);
            let u = (c - nalgebra::Vector2::new(b.x, b.y)).normalize();
            (nalgebra::Matrix2x3::new(1.0, 0.0, -r.y, 0.0, 1.0, r.x), u)
        })
        .collect()
}

/// `sqrt(eig(M^-1 K)) / 2 pi`, sorted, for symmetric `K` and positive definite `M`.
fn frequencies_hz(k: &Matrix3<f64>, m: &Matrix3<f64>) -> [f64; 3] {
    let l_inv = m.cholesky().unwrap().l().try_inverse().unwrap();
    let mut w2: Vec<f64> = SymmetricEigen::new(l_inv * k * l_inv.transpose())
        .eigenvalues
        .iter()
        .copied()
        .collect();
    w2.sort_by(f64::total_cmp);
    std::array::from_fn(|q| w2[q].sqrt() / (2.0 * PI))
}

/// The platform's mass matrix `diag(m_p, m_p, I_p)`.
fn platform_mass(machine: &Machine) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(
        machine.platform_mass,
        machine.platform_mass,
        machine.platform_inertia,
    ))
}

/// The platform modes of a rigid platform on three axial springs (Rayleigh).
///
/// Platform coordinates `q = (x, y, phi)`; joint `C_i = P + R(phi) a_i`, its small motion
/// `dC_i = G_i dq` with `G_i = [[1, 0, -r_iy], [0, 1, r_ix]]`, `r_i = R(phi) a_i`. Link `i`
/// (chord unit vector `u_i` from the slider's pin `B_i`, locked, to `C_i`) stretches by
/// `u_i . dC_i`, so `K = sum_i (EA / l) G_i^T u_i u_i^T G_i` (no preload at rest, so no
/// geometric stiffness). With bending far stiffer than the platform modes need, a link turns
/// as a rigid bar about `B_i` across its chord, and stretches along it in its static shape
/// (linear in `xi`): either way a point at `xi` moves `xi dC_i`, so the link's kinetic
/// energy is `(m_l / 3) |dC_i'|^2 / 2` and
/// `M = diag(m_p, m_p, I_p) + sum_i (m_l / 3) G_i^T G_i`.
fn platform_on_axial_springs_hz(machine: &Machine, at: Pose, axial_stiffness: f64) -> [f64; 3] {
    let (mut k, mut m) = (Matrix3::zeros(), platform_mass(machine));
    for (i, (g, u)) in chords(machine, at).iter().enumerate() {
        let j = u.transpose() * g;
        k += axial_stiffness / machine.links[i].length() * j.transpose() * j;
        m += machine.links[i].mass() / 3.0 * g.transpose() * g;
    }
    frequencies_hz(&k, &m)
}

/// The dynamic stiffness at its free end of a chain of `n` equal springs (each `n k`) and
/// lumped masses (`m / n` inside, `m / 2n` at the free end), fixed at the other end: the
/// nonlinear model's link along its chord. Recursion from the fixed end: a spring `s` in
/// series with the chain behind it, `S <- s S / (s + S)`, then the node's inertia
/// `S <- S - omega^2 m_j`.
fn chain_stiffness(k: f64, m: f64, n: usize, omega: f64) -> f64 {
    let (spring, node) = (n as f64 * k, m / n as f64);
    let mut behind = spring;
    for _ in 1..n {
        let with_node = behind - omega * omega * node;
        behind = spring * with_node / (spring + with_node);
    }
    behind - omega * omega * 0.5 * node
}

/// The platform modes with the links' axial inertia exact for the model's lumped chain: the
/// roots of `det(K(omega) - omega^2 M_t) = 0` with `K(omega) = sum_i S(omega) J_i^T J_i`
/// ([`chain_stiffness`], which holds the link's mass along the chord) and `M_t` the platform
/// plus each link turning rigidly across its chord: `sum_j m_j xi_j^2 = m (2 n^2 + 1) /
/// (6 n^2)` for the lumped masses, plus the nodes' rotary inertia (`rhoA L_e^3 / 78` per
/// element end: `2 m / (78 n^2)` at the joint). Each root by the fixed point `omega_q^2 = q-th
/// eigenvalue of M_t^-1 K(omega_q)`, from the Rayleigh value.
fn platform_on_axial_chains_hz(
    machine: &Machine,
    at: Pose,
    axial_stiffness: f64,
    n: usize,
    start: [f64; 3],
) -> [f64; 3] {
    let links = chords(machine, at);
    let n_f = n as f64;
    let mut m = platform_mass(machine);
    for (i, (g, u)) in links.iter().enumerate() {
        let across = nalgebra::Matrix2::identity() - u * u.transpose();
        // Node masses at xi_j = j / n, and the nodes' rotary inertia (rhoA L_e^3 / 78 per
        // element end, each node turning with the bar at dC / l).
        let turning = machine.links[i].mass()
            * ((2.0 * n_f * n_f + 1.0) / (6.0 * n_f * n_f) + 2.0 / (78.0 * n_f * n_f));
        m += turning * g.transpose() * across * g;
    }
    std::array::from_fn(|q| {
        let mut f = start[q];
        for _ in 0..50 {
            let omega = 2.0 * PI * f;
            let mut k = Matrix3::zeros();
            for (i, (g, u)) in links.iter().enumerate() {
                let j = u.transpose() * g;
                let s = chain_stiffness(
                    axial_stiffness / machine.links[i].length(),
                    machine.links[i].mass(),
                    n,
                    omega,
                );
                k += s * j.transpose() * j;
            }
            f = frequencies_hz(&k, &m)[q];
        }
        f
    })
}

#[test]
fn nonlinear_platform_modes_are_a_platform_on_axial_springs() {
    // Bending 1e8 times stiffer (first bending mode above 1 MHz): the links turn rigidly
    // across their chords, and the lowest three modes are the platform's (1.9 and 3.7 kHz
    // at the centre), the next ones the links' axial modes (13 kHz).
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let base = NonlinearOptions::paper(paper::YOUNGS_MODULUS);
    let ea = base.axial_stiffness[0];
    let elements = 8;
    // Lumped nodal masses: the chains below are lumped (the consistent mass of the default
    // has its own axial chain, checked by the whole-machine modes against the reference).
    let options = NonlinearOptions {
        elements,
        bending_stiffness: base.bending_stiffness.map(|ei| 1e8 * ei),
        mass: flexprr_dynamics::nonlinear::NodalMass::Lumped,
        ..base
    };
    for p in POSES {
        let at = pose(p);
        let mut model = NonlinearSystem::new(machine.clone(), rest(at), options).unwrap();
        model.start_at(0.0).unwrap();
        let mut model: Box<dyn SceneModel> = Box::new(model);
        let y0 = model.initial_state();
        let lin = linearize(model.as_mut(), 0.0, &y0, &[], &[]).unwrap();
        let found = modes(&lin).unwrap();
        let rayleigh = platform_on_axial_springs_hz(&machine, at, ea);
        let chains = platform_on_axial_chains_hz(&machine, at, ea, elements, rayleigh);
        let worst = |expected: [f64; 3]| {
            (0..3)
                .map(|q| (found[q].frequency_hz - expected[q]).abs() / expected[q])
                .fold(0.0_f64, f64::max)
        };
        println!(
            "{p:?}: platform modes {:.2} {:.2} {:.2} Hz; on axial springs (Rayleigh) {:.2} {:.2} {:.2} Hz ({:.1e}); on lumped axial chains {:.2} {:.2} {:.2} Hz ({:.1e}); next mode {:.0} Hz",
            found[0].frequency_hz,
            found[1].frequency_hz,
            found[2].frequency_hz,
            rayleigh[0],
            rayleigh[1],
            rayleigh[2],
            worst(rayleigh),
            chains[0],
            chains[1],
            chains[2],
            worst(chains),
            found[3].frequency_hz
        );
        // With the links' axial inertia in full, the model's platform modes to 1e-6.
        assert!(worst(chains) < 1e-6, "{p:?}: {}", worst(chains));
        // The springs with m_l / 3 (Rayleigh's static shape) are high by the links' axial
        // inertia: the links carry 40 % of the platform's rotational inertia, and the
        // rotation mode (3.7 kHz) is a third of the way to the links' axial modes (a
        // clamped-free rod with the platform's share at its end: 10-13 kHz here), which
        // puts it 1 % low; the translations (1.9 kHz) 0.1 % low.
        assert!(worst(rayleigh) < 1.5e-2, "{p:?}: {}", worst(rayleigh));
        assert!(found[3].frequency_hz > 3.0 * found[2].frequency_hz);
    }
}

/// The rigid machine's mass matrix in slider coordinates at `at` at rest, from the rigid
/// inverse dynamics: the driving forces `F = M_rho rho''` of three platform accelerations.
fn slider_mass_matrix(machine: &Machine, at: Pose) -> Matrix3<f64> {
    let (mut forces, mut accelerations) = (Matrix3::zeros(), Matrix3::zeros());
    for k in 0..3 {
        let mut acceleration = Vector3::zeros();
        acceleration[k] = 1.0;
        let motion = PlatformMotion {
            pose: at,
            velocity: Vector3::zeros(),
            acceleration,
        };
        let state = machine
            .geometry
            .inverse_kinematics_unchecked(&motion)
            .unwrap();
        let reactions = inverse_dynamics(machine, &state, None, 0.0).unwrap();
        forces.set_column(k, &Vector3::from(reactions.driving_force));
        accelerations.set_column(
            k,
            &Vector3::from(std::array::from_fn::<f64, 3, _>(|i| state.legs[i].rho_ddot)),
        );
    }
    forces * accelerations.try_inverse().unwrap()
}

#[test]
fn servo_modes_of_rigid_links_are_kp_against_the_rigid_mass_matrix() {
    let kp = 2.0e5;
    let stiff = Arc::new(paper::machine(3, 1.0e4 * paper::YOUNGS_MODULUS).unwrap());
    for p in POSES {
        let at = pose(p);
        let mut model = coupled(stiff.clone(), at, Some(pd(kp, 0.0)));
        let y0 = model.initial_state();
        let lin = linearize(model.as_mut(), 0.0, &y0, &[], &[Output::SliderPosition(0)]).unwrap();
        let found = modes(&lin).unwrap();
        // omega^2 are the eigenvalues of M^-1 kp, i.e. kp / (eigenvalues of M) for the
        // symmetric mass matrix.
        let mass = slider_mass_matrix(&stiff, at);
        let mass = 0.5 * (mass + mass.transpose());
        let mut expected: Vec<f64> = SymmetricEigen::new(mass)
            .eigenvalues
            .iter()
            .map(|m| (kp / m).sqrt() / (2.0 * PI))
            .collect();
        expected.sort_by(f64::total_cmp);
        let worst = (0..3)
            .map(|q| (found[q].frequency_hz - expected[q]).abs() / expected[q])
            .fold(0.0_f64, f64::max);
        println!(
            "{p:?}: servo modes {:.3} {:.3} {:.3} Hz, rigid closed form {:.3} {:.3} {:.3} Hz: {worst:.1e}",
            found[0].frequency_hz,
            found[1].frequency_hz,
            found[2].frequency_hz,
            expected[0],
            expected[1],
            expected[2]
        );
        // Links 1e4 times stiffer: their bending (11.6 kHz) shifts the 90 Hz servo modes by
        // about (90 / 11600)^2 ~ 6e-5 of the links' share of the mass.
        assert!(worst < 1e-4, "{p:?}: {worst}");
    }
}

#[test]
fn the_static_limit_of_a_frequency_response_is_the_point_load_deflection() {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let (xi_f, xi) = (0.3, 0.6);
    let l = paper::LINK_LENGTH;
    let ei = paper::YOUNGS_MODULUS * paper::HEIGHT * paper::THICKNESS.powi(3) / 12.0;
    // Three sine modes: w = sum_k 2 l^3 / (EI k^4 pi^4) sin(k pi xi) sin(k pi xi_f) per N.
    let three_modes: f64 = (1..=3)
        .map(|k| {
            let k = f64::from(k);
            2.0 * l.powi(3) / (ei * k.powi(4) * PI.powi(4))
                * (k * PI * xi).sin()
                * (k * PI * xi_f).sin()
        })
        .sum();
    // The exact beam (Timoshenko & Gere): load at a = xi_f l, b = l - a; for x >= a,
    // w = P a (l - x) (2 l x - x^2 - a^2) / (6 EI l).
    let (a, x) = (xi_f * l, xi * l);
    let exact = a * (l - x) * (2.0 * l * x - x * x - a * a) / (6.0 * ei * l);
    for p in POSES {
        let mut model = coupled(machine.clone(), pose(p), None);
        let y0 = model.initial_state();
        let lin = linearize(
            model.as_mut(),
            0.0,
            &y0,
            &[Input::PointForce { link: 1, xi: xi_f }],
            &[Output::Deflection { link: 1, xi }],
        )
        .unwrap();
        let h = frequency_response_direct(&lin, &[0.0, 1e-3]).unwrap();
        for r in &h {
            let w = r[0][0];
            assert!(w.im.abs() < 1e-12 * w.re.abs());
            let error = (w.re - three_modes).abs() / three_modes;
            assert!(
                error < 1e-7,
                "{p:?}: {} against {three_modes}: {error}",
                w.re
            );
        }
        let truncation = (three_modes - exact) / exact;
        println!(
            "{p:?}: static compliance {:.6e} m/N, three-mode series {three_modes:.6e}, exact beam {exact:.6e} (truncation {truncation:.1e})",
            h[0][0][0].re
        );
        assert!(truncation.abs() < 5e-3);
    }
}

/// `C (s I - A)^-1 B + D` by a dense complex LU (nalgebra), a third method.
fn dense_response(lin: &flexprr_linear::Linearization, f: f64) -> Vec<Vec<nalgebra::Complex<f64>>> {
    use nalgebra::{Complex, DMatrix};
    let n = lin.a.nrows();
    let s = Complex::new(0.0, 2.0 * PI * f);
    let m = DMatrix::from_fn(n, n, |i, j| {
        let d = if i == j { s } else { Complex::new(0.0, 0.0) };
        d - Complex::new(lin.a[(i, j)], 0.0)
    });
    let b = DMatrix::from_fn(n, lin.b.ncols(), |i, j| Complex::new(lin.b[(i, j)], 0.0));
    let x = m.lu().solve(&b).unwrap();
    (0..lin.c.nrows())
        .map(|o| {
            (0..lin.b.ncols())
                .map(|i| {
                    (0..n).fold(Complex::new(lin.d[(o, i)], 0.0), |sum, k| {
                        sum + x[(k, i)] * lin.c[(o, k)]
                    })
                })
                .collect()
        })
        .collect()
}

#[test]
fn the_hessenberg_response_agrees_with_a_dense_solve() {
    // The servo machine at a pose where no two modes coincide (the eigenvector form is
    // well conditioned there too).
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let mut model = coupled(machine, pose((-0.05, 0.02, 40.0)), Some(pd(2.0e5, 400.0)));
    let y0 = model.initial_state();
    let lin = linearize(
        model.as_mut(),
        0.0,
        &y0,
        &[
            Input::SliderForce(0),
            Input::PointForce { link: 2, xi: 0.4 },
        ],
        &[
            Output::SliderPosition(1),
            Output::Platform(Axis::Phi),
            Output::Acceleration { link: 0, xi: 0.5 },
        ],
    )
    .unwrap();
    let f: Vec<f64> = (0..400).map(|k| 0.5 + 4.0 * f64::from(k)).collect();
    let direct = frequency_response_direct(&lin, &f).unwrap();
    let modal = frequency_response(&lin, &f).unwrap();
    let (mut worst_direct, mut worst_modal) = (0.0_f64, 0.0_f64);
    for (k, fk) in f.iter().enumerate() {
        let dense = dense_response(&lin, *fk);
        for o in 0..3 {
            for i in 0..2 {
                // Relative to the response or, where it is smaller, the feedthrough D that
                // the acceleration's response cancels.
                let r = dense[o][i];
                let scale = r.norm().max(lin.d[(o, i)].abs()).max(1e-300);
                let (a, b) = (direct[k][o][i], modal[k][o][i]);
                worst_direct = worst_direct.max((a.re - r.re).hypot(a.im - r.im) / scale);
                worst_modal = worst_modal.max((b.re - r.re).hypot(b.im - r.im) / scale);
            }
        }
    }
    println!("against a dense complex LU: Hessenberg {worst_direct:.1e}, modal {worst_modal:.1e}");
    assert!(worst_direct < 1e-9, "{worst_direct}");
    assert!(worst_modal < 1e-6, "{worst_modal}");
}

/// A motor on a compliant ball screw of stiffness `k` (no friction, no drive).
fn screw_motor(k: f64) -> MotorBallScrew {
    MotorBallScrew {
        rotor_inertia: 1.6e-5,
        lead: 0.01,
        efficiency: 0.9,
        ratings: MotorRatings {
            peak_torque: 3.5,
            continuous_torque: 1.2,
            max_speed: 100.0,
        },
        viscous_friction: 0.0,
        coulomb_friction: 0.0,
        coulomb_smoothing: 0.01,
        drive: None,
        friction_feedforward: false,
        lugre: None,
        screw: Some(Screw {
            stiffness: k,
            damping: 0.0,
        }),
    }
    .validated()
    .unwrap()
}

/// The closed form of a rigid machine's screw modes: each rotor a mass `m_r = J g^2` at its
/// slider's travel `x_r`, on the screw's spring `k` to the slider `x_s`; the PD law's force
/// `-kp x_s` acts on the rotor (through the motor torque), the sliders carry the rigid
/// machine's mass matrix `M_rho`:
/// `m_r x_r'' = -kp x_s - k (x_r - x_s)`, `M_rho x_s'' = k (x_r - x_s)`. Returns the
/// frequencies (Hz, ascending) and the eigenvectors `(x_r, x_s)` of `M^-1 K`.
fn screw_modes(
    mass: &Matrix3<f64>,
    m_r: f64,
    k: f64,
    kp: f64,
) -> Vec<(f64, nalgebra::DVector<f64>)> {
    let mut system = nalgebra::DMatrix::<f64>::zeros(6, 6);
    let inverse = mass.try_inverse().unwrap();
    for i in 0..3 {
        system[(i, i)] = k / m_r;
        system[(i, 3 + i)] = (kp - k) / m_r;
        for j in 0..3 {
            // x_s'' = M^-1 k (x_r - x_s): row 3 + i of M^-1 K is -(M^-1 k)_ij on x_r_j.
            system[(3 + i, j)] = -k * inverse[(i, j)];
            system[(3 + i, 3 + j)] = k * inverse[(i, j)];
        }
    }
    let eigen = system.complex_eigenvalues();
    let mut modes: Vec<(f64, nalgebra::DVector<f64>)> = eigen
        .iter()
        .map(|lambda| {
            assert!(lambda.im.abs() <= 1e-9 * lambda.re.abs(), "{lambda}");
            let omega2 = lambda.re;
            // The eigenvector: the null space of (M^-1 K - omega^2 I).
            let shifted = &system - nalgebra::DMatrix::<f64>::identity(6, 6) * omega2;
            let svd = shifted.svd(false, true);
            let v_t = svd.v_t.unwrap();
            let smallest = (0..6)
                .min_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b]))
                .unwrap();
            (omega2.sqrt() / (2.0 * PI), v_t.row(smallest).transpose())
        })
        .collect();
    modes.sort_by(|a, b| a.0.total_cmp(&b.0));
    modes
}

/// Issue 38, the screw's axial stiffness: with rigid links the machine's three screw modes
/// are the closed form of [`screw_modes`] (a two-mass oscillator per slider,
/// `sqrt(k (1/m_r + 1/m_s)) / 2 pi` for a lone slider), found in the linear model's modes
/// and in a ring-down of a run started in one of them.
#[test]
fn screw_modes_of_rigid_links_are_the_rotors_on_the_screws_against_the_rigid_mass_matrix() {
    let (kp, k) = (2.0e5, 1.0e8);
    let stiff = Arc::new(paper::machine(3, 1.0e4 * paper::YOUNGS_MODULUS).unwrap());
    let motor = screw_motor(k);
    let (g, m_r) = (motor.ratio(), motor.reflected_mass());
    let actuator: Arc<dyn Actuator> = Arc::new(motor);
    let actuation = Actuation {
        controller: Arc::new(Pid::pd(kp, 0.0, false, 0.0).unwrap()),
        actuators: [actuator.clone(), actuator.clone(), actuator],
    };
    let lone = (k * (1.0 / m_r + 1.0 / stiff.slider_mass[0])).sqrt() / (2.0 * PI);
    for p in POSES {
        let at = pose(p);
        let mass = slider_mass_matrix(&stiff, at);
        let expected = screw_modes(&mass, m_r, k, kp);
        let mut model = coupled(stiff.clone(), at, Some(actuation.clone()));
        let y0 = model.initial_state();
        let lin = linearize(model.as_mut(), 0.0, &y0, &[], &[Output::SliderPosition(0)]).unwrap();
        let found = modes(&lin).unwrap();
        let mut worst: f64 = 0.0;
        for (f, _) in &expected[3..] {
            let nearest = found
                .iter()
                .map(|m| m.frequency_hz)
                .min_by(|a, b| (a - f).abs().total_cmp(&(b - f).abs()))
                .unwrap();
            worst = worst.max((nearest - f).abs() / f);
        }
        println!(
            "{p:?}: screw modes {:.2} {:.2} {:.2} Hz (a lone slider's two masses {lone:.2} Hz): linear model within {worst:.1e}",
            expected[3].0, expected[4].0, expected[5].0
        );
        assert!(worst < 1e-3, "{p:?}: {worst}");

        // A ring-down from the highest screw mode's shape (small, at rest): the twists ring
        // at its frequency.
        let (f, shape) = &expected[5];
        let n = model.modes();
        let mut y = y0.clone();
        let amplitude = 1e-6 / shape.amax();
        let tail = 2 * n;
        for i in 0..3 {
            let (x_r, x_s) = (amplitude * shape[i], amplitude * shape[3 + i]);
            y[n - 3 + i] += x_s;
            // The rotor's states: twist g (x_r - x_s), speed 0 (after the law's none).
            y[tail + 2 * i] = g * (x_r - x_s);
        }
        let periods = 30.0;
        let end = periods / f;
        let times: Vec<f64> = (0..=3000).map(|j| end * f64::from(j) / 3000.0).collect();
        let integrator = Rk45::new(Options::default().rtol(1e-10).atol(1e-16));
        let solution = integrator.solve(model.as_mut(), 0.0, &y, &times).unwrap();
        // The first twist's upward zero crossings, linearly interpolated.
        let twist: Vec<f64> = (0..times.len()).map(|j| solution.y(j)[tail]).collect();
        let crossings: Vec<f64> = (1..times.len())
            .filter(|&j| twist[j - 1] < 0.0 && twist[j] >= 0.0)
            .map(|j| {
                times[j - 1] + (times[j] - times[j - 1]) * twist[j - 1] / (twist[j - 1] - twist[j])
            })
            .collect();
        let ringing =
            (crossings.len() - 1) as f64 / (crossings[crossings.len() - 1] - crossings[0]);
        println!("  ring-down from its shape: {ringing:.3} Hz against {f:.3} Hz");
        assert!((ringing / f - 1.0).abs() < 1e-3, "{ringing} vs {f}");
    }
}

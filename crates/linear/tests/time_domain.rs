//! Linear against nonlinear: the models integrated in time from a small disturbance of
//! their rest state ring at the frequencies and decay at the damping ratios of their
//! linearisation (docs/linear.md, "Validation").
//!
//! * The geometrically exact (nonlinear) links, sliders locked: a short hammer blow on link 1
//!   (1 N for 0.1 ms); the spectrum of the link's deflection (Hann window, 0.25 s, 4 Hz
//!   resolution) has its peaks at the linearisation's modes, within the resolution.
//! * The coupled machine under PD control (`kp = 2e5 N/m`, `kd = 400 N s/m`): started along
//!   one servo mode's eigenvector (a real initial state `Re(v)` excites `v` and its
//!   conjugate only, in linear theory), the slider motion is one damped oscillation; its
//!   pole, fitted by Prony's method of order 2 (`y_{n+1} = a y_n + b y_{n-1}`: `b = -r^2`,
//!   `a = 2 r cos theta`, `lambda = (ln r + i theta) / dt`; Hildebrand, *Introduction to
//!   Numerical Analysis*, 1956, 9.4), gives the frequency and the damping ratio.

use std::f64::consts::PI;
use std::sync::Arc;

use faer::linalg::solvers::Eigen;
use flexprr_control::{Actuator, IdealForce, Pid};
use flexprr_dynamics::{
    Actuation, CoupledOptions, CoupledSystem, ExternalLoads, ModalDamping, NonlinearOptions,
    NonlinearSystem, PointForce, SceneModel, paper,
};
use flexprr_integrators::{GeneralizedAlpha, Integrator, Options, Rk45};
use flexprr_kinematics::{Line, Pose, Trajectory};
use flexprr_linear::{Output, linearize, modes};
use nalgebra::Vector3;

fn rest(at: Pose) -> Arc<dyn Trajectory + Send + Sync> {
    Arc::new(Line::new(at, Vector3::zeros(), 0.0).unwrap())
}

/// The magnitude spectrum of `y` (Hann window) at `k / (n dt)`.
fn spectrum(y: &[f64]) -> Vec<f64> {
    let n = y.len();
    let w: Vec<f64> = (0..n)
        .map(|k| y[k] * (0.5 - 0.5 * (2.0 * PI * k as f64 / n as f64).cos()))
        .collect();
    (0..n / 2)
        .map(|k| {
            let (mut re, mut im) = (0.0, 0.0);
            for (j, v) in w.iter().enumerate() {
                let a = -2.0 * PI * (k * j) as f64 / n as f64;
                re += v * a.cos();
                im += v * a.sin();
            }
            re.hypot(im)
        })
        .collect()
}

#[test]
fn a_hammer_blow_on_the_nonlinear_links_rings_at_the_linear_modes() {
    let at = Pose::new(0.0, 0.0, 45f64.to_radians());
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let options = NonlinearOptions {
        elements: 8,
        ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
    };
    let mut model = NonlinearSystem::new(machine, rest(at), options).unwrap();
    model.start_at(0.0).unwrap();
    let y0 = SceneModel::initial_state(&model);
    let lin = linearize(
        &mut model,
        0.0,
        &y0,
        &[],
        &[Output::Deflection { link: 0, xi: 0.3 }],
    )
    .unwrap();
    let linear: Vec<f64> = modes(&lin)
        .unwrap()
        .iter()
        .map(|m| m.frequency_hz)
        .collect();
    // The blow: 1 N at xi = 0.3 of link 1 for 0.1 ms, then free.
    // The links' axial modes hold an explicit method to sub-microsecond steps with the
    // consistent element mass: the implicit method without numerical damping (rho_inf = 1,
    // so the ringing keeps its energy) resolves the bending modes instead.
    let solver =
        GeneralizedAlpha::new(Options::default().rtol(1e-9).atol(1e-15)).spectral_radius(1.0);
    let blow = ExternalLoads {
        point: vec![PointForce {
            link: 0,
            xi: 0.3,
            force: 1.0,
        }],
        ..ExternalLoads::default()
    };
    model.set_loads(&blow).unwrap();
    let hit = solver.solve(&mut model, 0.0, &y0, &[1e-4]).unwrap();
    model.set_loads(&ExternalLoads::default()).unwrap();
    let (dt, n) = (1.0 / 8192.0, 2048);
    let times: Vec<f64> = (0..n).map(|k| 1e-4 + k as f64 * dt).collect();
    let free = solver
        .solve(&mut model, 1e-4, hit.y(hit.len() - 1), &times)
        .unwrap();
    let w: Vec<f64> = (0..free.len())
        .map(|k| model.deflection(times[k], 0, 0.3, free.y(k)).unwrap())
        .collect();
    let peak = w.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let s = spectrum(&w);
    let resolution = 1.0 / (n as f64 * dt);
    let largest = s.iter().copied().fold(0.0_f64, f64::max);
    // Local maxima above 1 % of the largest, below 1.5 kHz.
    let peaks: Vec<f64> = (1..s.len() - 1)
        .filter(|&k| s[k] > s[k - 1] && s[k] >= s[k + 1] && s[k] > 1e-2 * largest)
        .map(|k| k as f64 * resolution)
        .filter(|f| *f < 1500.0)
        .collect();
    println!(
        "peak deflection {peak:.2e} m; spectral peaks {peaks:?} Hz (resolution {resolution} Hz); linear modes below 1.5 kHz: {:?}",
        linear
            .iter()
            .filter(|f| **f < 1500.0)
            .map(|f| (f * 100.0).round() / 100.0)
            .collect::<Vec<_>>()
    );
    assert!(peak < 1e-4, "a small blow: {peak}");
    assert!(peaks.len() >= 3, "{peaks:?}");
    for f in &peaks {
        let nearest = linear
            .iter()
            .map(|m| (m - f).abs())
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest <= resolution,
            "peak at {f} Hz: nearest mode {nearest} Hz away"
        );
    }
    // The first three bending families all ring.
    for family in [116.0, 465.0, 1045.0] {
        assert!(
            peaks.iter().any(|f| (f - family).abs() < 0.02 * family),
            "{family}: {peaks:?}"
        );
    }
}

/// `lambda` of the one damped oscillation in the samples `y` at step `dt` (Prony, order 2,
/// least squares over all samples).
fn prony(y: &[f64], dt: f64) -> (f64, f64) {
    let (mut s11, mut s12, mut s22, mut r1, mut r2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 1..y.len() - 1 {
        let (p, q, t) = (y[k], y[k - 1], y[k + 1]);
        s11 += p * p;
        s12 += p * q;
        s22 += q * q;
        r1 += p * t;
        r2 += q * t;
    }
    let det = s11 * s22 - s12 * s12;
    let a = (r1 * s22 - r2 * s12) / det;
    let b = (s11 * r2 - s12 * r1) / det;
    let r = (-b).sqrt();
    let theta = (a / (2.0 * r)).acos();
    (r.ln() / dt, theta / dt)
}

#[test]
fn a_servo_mode_decays_at_its_linear_damping_ratio() {
    let at = Pose::new(-0.1, 0.0, 45f64.to_radians());
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let force: Arc<dyn Actuator> = Arc::new(IdealForce);
    let actuation = Actuation {
        controller: Arc::new(Pid::pd(2.0e5, 400.0, true, 0.0).unwrap()),
        actuators: [force.clone(), force.clone(), force],
    };
    let mut model: Box<dyn SceneModel> = Box::new(
        CoupledSystem::new(
            machine,
            rest(at),
            ModalDamping::none(),
            CoupledOptions::full(),
        )
        .unwrap()
        .with_actuation(actuation, 0.0)
        .unwrap(),
    );
    let y0 = model.initial_state();
    let lin = linearize(model.as_mut(), 0.0, &y0, &[], &[Output::SliderPosition(0)]).unwrap();
    let linear = modes(&lin).unwrap();
    let n = lin.a.nrows();
    let eigen = Eigen::new_from_real(lin.a.as_ref()).unwrap();
    let solver = Rk45::new(Options::default().rtol(1e-11).atol(1e-16));
    for servo in &linear[..3] {
        // The eigenvector of this mode (upper half-plane), scaled to a 10 um slider motion.
        let k = (0..n)
            .min_by(|&i, &j| {
                let d = |m: usize| {
                    let v = eigen.S()[m];
                    (v.re - servo.eigenvalue.re).hypot(v.im - servo.eigenvalue.im)
                };
                d(i).total_cmp(&d(j))
            })
            .unwrap();
        let v: Vec<f64> = (0..n).map(|i| eigen.U()[(i, k)].re).collect();
        let largest = (0..lin.coordinates)
            .map(|i| v[i].abs())
            .fold(0.0_f64, f64::max);
        let start: Vec<f64> = y0
            .iter()
            .zip(&v)
            .map(|(y, d)| y + 1e-5 * d / largest)
            .collect();
        let dt = 1e-4;
        let times: Vec<f64> = (0..400).map(|j| f64::from(j) * dt).collect();
        let run = solver.solve(model.as_mut(), 0.0, &start, &times).unwrap();
        // Every state component rings alike; the largest coordinate is the cleanest.
        let pick = (0..lin.coordinates)
            .max_by(|&i, &j| v[i].abs().total_cmp(&v[j].abs()))
            .unwrap();
        let y: Vec<f64> = (0..run.len()).map(|j| run.y(j)[pick] - y0[pick]).collect();
        let (re, im) = prony(&y, dt);
        let modulus = re.hypot(im);
        let (f, zeta) = (modulus / (2.0 * PI), -re / modulus);
        let (df, dz) = (
            (f - servo.frequency_hz) / servo.frequency_hz,
            zeta - servo.damping_ratio,
        );
        println!(
            "servo mode {:.4} Hz, zeta {:.6} (linear); from the time response {f:.4} Hz, zeta {zeta:.6} ({df:.1e}, {dz:.1e})",
            servo.frequency_hz, servo.damping_ratio
        );
        // A 10 um motion: the geometric nonlinearity is of relative size 1e-5 / 0.1 m, the
        // integration error 1e-11.
        assert!(df.abs() < 1e-4, "{df}");
        assert!(dz.abs() < 1e-4, "{dz}");
    }
}

/// The step response of the discrete-time model of a sampled loop against the time run of
/// the same model with its law sampled: a 1 N step force on slider 1 (about 5 um of
/// motion), the coupled machine under a sampled PD law and under a sampled PID law (whose
/// integral is a state of the law, advanced at each sample), at 1 ms; the slider's position
/// and the law's tracking error at the sample times.
#[test]
fn a_sampled_loop_steps_as_its_discrete_model() {
    use flexprr_integrators::Integrator;
    let at = Pose::new(-0.05, 0.02, 40f64.to_radians());
    let period = 1e-3;
    for (name, law) in [
        ("pd", Pid::pd(2.0e5, 400.0, true, period).unwrap()),
        ("pid", Pid::new(2.0e5, 400.0, 4.0e6, true, period).unwrap()),
    ] {
        let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
        let force: Arc<dyn Actuator> = Arc::new(IdealForce);
        let actuation = Actuation {
            controller: Arc::new(law),
            actuators: [force.clone(), force.clone(), force],
        };
        let mut model: Box<dyn SceneModel> = Box::new(
            CoupledSystem::new(
                machine,
                rest(at),
                ModalDamping::none(),
                CoupledOptions::full(),
            )
            .unwrap()
            .with_actuation(actuation, 0.0)
            .unwrap(),
        );
        let y0 = model.initial_state();
        let outputs = [Output::SliderPosition(0), Output::SliderError(0)];
        let lin = linearize(
            model.as_mut(),
            0.0,
            &y0,
            &[flexprr_linear::Input::SliderForce(0)],
            &outputs,
        )
        .unwrap();
        assert!((lin.dt - period).abs() < 1e-15, "{}", lin.dt);
        assert_eq!(lin.law_states, if name == "pid" { 3 } else { 0 });
        // The discrete step response: x[k+1] = A x[k] + B, y[k] = C x[k] + D.
        let samples = 60;
        let n = lin.a.nrows();
        let mut x = vec![0.0; n];
        let mut linear = Vec::with_capacity(samples);
        for _ in 0..samples {
            linear.push(
                (0..2)
                    .map(|o| lin.d[(o, 0)] + (0..n).map(|j| lin.c[(o, j)] * x[j]).sum::<f64>())
                    .collect::<Vec<_>>(),
            );
            x = (0..n)
                .map(|i| lin.b[(i, 0)] + (0..n).map(|j| lin.a[(i, j)] * x[j]).sum::<f64>())
                .collect();
        }
        // The time run: the same step force from t = 0, the law sampling at its stops.
        model
            .set_loads(&ExternalLoads {
                slider: [1.0, 0.0, 0.0],
                ..ExternalLoads::default()
            })
            .unwrap();
        let times: Vec<f64> = (0..samples).map(|k| k as f64 * period).collect();
        // The law's sample times are generated as the run goes (`OdeSystem::next_stop`).
        let stops: Vec<f64> = Vec::new();
        let solver = Rk45::new(Options::default().rtol(1e-11).atol(1e-16));
        let run = solver
            .solve_observed(model.as_mut(), 0.0, &y0, &times, &stops, &mut ())
            .unwrap();
        let mut worst = [0.0f64; 2];
        let mut peak = [0.0f64; 2];
        let mut measured = [0.0; 2];
        for k in 0..samples {
            flexprr_dynamics::channel::measure(
                model.as_mut(),
                times[k],
                run.y(k),
                &ExternalLoads::default(),
                &outputs,
                &[[0.0; 2]; 2],
                &mut measured,
            )
            .unwrap();
            let zero = [lin.output_values[0], lin.output_values[1]];
            for o in 0..2 {
                let got = measured[o] - zero[o];
                worst[o] = worst[o].max((got - linear[k][o]).abs());
                peak[o] = peak[o].max(got.abs());
            }
        }
        println!(
            "{name}: slider 1 peak {:.3e} m, largest difference {:.2e} ({:.1e} of the peak); error peak {:.3e} m, difference {:.2e}",
            peak[0],
            worst[0],
            worst[0] / peak[0],
            peak[1],
            worst[1]
        );
        for o in 0..2 {
            assert!(
                peak[o] > 1e-6,
                "{name}: the step moves the slider: {}",
                peak[o]
            );
            assert!(
                worst[o] < 2e-5 * peak[o],
                "{name}, output {o}: {} of {}",
                worst[o],
                peak[o]
            );
        }
        // Its poles: the servo's well inside the unit circle, the undamped links' on it.
        for m in modes(&lin).unwrap() {
            assert!(m.z.unwrap().norm() < 1.0 + 1e-4, "{name}: {m:?}");
        }
    }
}

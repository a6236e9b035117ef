//! The motor's own dynamics (docs/control.md, "A real drive"): the winding's current, the
//! current loop and the compliant screw, integrated on their own (classical fourth-order
//! Runge-Kutta at a step far below every time constant) and checked against closed forms:
//!
//! * the winding at stall without a current loop rises as `V/R (1 - e^{-t R/L})` when the
//!   voltage clips at the bus, `i_r (1 - e^{-t R/L})` below it;
//! * the PI current loop at stall follows a step as `1 - e^{-2 pi f_c t}`, and at speed too
//!   (the back-EMF is fed forward);
//! * a motor driving a free slider without friction runs up to the no-load speed `V / K_e`;
//! * the dynamic drive settles on the steady-state drive's force and signals (the
//!   torque-speed envelope), to round-off;
//! * the compliant screw between the rotor (mass `m_r = J g^2` at the slider) and a free
//!   slider `m_s` rings at `(1/2 pi) sqrt(k (1/m_r + 1/m_s))`, at `(1/2 pi) sqrt(k / m_r)`
//!   with the slider held, and decays as the damped two-mass oscillator;
//! * as the screw stiffens, a run converges to the rigid screw's.

use std::f64::consts::TAU;

use flexprr_control::{
    Actuator, Drive, MOTOR_CURRENT, MOTOR_SPEED, MOTOR_TORQUE, MOTOR_VOLTAGE, MotorBallScrew,
    MotorRatings, Screw, Winding,
};

/// A motor without friction, efficiency 0.9, 10 mm lead.
fn motor(drive: Option<Drive>, screw: Option<Screw>) -> MotorBallScrew {
    MotorBallScrew {
        rotor_inertia: 1.0e-4,
        lead: 0.01,
        efficiency: 0.9,
        ratings: MotorRatings {
            peak_torque: 20.0,
            continuous_torque: 5.0,
            max_speed: 200.0,
        },
        viscous_friction: 0.0,
        coulomb_friction: 0.0,
        coulomb_smoothing: 0.01,
        drive,
        friction_feedforward: false,
        lugre: None,
        screw,
    }
    .validated()
    .unwrap()
}

/// `K_t = 0.2`, `R = 1.5`, `V = 100`, `L = 3 mH` (`L / R = 2 ms`), current loop at `f_c`.
fn drive(current_bandwidth: Option<f64>, current_limit: f64) -> Drive {
    Drive {
        torque_constant: 0.2,
        resistance: 1.5,
        bus_voltage: 100.0,
        current_limit,
        winding: Some(Winding {
            inductance: 3.0e-3,
            current_bandwidth,
        }),
    }
}

/// The slider: held at a velocity, or free with a mass of its own.
#[derive(Clone, Copy)]
enum Slider {
    Held(f64),
    Free(f64),
}

/// Integrates the actuator's states (and a free slider's velocity, started at rest) under
/// the force command `command(t)` to `end` with RK4 at step `h`; returns at each step the
/// time, the states, the slider velocity and the actuator's output signals
/// `(force, torque, speed, current, voltage)`.
fn simulate(
    actuator: &MotorBallScrew,
    slider: Slider,
    command: &dyn Fn(f64) -> f64,
    end: f64,
    h: f64,
) -> Vec<(f64, Vec<f64>, f64, [f64; 5])> {
    let n = actuator.states();
    let mut x = vec![0.0; n + 1];
    let v0 = match slider {
        Slider::Held(v) => v,
        Slider::Free(_) => 0.0,
    };
    actuator.initial_states(v0, &mut x[..n]);
    x[n] = v0;
    let mass = |m: f64| m + actuator.mass_on_slider();
    let rates = |t: f64, x: &[f64], dx: &mut [f64]| {
        let out = actuator.apply_with_states(command(t), x[n], None, &x[..n], &mut dx[..n]);
        dx[n] = match slider {
            Slider::Held(_) => 0.0,
            Slider::Free(m) => out.force / mass(m),
        };
        out
    };
    let signals = |out: flexprr_control::ActuatorOutput| {
        [
            out.force,
            out.signal(MOTOR_TORQUE).unwrap_or(f64::NAN),
            out.signal(MOTOR_SPEED).unwrap_or(f64::NAN),
            out.signal(MOTOR_CURRENT).unwrap_or(f64::NAN),
            out.signal(MOTOR_VOLTAGE).unwrap_or(f64::NAN),
        ]
    };
    let steps = (end / h).round() as usize;
    let mut out = Vec::with_capacity(steps + 1);
    let mut scratch = vec![0.0; n + 1];
    let (mut k1, mut k2, mut k3, mut k4) = (x.clone(), x.clone(), x.clone(), x.clone());
    for step in 0..=steps {
        let t = step as f64 * h;
        let now = rates(t, &x, &mut k1);
        out.push((t, x[..n].to_vec(), x[n], signals(now)));
        if step == steps {
            break;
        }
        for j in 0..=n {
            scratch[j] = x[j] + 0.5 * h * k1[j];
        }
        rates(t + 0.5 * h, &scratch, &mut k2);
        for j in 0..=n {
            scratch[j] = x[j] + 0.5 * h * k2[j];
        }
        rates(t + 0.5 * h, &scratch, &mut k3);
        for j in 0..=n {
            scratch[j] = x[j] + h * k3[j];
        }
        rates(t + h, &scratch, &mut k4);
        for j in 0..=n {
            x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
        }
    }
    out
}

/// The force command for the motor torque `torque` (N m) of `m`: `F = g eta tau`.
fn force_for(m: &MotorBallScrew, torque: f64) -> f64 {
    m.ratio() * m.efficiency * torque
}

#[test]
fn the_winding_at_stall_rises_with_its_time_constant() {
    let (r, l, v) = (1.5, 3.0e-3, 100.0);
    let tau = l / r;
    // Clipped at the bus: i_r R = 200 V > 100 V (the peak torque 20 N m is 100 A).
    let m = motor(Some(drive(None, f64::INFINITY)), None);
    let run = simulate(
        &m,
        Slider::Held(0.0),
        &|_| force_for(&m, 20.0),
        5.0 * tau,
        tau / 2000.0,
    );
    let mut worst: f64 = 0.0;
    for (t, _, _, s) in &run {
        let expected = v / r * (1.0 - (-t / tau).exp());
        worst = worst.max((s[3] - expected).abs() / (v / r));
        assert!(
            (s[4] - v).abs() <= 1e-12,
            "the voltage clips at the bus: {}",
            s[4]
        );
        assert!((s[1] - 0.2 * s[3]).abs() <= 1e-12, "tau = K_t i");
    }
    println!("winding at stall, clipped at the bus: worst {worst:.1e} of V/R");
    assert!(worst < 1e-10, "{worst}");
    // Below the bus voltage the current approaches its reference with the same lag.
    let i_r = 20.0;
    let run = simulate(
        &m,
        Slider::Held(0.0),
        &|_| force_for(&m, 0.2 * i_r),
        5.0 * tau,
        tau / 2000.0,
    );
    let worst = run
        .iter()
        .map(|(t, _, _, s)| (s[3] - i_r * (1.0 - (-t / tau).exp())).abs() / i_r)
        .fold(0.0, f64::max);
    assert!(worst < 1e-10, "{worst}");
}

#[test]
fn the_current_loop_follows_a_step_as_a_first_order_lag_of_its_bandwidth() {
    let f_c = 1000.0;
    let tau = 1.0 / (TAU * f_c);
    let m = motor(Some(drive(Some(f_c), f64::INFINITY)), None);
    // i_r = 10 A: the loop's first voltage k_p i_r = 2 pi 1000 3e-3 10 = 188 V clips at
    // 100 V. Take 3 A (57 V, 94 V with the back-EMF at 30 rev/s) for the linear loop.
    let i_r = 3.0;
    for speed in [0.0, 30.0] {
        // At 30 rev/s the back-EMF is 0.2 2 pi 30 = 37.7 V, fed forward: the same response.
        let velocity = speed * m.lead;
        let run = simulate(
            &m,
            Slider::Held(velocity),
            &|_| force_for(&m, 0.2 * i_r),
            10.0 * tau,
            tau / 2000.0,
        );
        let worst = run
            .iter()
            .map(|(t, _, _, s)| (s[3] - i_r * (1.0 - (-t / tau).exp())).abs() / i_r)
            .fold(0.0, f64::max);
        println!("current loop step at {speed} rev/s: worst {worst:.1e} of the step");
        assert!(worst < 1e-10, "{speed}: {worst}");
        let peak = run.iter().map(|r| r.3[4].abs()).fold(0.0, f64::max);
        assert!(peak < 100.0, "the voltage stays below the bus: {peak}");
    }
}

#[test]
fn a_motor_on_a_free_slider_runs_up_to_the_no_load_speed() {
    let m = motor(Some(drive(Some(1000.0), 30.0)), None);
    let no_load = 100.0 / 0.2 / TAU; // V / K_e in rev/s: 79.58
    // Mechanical time constant (m_s + m_r) R / (g^2 eta K_t^2) = 24 ms with m_s = 2 kg.
    let slider = 2.0;
    let run = simulate(&m, Slider::Free(slider), &|_| 1.0e5, 0.8, 2.0e-6);
    let (_, _, velocity, s) = run.last().unwrap();
    let speed = velocity / m.lead;
    println!(
        "no-load speed: {speed:.9} rev/s (V / K_e = {no_load:.9}), current {:.2e} A",
        s[3]
    );
    assert!(
        (speed - no_load).abs() <= 1e-8 * no_load,
        "{speed} vs {no_load}"
    );
    assert!(
        (s[2] - no_load).abs() <= 1e-8 * no_load,
        "speed signal {}",
        s[2]
    );
    // On the way the current held its limit of 30 A until the voltage ran out.
    let peak = run.iter().map(|r| r.3[3]).fold(0.0, f64::max);
    assert!(peak <= 30.0 * (1.0 + 1e-9) && peak > 29.9, "{peak}");
}

#[test]
fn the_dynamic_drive_settles_on_the_steady_state_envelope() {
    let f_c = 800.0;
    let with_loop = motor(Some(drive(Some(f_c), 30.0)), None);
    let without = motor(Some(drive(None, 30.0)), None);
    let steady = MotorBallScrew {
        drive: Some(Drive {
            winding: None,
            ..drive(None, 30.0)
        }),
        ..with_loop
    };
    // Within the envelope, on the current limit, on the voltage envelope motoring, braking.
    let cases = [
        (2.0, 10.0),
        (8.0, 5.0),
        (5.0, 60.0),
        (-8.0, 60.0),
        (-1.0, -40.0),
    ];
    for m in [with_loop, without] {
        for (torque, speed) in cases {
            let velocity = speed * m.lead;
            let command = force_for(&m, torque);
            let end = 40.0 * 2.0e-3;
            let run = simulate(&m, Slider::Held(velocity), &|_| command, end, 2.0e-7);
            let (_, _, _, s) = run.last().unwrap();
            let reference = steady.apply(command, velocity);
            let expected = [
                reference.force,
                reference.signal(MOTOR_TORQUE).unwrap(),
                reference.signal(MOTOR_SPEED).unwrap(),
                reference.signal(MOTOR_CURRENT).unwrap(),
                reference.signal(MOTOR_VOLTAGE).unwrap(),
            ];
            for k in 0..5 {
                let scale = expected[k].abs().max(1.0);
                assert!(
                    (s[k] - expected[k]).abs() <= 1e-9 * scale,
                    "{torque} N m at {speed} rev/s, signal {k}: {} vs steady state {}",
                    s[k],
                    expected[k]
                );
            }
        }
    }
}

/// The free two-mass oscillator's relative coordinate.
fn two_mass_hz(k: f64, m_r: f64, m_s: f64) -> f64 {
    (k * (1.0 / m_r + 1.0 / m_s)).sqrt() / TAU
}

#[test]
fn the_screw_rings_at_the_two_mass_frequency() {
    let k = 5.0e7;
    let m = motor(
        None,
        Some(Screw {
            stiffness: k,
            damping: 0.0,
        }),
    );
    let m_r = m.reflected_mass(); // 1e-4 (2 pi / 0.01)^2 = 39.5 kg
    assert!(m.mass_on_slider().abs() <= 0.0);
    // A force step of 1 kN sets off the ring-down about the static twist.
    let command = 1000.0;
    for (slider, expected) in [
        (Slider::Held(0.0), m.screw_mode_held_hz().unwrap()),
        (Slider::Free(5.0), two_mass_hz(k, m_r, 5.0)),
    ] {
        let period = 1.0 / expected;
        let run = simulate(&m, slider, &|_| command, 6.0 * period, period / 4000.0);
        // The relative displacement theta / g - rho = phi / g about its mean: the closed
        // form `delta(t) = delta_s (1 - cos(2 pi f t))`, with `delta_s` the static
        // compression (held: F_c / k; free: F_c m_s / (k (m_r + m_s))).
        let g = m.ratio();
        let delta_s = match slider {
            Slider::Held(_) => command / k,
            Slider::Free(m_s) => command * m_s / (k * (m_r + m_s)),
        };
        let worst = run
            .iter()
            .map(|(t, x, _, _)| {
                let closed = delta_s * (1.0 - (TAU * expected * t).cos());
                (x[0] / g - closed).abs() / delta_s
            })
            .fold(0.0, f64::max);
        println!("screw mode {expected:.3} Hz: worst {worst:.1e} of the static compression");
        assert!(worst < 1e-8, "{expected}: {worst}");
    }
}

#[test]
fn the_screws_damping_decays_as_the_damped_two_mass_oscillator() {
    let (k, c, m_s) = (5.0e7, 2.0e3, 5.0);
    let m = motor(
        None,
        Some(Screw {
            stiffness: k,
            damping: c,
        }),
    );
    let m_r = m.reflected_mass();
    let mu = m_r * m_s / (m_r + m_s);
    let (omega_n, zeta) = ((k / mu).sqrt(), c / (2.0 * (k * mu).sqrt()));
    let omega_d = omega_n * (1.0 - zeta * zeta).sqrt();
    let command = 1000.0;
    let delta_s = command * m_s / (k * (m_r + m_s));
    let period = TAU / omega_d;
    let run = simulate(
        &m,
        Slider::Free(m_s),
        &|_| command,
        8.0 * period,
        period / 4000.0,
    );
    let g = m.ratio();
    // Step response of mu d'' + c d' + k d = mu F / m_r: d = d_s (1 - e^{-zeta w t}
    // (cos w_d t + zeta w / w_d sin w_d t)).
    let worst = run
        .iter()
        .map(|(t, x, _, _)| {
            let decay = (-zeta * omega_n * t).exp();
            let closed = delta_s
                * (1.0
                    - decay
                        * ((omega_d * t).cos() + zeta * omega_n / omega_d * (omega_d * t).sin()));
            (x[0] / g - closed).abs() / delta_s
        })
        .fold(0.0, f64::max);
    println!("damped screw (zeta = {zeta:.4}): worst {worst:.1e}");
    assert!(worst < 1e-8, "{worst}");
}

#[test]
fn a_stiffening_screw_converges_to_the_rigid_one() {
    let rigid = motor(None, None);
    let command = |t: f64| 800.0 * (TAU * 20.0 * t).sin();
    let end = 0.05;
    let reference = simulate(&rigid, Slider::Free(5.0), &command, end, 1e-6);
    let mut errors = Vec::new();
    for k in [1e7, 1e8, 1e9] {
        let m = motor(
            None,
            Some(Screw {
                stiffness: k,
                damping: 0.0,
            }),
        );
        let run = simulate(&m, Slider::Free(5.0), &command, end, 1e-6);
        let error = run
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a.2 - b.2).abs())
            .fold(0.0, f64::max);
        errors.push(error);
    }
    println!(
        "compliant minus rigid slider velocity (k = 1e7, 1e8, 1e9 N/m): {:.2e} {:.2e} {:.2e}",
        errors[0], errors[1], errors[2]
    );
    // The difference falls with the compliance 1/k.
    assert!(
        errors[1] < 0.2 * errors[0] && errors[2] < 0.2 * errors[1],
        "{errors:?}"
    );
}

#[test]
fn bad_drive_and_screw_parameters_are_refused_by_key() {
    let bad = |drive: Option<Drive>, screw: Option<Screw>, inertia: f64| {
        MotorBallScrew {
            rotor_inertia: inertia,
            drive,
            screw,
            ..motor(None, None)
        }
        .validated()
        .unwrap_err()
        .to_string()
    };
    let mut d = drive(Some(1000.0), 10.0);
    d.winding = Some(Winding {
        inductance: 0.0,
        current_bandwidth: None,
    });
    assert!(bad(Some(d), None, 1e-4).starts_with("inductance = 0"));
    let e = bad(Some(drive(Some(-5.0), 10.0)), None, 1e-4);
    assert!(e.starts_with("current_bandwidth = -5"), "{e}");
    let screw = |stiffness, damping| Some(Screw { stiffness, damping });
    assert!(bad(None, screw(0.0, 0.0), 1e-4).starts_with("screw_stiffness = 0"));
    assert!(bad(None, screw(1e8, -1.0), 1e-4).starts_with("screw_damping = -1"));
    let e = bad(None, screw(1e8, 0.0), 0.0);
    assert!(
        e.starts_with("rotor_inertia = 0") && e.contains("screw_stiffness"),
        "{e}"
    );
}

//! Input shapers against their closed forms and against a direct simulation of a damped
//! oscillator (an independent check of the residual-vibration formula).

use std::f64::consts::{PI, TAU};

use flexprr_kinematics::Impulse;
use flexprr_planning::shaping::{
    Mode, Shaper, convolve, design, design_for_modes, duration, residual_vibration,
};
use proptest::prelude::*;

#[test]
fn zv_leaves_no_residual_at_its_design_frequency() {
    for damping in [0.0, 0.01, 0.05, 0.2] {
        let mode = Mode {
            frequency: 116.4,
            damping,
        };
        let zv = design(Shaper::Zv, mode).unwrap();
        assert!(residual_vibration(&zv, mode) <= 1e-14, "z {damping}");
        let zvd = design(Shaper::Zvd, mode).unwrap();
        assert!(residual_vibration(&zvd, mode) <= 1e-14, "z {damping}");
        // One half damped period, and two.
        let half = 0.5 / (mode.frequency * (1.0 - damping * damping).sqrt());
        assert!((duration(&zv) - half).abs() <= 1e-15);
        assert!((duration(&zvd) - 2.0 * half).abs() <= 1e-15);
        // Off design it is not zero.
        let off = Mode {
            frequency: 1.1 * mode.frequency,
            damping,
        };
        assert!(residual_vibration(&zv, off) > 0.1);
    }
}

#[test]
fn undamped_insensitivity_curves_match_their_closed_forms() {
    // Undamped, T = pi / w0: ZV gives |cos(pi r / 2)|, ZVD cos^2(pi r / 2) with r = w / w0;
    // EI with tolerance V gives |(1 + V) cos(pi r) / 2 + (1 - V) / 2|.
    let f0 = 90.0;
    let v = 0.05;
    let mode = Mode::undamped(f0);
    let zv = design(Shaper::Zv, mode).unwrap();
    let zvd = design(Shaper::Zvd, mode).unwrap();
    let ei = design(Shaper::Ei(v), mode).unwrap();
    for k in 0..=200 {
        let r = 0.5 + k as f64 / 200.0;
        let at = Mode::undamped(r * f0);
        let c = (0.5 * PI * r).cos();
        assert!((residual_vibration(&zv, at) - c.abs()).abs() <= 1e-12);
        assert!((residual_vibration(&zvd, at) - c * c).abs() <= 1e-12);
        let expected = (0.5 * (1.0 + v) * (PI * r).cos() + 0.5 * (1.0 - v)).abs();
        assert!(
            (residual_vibration(&ei, at) - expected).abs() <= 1e-12,
            "r {r}"
        );
    }
    // EI: V at the design frequency, zero on both sides of it.
    assert!((residual_vibration(&ei, mode) - v).abs() <= 1e-12);
    // The documented insensitivities: ZVD below 5 % over about +-14 % (cos^2(pi r/2) <= 0.05
    // for |r - 1| <= 0.144), EI below V over a wider band than ZVD.
    let band = |impulses: &[Impulse]| {
        (0..=4000)
            .map(|k| 0.5 + k as f64 / 4000.0)
            .filter(|r| residual_vibration(impulses, Mode::undamped(r * f0)) <= 0.05 + 1e-12)
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
                (lo.min(r), hi.max(r))
            })
    };
    let (lo, hi) = band(&zvd);
    assert!((hi - lo) > 0.28 && (hi - lo) < 0.3, "ZVD band {lo}..{hi}");
    let (lo_ei, hi_ei) = band(&ei);
    assert!(hi_ei - lo_ei > 1.3 * (hi - lo), "EI band {lo_ei}..{hi_ei}");
}

#[test]
fn damped_ei_keeps_its_shape() {
    // The K-weighted EI: at most V at the design frequency, exact V undamped.
    for damping in [0.01, 0.05, 0.1] {
        let mode = Mode {
            frequency: 100.0,
            damping,
        };
        let ei = design(Shaper::Ei(0.05), mode).unwrap();
        let at = residual_vibration(&ei, mode);
        assert!(
            at <= 0.05 && at >= 0.05 * (1.0 - PI * damping),
            "z {damping}: {at}"
        );
    }
}

#[test]
fn convolved_shapers_cancel_every_mode() {
    let modes = [
        Mode {
            frequency: 78.0,
            damping: 0.02,
        },
        Mode {
            frequency: 96.0,
            damping: 0.03,
        },
    ];
    let shaper = design_for_modes(Shaper::Zv, &modes).unwrap();
    assert_eq!(shaper.len(), 4);
    let sum: f64 = shaper.iter().map(|i| i.amplitude).sum();
    assert!((sum - 1.0).abs() <= 1e-15);
    for mode in modes {
        assert!(residual_vibration(&shaper, mode) <= 1e-14);
    }
    // Coincident delays merge: ZV * ZV of one mode is ZVD.
    let zv = design(Shaper::Zv, modes[0]).unwrap();
    let zvd = design(Shaper::Zvd, modes[0]).unwrap();
    let twice = convolve(&zv, &zv);
    assert_eq!(twice.len(), 3);
    for (a, b) in twice.iter().zip(&zvd) {
        assert!((a.amplitude - b.amplitude).abs() <= 1e-15);
        assert!((a.delay - b.delay).abs() <= 1e-15);
    }
    assert!(design_for_modes(Shaper::Zv, &[]).is_err());
}

/// Residual amplitude of `x'' + 2 z w x' + w^2 x = w^2 r(t)`, `r` the shaped unit step, after
/// the last impulse: RK4 with a fine step, then the amplitude of the free vibration about 1.
fn simulated_residual(impulses: &[Impulse], mode: Mode) -> f64 {
    let w = TAU * mode.frequency;
    let z = mode.damping;
    let command = |t: f64| -> f64 {
        impulses
            .iter()
            .filter(|i| t >= i.delay)
            .map(|i| i.amplitude)
            .sum()
    };
    let h = 1.0 / (mode.frequency * 4000.0);
    let end = duration(impulses);
    let (mut x, mut v, mut t) = (0.0, 0.0, 0.0);
    // Step so that every impulse time falls on a step boundary (the command is piecewise
    // constant between them).
    let mut times: Vec<f64> = impulses.iter().map(|i| i.delay).collect();
    times.push(end);
    for pair in times.windows(2) {
        let steps = ((pair[1] - pair[0]) / h).ceil().max(1.0) as usize;
        let dt = (pair[1] - pair[0]) / steps as f64;
        for _ in 0..steps {
            let mid = t + 0.5 * dt;
            let level = command(mid);
            let g = |x: f64, v: f64| (v, w * w * (level - x) - 2.0 * z * w * v);
            let (k1x, k1v) = g(x, v);
            let (k2x, k2v) = g(x + 0.5 * dt * k1x, v + 0.5 * dt * k1v);
            let (k3x, k3v) = g(x + 0.5 * dt * k2x, v + 0.5 * dt * k2v);
            let (k4x, k4v) = g(x + dt * k3x, v + dt * k3v);
            x += dt * (k1x + 2.0 * k2x + 2.0 * k3x + k4x) / 6.0;
            v += dt * (k1v + 2.0 * k2v + 2.0 * k3v + k4v) / 6.0;
            t += dt;
        }
    }
    // Free vibration about 1 from here: amplitude of (x - 1, v) for the damped oscillator.
    let wd = w * (1.0 - z * z).sqrt();
    let e = x - 1.0;
    (e * e + ((v + z * w * e) / wd).powi(2)).sqrt()
}

/// Simulated ringing left at the last impulse relative to the ringing an unshaped unit step
/// starts with (Singer & Seering's percentage vibration).
fn simulated_ratio(impulses: &[Impulse], mode: Mode) -> f64 {
    let unit = [Impulse {
        amplitude: 1.0,
        delay: 0.0,
    }];
    simulated_residual(impulses, mode) / simulated_residual(&unit, mode)
}

#[test]
fn a_shaped_step_leaves_no_residual_vibration_by_direct_simulation() {
    let mode = Mode {
        frequency: 90.0,
        damping: 0.02,
    };
    for shaper in [Shaper::Zv, Shaper::Zvd] {
        let impulses = design(shaper, mode).unwrap();
        let residual = simulated_ratio(&impulses, mode);
        assert!(residual <= 1e-6, "{shaper:?}: {residual}");
    }
    // EI leaves V (5 %) at the design frequency, as designed.
    let ei = design(Shaper::Ei(0.05), Mode::undamped(90.0)).unwrap();
    let simulated = simulated_ratio(&ei, Mode::undamped(90.0));
    assert!((simulated - 0.05).abs() <= 1e-6, "{simulated}");
    // Off design the simulation follows the residual formula.
    for shaper in [Shaper::Zv, Shaper::Zvd, Shaper::Ei(0.05)] {
        let impulses = design(shaper, mode).unwrap();
        for frequency in [70.0, 100.0, 120.0] {
            let off = Mode {
                frequency,
                damping: 0.02,
            };
            let simulated = simulated_ratio(&impulses, off);
            let formula = residual_vibration(&impulses, off);
            assert!(
                (simulated - formula).abs() <= 1e-6,
                "{shaper:?} at {frequency}: {simulated} vs {formula}"
            );
        }
    }
}

proptest! {
    #[test]
    fn every_shaper_sums_to_one_and_zeroes_its_mode(
        frequency in 1.0f64..500.0,
        damping in 0.0f64..0.5,
        v in 0.01f64..0.2,
    ) {
        let mode = Mode { frequency, damping };
        for shaper in [Shaper::Zv, Shaper::Zvd, Shaper::Ei(v)] {
            let impulses = design(shaper, mode).unwrap();
            let sum: f64 = impulses.iter().map(|i| i.amplitude).sum();
            prop_assert!((sum - 1.0).abs() <= 1e-12);
            prop_assert!(impulses.iter().all(|i| i.amplitude > 0.0));
            let at = residual_vibration(&impulses, mode);
            match shaper {
                Shaper::Ei(v) => prop_assert!(at <= v + 1e-12),
                _ => prop_assert!(at <= 1e-12),
            }
        }
    }
}

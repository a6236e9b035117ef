//! Property tests of the kinematics over random machines and reachable poses: closure,
//! FK(IK) = identity, rates against central differences, Jacobians, and the errors.

// Legs and axes are indexed in parallel across several arrays.
#![allow(clippy::needless_range_loop)]

mod common;

use common::{Case, angle_diff, arb_case, leg_through, min_measure, rotate, unit};
use flexprr_kinematics::{
    Branch, Geometry, KinematicsError, LegDrive, PlatformMotion, Pose, SingularityKind, Thresholds,
};
use nalgebra::{Vector2, Vector3};
use proptest::prelude::*;

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 256,
        max_global_rejects: 4096,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// A random smooth platform motion through the case's pose at t = 0:
/// `q(t) = q(0) + a o (sin(w t + psi) - sin psi)`, with its exact derivatives.
#[derive(Debug, Clone)]
struct Wiggle {
    base: Vector3<f64>,
    amplitude: Vector3<f64>,
    omega: Vector3<f64>,
    phase: Vector3<f64>,
}

impl Wiggle {
    fn motion(&self, t: f64) -> PlatformMotion {
        let mut q = self.base;
        let mut v = Vector3::zeros();
        let mut a = Vector3::zeros();
        for k in 0..3 {
            let arg = self.omega[k] * t + self.phase[k];
            q[k] += self.amplitude[k] * (arg.sin() - self.phase[k].sin());
            v[k] = self.amplitude[k] * self.omega[k] * arg.cos();
            a[k] = -self.amplitude[k] * self.omega[k] * self.omega[k] * arg.sin();
        }
        PlatformMotion {
            pose: Pose::from_vector(&q),
            velocity: v,
            acceleration: a,
        }
    }
}

prop_compose! {
    fn arb_wiggle(scale: f64, pose: Pose)(
        amp in prop::array::uniform3(-1.0f64..1.0),
        omega in prop::array::uniform3(0.5f64..3.0),
        phase in prop::array::uniform3(-3.0f64..3.0),
    ) -> Wiggle {
        Wiggle {
            base: pose.to_vector(),
            amplitude: Vector3::new(0.3 * scale * amp[0], 0.3 * scale * amp[1], 0.5 * amp[2]),
            omega: Vector3::from(omega),
            phase: Vector3::from(phase),
        }
    }
}

fn arb_case_and_wiggle() -> impl Strategy<Value = (Case, Wiggle)> {
    arb_case().prop_flat_map(|case| {
        let wiggle = arb_wiggle(case.scale, case.pose);
        (Just(case), wiggle)
    })
}

/// Five-point central differences (truncation error O(h^4), rounding O(eps/h^2) for f'') of samples at `-2h, -h, 0, h, 2h`:
/// `(f', f'')`.
fn five_point(f: [f64; 5], h: f64) -> (f64, f64) {
    (
        (f[0] - 8.0 * f[1] + 8.0 * f[3] - f[4]) / (12.0 * h),
        (-f[0] + 16.0 * f[1] - 30.0 * f[2] + 16.0 * f[3] - f[4]) / (12.0 * h * h),
    )
}

/// Derivatives from nine samples at `k h`, `k = -4..=4`: five-point differences with step
/// `h`, and the size of their truncation error estimated from the same stencil with step
/// `2h` (for an O(h^4) formula `|D(h) - D(2h)| ~ 15 |D(h) - exact|`). Returns
/// `(f', err f', f'', err f'')`.
fn derivatives(f: [f64; 9], h: f64) -> (f64, f64, f64, f64) {
    let (d1, d2) = five_point([f[2], f[3], f[4], f[5], f[6]], h);
    let (e1, e2) = five_point([f[0], f[2], f[4], f[6], f[8]], 2.0 * h);
    (d1, (d1 - e1).abs(), d2, (d2 - e2).abs())
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

proptest! {
    #![proptest_config(config())]

    /// |C_i - B_i| = l_i to 1e-12 relative, B_i on its guide line, C_i = p + R c_i, and the
    /// IK returns the slider positions the machine was built with.
    #[test]
    fn closure_holds(case in arb_case()) {
        let legs = case.geometry.inverse_position(&case.pose).unwrap();
        for (i, p) in legs.iter().enumerate() {
            let leg = &case.geometry.legs[i];
            let l = leg.link_length;
            prop_assert!(close((p.c - p.b).norm(), l, 1e-12 * l), "leg {i}: |C-B| = {} vs l = {l}", (p.c - p.b).norm());
            let u = leg.guide.direction.into_inner();
            let off_line = (p.b - leg.guide.anchor).perp(&u);
            prop_assert!(off_line.abs() <= 1e-12 * case.scale);
            let c_expected = case.pose.position() + rotate(&leg.attachment, case.pose.phi);
            prop_assert!((p.c - c_expected).norm() <= 1e-13 * case.scale);
            prop_assert!((p.e.norm() - 1.0).abs() <= 1e-12);
            prop_assert!(p.e.dot(&p.n).abs() <= 1e-15);
            // The closed form may lose digits when the two roots nearly coincide
            // (|e.u| small): compare in the closure's own conditioning.
            let e_dot_u = p.e.dot(&u).abs();
            prop_assert!(close(p.rho, case.rho[i], 1e-12 * case.scale / e_dot_u.max(1e-3)),
                "leg {i}: rho {} vs built {}", p.rho, case.rho[i]);
        }
    }

    /// FK(IK(pose)) = pose from a nearby guess, with the geometry's and with modified lengths.
    #[test]
    fn forward_inverts_inverse(case in arb_case(), dq in prop::array::uniform3(-1.0f64..1.0), stretch in prop::array::uniform3(-0.01f64..0.01)) {
        prop_assume!(min_measure(&case) > 0.05);
        let g = &case.geometry;
        let legs = g.inverse_position(&case.pose).unwrap();
        let rho = [legs[0].rho, legs[1].rho, legs[2].rho];
        let guess = Pose::new(case.pose.x + 0.01 * case.scale * dq[0], case.pose.y + 0.01 * case.scale * dq[1], case.pose.phi + 0.01 * dq[2]);
        let fk = g.forward_kinematics(rho, &guess).unwrap();
        prop_assert!(close(fk.x, case.pose.x, 1e-10 * case.scale) && close(fk.y, case.pose.y, 1e-10 * case.scale) && close(fk.phi, case.pose.phi, 1e-10),
            "fk {fk:?} vs {:?}", case.pose);
        // Modified link lengths l_i (1 + s_i) at a shifted pose: IK with those lengths, then
        // FK with the same override, from a nearby guess; when that configuration is itself
        // well away from singularities (checked on a geometry carrying those lengths).
        let lengths: [f64; 3] = std::array::from_fn(|i| g.legs[i].link_length * (1.0 + stretch[i]));
        let pose2 = Pose::new(case.pose.x + 0.001 * case.scale, case.pose.y, case.pose.phi);
        let mut g2 = *g;
        for i in 0..3 {
            g2.legs[i].link_length = lengths[i];
        }
        let well_posed = g2.singularity(&pose2).map(|m| m.type_i.iter().fold(m.type_ii, |a, b| a.min(*b)) > 0.05);
        if let Ok(true) = well_posed {
            let legs2 = g.inverse_position_with_lengths(&pose2, lengths).unwrap();
            let rho2 = [legs2[0].rho, legs2[1].rho, legs2[2].rho];
            let guess2 = Pose::new(pose2.x - 0.01 * case.scale * dq[1], pose2.y + 0.01 * case.scale * dq[0], pose2.phi - 0.01 * dq[2]);
            let fk2 = g.forward_kinematics_with_lengths(rho2, lengths, &guess2).unwrap();
            prop_assert!((fk2.to_vector() - pose2.to_vector()).norm() <= 1e-10 * case.scale.max(1.0), "{fk2:?} vs {pose2:?}");
            let fk3 = g2.forward_kinematics(rho2, &guess2).unwrap();
            prop_assert!((fk3.to_vector() - fk2.to_vector()).norm() <= 1e-10 * case.scale.max(1.0));
        }
    }

    /// rho', beta', rho'', beta'' agree with central differences of the position IK along a
    /// random smooth trajectory; C' and C'' too.
    #[test]
    fn rates_match_central_differences((case, wiggle) in arb_case_and_wiggle()) {
        prop_assume!(min_measure(&case) > 0.1);
        let g = &case.geometry;
        // Step 1e-3 keeps rounding noise in f'' near 1e-10 relative; near a singularity the
        // truncation error grows, so its estimate is allowed on top of the tolerance (a
        // wrong formula gives an O(1) discrepancy that both step sizes agree on).
        let h = 1e-3;
        let mut samples = Vec::with_capacity(9);
        for k in -4..=4 {
            match g.inverse_position(&wiggle.motion(k as f64 * h).pose) {
                Ok(legs) => samples.push(legs),
                Err(_) => return Err(TestCaseError::reject("left the workspace")),
            }
        }
        let state = g.inverse_kinematics_unchecked(&wiggle.motion(0.0)).unwrap();
        let sc = case.scale;
        for i in 0..3 {
            let s = &state.legs[i];
            let leg = i + 1;
            let (rho_dot, e_rho_dot, rho_ddot, e_rho_ddot) = derivatives(std::array::from_fn(|k| samples[k][i].rho), h);
            // Unwrap beta relative to the centre sample.
            let (beta_dot, e_beta_dot, beta_ddot, e_beta_ddot) =
                derivatives(std::array::from_fn(|k| angle_diff(samples[k][i].beta, samples[4][i].beta)), h);
            prop_assert!(close(s.rho, samples[4][i].rho, 1e-15 * sc));
            prop_assert!(close(s.rho_dot, rho_dot, 1e-8 * (sc + s.rho_dot.abs()) + e_rho_dot), "leg {leg}: rho' {} vs fd {rho_dot}", s.rho_dot);
            prop_assert!(close(s.beta_dot, beta_dot, 1e-8 * (1.0 + s.beta_dot.abs()) + e_beta_dot), "leg {leg}: beta' {} vs fd {beta_dot}", s.beta_dot);
            prop_assert!(close(s.rho_ddot, rho_ddot, 1e-6 * (sc + s.rho_ddot.abs()) + e_rho_ddot), "leg {leg}: rho'' {} vs fd {rho_ddot}", s.rho_ddot);
            prop_assert!(close(s.beta_ddot, beta_ddot, 1e-6 * (1.0 + s.beta_ddot.abs()) + e_beta_ddot), "leg {leg}: beta'' {} vs fd {beta_ddot}", s.beta_ddot);
            for axis in 0..2 {
                let (c_dot, e_c_dot, c_ddot, e_c_ddot) = derivatives(std::array::from_fn(|k| samples[k][i].c[axis]), h);
                prop_assert!(close(s.c_dot[axis], c_dot, 1e-8 * (sc + s.c_dot.norm()) + e_c_dot));
                prop_assert!(close(s.c_ddot[axis], c_ddot, 1e-6 * (sc + s.c_ddot.norm()) + e_c_ddot));
            }
        }
    }

    /// The velocity Jacobians map a twist to the slider rates given by central differences
    /// of the position IK, agree with the IK's rho', and invert (platform twist from rates).
    #[test]
    fn jacobian_maps_twist_to_slider_rates(case in arb_case(), twist in prop::array::uniform3(-1.0f64..1.0)) {
        prop_assume!(min_measure(&case) > 0.1);
        let g = &case.geometry;
        let twist = Vector3::new(twist[0] * case.scale, twist[1] * case.scale, twist[2]);
        let jac = g.velocity_jacobians(&case.pose).unwrap();
        let rates = jac.slider_rates(&twist);
        let h = 1e-6;
        let q = case.pose.to_vector();
        let (Ok(plus), Ok(minus)) = (
            g.inverse_position(&Pose::from_vector(&(q + h * twist))),
            g.inverse_position(&Pose::from_vector(&(q - h * twist))),
        ) else { return Err(TestCaseError::reject("left the workspace")); };
        let state = g.inverse_kinematics_unchecked(&PlatformMotion { pose: case.pose, velocity: twist, acceleration: Vector3::zeros() }).unwrap();
        for i in 0..3 {
            let fd = (plus[i].rho - minus[i].rho) / (2.0 * h);
            prop_assert!(close(rates[i], fd, 1e-6 * (case.scale + fd.abs())), "leg {i}: J t = {} vs fd {fd}", rates[i]);
            prop_assert!(close(rates[i], state.legs[i].rho_dot, 1e-12 * (case.scale + fd.abs())));
        }
        let back = jac.platform_twist(&rates).unwrap();
        prop_assert!((back - twist).norm() <= 1e-9 * (case.scale + twist.norm()));
    }

    /// The closure's partial derivatives against central differences.
    #[test]
    fn closure_jacobian_matches_differences(case in arb_case(), drho in prop::array::uniform3(-0.1f64..0.1)) {
        let g = &case.geometry;
        let rho: [f64; 3] = std::array::from_fn(|i| case.rho[i] + drho[i] * case.scale);
        let lengths = g.link_lengths();
        let cl = g.closure(&case.pose, rho, lengths);
        let h = 1e-6;
        let sc = case.scale;
        for k in 0..3 {
            let step = if k < 2 { h * sc } else { h };
            let mut qp = case.pose.to_vector();
            let mut qm = qp;
            qp[k] += step;
            qm[k] -= step;
            let fp = g.closure(&Pose::from_vector(&qp), rho, lengths).residual;
            let fm = g.closure(&Pose::from_vector(&qm), rho, lengths).residual;
            for i in 0..3 {
                let fd = (fp[i] - fm[i]) / (2.0 * step);
                prop_assert!(close(cl.pose_jacobian[(i, k)], fd, 1e-6 * sc * sc), "df{i}/dq{k}");
            }
            let mut rp = rho;
            let mut rm = rho;
            rp[k] += h * sc;
            rm[k] -= h * sc;
            let fd = (g.closure(&case.pose, rp, lengths).residual[k] - g.closure(&case.pose, rm, lengths).residual[k]) / (2.0 * h * sc);
            prop_assert!(close(cl.slider_jacobian[k], fd, 1e-6 * sc));
            let mut lp = lengths;
            let mut lm = lengths;
            lp[k] += h * sc;
            lm[k] -= h * sc;
            let fd = (g.closure(&case.pose, rho, lp).residual[k] - g.closure(&case.pose, rho, lm).residual[k]) / (2.0 * h * sc);
            prop_assert!(close(cl.length_jacobian[k], fd, 1e-6 * sc));
        }
    }

    /// forward_motion inverts the IK rates (rigid links), and with time-varying link lengths
    /// it matches central differences of the forward position kinematics.
    #[test]
    fn forward_motion_rates((case, wiggle) in arb_case_and_wiggle(), ldot in prop::array::uniform3(-0.1f64..0.1), lddot in prop::array::uniform3(-0.1f64..0.1)) {
        prop_assume!(min_measure(&case) > 0.1);
        let g = &case.geometry;
        let motion = wiggle.motion(0.0);
        let state = g.inverse_kinematics_unchecked(&motion).unwrap();
        let rho: [f64; 3] = std::array::from_fn(|i| state.legs[i].rho);
        let drive = LegDrive::rigid(g, rho, std::array::from_fn(|i| state.legs[i].rho_dot), std::array::from_fn(|i| state.legs[i].rho_ddot));
        let fm = g.forward_motion(&drive, &case.pose).unwrap();
        let sc = case.scale;
        prop_assert!((fm.velocity - motion.velocity).norm() <= 1e-8 * (sc + motion.velocity.norm()));
        prop_assert!((fm.acceleration - motion.acceleration).norm() <= 1e-7 * (sc + motion.acceleration.norm()));
        // Lengths l_i(t) = l_i + ldot t + lddot t^2 / 2 (scaled), sliders fixed at rho.
        let lengths_at = |t: f64| -> [f64; 3] { std::array::from_fn(|i| g.legs[i].link_length + sc * (ldot[i] * t + 0.5 * lddot[i] * t * t)) };
        let varying = LegDrive {
            rho, rho_dot: [0.0; 3], rho_ddot: [0.0; 3],
            length: lengths_at(0.0),
            length_dot: std::array::from_fn(|i| sc * ldot[i]),
            length_ddot: std::array::from_fn(|i| sc * lddot[i]),
        };
        let fm = g.forward_motion(&varying, &case.pose).unwrap();
        // Samples at k h, k = -4..=4 (see `derivatives`); h = 1e-3 keeps the FK's rounding
        // noise (~1e-16 per sample) negligible in the second difference.
        let h = 1e-3;
        let mut samples = [Vector3::zeros(); 9];
        for (k, sample) in samples.iter_mut().enumerate() {
            match g.forward_kinematics_with_lengths(rho, lengths_at((k as f64 - 4.0) * h), &case.pose) {
                Ok(p) => *sample = p.to_vector(),
                Err(_) => return Err(TestCaseError::reject("FK failed off the centre")),
            }
        }
        for axis in 0..3 {
            let (v, ev, a, ea) = derivatives(std::array::from_fn(|k| samples[k][axis]), h);
            prop_assert!(close(fm.velocity[axis], v, 1e-8 * (sc + fm.velocity.norm()) + ev), "{} vs {v}", fm.velocity[axis]);
            prop_assert!(close(fm.acceleration[axis], a, 1e-6 * (sc + fm.acceleration.norm()) + ea), "{} vs {a}", fm.acceleration[axis]);
        }
    }

    /// A link shorter than the distance of C_i from its guide line: Unreachable, right leg,
    /// right shortfall, everywhere (position, checked and unchecked IK), never NaN.
    #[test]
    fn unreachable_leg_is_reported(case in arb_case(), k in 0usize..3, frac in 0.01f64..0.5) {
        let mut g = case.geometry;
        let legs = g.inverse_position(&case.pose).unwrap();
        let u = g.legs[k].guide.direction.into_inner();
        let offset = (legs[k].c - g.legs[k].guide.anchor).perp(&u).abs();
        prop_assume!(offset > 0.01 * case.scale);
        let shortfall = frac * offset;
        g.legs[k].link_length = offset - shortfall;
        let motion = PlatformMotion::at_rest(case.pose);
        for result in [
            g.inverse_position(&case.pose).map(|_| ()),
            g.inverse_kinematics(&motion).map(|_| ()),
            g.inverse_kinematics_unchecked(&motion).map(|_| ()),
        ] {
            match result {
                Err(KinematicsError::Unreachable { leg, shortfall: s }) => {
                    prop_assert_eq!(leg, k);
                    prop_assert!(close(s, shortfall, 1e-9 * case.scale), "shortfall {s} vs {shortfall}");
                    let msg = KinematicsError::Unreachable { leg, shortfall: s }.to_string();
                    let label = format!("leg {}", k + 1);
                    prop_assert!(msg.contains(&label) && !msg.contains('\n'), "message: {msg}");
                }
                other => prop_assert!(false, "expected Unreachable on leg {k}, got {other:?}"),
            }
        }
    }

    /// Slider outside its travel: TravelExceeded with the right leg and excess.
    #[test]
    fn travel_exceeded_is_reported(case in arb_case(), k in 0usize..3, margin in 0.001f64..0.5, above in any::<bool>()) {
        prop_assume!(min_measure(&case) > 0.02);
        let mut g = case.geometry;
        let rho = g.inverse_position(&case.pose).unwrap()[k].rho;
        let excess = margin * case.scale;
        g.legs[k].guide.travel = if above { (rho - 10.0, rho - excess) } else { (rho + excess, rho + 10.0) };
        match g.inverse_kinematics(&PlatformMotion::at_rest(case.pose)) {
            Err(KinematicsError::TravelExceeded { leg, excess: e, rho: r, .. }) => {
                prop_assert_eq!(leg, k);
                prop_assert!(close(e, excess, 1e-12 * (10.0 + rho.abs())));
                prop_assert!(close(r, rho, 0.0));
            }
            other => prop_assert!(false, "expected TravelExceeded on leg {k}, got {other:?}"),
        }
        // The unchecked IK does not look at the travel.
        prop_assert!(g.inverse_kinematics_unchecked(&PlatformMotion::at_rest(case.pose)).is_ok());
    }

    /// A link perpendicular to its guide (e.u -> 0): type-I singular on that leg.
    #[test]
    fn type_i_singularity_is_reported(case in arb_case(), k in 0usize..3) {
        let mut g = case.geometry;
        let m = g.singularity(&case.pose).unwrap();
        prop_assume!((0..3).filter(|&i| i != k).all(|i| m.type_i[i] > 0.02));
        let legs = g.inverse_position(&case.pose).unwrap();
        let u = g.legs[k].guide.direction.into_inner();
        let offset = (legs[k].c - g.legs[k].guide.anchor).perp(&u).abs();
        prop_assume!(offset > 0.01 * case.scale);
        // Link just long enough to reach the guide line: e.u = sqrt(2e-10) ~ 1.4e-5.
        g.legs[k].link_length = offset * (1.0 + 1e-10);
        let measure = g.singularity(&case.pose).unwrap().type_i[k];
        prop_assert!(measure < 1e-4, "type-I measure {measure}");
        match g.inverse_kinematics(&PlatformMotion::at_rest(case.pose)) {
            Err(KinematicsError::Singular { kind: SingularityKind::TypeI, leg: Some(leg), measure: mm, threshold }) => {
                prop_assert_eq!(leg, k);
                prop_assert!(mm < threshold);
            }
            other => prop_assert!(false, "expected type-I on leg {k}, got {other:?}"),
        }
    }

    /// Link lines through one point: type-II measure ~ 0, IK reports type II; the direct
    /// Jacobian is singular.
    #[test]
    fn type_ii_singularity_is_reported(
        case in arb_case(),
        point in prop::array::uniform2(-1.0f64..1.0),
        behind in prop::array::uniform3(0.5f64..2.0),
        guide_turn in prop::array::uniform3(-1.4f64..1.4),
    ) {
        let sc = case.scale;
        let pose = case.pose;
        let concurrency = Vector2::new(pose.x, pose.y) + sc * Vector2::new(point[0], point[1]);
        let legs: [flexprr_kinematics::Leg; 3] = std::array::from_fn(|i| {
            let attachment = case.geometry.legs[i].attachment;
            let c = Vector2::new(pose.x, pose.y) + rotate(&attachment, pose.phi);
            let to_point = concurrency - c;
            let link_angle = to_point.y.atan2(to_point.x);
            // Guide at an angle |turn| < 1.4 rad from the link: |e.u| > cos 1.4 = 0.17.
            leg_through(&pose, attachment, link_angle, behind[i] * sc, link_angle + guide_turn[i], 0.0)
        });
        prop_assume!(legs.iter().all(|l| {
            let c = Vector2::new(pose.x, pose.y) + rotate(&l.attachment, pose.phi);
            (concurrency - c).norm() > 0.05 * sc
        }));
        let g = Geometry::new(legs).unwrap();
        let m = g.singularity(&pose).unwrap();
        prop_assert!(m.type_ii < 1e-10, "type-II measure {}", m.type_ii);
        prop_assert!(g.velocity_jacobians(&pose).unwrap().direct.determinant().abs() < 1e-10 * sc * sc.max(1.0));
        match g.inverse_kinematics(&PlatformMotion::at_rest(pose)) {
            Err(KinematicsError::Singular { kind: SingularityKind::TypeII, leg: None, .. }) => {}
            other => prop_assert!(false, "expected type II, got {other:?}"),
        }
    }

    /// The type-II measure is invariant under a rigid motion and a uniform scaling of the
    /// whole machine (and of the pose with it), and lies in [0, 1].
    #[test]
    fn type_ii_measure_is_scale_free(case in arb_case(), k in 0.1f64..10.0, turn in -3.0f64..3.0, shift in prop::array::uniform2(-1.0f64..1.0)) {
        let g = &case.geometry;
        let m = g.singularity(&case.pose).unwrap();
        let shift = Vector2::new(shift[0], shift[1]);
        let map = |v: Vector2<f64>| k * rotate(&v, turn) + shift;
        let legs: [flexprr_kinematics::Leg; 3] = std::array::from_fn(|i| {
            let mut leg = g.legs[i];
            leg.guide.anchor = nalgebra::Point2::from(map(leg.guide.anchor.coords));
            leg.guide.direction = nalgebra::Unit::new_normalize(rotate(&leg.guide.direction, turn));
            leg.guide.travel = (k * leg.guide.travel.0, k * leg.guide.travel.1);
            leg.attachment *= k;
            leg.link_length *= k;
            leg
        });
        let g2 = Geometry::new(legs).unwrap();
        let p2 = map(Vector2::new(case.pose.x, case.pose.y));
        let pose2 = Pose::new(p2.x, p2.y, case.pose.phi + turn);
        let m2 = g2.singularity(&pose2).unwrap();
        prop_assert!((0.0..=1.0 + 1e-12).contains(&m.type_ii));
        prop_assert!(close(m.type_ii, m2.type_ii, 1e-9), "{} vs {}", m.type_ii, m2.type_ii);
        for i in 0..3 {
            prop_assert!(close(m.type_i[i], m2.type_i[i], 1e-9));
        }
    }

    /// A leg whose branch is flipped after computing rho: FK finds the pose (the closure does
    /// not know branches) and reports the mismatch on that leg.
    #[test]
    fn forward_reports_branch_mismatch(case in arb_case(), k in 0usize..3) {
        prop_assume!(min_measure(&case) > 0.05);
        let mut g = case.geometry;
        let legs = g.inverse_position(&case.pose).unwrap();
        let rho = [legs[0].rho, legs[1].rho, legs[2].rho];
        g.legs[k].branch = g.legs[k].branch.other();
        match g.forward_kinematics(rho, &case.pose) {
            Err(KinematicsError::BranchMismatch { leg, expected, .. }) => {
                prop_assert_eq!(leg, k);
                prop_assert_eq!(expected, g.legs[k].branch);
            }
            other => prop_assert!(false, "expected BranchMismatch on leg {k}, got {other:?}"),
        }
    }

    /// Sliders that no pose can reach (links far too short): FK errors, never NaN.
    #[test]
    fn forward_with_unreachable_sliders_errors(case in arb_case(), k in 0usize..3) {
        let g = case.geometry;
        let mut rho = case.rho;
        // Move slider k far away: its link cannot reach the platform any more.
        rho[k] += 50.0 * case.scale;
        let result = g.forward_kinematics(rho, &case.pose);
        prop_assert!(result.is_err(), "got {result:?}");
    }
}

/// Branch convention: `Behind` puts the slider behind C along u (e.u >= 0).
#[test]
fn branch_sign_convention() {
    let pose = Pose::new(0.0, 0.0, 0.0);
    let leg = leg_through(&pose, Vector2::new(0.1, 0.0), 0.3, 1.0, 0.0, 0.2);
    assert_eq!(leg.branch, Branch::Behind);
    let leg = leg_through(&pose, Vector2::new(0.1, 0.0), 2.9, 1.0, 0.0, 0.2);
    assert_eq!(leg.branch, Branch::Ahead);
    assert!(close(Branch::Behind.sign(), -1.0, 0.0) && close(Branch::Ahead.sign(), 1.0, 0.0));
    let _ = unit(0.0);
    let _ = Thresholds::default();
}

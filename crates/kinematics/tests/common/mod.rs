//! Shared generators for the kinematics tests: random 3-PRR geometries built around a
//! random pose so that the pose is reachable by construction.

#![allow(dead_code)]

use std::f64::consts::PI;

use flexprr_kinematics::{Branch, Geometry, Guide, Leg, Pose};
use nalgebra::{Point2, Unit, Vector2};
use proptest::prelude::*;

/// A random machine and a reachable pose of it, with the data it was built from.
#[derive(Debug, Clone)]
pub struct Case {
    pub geometry: Geometry,
    pub pose: Pose,
    /// The slider positions used to build the machine (the IK must return them).
    pub rho: [f64; 3],
    /// Size of the machine (m).
    pub scale: f64,
}

pub fn unit(angle: f64) -> Vector2<f64> {
    Vector2::new(angle.cos(), angle.sin())
}

pub fn rotate(v: &Vector2<f64>, phi: f64) -> Vector2<f64> {
    let (s, c) = phi.sin_cos();
    Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// Builds a leg so that, at `pose`, its platform joint `C = p + R c` is at distance `length`
/// from the slider `B = C - length * unit(link_angle)`, which sits at `rho` on a guide of
/// direction `unit(guide_angle)`. The branch follows from the sign of `e.u`.
pub fn leg_through(
    pose: &Pose,
    attachment: Vector2<f64>,
    link_angle: f64,
    length: f64,
    guide_angle: f64,
    rho: f64,
) -> Leg {
    let c = Vector2::new(pose.x, pose.y) + rotate(&attachment, pose.phi);
    let e = unit(link_angle);
    let b = c - length * e;
    let u = unit(guide_angle);
    Leg {
        guide: Guide {
            anchor: Point2::from(b - rho * u),
            direction: Unit::new_normalize(u),
            travel: (-1e3, 1e3),
        },
        attachment,
        link_length: length,
        branch: if e.dot(&u) >= 0.0 {
            Branch::Behind
        } else {
            Branch::Ahead
        },
    }
}

prop_compose! {
    /// A random geometry (any guide directions, anchors, attachment points, link lengths and
    /// branches) with a pose that closes exactly.
    pub fn arb_case()(
        scale in 0.05f64..2.0,
        x in -1.0f64..1.0, y in -1.0f64..1.0, phi in -PI..PI,
        attach_jitter in prop::array::uniform3(-0.6f64..0.6),
        attach_radius in prop::array::uniform3(0.2f64..1.0),
        link_angle in prop::array::uniform3(-PI..PI),
        length in prop::array::uniform3(0.5f64..2.0),
        guide_angle in prop::array::uniform3(-PI..PI),
        rho in prop::array::uniform3(-1.0f64..1.0),
    ) -> Case {
        let pose = Pose::new(x * scale, y * scale, phi);
        let legs: [Leg; 3] = std::array::from_fn(|i| {
            let attachment = attach_radius[i] * scale
                * unit(2.0 * PI * i as f64 / 3.0 + attach_jitter[i]);
            leg_through(&pose, attachment, link_angle[i], length[i] * scale, guide_angle[i], rho[i] * scale)
        });
        Case {
            geometry: Geometry::new(legs).expect("generated geometry is valid"),
            pose,
            rho: [rho[0] * scale, rho[1] * scale, rho[2] * scale],
            scale,
        }
    }
}

/// Smallest of the singularity measures of a case.
pub fn min_measure(case: &Case) -> f64 {
    let m = case
        .geometry
        .singularity(&case.pose)
        .expect("reachable by construction");
    m.type_i.iter().fold(m.type_ii, |a, b| a.min(*b))
}

/// Angle difference wrapped to (-pi, pi].
pub fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI { d - 2.0 * PI } else { d }
}

//! A mode's shape in physical terms, from its eigenvector seen at the shape outputs (sliders,
//! platform pose, link deflections), and a short classification of it.

use flexprr_dynamics::Machine;
use flexprr_kinematics::Pose;
use flexprr_linear::Complex;

/// The shape of one mode: real, scaled so that the largest displacement it gives (a
/// slider, a platform coordinate, the rotation times the platform's radius, or a link's
/// deflection) is 1.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeShape {
    /// Each slider's motion along its guide.
    pub sliders: [f64; 3],
    /// The platform's `(dx, dy, dphi)` (`dphi` in rad per unit of the largest
    /// displacement).
    pub platform: [f64; 3],
    /// The motion of each platform joint `C_i`: `(dx - dphi r_iy, dy + dphi r_ix)` with
    /// `r_i` the joint's arm from the platform's reference point.
    pub joints: [[f64; 2]; 3],
    /// Each link's deflection from its chord at the shape points.
    pub links: [Vec<f64>; 3],
    /// The largest imaginary part left after the scaling (0 for an undamped mode, small
    /// for a lightly damped one): how far the shape is from a standing wave.
    pub imaginary: f64,
    /// `sum m_i / 2 sum_k |a_ik|^2` (twice the kinetic energy per `omega^2`, kg m^2) of the
    /// links' axial modes of relaxed chords, on the scale of the shape; 0 without them.
    pub axial: [f64; 3],
}

impl ModeShape {
    /// The shape from `seen`, the eigenvector at the outputs in the order of
    /// `shape_outputs` (sliders, `x`, `y`, `phi`, then `points` deflections per link), at
    /// the platform pose `pose`.
    pub(crate) fn from_outputs(
        seen: &[Complex],
        added: &[Complex],
        points: usize,
        pose: Pose,
        machine: &flexprr_dynamics::Machine,
    ) -> Self {
        let geometry = &machine.geometry;
        let (sin, cos) = pose.phi.sin_cos();
        let arms: [[f64; 2]; 3] = std::array::from_fn(|i| {
            let c = geometry.legs[i].attachment;
            [cos * c.x - sin * c.y, sin * c.x + cos * c.y]
        });
        let radius = arms.iter().map(|a| a[0].hypot(a[1])).fold(0.0, f64::max);
        // The reference entry: the largest displacement (the rotation as the motion of a
        // joint on the platform's circle).
        let weight = |k: usize| if k == 5 { radius } else { 1.0 };
        let reference = (0..seen.len())
            .map(|k| seen[k].scale(weight(k)))
            .max_by(|a, b| a.norm().total_cmp(&b.norm()))
            .unwrap_or_default();
        let scaled: Vec<Complex> = if reference.norm() > 0.0 {
            seen.iter().map(|s| *s / reference).collect()
        } else {
            seen.to_vec()
        };
        let imaginary = scaled
            .iter()
            .enumerate()
            .map(|(k, s)| (s.im * weight(k)).abs())
            .fold(0.0, f64::max);
        let re = |k: usize| scaled.get(k).map_or(0.0, |s| s.re);
        let platform = [re(3), re(4), re(5)];
        let joints = arms.map(|a| {
            [
                platform[0] - platform[2] * a[1],
                platform[1] + platform[2] * a[0],
            ]
        });
        // The links' axial modes (after the platform's deviation), on the shape's scale.
        let per_link = added.len().saturating_sub(3) / 3;
        let axial = std::array::from_fn(|i| {
            let energy: f64 = (0..per_link)
                .map(|k| {
                    let a = added[3 + i * per_link + k];
                    let a = if reference.norm() > 0.0 {
                        a / reference
                    } else {
                        a
                    };
                    a.re * a.re + a.im * a.im
                })
                .sum();
            0.5 * machine.links[i].mass() * energy
        });
        Self {
            axial,
            sliders: [re(0), re(1), re(2)],
            platform,
            joints,
            links: std::array::from_fn(|link| {
                (0..points).map(|j| re(6 + link * points + j)).collect()
            }),
            imaginary,
        }
    }

    /// The largest displacement of the sliders, of the platform joints and of each link.
    pub fn amplitudes(&self) -> (f64, f64, [f64; 3]) {
        let sliders = self.sliders.iter().fold(0.0_f64, |m, s| m.max(s.abs()));
        let platform = self
            .joints
            .iter()
            .fold(0.0_f64, |m, j| m.max(j[0].hypot(j[1])));
        let links =
            std::array::from_fn(|k| self.links[k].iter().fold(0.0_f64, |m, w| m.max(w.abs())));
        (sliders, platform, links)
    }

    /// The largest displacement anywhere (m per unit of the shape).
    pub fn largest(&self) -> f64 {
        let (s, p, l) = self.amplitudes();
        l.iter().fold(s.max(p), |m, v| m.max(*v))
    }

    /// The kinetic energies (per unit of `omega^2 / 2`) of the platform,
    /// `m_p (dx^2 + dy^2) + I_p dphi^2`, and of the links' bending, `sum m_k mean(w_k^2)`.
    fn kinetic(&self, machine: &Machine) -> (f64, f64) {
        let [dx, dy, dphi] = self.platform;
        let platform =
            machine.platform_mass * (dx * dx + dy * dy) + machine.platform_inertia * dphi * dphi;
        let bending = (0..3)
            .map(|k| {
                let w = &self.links[k];
                let mean = w.iter().map(|v| v * v).sum::<f64>() / w.len().max(1) as f64;
                machine.links[k].mass() * mean
            })
            .sum();
        (platform, bending)
    }

    /// What moves most: `servo` when the sliders move at least half as much as anything
    /// else, `platform` when the platform's kinetic energy exceeds the links' bending
    /// kinetic energy (a heavy platform on the links' axial springs: the light links may
    /// swing more than it moves), else `bending link k` (or `bending links i, j` when
    /// several links bend by at least a quarter of the largest deflection) with the
    /// half-waves of the most deflected link.
    pub(crate) fn kind(&self, machine: &Machine) -> String {
        let (sliders, platform, links) = self.amplitudes();
        let bending = links.iter().fold(0.0_f64, |m, v| m.max(*v));
        let (platform_energy, bending_energy) = self.kinetic(machine);
        let slider_energy: f64 = (0..3)
            .map(|i| machine.slider_mass[i] * self.sliders[i] * self.sliders[i])
            .sum();
        let axial: f64 = self.axial.iter().sum();
        if axial > platform_energy.max(bending_energy).max(slider_energy) {
            let largest = self.axial.iter().fold(0.0_f64, |m, v| m.max(*v));
            let involved: Vec<String> = (0..3)
                .filter(|&k| self.axial[k] >= 0.25 * largest)
                .map(|k| (k + 1).to_string())
                .collect();
            return format!(
                "axial link{} {}",
                if involved.len() == 1 { "" } else { "s" },
                involved.join(", ")
            );
        }
        if sliders >= 0.5 * platform.max(bending) && sliders > 0.0 {
            return "servo".to_string();
        }
        if platform_energy > bending_energy {
            return "platform".to_string();
        }
        if bending <= 0.0 {
            return "rigid".to_string();
        }
        let involved: Vec<String> = (0..3)
            .filter(|&k| links[k] >= 0.25 * bending)
            .map(|k| (k + 1).to_string())
            .collect();
        let dominant = (0..3)
            .max_by(|&a, &b| links[a].total_cmp(&links[b]))
            .unwrap_or(0);
        let waves = half_waves(&self.links[dominant]);
        let which = if involved.len() == 1 {
            format!("link {}", involved[0])
        } else {
            format!("links {}", involved.join(", "))
        };
        let plural = if waves == 1 { "" } else { "s" };
        format!("bending {which} ({waves} half-wave{plural})")
    }
}

/// The number of half-waves of a deflection: sign changes along the link, ignoring values
/// below a thousandth of its largest, plus one.
fn half_waves(w: &[f64]) -> usize {
    let largest = w.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut positive: Option<bool> = None;
    let mut changes = 0;
    for v in w {
        if v.abs() <= 1e-3 * largest {
            continue;
        }
        let now = *v > 0.0;
        if positive.is_some_and(|p| p != now) {
            changes += 1;
        }
        positive = Some(now);
    }
    changes + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_waves_of_sines() {
        for n in 1..=4 {
            let w: Vec<f64> = (0..21)
                .map(|j| (n as f64 * std::f64::consts::PI * j as f64 / 20.0).sin())
                .collect();
            assert_eq!(half_waves(&w), n);
        }
    }
}

//! A section with bonded layers: the mass and bending stiffness that patches (piezoelectric
//! actuators and sensors, their electrodes and adhesive) add to a link over their spans.
//!
//! Each layer adds a constant `Delta rhoA` and `Delta EI` on `[xi_start, xi_end)`, so the
//! modal integrals of the link gain `Delta rhoA l int psi_j psi_k dxi` and
//! `Delta EI / l^3 int psi_j'' psi_k'' dxi` over the span (the Rayleigh-Ritz contributions of
//! a locally thicker beam; Meirovitch, *Fundamentals of Vibrations*, 2001, 8.5). The span
//! ends become breakpoints, so the quadrature panels are cut where the properties jump and
//! the integrals stay exact for polynomial bases.

use crate::section::Section;

/// One bonded layer: what it adds over `[xi_start, xi_end)` of the link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layer {
    /// Where it starts along the link (`0 <= xi_start < xi_end`).
    pub xi_start: f64,
    /// Where it ends (`<= 1`).
    pub xi_end: f64,
    /// Added mass per unit length `Delta rhoA` (kg/m).
    pub mass_per_length: f64,
    /// Added bending stiffness `Delta EI` (N m^2).
    pub bending_stiffness: f64,
}

/// `base` with `layers` bonded to it (module documentation).
pub struct LayeredSection<'a> {
    base: &'a dyn Section,
    layers: Vec<Layer>,
}

impl<'a> LayeredSection<'a> {
    /// The section `base` with `layers` added. Layers with an empty or reversed span add
    /// nothing; the caller validates spans where the user wrote them.
    pub fn new(base: &'a dyn Section, layers: Vec<Layer>) -> Self {
        let layers = layers
            .into_iter()
            .filter(|l| l.xi_start < l.xi_end)
            .collect();
        Self { base, layers }
    }

    fn added(&self, xi: f64, of: impl Fn(&Layer) -> f64) -> f64 {
        self.layers
            .iter()
            .filter(|l| l.xi_start <= xi && xi < l.xi_end)
            .map(of)
            .sum()
    }
}

impl Section for LayeredSection<'_> {
    fn bending_stiffness(&self, xi: f64) -> f64 {
        self.base.bending_stiffness(xi) + self.added(xi, |l| l.bending_stiffness)
    }

    fn mass_per_length(&self, xi: f64) -> f64 {
        self.base.mass_per_length(xi) + self.added(xi, |l| l.mass_per_length)
    }

    fn breakpoints(&self) -> Vec<f64> {
        let mut points = self.base.breakpoints();
        for l in &self.layers {
            points.extend([l.xi_start, l.xi_end]);
        }
        points.retain(|&x| x > 0.0 && x < 1.0);
        points.sort_by(f64::total_cmp);
        points.dedup();
        points
    }

    /// A layer is constant on its span, so the base's degrees hold on every panel.
    fn polynomial_degrees(&self) -> Option<(usize, usize)> {
        self.base.polynomial_degrees()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ModalIntegrals, SineBasis, UniformSection};

    /// A layer over the whole link that doubles `EI` and `rhoA` scales the stiffness and
    /// mass integrals by exactly 2 each; a layer over `[0.4, 0.6)` adds the closed-form
    /// `Delta rhoA l int_{0.4}^{0.6} sin^2(pi xi) dxi` to the first modal mass.
    #[test]
    fn layers_add_their_closed_form_integrals() {
        let base = UniformSection::new(1.0, 0.5).unwrap();
        let basis = SineBasis::new(3).unwrap();
        let l = 0.2;
        let plain = ModalIntegrals::compute(&basis, &base, l).unwrap();
        let whole = LayeredSection::new(
            &base,
            vec![Layer {
                xi_start: 0.0,
                xi_end: 1.0,
                mass_per_length: 0.5,
                bending_stiffness: 1.0,
            }],
        );
        let doubled = ModalIntegrals::compute(&basis, &whole, l).unwrap();
        for j in 0..3 {
            let (m0, m1) = (plain.mass[(j, j)], doubled.mass[(j, j)]);
            assert!((m1 / m0 - 2.0).abs() < 1e-12, "{m1} {m0}");
            let (k0, k1) = (plain.stiffness[(j, j)], doubled.stiffness[(j, j)]);
            assert!((k1 / k0 - 2.0).abs() < 1e-12, "{k1} {k0}");
        }
        let (a, b) = (0.4, 0.6);
        let dm = 0.3;
        let middle = LayeredSection::new(
            &base,
            vec![Layer {
                xi_start: a,
                xi_end: b,
                mass_per_length: dm,
                bending_stiffness: 0.0,
            }],
        );
        let patched = ModalIntegrals::compute(&basis, &middle, l).unwrap();
        let pi = std::f64::consts::PI;
        // int sin^2(pi xi) = xi / 2 - sin(2 pi xi) / (4 pi)
        let integral = |x: f64| x / 2.0 - (2.0 * pi * x).sin() / (4.0 * pi);
        let expected = dm * l * (integral(b) - integral(a));
        let added = patched.mass[(0, 0)] - plain.mass[(0, 0)];
        assert!(
            (added - expected).abs() < 1e-12 * expected.abs().max(1e-3),
            "{added} {expected}"
        );
        assert_eq!(middle.breakpoints(), vec![0.4, 0.6]);
    }
}

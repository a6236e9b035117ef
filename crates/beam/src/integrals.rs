//! Modal integrals of one link (model.md section 6), by Gauss quadrature.

use crate::quadrature::{CompositeRule, MAX_GAUSS_POINTS, panel_edges};
use crate::{AxialLoad, Basis, BeamError, Section};
use faer::{Mat, MatMut};

/// The modal matrices and vectors of one link of length `l`, for a basis `psi_j` and a
/// section `EI(xi)`, `rhoA(xi)` (model.md section 6; the paper's eq. 17-21 keep only the
/// diagonals, which are views of these full matrices: `integrals.mass.diagonal()`).
///
/// All matrices are symmetric (computed on the upper triangle and mirrored).
#[derive(Debug, Clone)]
pub struct ModalIntegrals {
    /// Link length `l` (m).
    pub length: f64,
    /// `M_jk = l int rhoA psi_j psi_k dxi` (kg).
    pub mass: Mat<f64>,
    /// `Kf_jk = (1/l^3) int EI psi_j'' psi_k'' dxi` (N/m). The paper's eq. 20 prints
    /// `psi'^2`, a typo (model.md section 6).
    pub stiffness: Mat<f64>,
    /// `Gn_jk = int xi^n psi_j' psi_k' dxi`, n = 0, 1, 2 (dimensionless).
    pub g: [Mat<f64>; 3],
    /// `l int rhoA psi_j dxi` (kg); `m int psi` for a uniform section.
    pub mass_psi: Vec<f64>,
    /// `l int rhoA xi psi_j dxi` (kg); `m int xi psi` for a uniform section.
    pub mass_xi_psi: Vec<f64>,
    /// `int psi_j dxi` (unweighted).
    pub int_psi: Vec<f64>,
    /// `int xi psi_j dxi` (unweighted).
    pub int_xi_psi: Vec<f64>,
    /// `l int rhoA dxi` (kg).
    pub total_mass: f64,
    /// Gauss points per panel of the rule used.
    pub points_per_panel: usize,
    /// Number of quadrature panels (cut at basis and section breakpoints).
    pub panels: usize,
}

/// Integrals before scaling by powers of `l`, in flat row-major `r x r` arrays.
struct RawIntegrals {
    r: usize,
    mass: Vec<f64>,
    bending: Vec<f64>,
    g: [Vec<f64>; 3],
    mass_psi: Vec<f64>,
    mass_xi_psi: Vec<f64>,
    int_psi: Vec<f64>,
    int_xi_psi: Vec<f64>,
    total_mass: f64,
}

impl RawIntegrals {
    fn compute(
        basis: &dyn Basis,
        section: &dyn Section,
        rule: &CompositeRule,
    ) -> Result<Self, BeamError> {
        let r = basis.len();
        let zeros = || vec![0.0; r * r];
        let mut raw = RawIntegrals {
            r,
            mass: zeros(),
            bending: zeros(),
            g: [zeros(), zeros(), zeros()],
            mass_psi: vec![0.0; r],
            mass_xi_psi: vec![0.0; r],
            int_psi: vec![0.0; r],
            int_xi_psi: vec![0.0; r],
            total_mass: 0.0,
        };
        let mut values = vec![[0.0; 3]; r];
        for (&xi, &w) in rule.nodes().iter().zip(rule.weights()) {
            let ei = section.bending_stiffness(xi);
            let rho_a = section.mass_per_length(xi);
            if !ei.is_finite() {
                return Err(BeamError::NonFinite {
                    what: "bending stiffness",
                    mode: 0,
                    xi,
                });
            }
            if !rho_a.is_finite() {
                return Err(BeamError::NonFinite {
                    what: "mass per length",
                    mode: 0,
                    xi,
                });
            }
            for (j, v) in values.iter_mut().enumerate() {
                *v = basis.eval(j, xi);
                if !v.iter().all(|x| x.is_finite()) {
                    return Err(BeamError::NonFinite {
                        what: "basis function",
                        mode: j,
                        xi,
                    });
                }
            }
            let (w_m, w_k) = (w * rho_a, w * ei);
            let (w0, w1, w2) = (w, w * xi, w * xi * xi);
            raw.total_mass += w_m;
            for j in 0..r {
                let [pj, dj, cj] = values[j];
                raw.mass_psi[j] += w_m * pj;
                raw.mass_xi_psi[j] += w_m * xi * pj;
                raw.int_psi[j] += w * pj;
                raw.int_xi_psi[j] += w * xi * pj;
                let row = j * r;
                for (k, &[pk, dk, ck]) in values.iter().enumerate().skip(j) {
                    raw.mass[row + k] += w_m * pj * pk;
                    raw.bending[row + k] += w_k * cj * ck;
                    let slope = dj * dk;
                    raw.g[0][row + k] += w0 * slope;
                    raw.g[1][row + k] += w1 * slope;
                    raw.g[2][row + k] += w2 * slope;
                }
            }
        }
        for m in [&mut raw.mass, &mut raw.bending]
            .into_iter()
            .chain(raw.g.iter_mut())
        {
            for j in 0..r {
                for k in 0..j {
                    m[j * r + k] = m[k * r + j];
                }
            }
        }
        Ok(raw)
    }

    /// Largest change relative to each block's size, and the block's name.
    fn change_from(&self, other: &Self) -> (f64, &'static str) {
        fn rel(a: &[f64], b: &[f64]) -> f64 {
            let scale = b.iter().fold(0.0f64, |s, x| s.max(x.abs()));
            if scale <= 0.0 {
                return 0.0;
            }
            a.iter()
                .zip(b)
                .fold(0.0f64, |s, (x, y)| s.max((x - y).abs()))
                / scale
        }
        let blocks: [(&'static str, &[f64], &[f64]); 10] = [
            ("M", &self.mass, &other.mass),
            ("Kf", &self.bending, &other.bending),
            ("G0", &self.g[0], &other.g[0]),
            ("G1", &self.g[1], &other.g[1]),
            ("G2", &self.g[2], &other.g[2]),
            ("mass_psi", &self.mass_psi, &other.mass_psi),
            ("mass_xi_psi", &self.mass_xi_psi, &other.mass_xi_psi),
            ("int_psi", &self.int_psi, &other.int_psi),
            ("int_xi_psi", &self.int_xi_psi, &other.int_xi_psi),
            (
                "total_mass",
                std::slice::from_ref(&self.total_mass),
                std::slice::from_ref(&other.total_mass),
            ),
        ];
        blocks
            .iter()
            .map(|(name, a, b)| (rel(a, b), *name))
            .fold((0.0, "M"), |acc, x| if x.0 > acc.0 { x } else { acc })
    }
}

/// Relative change between two quadrature orders below which the integrals are accepted.
const SETTLED: f64 = 1e-12;

impl ModalIntegrals {
    /// Computes all integrals once.
    ///
    /// **Quadrature order.** Panels are cut at the basis' and the section's breakpoints.
    /// If both are piecewise polynomial ([`Basis::polynomial_degree`] `p`,
    /// [`Section::polynomial_degrees`] `(d_EI, d_rhoA)`), the highest integrand degree is
    /// `D = max(2p + d_rhoA, 2(p - 2) + d_EI, 2p, p + 1 + d_rhoA)` and the rule has
    /// `D/2 + 1` points per panel (exact for degree `2n - 1 >= D`); the result is checked
    /// against one more point. Otherwise the order starts from the basis' wavenumber `k`
    /// (`k/2 + 12` points per unit length) and grows by half until two successive orders
    /// agree to `1e-12` relative to each matrix's largest entry; the finer one is kept
    /// (Gauss rules converge exponentially on these analytic integrands, so its error is far
    /// below the last change).
    pub fn compute(
        basis: &dyn Basis,
        section: &dyn Section,
        length: f64,
    ) -> Result<Self, BeamError> {
        if !(length.is_finite() && length > 0.0) {
            return Err(BeamError::InvalidParameter {
                name: "length",
                value: length,
                reason: "must be finite and positive",
            });
        }
        if basis.is_empty() {
            return Err(BeamError::InvalidCount {
                name: "modes",
                value: 0,
                reason: "the basis has no functions",
            });
        }
        let mut breakpoints = basis.breakpoints();
        breakpoints.extend(section.breakpoints());
        let edges = panel_edges(&breakpoints)?;
        let longest_panel = edges.windows(2).map(|p| p[1] - p[0]).fold(0.0, f64::max);

        let exact_points = match (basis.polynomial_degree(), section.polynomial_degrees()) {
            (Some(p), Some((d_ei, d_rho_a))) => {
                let degree = (2 * p + d_rho_a)
                    .max(2 * p.saturating_sub(2) + d_ei)
                    .max(2 * p)
                    .max(p + 1 + d_rho_a);
                Some(degree / 2 + 1)
            }
            _ => None,
        };
        let (raw, rule) = if let Some(n) = exact_points {
            let rule = CompositeRule::new(n, &breakpoints)?;
            let raw = RawIntegrals::compute(basis, section, &rule)?;
            let check =
                RawIntegrals::compute(basis, section, &CompositeRule::new(n + 1, &breakpoints)?)?;
            let (change, matrix) = check.change_from(&raw);
            if change > SETTLED {
                return Err(BeamError::QuadratureNotConverged {
                    matrix,
                    points: n + 1,
                    change,
                });
            }
            (raw, rule)
        } else {
            let wavenumber = basis.max_wavenumber() * longest_panel;
            let mut n = ((wavenumber / 2.0).ceil() as usize + 12).clamp(8, MAX_GAUSS_POINTS);
            let mut rule = CompositeRule::new(n, &breakpoints)?;
            let mut raw = RawIntegrals::compute(basis, section, &rule)?;
            let mut last = (f64::INFINITY, "M");
            loop {
                let finer_n = n + n / 2;
                if finer_n > MAX_GAUSS_POINTS {
                    return Err(BeamError::QuadratureNotConverged {
                        matrix: last.1,
                        points: n,
                        change: last.0,
                    });
                }
                let finer_rule = CompositeRule::new(finer_n, &breakpoints)?;
                let finer = RawIntegrals::compute(basis, section, &finer_rule)?;
                last = finer.change_from(&raw);
                let change = last.0;
                n = finer_n;
                rule = finer_rule;
                raw = finer;
                if change <= SETTLED {
                    break;
                }
            }
            (raw, rule)
        };
        Ok(Self::scale(raw, length, &rule))
    }

    fn scale(raw: RawIntegrals, l: f64, rule: &CompositeRule) -> Self {
        let r = raw.r;
        let to_mat =
            |flat: &[f64], factor: f64| Mat::from_fn(r, r, |j, k| factor * flat[j * r + k]);
        let [g0, g1, g2] = &raw.g;
        Self {
            length: l,
            mass: to_mat(&raw.mass, l),
            stiffness: to_mat(&raw.bending, 1.0 / (l * l * l)),
            g: [to_mat(g0, 1.0), to_mat(g1, 1.0), to_mat(g2, 1.0)],
            mass_psi: raw.mass_psi.iter().map(|x| l * x).collect(),
            mass_xi_psi: raw.mass_xi_psi.iter().map(|x| l * x).collect(),
            int_psi: raw.int_psi,
            int_xi_psi: raw.int_xi_psi,
            total_mass: l * raw.total_mass,
            points_per_panel: rule.points_per_panel(),
            panels: rule.panels(),
        }
    }

    /// Number of modes `r`.
    pub fn r(&self) -> usize {
        self.mass.nrows()
    }

    /// `Kp = (P0/l) G0 + P1 G1 + P2 l G2`, the geometric stiffness of the axial force
    /// `P(x) = P0 + P1 x + P2 x^2` (`Kp_jk = int_0^l P psi_j' psi_k' dx`, model.md section 6),
    /// written into `out` (`r x r`; no allocation).
    ///
    /// # Panics
    /// If `out` is not `r x r`.
    pub fn geometric_stiffness_into(&self, load: &AxialLoad, mut out: MatMut<'_, f64>) {
        let r = self.r();
        assert!(
            out.nrows() == r && out.ncols() == r,
            "geometric stiffness output must be {r}x{r}"
        );
        let (c0, c1, c2) = (load.p0 / self.length, load.p1, load.p2 * self.length);
        let [g0, g1, g2] = &self.g;
        for k in 0..r {
            for j in 0..r {
                out[(j, k)] = c0 * g0[(j, k)] + c1 * g1[(j, k)] + c2 * g2[(j, k)];
            }
        }
    }

    /// `Kf + Kp(load)` written into `out` (`r x r`; no allocation).
    ///
    /// # Panics
    /// If `out` is not `r x r`.
    pub fn total_stiffness_into(&self, load: &AxialLoad, mut out: MatMut<'_, f64>) {
        self.geometric_stiffness_into(load, out.as_mut());
        let r = self.r();
        for k in 0..r {
            for j in 0..r {
                out[(j, k)] += self.stiffness[(j, k)];
            }
        }
    }

    /// Allocating form of [`ModalIntegrals::geometric_stiffness_into`].
    pub fn geometric_stiffness(&self, load: &AxialLoad) -> Mat<f64> {
        let mut out = Mat::zeros(self.r(), self.r());
        self.geometric_stiffness_into(load, out.as_mut());
        out
    }
}

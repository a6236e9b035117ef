//! Realisations of a linear model for export (docs/linear.md, "Scaling").
//!
//! The physical state mixes metres, radians and their rates with modal amplitudes, and its
//! `A` pairs stiff axial modes (`omega^2 ~ 1e8 .. 1e12` 1/s^2) with slow servo modes: its
//! condition number reaches 1e9 and more, and tools that factor `A` or `s I - A` lose
//! digits (python-control's `stability_margins` fails on it). The scaled realisation is the
//! same model in the state `x = S x~` with `S = diag(s)` a diagonal of powers of two chosen
//! by balancing `A` (Parlett & Reinsch 1969; LAPACK's `gebal`, MATLAB's `ssbal`):
//! `A~ = S^-1 A S`, `B~ = S^-1 B`, `C~ = C S`, `D~ = D`. Powers of two make the change exact
//! in floating point; the inputs, outputs, transfer functions, poles and names are those of
//! the physical model, and `x = s * x~` gives the physical state back.

use faer::Mat;

use crate::Linearization;

/// How an exported model's state is realised.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Realization {
    /// The state in physical units and the model's own coordinates.
    Physical,
    /// The physical state divided by the balancing scales (the default for export).
    #[default]
    Scaled,
}

impl Realization {
    /// `physical` or `scaled`.
    pub fn name(self) -> &'static str {
        match self {
            Realization::Physical => "physical",
            Realization::Scaled => "scaled",
        }
    }
}

impl std::str::FromStr for Realization {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "physical" => Ok(Realization::Physical),
            "scaled" => Ok(Realization::Scaled),
            other => Err(format!(
                "realization {other:?}: expected \"scaled\" (the state divided by powers of two \
                 that balance A; the default) or \"physical\""
            )),
        }
    }
}

/// The balancing scales `s` of `a` (powers of two): `S^-1 A S` has rows and columns of about
/// equal norm.
pub fn balancing_scales(a: &Mat<f64>) -> Vec<f64> {
    crate::balance::balance(a).1
}

/// `lin` in the state `x = diag(scale) x~`.
pub fn rescaled(lin: &Linearization, scale: &[f64]) -> Linearization {
    let n = lin.a.nrows();
    let mut out = lin.clone();
    out.a = Mat::from_fn(n, n, |i, j| lin.a[(i, j)] * scale[j] / scale[i]);
    out.b = Mat::from_fn(n, lin.b.ncols(), |i, j| lin.b[(i, j)] / scale[i]);
    out.c = Mat::from_fn(lin.c.nrows(), n, |i, j| lin.c[(i, j)] * scale[j]);
    out.state = lin.state.iter().zip(scale).map(|(x, s)| x / s).collect();
    out
}

/// `lin` realised as asked, with the scales of its state (all 1 for the physical one).
pub fn realize(lin: &Linearization, realization: Realization) -> (Linearization, Vec<f64>) {
    match realization {
        Realization::Physical => (lin.clone(), vec![1.0; lin.a.nrows()]),
        Realization::Scaled => {
            let scale = balancing_scales(&lin.a);
            (rescaled(lin, &scale), scale)
        }
    }
}

/// The 2-norm condition number `sigma_max / sigma_min` of `a` (infinite when singular).
pub fn condition_number(a: &Mat<f64>) -> f64 {
    let Ok(s) = a.singular_values() else {
        return f64::INFINITY;
    };
    let largest = s.iter().copied().fold(0.0, f64::max);
    let smallest = s.iter().copied().fold(f64::INFINITY, f64::min);
    if smallest > 0.0 {
        largest / smallest
    } else {
        f64::INFINITY
    }
}

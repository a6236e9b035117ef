//! Paths with a designed orientation (docs/planning.md, "The platform's orientation"): the
//! position `(x, y)(s)` of a base path kept, the orientation replaced or corrected by a smooth
//! law of the path parameter,
//!
//! ```text
//! phi(s) = phi_base(s) + g(s / S)      (relative)
//! phi(s) = g(s / S)                    (absolute)
//! ```
//!
//! with `g` a constant, a clamped cubic B-spline ([`PhiSpline`]) or a Fourier series
//! ([`PhiFourier`]) of the normalised parameter `w = s / S in [0, 1]`. The parameter `s` stays
//! the base path's, so any timing `s(t)` of the base path times the oriented path too. The
//! paper ends on this freedom: "the configurations of the manipulator may be optimized so that
//! the axial forces in the flexible links are in extension".

use nalgebra::Vector3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::KinematicsError;
use crate::path::{GeometricPath, Path, PathPoint};
use crate::planned::bad;

fn all_finite(field: &'static str, values: &[f64]) -> Result<(), KinematicsError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(k) => Err(bad(field, Some(k), values[k], "must be finite (rad)")),
        None => Ok(()),
    }
}

/// One derivative level of a B-spline: degree, knots and coefficients.
#[derive(Debug, Clone, PartialEq)]
struct Level {
    degree: usize,
    knots: Vec<f64>,
    coefficients: Vec<f64>,
}

impl Level {
    /// The derivative spline (degree one less): `Q_i = p (C_{i+1} - C_i) / (T_{i+p+1} -
    /// T_{i+1})` on the knots without their first and last (de Boor, "A Practical Guide to
    /// Splines", ch. X).
    fn derivative(&self) -> Level {
        let p = self.degree;
        let t = &self.knots;
        let coefficients = self
            .coefficients
            .windows(2)
            .enumerate()
            .map(|(i, c)| {
                let span = t[i + p + 1] - t[i + 1];
                if span > 0.0 {
                    p as f64 * (c[1] - c[0]) / span
                } else {
                    0.0
                }
            })
            .collect();
        Level {
            degree: p - 1,
            knots: t[1..t.len() - 1].to_vec(),
            coefficients,
        }
    }

    /// The value at `x in [0, 1]` by de Boor's algorithm (no allocation).
    fn value(&self, x: f64) -> f64 {
        let p = self.degree;
        let t = &self.knots;
        let c = &self.coefficients;
        let m = c.len();
        // The span k, p <= k <= m - 1, with t_k <= x < t_{k+1} (the last span at x = 1).
        let (mut lo, mut hi) = (p, m - 1);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if t[mid] <= x {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        let k = lo;
        let mut d = [0.0; 4];
        d[..=p].copy_from_slice(&c[k - p..=k]);
        for r in 1..=p {
            for j in (r..=p).rev() {
                let left = t[j + k - p];
                let span = t[j + 1 + k - r] - left;
                let alpha = if span > 0.0 { (x - left) / span } else { 0.0 };
                d[j] = (1.0 - alpha) * d[j - 1] + alpha * d[j];
            }
        }
        d[p]
    }
}

/// A clamped cubic B-spline of `w in [0, 1]` on uniform knots: `n >= 4` control values
/// `c_0 .. c_{n-1}`, `n - 3` polynomial pieces. It starts at `c_0` and ends at `c_{n-1}`,
/// stays within the range of its control values (convex hull) and is `C^2`; its third
/// derivative jumps at the `n - 4` interior knots.
#[derive(Debug, Clone, PartialEq)]
pub struct PhiSpline {
    levels: [Level; 4],
}

/// The serialised form of a [`PhiSpline`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhiSplineData {
    /// Control values (rad), at least four.
    pub values: Vec<f64>,
}

impl PhiSpline {
    /// The spline with control values `values` (rad).
    ///
    /// # Errors
    /// Fewer than four values, or a value that is not finite (named by its index).
    pub fn new(values: Vec<f64>) -> Result<Self, KinematicsError> {
        if values.len() < 4 {
            return Err(bad(
                "law.values",
                None,
                values.len() as f64,
                "a cubic B-spline needs at least 4 control values",
            ));
        }
        all_finite("law.values", &values)?;
        let n = values.len();
        let pieces = (n - 3) as f64;
        let mut knots = vec![0.0; 4];
        knots.extend((1..n - 3).map(|j| j as f64 / pieces));
        knots.extend([1.0; 4]);
        let value = Level {
            degree: 3,
            knots,
            coefficients: values,
        };
        let first = value.derivative();
        let second = first.derivative();
        let third = second.derivative();
        Ok(Self {
            levels: [value, first, second, third],
        })
    }

    /// The control values (rad).
    pub fn values(&self) -> &[f64] {
        &self.levels[0].coefficients
    }

    /// The interior knots in `w` (where the third derivative jumps).
    pub fn interior_knots(&self) -> &[f64] {
        let knots = &self.levels[0].knots;
        &knots[4..knots.len() - 4]
    }

    /// `g(w)` and its first three derivatives in `w`.
    pub fn eval(&self, w: f64) -> [f64; 4] {
        let w = w.clamp(0.0, 1.0);
        [
            self.levels[0].value(w),
            self.levels[1].value(w),
            self.levels[2].value(w),
            self.levels[3].value(w),
        ]
    }
}

impl Serialize for PhiSpline {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        PhiSplineData {
            values: self.values().to_vec(),
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for PhiSpline {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let data = PhiSplineData::deserialize(deserializer)?;
        Self::new(data.values).map_err(serde::de::Error::custom)
    }
}

/// A Fourier series of `w in [0, 1]`, period 1:
/// `g(w) = mean + sum_k (cos_k cos(2 pi k w) + sin_k sin(2 pi k w))`, `k = 1 .. H`. Smooth and
/// periodic: it keeps a closed path closed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PhiFourierData", into = "PhiFourierData")]
pub struct PhiFourier {
    data: PhiFourierData,
}

/// The serialised form of a [`PhiFourier`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhiFourierData {
    /// Mean value (rad).
    pub mean: f64,
    /// Cosine coefficients of harmonics 1 .. H (rad).
    #[serde(default)]
    pub cos: Vec<f64>,
    /// Sine coefficients of harmonics 1 .. H (rad), as many as `cos`.
    #[serde(default)]
    pub sin: Vec<f64>,
}

impl TryFrom<PhiFourierData> for PhiFourier {
    type Error = KinematicsError;
    fn try_from(data: PhiFourierData) -> Result<Self, KinematicsError> {
        Self::new(data.mean, data.cos, data.sin)
    }
}

impl From<PhiFourier> for PhiFourierData {
    fn from(law: PhiFourier) -> Self {
        law.data
    }
}

impl PhiFourier {
    /// The series with `mean` and the harmonics' coefficients (rad).
    ///
    /// # Errors
    /// A value that is not finite (named by its index); `cos` and `sin` of different lengths.
    pub fn new(mean: f64, cos: Vec<f64>, sin: Vec<f64>) -> Result<Self, KinematicsError> {
        all_finite("law.mean", &[mean])?;
        all_finite("law.cos", &cos)?;
        all_finite("law.sin", &sin)?;
        if cos.len() != sin.len() {
            return Err(bad(
                "law.sin",
                None,
                sin.len() as f64,
                "needs as many coefficients as law.cos (one of each per harmonic)",
            ));
        }
        Ok(Self {
            data: PhiFourierData { mean, cos, sin },
        })
    }

    /// The coefficients.
    pub fn data(&self) -> &PhiFourierData {
        &self.data
    }

    /// `g(w)` and its first three derivatives in `w`.
    pub fn eval(&self, w: f64) -> [f64; 4] {
        let mut g = [self.data.mean, 0.0, 0.0, 0.0];
        for (k, (a, b)) in self.data.cos.iter().zip(&self.data.sin).enumerate() {
            let omega = std::f64::consts::TAU * (k + 1) as f64;
            let (sin, cos) = (omega * w).sin_cos();
            let even = a * cos + b * sin;
            let odd = b * cos - a * sin;
            g[0] += even;
            g[1] += omega * odd;
            g[2] -= omega * omega * even;
            g[3] -= omega * omega * omega * odd;
        }
        g
    }
}

/// A law `g(w)` of the normalised path parameter `w = s / S` (module documentation). As data:
/// a table with `kind = "constant"` (`phi`), `"spline"` (`values`) or `"fourier"` (`mean`,
/// `cos`, `sin`), angles in rad.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PhiLaw {
    /// `g = phi`.
    Constant {
        /// The value (rad).
        phi: f64,
    },
    /// A clamped cubic B-spline.
    Spline(PhiSpline),
    /// A Fourier series (periodic).
    Fourier(PhiFourier),
}

impl PhiLaw {
    /// `g(w)` and its first three derivatives in `w`.
    #[inline]
    pub fn eval(&self, w: f64) -> [f64; 4] {
        match self {
            PhiLaw::Constant { phi } => [*phi, 0.0, 0.0, 0.0],
            PhiLaw::Spline(spline) => spline.eval(w),
            PhiLaw::Fourier(series) => series.eval(w),
        }
    }

    /// Whether `g` and its derivatives are periodic in `w` with period 1.
    pub fn is_periodic(&self) -> bool {
        !matches!(self, PhiLaw::Spline(_))
    }

    /// The free coefficients, in a fixed order: `[phi]`; the spline's control values;
    /// `[mean, cos_1 .. cos_H, sin_1 .. sin_H]`.
    pub fn coefficients(&self) -> Vec<f64> {
        match self {
            PhiLaw::Constant { phi } => vec![*phi],
            PhiLaw::Spline(spline) => spline.values().to_vec(),
            PhiLaw::Fourier(series) => {
                let d = series.data();
                let mut out = vec![d.mean];
                out.extend(&d.cos);
                out.extend(&d.sin);
                out
            }
        }
    }

    /// The law of the same kind and size with other coefficients (the order of
    /// [`PhiLaw::coefficients`]).
    ///
    /// # Errors
    /// A different number of coefficients; a value that is not finite.
    pub fn with_coefficients(&self, values: &[f64]) -> Result<Self, KinematicsError> {
        let expected = match self {
            PhiLaw::Constant { .. } => 1,
            PhiLaw::Spline(spline) => spline.values().len(),
            PhiLaw::Fourier(series) => 1 + 2 * series.data().cos.len(),
        };
        if values.len() != expected {
            return Err(bad(
                "law coefficients",
                None,
                values.len() as f64,
                "must keep the law's number of coefficients",
            ));
        }
        Ok(match self {
            PhiLaw::Constant { .. } => {
                all_finite("law.phi", values)?;
                PhiLaw::Constant { phi: values[0] }
            }
            PhiLaw::Spline(_) => PhiLaw::Spline(PhiSpline::new(values.to_vec())?),
            PhiLaw::Fourier(_) => {
                let h = (values.len() - 1) / 2;
                PhiLaw::Fourier(PhiFourier::new(
                    values[0],
                    values[1..=h].to_vec(),
                    values[h + 1..].to_vec(),
                )?)
            }
        })
    }

    /// Interior parameters `w` where the third derivative jumps (spline knots).
    pub fn breakpoints(&self) -> &[f64] {
        match self {
            PhiLaw::Spline(spline) => spline.interior_knots(),
            _ => &[],
        }
    }
}

/// How a path's orientation is set: `phi = phi_base(s) + g(s / S)` (`relative`) or
/// `phi = g(s / S)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Orientation {
    /// Whether the law corrects the base path's orientation (`true`) or replaces it.
    pub relative: bool,
    /// The law.
    pub law: PhiLaw,
}

impl Orientation {
    /// A constant orientation `phi` (rad), replacing the base path's.
    pub fn constant(phi: f64) -> Self {
        Self {
            relative: false,
            law: PhiLaw::Constant { phi },
        }
    }

    /// The base path's own orientation (a zero correction).
    pub fn unchanged() -> Self {
        Self {
            relative: true,
            law: PhiLaw::Constant { phi: 0.0 },
        }
    }

    /// The orientation on `base` (checked as [`OrientedPath::new`]).
    ///
    /// # Errors
    /// As [`OrientedPath::new`].
    pub fn on<P: Path>(&self, base: P) -> Result<OrientedPath<P>, KinematicsError> {
        OrientedPath::new(base, self.clone())
    }
}

/// A base path with its orientation set by an [`Orientation`] (module documentation). Its
/// parameter, length and unit are the base path's; it is closed when the base path is and
/// the law is periodic; its breakpoints are the base path's and the law's knots.
///
/// ```
/// use flexprr_kinematics::{CirclePath, Orientation, Path, PhiLaw, PhiFourier};
///
/// let circle = CirclePath::new([-0.05, 0.0], 0.05, 0.0, 0.0, false).unwrap();
/// // phi = 45 deg + 5 deg sin(theta) around the circle.
/// let law = PhiFourier::new(45f64.to_radians(), vec![0.0], vec![5f64.to_radians()]).unwrap();
/// let orientation = Orientation { relative: false, law: PhiLaw::Fourier(law) };
/// let path = orientation.on(circle).unwrap();
/// let quarter = path.point(path.length() / 4.0);
/// assert!((quarter.pose.phi - 50f64.to_radians()).abs() < 1e-12);
/// assert!(path.is_closed());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct OrientedPath<P = GeometricPath> {
    base: P,
    orientation: Orientation,
    breakpoints: Vec<f64>,
}

impl<P: Path> OrientedPath<P> {
    /// `base` with `orientation`.
    ///
    /// # Errors
    /// A base path whose length is not positive and finite; an absolute orientation on a
    /// base path that only turns (its position is fixed: nothing would move).
    pub fn new(base: P, orientation: Orientation) -> Result<Self, KinematicsError> {
        let length = base.length();
        if !(length.is_finite() && length > 0.0) {
            return Err(bad(
                "base path length",
                None,
                length,
                "must be finite and > 0",
            ));
        }
        if !orientation.relative && base.unit() == "rad" {
            return Err(bad(
                "orientation",
                None,
                length,
                "an orientation law cannot replace the orientation of a path that only turns (its position does not move)",
            ));
        }
        let mut breakpoints = base.breakpoints();
        breakpoints.extend(orientation.law.breakpoints().iter().map(|w| w * length));
        breakpoints.sort_by(f64::total_cmp);
        breakpoints.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * length);
        Ok(Self {
            base,
            orientation,
            breakpoints,
        })
    }

    /// The base path.
    pub fn base(&self) -> &P {
        &self.base
    }

    /// The orientation.
    pub fn orientation(&self) -> &Orientation {
        &self.orientation
    }
}

impl<P: Path> Path for OrientedPath<P> {
    fn length(&self) -> f64 {
        self.base.length()
    }

    fn point(&self, s: f64) -> PathPoint {
        let mut point = self.base.point(s);
        let length = self.base.length();
        let [g, g1, g2, g3] = self.orientation.law.eval(point.s / length);
        let inverse = 1.0 / length;
        let law = Vector3::new(
            g1 * inverse,
            g2 * inverse * inverse,
            g3 * inverse * inverse * inverse,
        );
        if self.orientation.relative {
            point.pose.phi += g;
            point.d1.z += law.x;
            point.d2.z += law.y;
            point.d3.z += law.z;
        } else {
            point.pose.phi = g;
            point.d1.z = law.x;
            point.d2.z = law.y;
            point.d3.z = law.z;
        }
        point
    }

    fn is_closed(&self) -> bool {
        self.base.is_closed() && self.orientation.law.is_periodic()
    }

    fn breakpoints(&self) -> Vec<f64> {
        self.breakpoints.clone()
    }

    fn unit(&self) -> &'static str {
        self.base.unit()
    }
}

/// The serialised form of an [`OrientedPath`] on a [`GeometricPath`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrientedData {
    /// The base path (its position, and its orientation when `relative`).
    pub base: GeometricPath,
    /// Whether the law corrects the base path's orientation or replaces it.
    pub relative: bool,
    /// The law.
    pub law: PhiLaw,
}

impl Serialize for OrientedPath<GeometricPath> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        OrientedData {
            base: self.base.clone(),
            relative: self.orientation.relative,
            law: self.orientation.law.clone(),
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for OrientedPath<GeometricPath> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let data = OrientedData::deserialize(deserializer)?;
        Self::new(
            data.base,
            Orientation {
                relative: data.relative,
                law: data.law,
            },
        )
        .map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::{CirclePath, SegmentPath};
    use crate::pose::Pose;

    fn differences(eval: impl Fn(f64) -> [f64; 4], w: f64) {
        let h = 1e-6;
        let (a, g, b) = (eval(w - h), eval(w), eval(w + h));
        for order in 0..3 {
            let slope = (b[order] - a[order]) / (2.0 * h);
            let scale = 1.0 + g[order + 1].abs();
            assert!(
                (slope - g[order + 1]).abs() <= 2e-5 * scale,
                "derivative {} at {w}: {slope} vs {}",
                order + 1,
                g[order + 1]
            );
        }
    }

    #[test]
    fn spline_derivatives_agree_with_differences() {
        let spline = PhiSpline::new(vec![0.3, -0.2, 0.5, 0.1, 0.9, -0.4, 0.2]).unwrap();
        assert_eq!(spline.interior_knots(), &[0.25, 0.5, 0.75]);
        for k in 1..40 {
            let w = k as f64 / 40.0 + 0.003;
            differences(|w| spline.eval(w), w);
        }
    }

    #[test]
    fn spline_interpolates_its_ends_and_reproduces_constants_and_lines() {
        let values = vec![0.3, -0.2, 0.5, 0.1, 0.9];
        let spline = PhiSpline::new(values.clone()).unwrap();
        assert!((spline.eval(0.0)[0] - 0.3).abs() <= 1e-15);
        assert!((spline.eval(1.0)[0] - 0.9).abs() <= 1e-15);
        // Partition of unity: equal control values give that constant, zero derivatives.
        let flat = PhiSpline::new(vec![0.7; 6]).unwrap();
        // Linear precision: control values at the Greville abscissae
        // (t_{i+1} + t_{i+2} + t_{i+3}) / 3 give g(w) = w exactly.
        let n = 7;
        let knots = &PhiSpline::new(vec![0.0; n]).unwrap().levels[0]
            .knots
            .clone();
        let greville: Vec<f64> = (0..n)
            .map(|i| (knots[i + 1] + knots[i + 2] + knots[i + 3]) / 3.0)
            .collect();
        let line = PhiSpline::new(greville).unwrap();
        for k in 0..=50 {
            let w = k as f64 / 50.0;
            let g = flat.eval(w);
            assert!((g[0] - 0.7).abs() <= 1e-15 && g[1].abs() <= 1e-12 && g[2].abs() <= 1e-9);
            let g = line.eval(w);
            assert!((g[0] - w).abs() <= 1e-15, "{w}: {}", g[0]);
            assert!((g[1] - 1.0).abs() <= 1e-13 && g[2].abs() <= 1e-11 && g[3].abs() <= 1e-9);
            // Convex hull.
            let v = spline.eval(w)[0];
            assert!((-0.2..=0.9).contains(&v));
        }
        // Four values: one Bezier cubic, B(w) = sum c_i C(3, i) w^i (1 - w)^(3 - i).
        let bezier = PhiSpline::new(vec![1.0, -2.0, 0.5, 3.0]).unwrap();
        let w: f64 = 0.37;
        let u = 1.0 - w;
        let exact = u.powi(3) - 2.0 * 3.0 * w * u * u + 0.5 * 3.0 * w * w * u + 3.0 * w.powi(3);
        assert!((bezier.eval(w)[0] - exact).abs() <= 1e-15);
    }

    #[test]
    fn fourier_series_matches_its_closed_form_and_is_periodic() {
        let series = PhiFourier::new(0.2, vec![0.1, -0.05], vec![0.03, 0.02]).unwrap();
        for k in 0..20 {
            let w = k as f64 / 20.0 + 0.01;
            differences(|w| series.eval(w), w);
            let a = series.eval(w);
            let b = series.eval(w + 1.0);
            for j in 0..4 {
                assert!((a[j] - b[j]).abs() <= 1e-9 * (1.0 + a[j].abs()));
            }
        }
        let tau = std::f64::consts::TAU;
        let w: f64 = 0.3;
        let exact = 0.2
            + 0.1 * (tau * w).cos()
            + 0.03 * (tau * w).sin()
            + -0.05 * (2.0 * tau * w).cos()
            + 0.02 * (2.0 * tau * w).sin();
        assert!((series.eval(w)[0] - exact).abs() <= 1e-15);
        assert!(PhiFourier::new(0.0, vec![0.1], vec![]).is_err());
    }

    #[test]
    fn coefficients_round_trip() {
        let laws = [
            PhiLaw::Constant { phi: 0.4 },
            PhiLaw::Spline(PhiSpline::new(vec![0.1, 0.2, 0.3, 0.4, 0.5]).unwrap()),
            PhiLaw::Fourier(PhiFourier::new(0.1, vec![0.2, 0.3], vec![0.4, 0.5]).unwrap()),
        ];
        for law in laws {
            let c = law.coefficients();
            assert_eq!(law.with_coefficients(&c).unwrap(), law);
            assert!(law.with_coefficients(&c[1..]).is_err());
        }
        let spline = PhiLaw::Spline(PhiSpline::new(vec![0.0; 4]).unwrap());
        let error = spline
            .with_coefficients(&[0.0, 0.0, f64::NAN, 0.0])
            .unwrap_err();
        assert!(error.to_string().contains("law.values[2]"), "{error}");
    }

    #[test]
    fn constant_orientation_on_a_circle_is_the_circle_at_that_orientation() {
        let base = CirclePath::new([-0.05, 0.0], 0.05, 0.0, 0.3, false).unwrap();
        let phi = 0.8;
        let reference = CirclePath::new([-0.05, 0.0], 0.05, phi, 0.3, false).unwrap();
        let path = Orientation::constant(phi).on(base).unwrap();
        assert!(path.is_closed());
        for k in 0..10 {
            let s = path.length() * k as f64 / 10.0;
            assert_eq!(path.point(s), reference.point(s));
        }
        // A spline law opens the loop.
        let spline = Orientation {
            relative: true,
            law: PhiLaw::Spline(PhiSpline::new(vec![0.0, 0.1, 0.1, 0.0, 0.0]).unwrap()),
        };
        let open = spline.on(base).unwrap();
        assert!(!open.is_closed());
        assert_eq!(open.breakpoints().len(), 1);
    }

    #[test]
    fn relative_law_adds_to_the_base_orientation_with_chain_rule_derivatives() {
        let a = Pose::new(-0.08, -0.03, 0.5);
        let b = Pose::new(-0.02, 0.033, 0.2);
        let base = SegmentPath::new(a, b).unwrap();
        let law = PhiLaw::Spline(PhiSpline::new(vec![0.0, 0.2, -0.1, 0.3, 0.0]).unwrap());
        let path = Orientation {
            relative: true,
            law: law.clone(),
        }
        .on(base)
        .unwrap();
        let length = base.length();
        assert_eq!(path.breakpoints().len(), 1);
        for k in 0..=10 {
            let s = length * k as f64 / 10.0;
            let (p, q) = (path.point(s), base.point(s));
            let g = law.eval(s / length);
            assert!((p.pose.phi - q.pose.phi - g[0]).abs() <= 1e-15);
            assert!((p.pose.x - q.pose.x).abs() <= 0.0 && (p.d2.x - q.d2.x).abs() <= 0.0);
            assert!((p.d1.z - q.d1.z - g[1] / length).abs() <= 1e-12);
            let h = 1e-6 * length;
            if s > h && s < length - h {
                let slope = (path.point(s + h).pose.phi - path.point(s - h).pose.phi) / (2.0 * h);
                assert!((slope - p.d1.z).abs() <= 1e-6 * (1.0 + p.d1.z.abs()));
                let curvature = (path.point(s + h).d1.z - path.point(s - h).d1.z) / (2.0 * h);
                assert!((curvature - p.d2.z).abs() <= 1e-5 * (1.0 + p.d2.z.abs()));
            }
        }
        // The ends keep the base orientation when the law vanishes there.
        assert!((path.point(0.0).pose.phi - 0.5).abs() <= 1e-15);
        assert!((path.point(length).pose.phi - 0.2).abs() <= 1e-15);
    }

    #[test]
    fn a_turn_in_place_cannot_be_given_an_absolute_orientation() {
        let a = Pose::new(-0.05, 0.0, 0.0);
        let turn = SegmentPath::new(a, Pose::new(-0.05, 0.0, 1.0)).unwrap();
        let error = Orientation::constant(0.3).on(turn).unwrap_err();
        assert!(error.to_string().contains("only turns"), "{error}");
        assert!(Orientation::unchanged().on(turn).is_ok());
    }

    #[test]
    fn oriented_paths_round_trip_through_serde() {
        let base =
            GeometricPath::Circle(CirclePath::new([0.0, 0.0], 0.05, 0.1, 0.0, true).unwrap());
        let law = PhiLaw::Fourier(PhiFourier::new(0.1, vec![0.02], vec![-0.01]).unwrap());
        let path = GeometricPath::Oriented(Box::new(
            Orientation {
                relative: false,
                law,
            }
            .on(base)
            .unwrap(),
        ));
        let text = serde_json::to_string(&path).unwrap();
        let back: GeometricPath = serde_json::from_str(&text).unwrap();
        assert_eq!(back, path, "{text}");
        assert!(back.is_closed());
        let bad = r#"{"kind": "oriented", "relative": true,
            "base": {"kind": "segment", "from": [0, 0, 0], "to": [0.01, 0, 0]},
            "law": {"kind": "spline", "values": [0, 0, 0]}}"#;
        let error = serde_json::from_str::<GeometricPath>(bad).unwrap_err();
        assert!(error.to_string().contains("at least 4"), "{error}");
    }
}

//! The largest constant path speed of a closed path (docs/planning.md, "Closed paths at
//! constant speed").
//!
//! At a constant path speed `s' = y` (`u = 0`, `x = y^2`) every row is
//! `b y^2 + c y + d`: slider velocities scale with the frequency, rigid inverse-dynamics
//! forces with its square (the closed-form scaling `f_max = min(f1 v_max / v1,
//! f1 sqrt(F_max / F1))` from one evaluation at `f1`), friction adds the linear and constant
//! terms. For each row the largest `y` such that every speed in `[0, y]` meets it is the first
//! positive root of a quadratic, `y = 2 (U - d) / (c + sqrt(c^2 - 4 b (d - U)))` (written
//! without cancellation). The minimum over a dense sample of the path, refined by a
//! golden-section search around the smallest sample, is the answer; the frequency is
//! `y / S` revolutions per second.

use crate::constraint::Row;
use crate::error::{Infeasibility, PlanningError, Where};
use crate::plan::Planner;

/// The fastest constant-speed traversal of a closed path.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstantSpeed {
    /// Revolutions per second (Hz).
    pub frequency: f64,
    /// Path speed `s'` (path unit per second).
    pub path_speed: f64,
    /// The constraint that sets it.
    pub constraint: String,
    /// Its row.
    pub label: String,
    /// Where it binds.
    pub at: Where,
    /// Points sampled (before the golden-section refinement).
    pub samples: usize,
}

/// Largest `y >= 0` with `b y^2 + c y + d <= upper` on all of `[0, y]`.
fn first_root(b: f64, c: f64, d: f64, upper: f64) -> f64 {
    if !upper.is_finite() {
        return f64::INFINITY;
    }
    let room = upper - d;
    if room <= 0.0 {
        return 0.0;
    }
    let disc = c * c + 4.0 * b * room;
    if disc < 0.0 {
        return f64::INFINITY;
    }
    let denominator = c + disc.sqrt();
    if denominator > 0.0 {
        2.0 * room / denominator
    } else {
        f64::INFINITY
    }
}

/// Largest constant path speed a row allows.
fn row_speed(row: &Row) -> f64 {
    if !row.is_active() {
        return f64::INFINITY;
    }
    first_root(row.x, row.sqrt_x, row.offset, row.upper).min(first_root(
        -row.x,
        -row.sqrt_x,
        -row.offset,
        -row.lower,
    ))
}

impl Planner<'_> {
    /// The largest frequency of the closed path at constant speed (module documentation),
    /// sampled at `grid * check_factor` points.
    ///
    /// # Errors
    /// An open path; workspace and dynamics errors; a limit broken at rest.
    pub fn constant_speed(&self) -> Result<ConstantSpeed, PlanningError> {
        let path = self.path();
        if !path.is_closed() {
            return Err(PlanningError::OpenPath);
        }
        let sampler = self.sampler();
        let width: usize = self.constraints().iter().map(|c| c.count()).sum();
        let mut rows = vec![Row::INACTIVE; width];
        let length = path.length();
        let n = self.settings().grid * self.settings().check_factor;
        let mut evaluate = |s: f64| -> Result<(f64, usize, Where), PlanningError> {
            let sample = sampler.sample(path, s)?;
            let mut offset = 0;
            for c in self.constraints() {
                c.rows(&sample, &mut rows[offset..offset + c.count()]);
                offset += c.count();
            }
            let mut best = (f64::INFINITY, 0);
            for (j, row) in rows.iter().enumerate() {
                let y = row_speed(row);
                if y < best.0 {
                    best = (y, j);
                }
            }
            Ok((best.0, best.1, sample.place()))
        };
        let mut best = (f64::INFINITY, 0, 0usize);
        for k in 0..n {
            let (y, j, _) = evaluate(length * k as f64 / n as f64)?;
            if y < best.0 {
                best = (y, j, k);
            }
        }
        // Golden-section search for the minimum between the neighbouring samples.
        let h = length / n as f64;
        let centre = length * best.2 as f64 / n as f64;
        let (mut a, mut b) = (centre - h, centre + h);
        let ratio = 0.5 * (5f64.sqrt() - 1.0);
        let mut c = b - ratio * (b - a);
        let mut d = a + ratio * (b - a);
        let mut fc = evaluate(c)?.0;
        let mut fd = evaluate(d)?.0;
        for _ in 0..60 {
            if fc < fd {
                b = d;
                d = c;
                fd = fc;
                c = b - ratio * (b - a);
                fc = evaluate(c)?.0;
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + ratio * (b - a);
                fd = evaluate(d)?.0;
            }
            if (b - a).abs() <= 1e-12 * length {
                break;
            }
        }
        let refined = evaluate(0.5 * (a + b))?;
        let (y, j, at) = if refined.0 < best.0 {
            refined
        } else {
            evaluate(centre)?
        };
        if !y.is_finite() {
            return Err(PlanningError::Unbounded { at });
        }
        if y <= 0.0 {
            let mut offset = 0;
            let mut owner = (0, 0);
            for (ci, cons) in self.constraints().iter().enumerate() {
                if j < offset + cons.count() {
                    owner = (ci, j - offset);
                    break;
                }
                offset += cons.count();
            }
            let cons = &self.constraints()[owner.0];
            return Err(PlanningError::Infeasible(Box::new(Infeasibility {
                constraint: cons.name().to_owned(),
                label: cons.label(owner.1),
                at,
                reason: "it allows no constant speed here",
                value: 0.0,
                limit: 0.0,
                unit: cons.unit().to_owned(),
            })));
        }
        let mut offset = 0;
        let (mut name, mut label) = (String::new(), String::new());
        for cons in self.constraints() {
            if j < offset + cons.count() {
                name = cons.name().to_owned();
                label = cons.label(j - offset);
                break;
            }
            offset += cons.count();
        }
        Ok(ConstantSpeed {
            frequency: y / length,
            path_speed: y,
            constraint: name,
            label,
            at,
            samples: n,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_root_solves_the_quadratic() {
        // y^2 <= 4: y = 2.
        assert!((first_root(1.0, 0.0, 0.0, 4.0) - 2.0).abs() <= 1e-15);
        // 3 y <= 6: y = 2.
        assert!((first_root(0.0, 3.0, 0.0, 6.0) - 2.0).abs() <= 1e-15);
        // y^2 + y + 1 <= 3: y = 1.
        assert!((first_root(1.0, 1.0, 1.0, 3.0) - 1.0).abs() <= 1e-15);
        // -y^2 + 4 y <= 3: fails first at y = 1 (roots 1 and 3).
        assert!((first_root(-1.0, 4.0, 0.0, 3.0) - 1.0).abs() <= 1e-15);
        // -y^2 + y <= 1: never.
        assert!(first_root(-1.0, 1.0, 0.0, 1.0).is_infinite());
        // Broken at rest.
        assert!(first_root(1.0, 0.0, 2.0, 1.0) <= 0.0);
    }
}

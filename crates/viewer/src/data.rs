//! The plain data a viewer or figure is drawn from, and its validation.

use std::fmt;

/// A straight guide of one prismatic joint, as drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuideView {
    /// Guide centre `A_i` in the fixed frame (m); slider positions are measured from here.
    pub anchor: [f64; 2],
    /// Unit direction `u_i` of positive slider position.
    pub direction: [f64; 2],
    /// Travel limits `(min, max)` of the slider position (m), `min < max`.
    pub travel: (f64, f64),
}

/// One flexible link: its static description and its time series.
///
/// The transverse deflection along the link normal `n_i` (model.md section 1) is the
/// assumed-mode sum `w_i(xi, t) = sum_k psi_k(xi) q_k(t)`, `xi = x / l` measured from the
/// slider joint `B_i`. The viewer stores the sampled mode shapes once and the modal
/// coordinates per frame, so the deflected line is the scene's own basis, not a sketch.
/// A model that only has deflection samples can pass unit vectors as "mode shapes".
#[derive(Debug, Clone, PartialEq)]
pub struct LinkView {
    /// Undeformed link length `l_i` (m).
    pub length: f64,
    /// Name of the assumed-mode basis (shown on the page, e.g. `"sine"`).
    pub basis: String,
    /// Sample points `xi_j` in `[0, 1]`, strictly increasing.
    pub xi: Vec<f64>,
    /// Mode shapes `psi_k(xi_j)`, indexed `[mode][j]` (dimensionless).
    pub mode_shapes: Vec<Vec<f64>>,
    /// Modal coordinates `q_k` (m), indexed `[frame][mode]`.
    pub modal: Vec<Vec<f64>>,
    /// Axial force per frame (N), tension positive (model.md section 5).
    pub axial_force: Vec<f64>,
    /// Instantaneous first-mode frequency per frame (Hz). While the link buckles (its
    /// stiffness is not positive definite) pass a finite stand-in, e.g. 0, and list the
    /// interval in `buckling`.
    pub first_frequency: Vec<f64>,
    /// Time intervals `(start, end)` (s) in which the link buckles.
    pub buckling: Vec<(f64, f64)>,
    /// The spans `(xi_start, xi_end)` of the piezoelectric patches bonded to the link
    /// (docs/piezo.md), drawn as a thicker coloured band; empty without patches.
    pub patches: Vec<(f64, f64)>,
}

impl LinkView {
    /// Deflection `w(xi_j)` (m) at sample `j` of frame `frame`.
    pub fn deflection(&self, frame: usize, j: usize) -> f64 {
        self.mode_shapes
            .iter()
            .zip(&self.modal[frame])
            .map(|(shape, q)| shape[j] * q)
            .sum()
    }

    /// Deflection (m) at an arbitrary `xi` of frame `frame`: the modal sum of the mode
    /// shapes interpolated linearly between the samples (exact at a sample point). Needs at
    /// least two samples (as [`ViewerData::validate`] checks); `xi` outside the samples
    /// takes the end value.
    pub fn deflection_at(&self, frame: usize, xi: f64) -> f64 {
        let n = self.xi.len();
        let j = self.xi.partition_point(|&x| x <= xi).clamp(1, n - 1);
        let (x0, x1) = (self.xi[j - 1], self.xi[j]);
        let s = ((xi - x0) / (x1 - x0)).clamp(0.0, 1.0);
        (1.0 - s) * self.deflection(frame, j - 1) + s * self.deflection(frame, j)
    }
}

/// Everything the viewer page and the static figures draw: the machine, and one run's
/// frames at the times `time`.
///
/// Every per-frame series has one entry per element of `time`. Lengths are in metres,
/// angles in radians, forces in newtons and frequencies in hertz; the page converts to
/// prefixed units for display.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewerData {
    /// Title shown on the page (scene name and model).
    pub title: String,
    /// Free text under the title, e.g. the model, integrator and tolerances.
    pub subtitle: String,
    /// The three guides.
    pub guides: [GuideView; 3],
    /// Platform joints `c_i` in the platform frame (m).
    pub attachments: [[f64; 2]; 3],
    /// The three links.
    pub links: [LinkView; 3],
    /// Frame times (s), strictly increasing.
    pub time: Vec<f64>,
    /// Platform pose `(x, y, phi)` per frame (m, m, rad): the rigid-body (commanded) pose.
    pub pose: Vec<[f64; 3]>,
    /// Slider positions `rho_i` per frame (m).
    pub sliders: Vec<[f64; 3]>,
    /// Coupled model only: actual minus rigid platform pose per frame (m, m, rad). The page
    /// draws the platform at `pose + a * deviation` with a user-set amplification `a`.
    pub deviation: Option<Vec<[f64; 3]>>,
    /// Actuated sliders only: the commanded slider positions `rho_ref` per frame (m), where
    /// `sliders` are the actual ones. The page draws each reference as a hollow block and
    /// the actual slider at `rho_ref + a (rho - rho_ref)`, with the deviation's
    /// amplification `a` (1 without a deviation).
    pub reference_sliders: Option<Vec<[f64; 3]>>,
}

/// What is wrong with a [`ViewerData`]: the field, and where (frame, link, mode).
#[derive(Debug, Clone, PartialEq)]
pub enum ViewerError {
    /// A series has the wrong number of entries.
    Length {
        /// Field name, e.g. `"links[1].axial_force"`.
        field: String,
        /// Entries found.
        found: usize,
        /// Entries expected.
        expected: usize,
    },
    /// A value is NaN or infinite.
    NotFinite {
        /// Field name.
        field: String,
        /// Index of the offending entry (frame, sample or interval).
        index: usize,
    },
    /// A value breaks a rule (ordering, range, unit length).
    Invalid {
        /// Field name.
        field: String,
        /// Index of the offending entry.
        index: usize,
        /// The value.
        value: f64,
        /// The rule it breaks.
        reason: &'static str,
    },
    /// A figure could not be drawn.
    Figure(String),
}

impl fmt::Display for ViewerError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ViewerError::Length {
                field,
                found,
                expected,
            } => write!(f, "{field}: {found} entries, expected {expected}"),
            ViewerError::NotFinite { field, index } => {
                write!(f, "{field}[{index}] is not finite")
            }
            ViewerError::Invalid {
                field,
                index,
                value,
                reason,
            } => write!(f, "{field}[{index}] = {value}: {reason}"),
            ViewerError::Figure(message) => write!(f, "figure: {message}"),
        }
    }
}

impl std::error::Error for ViewerError {}

fn check_len(field: impl Into<String>, found: usize, expected: usize) -> Result<(), ViewerError> {
    if found == expected {
        Ok(())
    } else {
        Err(ViewerError::Length {
            field: field.into(),
            found,
            expected,
        })
    }
}

fn check_finite<'a>(
    field: impl Fn() -> String,
    values: impl IntoIterator<Item = &'a f64>,
) -> Result<(), ViewerError> {
    for (index, v) in values.into_iter().enumerate() {
        if !v.is_finite() {
            return Err(ViewerError::NotFinite {
                field: field(),
                index,
            });
        }
    }
    Ok(())
}

fn check_increasing(field: &str, values: &[f64]) -> Result<(), ViewerError> {
    for (index, pair) in values.windows(2).enumerate() {
        if pair[1] <= pair[0] {
            return Err(ViewerError::Invalid {
                field: field.to_string(),
                index: index + 1,
                value: pair[1],
                reason: "must be larger than the previous entry",
            });
        }
    }
    Ok(())
}

impl ViewerData {
    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.time.len()
    }

    /// Checks every length, that every number is finite, times and `xi` strictly
    /// increasing, `xi` in `[0, 1]`, guide directions of unit length, travel `min < max`,
    /// link lengths positive, buckling intervals ordered and patch spans inside `[0, 1]`
    /// with their start before their end.
    ///
    /// # Errors
    /// The first problem found, naming the field and the index.
    pub fn validate(&self) -> Result<(), ViewerError> {
        let n = self.time.len();
        if n == 0 {
            return Err(ViewerError::Length {
                field: "time".into(),
                found: 0,
                expected: 1,
            });
        }
        check_finite(|| "time".into(), &self.time)?;
        check_increasing("time", &self.time)?;
        check_len("pose", self.pose.len(), n)?;
        check_finite(|| "pose".into(), self.pose.iter().flatten())?;
        check_len("sliders", self.sliders.len(), n)?;
        check_finite(|| "sliders".into(), self.sliders.iter().flatten())?;
        if let Some(deviation) = &self.deviation {
            check_len("deviation", deviation.len(), n)?;
            check_finite(|| "deviation".into(), deviation.iter().flatten())?;
        }
        if let Some(reference) = &self.reference_sliders {
            check_len("reference_sliders", reference.len(), n)?;
            check_finite(|| "reference_sliders".into(), reference.iter().flatten())?;
        }
        check_finite(|| "attachments".into(), self.attachments.iter().flatten())?;
        self.validate_guides()?;
        for (i, link) in self.links.iter().enumerate() {
            let name = |f: &str| format!("links[{i}].{f}");
            if !(link.length.is_finite() && link.length > 0.0) {
                return Err(ViewerError::Invalid {
                    field: name("length"),
                    index: 0,
                    value: link.length,
                    reason: "must be finite and positive",
                });
            }
            if link.xi.len() < 2 {
                return Err(ViewerError::Length {
                    field: name("xi"),
                    found: link.xi.len(),
                    expected: 2,
                });
            }
            check_finite(|| name("xi"), &link.xi)?;
            check_increasing(&name("xi"), &link.xi)?;
            for (index, &x) in link.xi.iter().enumerate() {
                if !(0.0..=1.0).contains(&x) {
                    return Err(ViewerError::Invalid {
                        field: name("xi"),
                        index,
                        value: x,
                        reason: "must lie in [0, 1]",
                    });
                }
            }
            if link.mode_shapes.is_empty() {
                return Err(ViewerError::Length {
                    field: name("mode_shapes"),
                    found: 0,
                    expected: 1,
                });
            }
            for (k, shape) in link.mode_shapes.iter().enumerate() {
                let field = format!("links[{i}].mode_shapes[{k}]");
                check_len(field.clone(), shape.len(), link.xi.len())?;
                check_finite(|| field.clone(), shape)?;
            }
            check_len(name("modal"), link.modal.len(), n)?;
            for (frame, q) in link.modal.iter().enumerate() {
                let field = format!("links[{i}].modal[{frame}]");
                check_len(field.clone(), q.len(), link.mode_shapes.len())?;
                check_finite(|| field.clone(), q)?;
            }
            check_len(name("axial_force"), link.axial_force.len(), n)?;
            check_finite(|| name("axial_force"), &link.axial_force)?;
            check_len(name("first_frequency"), link.first_frequency.len(), n)?;
            check_finite(|| name("first_frequency"), &link.first_frequency)?;
            for (index, &(a, b)) in link.buckling.iter().enumerate() {
                if !(a.is_finite() && b.is_finite()) {
                    return Err(ViewerError::NotFinite {
                        field: name("buckling"),
                        index,
                    });
                }
                if b < a {
                    return Err(ViewerError::Invalid {
                        field: name("buckling"),
                        index,
                        value: b,
                        reason: "interval end before its start",
                    });
                }
            }
            for (index, &(a, b)) in link.patches.iter().enumerate() {
                if !(a >= 0.0 && a < b && b <= 1.0) {
                    return Err(ViewerError::Invalid {
                        field: name("patches"),
                        index,
                        value: if a.is_finite() && a >= 0.0 { b } else { a },
                        reason: "a patch must span 0 <= xi_start < xi_end <= 1",
                    });
                }
            }
        }
        Ok(())
    }

    /// Every guide finite, of unit direction and with `min < max` travel.
    fn validate_guides(&self) -> Result<(), ViewerError> {
        for (i, g) in self.guides.iter().enumerate() {
            let field = || format!("guides[{i}]");
            check_finite(
                field,
                g.anchor
                    .iter()
                    .chain(&g.direction)
                    .chain([&g.travel.0, &g.travel.1]),
            )?;
            let norm = g.direction[0].hypot(g.direction[1]);
            if (norm - 1.0).abs() > 1e-9 {
                return Err(ViewerError::Invalid {
                    field: format!("guides[{i}].direction"),
                    index: 0,
                    value: norm,
                    reason: "must have unit length",
                });
            }
            if g.travel.0 >= g.travel.1 {
                return Err(ViewerError::Invalid {
                    field: format!("guides[{i}].travel"),
                    index: 1,
                    value: g.travel.1,
                    reason: "max must exceed min",
                });
            }
        }
        Ok(())
    }
}

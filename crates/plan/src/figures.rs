//! The plan's figures (drawn with the run's plotting layer, `flexprr_run::plot`):
//! `phase_plane.svg`, the planned path speed against the path position with each limit's
//! maximum-velocity curve; `sliders.svg`, the slider speeds and rigid drive forces of the
//! planned motion's run against their limits; `deflections.svg`, the links' largest
//! deflection on the planned motion, its unshaped variant and the scene's own motion.

use flexprr_kinematics::Path;
use flexprr_planning::{PlanSpec, Row, Sampler};
use flexprr_run::plot::{Axis, Dash, Figure, Panel, Series, Style};

use crate::pipeline::PlanOutcome;

/// Points of the limit curves along the path.
const CURVE_POINTS: usize = 400;

/// Whether a path speed squared `x` admits some path acceleration within `rows`.
fn feasible(rows: &[Row], x: f64) -> bool {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for r in rows.iter().filter(|r| r.is_active()) {
        let rest = r.x * x + r.sqrt_x * x.sqrt() + r.offset;
        if r.u.abs() < 1e-300 {
            if rest < r.lower - 1e-12 * r.lower.abs() || rest > r.upper + 1e-12 * r.upper.abs() {
                return false;
            }
            continue;
        }
        let (a, b) = ((r.lower - rest) / r.u, (r.upper - rest) / r.u);
        lo = lo.max(a.min(b));
        hi = hi.min(a.max(b));
    }
    lo <= hi
}

/// The largest path speed that `rows` admit (the constraint's maximum-velocity curve), by
/// bisection on `x = s'^2` up to `ceiling`; `NaN` where the constraint does not bound it.
fn max_speed(rows: &[Row], ceiling: f64) -> f64 {
    if feasible(rows, ceiling) {
        return f64::NAN;
    }
    if !feasible(rows, 0.0) {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, ceiling);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if feasible(rows, mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo.sqrt()
}

/// The phase plane: the planned `s'(s)` and every limit's maximum-velocity curve.
fn phase_plane(outcome: &PlanOutcome) -> Option<Figure> {
    let machine = outcome.source.machine.as_ref();
    let path = &outcome.path;
    let timing = &outcome.plan.timing;
    // The fastest timing drawn: the time-optimal one when the deflection limit slowed it.
    let fastest = outcome
        .deflection
        .as_ref()
        .map_or(timing, |d| &d.fastest.timing);
    let top = fastest.speeds().iter().fold(0.0f64, |m, v| m.max(*v));
    let unit = path.unit();
    let mut panel =
        Panel::new(Axis::new("path speed s'", format!("{unit}/s"))).series(Series::new(
            if outcome.plan.impulses.is_empty() {
                "planned".to_string()
            } else {
                "planned (before shaping)".to_string()
            },
            timing.grid(),
            timing.speeds(),
            Style::nth(0),
        ));
    if let Some(search) = outcome.deflection.as_ref().filter(|d| d.binds()) {
        let fastest = &search.fastest.timing;
        panel = panel.series(Series::new(
            format!("time-optimal ({:.3}x faster)", search.stretch),
            fastest.grid(),
            fastest.speeds(),
            Style::nth(0).dash(Dash::Dotted),
        ));
    }
    let constraints = outcome
        .spec
        .constraints(
            machine,
            flexprr_scene::motor_of(&outcome.planned_file).as_ref(),
        )
        .ok()?;
    let sampler = Sampler::new(machine, Some(outcome.source.axial_model.as_ref()));
    let length = path.length();
    let s: Vec<f64> = (0..=CURVE_POINTS)
        .map(|k| length * k as f64 / CURVE_POINTS as f64)
        .collect();
    let samples: Vec<_> = s.iter().map(|&s| sampler.sample(path, s).ok()).collect();
    let ceiling = (20.0 * top).powi(2).max(1e-12);
    let cut = 3.0 * top;
    // The maximum-velocity curve of `rows_at` along the path, cut at `cut`; `None` where it
    // never bounds the speed below the cut.
    let curve_of = |rows_at: &dyn Fn(&flexprr_planning::PathSample, &mut Vec<Row>)| {
        let mut rows = Vec::new();
        let curve: Vec<f64> = samples
            .iter()
            .map(|sample| match sample {
                Some(sample) => {
                    rows_at(sample, &mut rows);
                    max_speed(&rows, ceiling).min(cut)
                }
                None => f64::NAN,
            })
            .collect();
        curve
            .iter()
            .any(|v| *v < cut * (1.0 - 1e-9))
            .then_some(curve)
    };
    for (k, c) in constraints.iter().enumerate() {
        let alone = curve_of(&|sample, rows| {
            rows.clear();
            rows.resize(c.count(), Row::INACTIVE);
            c.rows(sample, rows);
        });
        // A limit that bounds the speed only together with another (the bus voltage, which
        // a large braking torque could meet at any speed) draws no curve of its own.
        if let Some(curve) = alone {
            panel = panel.series(Series::new(
                format!("{} limit", c.name()),
                &s,
                &curve,
                Style::nth(k + 1).dash(Dash::Dashed),
            ));
        }
    }
    if constraints.len() > 1 {
        let together = curve_of(&|sample, rows| {
            rows.clear();
            for c in &constraints {
                let start = rows.len();
                rows.resize(start + c.count(), Row::INACTIVE);
                c.rows(sample, &mut rows[start..]);
            }
        });
        if let Some(curve) = together {
            panel = panel.series(Series::new(
                "all limits together",
                &s,
                &curve,
                Style::nth(5).dash(Dash::Dotted),
            ));
        }
    }
    Some(
        Figure::new(Axis::new("path position s", unit))
            .title(format!("{}: phase plane", outcome.scene))
            .description(
                "The planned path speed against the path position, with the largest path speed \
                 each limit alone admits at some path acceleration (its maximum-velocity curve, \
                 cut at three times the planned peak), and the curve of all limits together.",
            )
            .panel(panel),
    )
}

/// `|column|` of each leg with the limit as a flat line.
fn leg_panel(
    table: &flexprr_run::Table,
    stem: &str,
    unit: &str,
    label: &str,
    axis_unit: &str,
    limit: Option<f64>,
) -> Option<Panel> {
    let t = table.time();
    let mut panel = Panel::new(Axis::new(label, axis_unit));
    for leg in 1..=3 {
        let values = table.column(&format!("{stem}_{leg}_{unit}"))?;
        panel = panel.series(Series::new(
            format!("leg {leg}"),
            t,
            values,
            Style::nth(leg - 1),
        ));
    }
    if let Some(limit) = limit {
        let ends = [t[0], t[t.len() - 1]];
        for (sign, name) in [(1.0, "limit"), (-1.0, "")] {
            panel = panel.series(Series::new(
                name,
                &ends,
                &[sign * limit, sign * limit],
                Style::nth(5).dash(Dash::Dashed),
            ));
        }
    }
    Some(panel)
}

/// Slider speeds and drive forces over time against their limits (the planned motion's
/// run).
fn sliders(outcome: &PlanOutcome, spec: &PlanSpec) -> Option<Figure> {
    let run = &outcome.flexible.as_ref()?.planned_run;
    let speed = leg_panel(
        run.table("kinematics")?,
        "rho_dot",
        "m_s",
        "slider speed",
        "m/s",
        spec.slider_speed,
    )?;
    let force = leg_panel(
        run.table("driving_forces")?,
        "F_a",
        "rigid_N",
        "rigid drive force",
        "N",
        spec.slider_force,
    )?;
    Some(
        Figure::new(Axis::new("time", "s"))
            .title(format!("{}: sliders on the planned motion", outcome.scene))
            .description(
                "Slider speeds and rigid drive forces of the planned motion, as the run layer \
                 computes them (inverse kinematics and rigid inverse dynamics), against the \
                 [plan] limits.",
            )
            .panel(speed)
            .panel(force),
    )
}

/// The links' largest deflection on the planned motion, its unshaped variant and the
/// scene's own motion.
fn deflections(outcome: &PlanOutcome) -> Option<Figure> {
    let flexible = outcome.flexible.as_ref()?;
    let mut panel = Panel::new(Axis::new("largest |w| of the links", "m")).series(Series::new(
        "planned",
        &flexible.planned.t,
        &flexible.planned.deflection,
        Style::nth(0),
    ));
    if let Some(u) = &flexible.unshaped {
        panel = panel.series(Series::new(
            "planned, unshaped",
            &u.t,
            &u.deflection,
            Style::nth(1),
        ));
    }
    if let Ok(o) = &flexible.original {
        panel = panel.series(Series::new(
            "the scene's own motion",
            &o.t,
            &o.deflection,
            Style::nth(2).dash(Dash::Dashed),
        ));
    }
    Some(
        Figure::new(Axis::new("time", "s"))
            .title(format!(
                "{}: deflections ({})",
                outcome.scene, flexible.model
            ))
            .description(
                "The largest deflection of any link at the requested positions over time, on \
                 the planned motion, its unshaped variant and the scene's own timing.",
            )
            .panel(panel),
    )
}

/// The figures of a plan: `(file name, figure)`.
pub fn plan_figures(outcome: &PlanOutcome) -> Vec<(String, Figure)> {
    let mut out = Vec::new();
    if let Some(f) = phase_plane(outcome) {
        out.push(("phase_plane.svg".to_string(), f));
    }
    if let Some(f) = sliders(outcome, &outcome.spec) {
        out.push(("sliders.svg".to_string(), f));
    }
    if let Some(f) = deflections(outcome) {
        out.push(("deflections.svg".to_string(), f));
    }
    out
}

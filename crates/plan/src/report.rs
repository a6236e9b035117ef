//! `plan.json`: what the plan is, what binds it, its margins, its grid convergence, how it
//! compares with the scene's own timing, the orientation search, the shaper and the residual
//! vibration, and what the deflection limit did.

use flexprr_kinematics::{GeometricPath, Path, Pose};
use flexprr_planning::{Boundary, Check, Plan, ScanPoint, Usage};
use serde_json::{Value, json};

use crate::deflection::{DeflectionSearch, STRETCH_TOLERANCE};
use crate::pipeline::{OrientationSearch, PlanOutcome};
use crate::vibration::{MotionVibration, ShapingDesign};

fn pose_json(pose: Pose) -> Value {
    json!({ "x_m": pose.x, "y_m": pose.y, "phi_deg": pose.phi.to_degrees() })
}

/// One limit's largest use in a check.
fn usage_json(usage: &Usage, path: &GeometricPath) -> Value {
    json!({
        "constraint": usage.constraint,
        "unit": usage.unit,
        "where": usage.label,
        "limit": usage.limit,
        "value": usage.value,
        "usage": usage.usage,
        "margin": usage.margin(),
        "s": usage.s,
        "t_s": usage.t,
        "pose": pose_json(path.point(usage.s.clamp(0.0, path.length())).pose),
    })
}

fn check_json(check: &Check, path: &GeometricPath) -> Value {
    let worst = check.worst();
    json!({
        "samples": check.samples,
        "max_usage": check.max_usage,
        "worst": worst.map(|u| u.constraint.clone()),
        "limits": check.constraints.iter().map(|u| usage_json(u, path)).collect::<Vec<_>>(),
    })
}

/// The timing facts of a plan.
fn plan_json(plan: &Plan, path: &GeometricPath) -> Value {
    let mut v = json!({
        "duration_s": plan.duration,
        "optimal_duration_s": plan.optimal_duration,
        "binding": plan.binding.iter().map(|b| json!({
            "constraint": b.constraint,
            "from_s": b.from,
            "to_s": b.to,
            "from_pose": pose_json(path.point(b.from).pose),
            "to_pose": pose_json(path.point(b.to).pose),
        })).collect::<Vec<_>>(),
        "check": check_json(&plan.check, path),
        "grid": {
            "points": plan.grid_points,
            "refinements": plan.refinements,
            "tightened_points": plan.tightened_points,
        },
        "convergence": plan.convergence.as_ref().map(|c| json!({
            "intervals": c.intervals,
            "durations_s": c.durations,
            "order": c.order,
        })),
        "tightening": plan.tightening,
        "peak_torque_factor": plan.peak_torque_factor,
        "rms_torque_Nm": plan.rms_torque,
        "smoothing_s": plan.smoothing,
    });
    if plan.boundary == Boundary::Periodic {
        v["period_s"] = json!(plan.duration);
        v["frequency_hz"] = json!(1.0 / plan.duration);
    }
    v
}

fn scan_json(scan: &[ScanPoint]) -> Value {
    Value::Array(
        scan.iter()
            .map(|p| match &p.value {
                Ok(v) => json!({ "phi_deg": p.phi.to_degrees(), "value": v }),
                Err(why) => json!({ "phi_deg": p.phi.to_degrees(), "infeasible": why }),
            })
            .collect(),
    )
}

fn orientation_json(search: &OrientationSearch, objective: &str) -> Value {
    let constant = match search {
        OrientationSearch::Constant(c) | OrientationSearch::Free { constant: c, .. } => c,
    };
    let original = match &constant.original {
        Ok(v) => json!(v),
        Err(why) => json!({ "infeasible": why }),
    };
    let mut v = json!({
        "objective": objective,
        "original_value": original,
        "best_constant": {
            "phi_deg": constant.phi.to_degrees(),
            "value": constant.value,
            "evaluations": constant.evaluations,
            "scan": scan_json(&constant.scan),
        },
    });
    if let OrientationSearch::Free { free, .. } = search {
        v["free"] = json!({
            "value": free.value,
            "start_value": free.start_value,
            "constant_value": free.constant_value,
            "phi_range_deg": [free.range.0.to_degrees(), free.range.1.to_degrees()],
            "evaluations": free.evaluations,
            "converged": free.converged,
            "restarts": free.restarts,
            "law": serde_json::to_value(&free.orientation).unwrap_or(Value::Null),
        });
    }
    v
}

fn shaping_json(design: &ShapingDesign, plan: &Plan, unshaped: Option<&Plan>) -> Value {
    json!({
        "modes_from": design.model,
        "poses": design.poses.iter().map(|p| json!({
            "s": p.s,
            "pose": pose_json(p.pose),
            "frequencies_hz": p.modes.iter().map(|m| m.frequency).collect::<Vec<_>>(),
            "damping_ratios": p.modes.iter().map(|m| m.damping).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "modes": design.modes.iter().map(|m| json!({
            "range_hz": [m.range_hz.0, m.range_hz.1],
            "end_pose_hz": m.end_hz,
            "design_hz": m.design_hz,
            "damping_ratio": m.damping,
            "half_width": m.half_width,
            "worst_residual_over_range": m.worst_residual,
        })).collect::<Vec<_>>(),
        "impulses": design.impulses.iter().map(|i| [i.amplitude, i.delay]).collect::<Vec<_>>(),
        "unshaped_duration_s": unshaped.map(|u| u.duration),
        "extra_time_s": unshaped.map(|u| plan.duration - u.duration),
    })
}

fn vibration_json(v: &MotionVibration) -> Value {
    json!({
        "move_end_s": v.move_end,
        "peak_deflection_during_move_m": v.peak_during,
        "residual_vibration_m": v.residual,
        "residual_peak_at_s": v.residual_at,
    })
}

fn deflection_json(search: &DeflectionSearch) -> Value {
    json!({
        "limit_m": search.limit,
        "binds": search.binds(),
        "stretch": search.stretch,
        "stretch_tolerance": STRETCH_TOLERANCE,
        "peak_deflection_m": search.peak,
        "fastest_duration_s": search.fastest.duration,
        "probes": search.probes.iter().map(|p| match &p.peak {
            Ok(w) => json!({ "stretch": p.stretch, "duration_s": finite(p.duration), "peak_deflection_m": w }),
            Err(why) => json!({ "stretch": p.stretch, "duration_s": finite(p.duration), "failed": why }),
        }).collect::<Vec<_>>(),
    })
}

/// A number, or `null` when not finite.
fn finite(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

/// The whole `plan.json`.
pub fn plan_report(outcome: &PlanOutcome) -> Value {
    let spec = &outcome.spec;
    let plan = &outcome.plan;
    let mut v = json!({
        "scene": outcome.scene,
        "flexprr_version": env!("CARGO_PKG_VERSION"),
        "settings": serde_json::to_value(spec).unwrap_or(Value::Null),
        "objective": "min_time",
        "boundary": match plan.boundary { Boundary::Periodic => "periodic", Boundary::RestToRest => "rest_to_rest" },
        "path": {
            "kind": outcome.base_path.kind(),
            "planned_kind": outcome.path.kind(),
            "length": outcome.path.length(),
            "unit": outcome.path.unit(),
            "start_pose": pose_json(outcome.path.point(0.0).pose),
            "end_pose": pose_json(outcome.path.point(outcome.path.length()).pose),
        },
        "start_s": outcome.start,
        "plan": plan_json(plan, &outcome.path),
    });
    match plan.boundary {
        Boundary::Periodic => {
            v["period_s"] = json!(plan.duration);
            v["frequency_hz"] = json!(1.0 / plan.duration);
        }
        Boundary::RestToRest => v["duration_s"] = json!(plan.duration),
    }
    let timing = &outcome.scene_timing;
    let (own_key, own_value) = if timing.periodic {
        ("frequency_hz", 1.0 / timing.duration)
    } else {
        ("duration_s", timing.duration)
    };
    v["scene_timing"] = json!({
        own_key: own_value,
        "duration_s": timing.duration,
        "periodic": timing.periodic,
        "planned_over_scene": plan.duration / timing.duration,
        "check": match &timing.check {
            Ok(check) => check_json(check, &outcome.base_path),
            Err(why) => json!({ "error": why }),
        },
    });
    if let Some(search) = &outcome.orientation {
        let objective = match spec.phi_objective.unwrap_or_default() {
            flexprr_planning::PhiGoal::MinTime => "min_time",
            flexprr_planning::PhiGoal::MaxMargin => "max_margin",
        };
        v["orientation"] = orientation_json(search, objective);
    }
    if let Some(design) = &outcome.shaping {
        // The shaper's own extra time, before any slowing for the deflection limit.
        let shaped = outcome.deflection.as_ref().map_or(plan, |d| &d.fastest);
        v["shaping"] = shaping_json(design, shaped, outcome.unshaped.as_ref());
    }
    if let Some(search) = &outcome.deflection {
        v["deflection_limit"] = deflection_json(search);
    }
    if let Some(flexible) = &outcome.flexible {
        let reduction = match (
            flexible.planned.residual,
            flexible.unshaped.as_ref().and_then(|u| u.residual),
        ) {
            (Some(shaped), Some(unshaped)) if unshaped > 0.0 => Some(shaped / unshaped),
            _ => None,
        };
        v["flexible_check"] = json!({
            "model": flexible.model,
            "settle_time_s": flexible.settle_time,
            "planned": vibration_json(&flexible.planned),
            "unshaped": flexible.unshaped.as_ref().map(vibration_json),
            "shaped_over_unshaped": reduction,
            "scene_motion": match &flexible.original {
                Ok(o) => vibration_json(o),
                Err(why) => json!({ "error": why }),
            },
        });
    }
    v["wall_time_s"] = json!(outcome.wall_time_s);
    v
}

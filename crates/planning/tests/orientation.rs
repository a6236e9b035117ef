//! The platform's orientation as a design variable (docs/planning.md, "The platform's
//! orientation"), checked against the machine's symmetries, brute-force scans, an independent
//! evaluation of the links' axial forces (inverse kinematics, rigid inverse dynamics, the
//! axial-force model along the whole link, Euler's load; none of the planner's path form) and
//! the independent re-check of planned motions at ten times the grid's resolution.

mod common;

use std::time::Instant;

use common::recheck::{Limits, lowest_axial_force, ten_times_finer};
use flexprr_dynamics::{
    AxialForceModel, JointReactionAxialForce, Machine, PaperAxialForce, inverse_dynamics,
};
use flexprr_kinematics::{
    Circle, CirclePath, Orientation, Path, PlannedTrajectory, Pose, SegmentPath, Timing, Trajectory,
};
use flexprr_planning::{
    Boundary, Buckling, ConstantPhi, PhiEnds, PhiObjective, PhiSearch, PlanSpec, Planner, Schedule,
    Settings, SliderForce, SliderSpeed,
};
use nalgebra::Point2;

fn deg(x: f64) -> f64 {
    x.to_radians()
}

fn limits(planner: Planner<'_>) -> Planner<'_> {
    planner
        .constraint(SliderSpeed::new(1.0).unwrap())
        .constraint(SliderForce::new(400.0).unwrap())
}

/// The largest compression of any link anywhere along it (ends and 49 interior points), as a
/// fraction of Euler's load, over `samples + 1` instants of `trajectory` in `span`:
/// independent of the planner.
fn independent_ratio(
    machine: &Machine,
    trajectory: &dyn Trajectory,
    span: (f64, f64),
    samples: usize,
    model: &dyn AxialForceModel,
) -> f64 {
    let euler = flexprr_testkit::paper::euler_load();
    let mut worst = f64::NEG_INFINITY;
    for k in 0..=samples {
        let t = span.0 + (span.1 - span.0) * k as f64 / samples as f64;
        let state = machine
            .geometry
            .inverse_kinematics(&trajectory.motion(t))
            .unwrap();
        let reactions = inverse_dynamics(machine, &state, None, t).unwrap();
        for i in 0..3 {
            let lowest = lowest_axial_force(machine, &state, &reactions, i, model);
            worst = worst.max(-lowest / euler);
        }
    }
    worst
}

/// The paper's circle at 20 Hz with constant orientation `phi`, as the scene runs it.
fn paper_circle_at(phi: f64) -> Circle {
    Circle::new(Point2::new(-0.05, 0.0), 0.05, 20.0, phi, 0.0).unwrap()
}

#[test]
fn the_machine_symmetries_carry_over_to_the_best_orientation() {
    // The machine is invariant under a rotation by 120 deg about its centre (legs relabelled,
    // the platform's orientation unchanged: its joints are 120 deg apart too) and under the
    // mirror x -> -x (phi -> -phi, the circle traversed the other way). The paper's circle and
    // its images must give the same best constant orientation (mirrored: its negative) and
    // the same objective.
    let machine = common::machine();
    let schedule = Schedule::revolution(std::f64::consts::TAU * 0.05, 20.0);
    let rotate = |angle: f64| {
        let (sin, cos) = deg(angle).sin_cos();
        CirclePath::new([-0.05 * cos, -0.05 * sin], 0.05, 0.0, deg(angle), false).unwrap()
    };
    let mirrored = CirclePath::new([0.05, 0.0], 0.05, 0.0, deg(180.0), true).unwrap();
    let paths = [rotate(0.0), rotate(120.0), rotate(240.0), mirrored];
    let margin = PhiSearch::new(
        deg(-180.0),
        deg(180.0),
        PhiObjective::MaxMargin(schedule.clone()),
    )
    .unwrap();
    let mut found = Vec::new();
    for path in &paths {
        let planner = limits(Planner::new(&machine, path, Settings::default()));
        let best = planner.best_constant_phi(&margin).unwrap();
        // Periodic time-optimal motion too (uniform grids: the images' grids coincide).
        let periodic = limits(Planner::new(
            &machine,
            path,
            Settings {
                boundary: Boundary::Periodic,
                ..Settings::default()
            },
        ));
        let mut fastest = margin.clone();
        fastest.objective = PhiObjective::MinTime;
        fastest.min = deg(5.0);
        fastest.max = deg(175.0);
        if path.data().clockwise {
            (fastest.min, fastest.max) = (-fastest.max, -fastest.min);
        }
        let quickest = periodic.best_constant_phi(&fastest).unwrap();
        println!(
            "centre ({:+.5}, {:+.5}) {}: largest margin at phi = {:.4} deg (ratio {:.6}), shortest period at phi = {:.4} deg ({:.7} s)",
            path.data().centre[0],
            path.data().centre[1],
            if path.data().clockwise { "cw" } else { "ccw" },
            best.phi.to_degrees(),
            best.value,
            quickest.phi.to_degrees(),
            quickest.value
        );
        found.push((best, quickest));
    }
    let (reference, reference_time) = &found[0];
    let tolerance = 2.0 * margin.tolerance;
    for (k, (best, quickest)) in found.iter().enumerate() {
        let sign = if k == 3 { -1.0 } else { 1.0 };
        assert!(
            (best.phi - sign * reference.phi).abs() <= tolerance,
            "image {k}: {} vs {}",
            best.phi,
            reference.phi
        );
        assert!((best.value - reference.value).abs() <= 1e-9 * reference.value);
        assert!(
            (quickest.phi - sign * reference_time.phi).abs() <= tolerance,
            "image {k}: {} vs {}",
            quickest.phi,
            reference_time.phi
        );
        assert!((quickest.value - reference_time.value).abs() <= 1e-9 * reference_time.value);
    }
    // A path the machine maps onto itself, the circle about the centre, mirrored onto itself:
    // searches over [-180, 0] and [0, 180] deg give mirror-image optima of equal value.
    let centred = CirclePath::new([0.0, 0.0], 0.04, 0.0, deg(90.0), false).unwrap();
    let planner = Planner::new(&machine, &centred, Settings::default());
    let schedule = Schedule::revolution(centred.length(), 20.0);
    let half = |lo: f64, hi: f64| {
        let search =
            PhiSearch::new(deg(lo), deg(hi), PhiObjective::MaxMargin(schedule.clone())).unwrap();
        planner.best_constant_phi(&search).unwrap()
    };
    let (left, right) = (half(-180.0, 0.0), half(0.0, 180.0));
    println!(
        "centred circle: best phi {:.4} and {:.4} deg, ratios {:.8} and {:.8}",
        left.phi.to_degrees(),
        right.phi.to_degrees(),
        left.value,
        right.value
    );
    assert!((left.phi + right.phi).abs() <= tolerance);
    assert!((left.value - right.value).abs() <= 1e-7 * right.value);
}

#[test]
fn a_brute_force_scan_agrees_with_the_best_constant_orientation() {
    let machine = common::machine();
    // The pick-and-place path at its time-optimal duration (a coarse grid keeps the scan
    // cheap; the search and the scan use the same objective).
    let segment = common::pick_and_place();
    let settings = Settings {
        grid: 250,
        ..Settings::default()
    };
    let planner = limits(Planner::new(&machine, &segment, settings));
    let search = PhiSearch::new(deg(-180.0), deg(180.0), PhiObjective::MinTime).unwrap();
    let started = Instant::now();
    let best = planner.best_constant_phi(&search).unwrap();
    let elapsed = started.elapsed();
    let started = Instant::now();
    let step = 0.1;
    let scan: Vec<(f64, f64)> = (0..=3600)
        .map(|k| {
            let phi = deg(-180.0 + step * k as f64);
            let value = planner
                .phi_objective(&search, &Orientation::constant(phi))
                .unwrap_or(f64::INFINITY);
            (phi, value)
        })
        .collect();
    let brute = scan
        .iter()
        .copied()
        .fold((0.0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
    let at_best = planner
        .phi_objective(&search, &Orientation::constant(best.phi))
        .unwrap();
    println!(
        "pick and place: best constant phi {:.4} deg ({:.7} s searched, {:.7} s checked) in {} evaluations, {elapsed:.2?}; brute force every {step} deg: {:.1} deg ({:.7} s), {:.2?}",
        best.phi.to_degrees(),
        at_best,
        best.value,
        best.evaluations,
        brute.0.to_degrees(),
        brute.1,
        started.elapsed()
    );
    assert!(
        at_best <= brute.1 * (1.0 + 1e-9),
        "{at_best} vs {}",
        brute.1
    );
    assert!(
        (best.phi - brute.0).abs() <= deg(step),
        "{} vs {}",
        best.phi,
        brute.0
    );
    // The checked value is the plan of the segment built at that orientation directly.
    let direct = SegmentPath::new(
        Pose::new(-0.08, -0.03, best.phi),
        Pose::new(-0.02, 0.033, best.phi),
    )
    .unwrap();
    let plan = limits(Planner::new(&machine, &direct, settings))
        .plan()
        .unwrap();
    assert!((plan.duration - best.value).abs() <= 1e-12 * plan.duration);

    // The paper's circle at 20 Hz, largest buckling margin: against the independent axial
    // force of the scene's circle trajectory, every 0.5 deg.
    let circle = common::circle();
    let planner = Planner::new(&machine, &circle, Settings::default());
    let schedule = Schedule::revolution(circle.length(), 20.0);
    let search =
        PhiSearch::new(deg(-180.0), deg(180.0), PhiObjective::MaxMargin(schedule)).unwrap();
    let best = planner.best_constant_phi(&search).unwrap();
    let model = JointReactionAxialForce;
    let brute = (0..=720)
        .filter_map(|k| {
            let phi = deg(-180.0 + 0.5 * k as f64);
            let circle = paper_circle_at(phi);
            // Poses the machine cannot reach are skipped (the search reports them).
            let reachable = (0..=100).all(|j| {
                machine
                    .geometry
                    .inverse_kinematics(&circle.motion(0.05 * j as f64 / 100.0))
                    .is_ok()
            });
            reachable.then(|| {
                (
                    phi,
                    independent_ratio(&machine, &circle, (0.0, 0.05), 400, &model),
                )
            })
        })
        .fold((0.0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
    let independent = independent_ratio(
        &machine,
        &paper_circle_at(best.phi),
        (0.0, 0.05),
        20_000,
        &model,
    );
    println!(
        "paper circle, 20 Hz: best constant phi {:.4} deg, ratio {:.6} (independent {:.6}); brute force every 0.5 deg: {:.1} deg, {:.6}",
        best.phi.to_degrees(),
        best.value,
        independent,
        brute.0.to_degrees(),
        brute.1
    );
    assert!(
        (independent - best.value).abs() <= 1e-5,
        "{independent} vs {}",
        best.value
    );
    assert!(best.value <= brute.1 + 1e-5);
    assert!((best.phi - brute.0).abs() <= deg(0.5));
}

/// Re-checks a min-time result's plan on its oriented path at ten times the grid's
/// resolution (slider speed 1 m/s, force 400 N) and its bounds.
fn recheck_free(
    machine: &Machine,
    base: &dyn Path,
    free: &flexprr_planning::FreePhi,
    search: &PhiSearch,
) {
    let plan = free.plan.as_ref().unwrap();
    assert!(
        plan.check.max_usage <= 1.0 + 1e-9,
        "{:?}",
        plan.check.worst()
    );
    let path = free.orientation.on(base).unwrap();
    let limits = Limits {
        speed: Some(1.0),
        force: Some(400.0),
        ..Limits::default()
    };
    ten_times_finer(machine, plan, &path, &limits);
    assert!(free.range.0 >= search.min - 1e-12 && free.range.1 <= search.max + 1e-12);
}

fn report(what: &str, constant: &ConstantPhi, free: &flexprr_planning::FreePhi, seconds: f64) {
    let original = constant.original.clone().unwrap();
    println!(
        "{what}: original {:.6} s, best constant phi {:.3} deg {:.6} s ({:+.2} %), free ({:.2}..{:.2} deg) {:.6} s ({:+.2} % against the constant, {:+.2} % against the original), {} evaluations, converged {}, {:.2} s",
        original,
        constant.phi.to_degrees(),
        constant.value,
        100.0 * (constant.value / original - 1.0),
        free.range.0.to_degrees(),
        free.range.1.to_degrees(),
        free.value,
        100.0 * (free.value / constant.value - 1.0),
        100.0 * (free.value / original - 1.0),
        free.evaluations,
        free.converged,
        seconds
    );
}

#[test]
fn a_free_orientation_is_never_worse_than_the_best_constant_and_keeps_every_limit() {
    let machine = common::machine();
    // configs/pick_and_place.toml's path under slider_speed = 1 m/s, slider_force = 400 N.
    let segment = common::pick_and_place();
    let planner = limits(Planner::new(&machine, &segment, Settings::default()));
    for ends in [PhiEnds::Free, PhiEnds::Fixed] {
        let mut search = PhiSearch::new(deg(-180.0), deg(180.0), PhiObjective::MinTime).unwrap();
        search.ends = ends;
        let started = Instant::now();
        let constant = planner.best_constant_phi(&search).unwrap();
        let free = planner.free_phi(&search, &constant).unwrap();
        report(
            &format!("pick and place, ends {ends:?}"),
            &constant,
            &free,
            started.elapsed().as_secs_f64(),
        );
        assert!(free.value <= free.start_value);
        assert!(free.value <= constant.original.clone().unwrap());
        if ends == PhiEnds::Free {
            assert!(free.value <= constant.value);
        } else {
            // The path's own end orientations are kept.
            let path = free.orientation.on(&segment).unwrap();
            assert!((path.point(0.0).pose.phi - deg(30.0)).abs() <= 1e-15);
            assert!((path.point(path.length()).pose.phi - deg(30.0)).abs() <= 1e-15);
        }
        recheck_free(&machine, &segment, &free, &search);
    }
    // The paper's circle repeated time-optimally (periodic: a Fourier law), within 20-70 deg.
    let circle = common::circle();
    let periodic = limits(Planner::new(
        &machine,
        &circle,
        Settings {
            boundary: Boundary::Periodic,
            ..Settings::default()
        },
    ));
    let mut search = PhiSearch::new(deg(20.0), deg(70.0), PhiObjective::MinTime).unwrap();
    search.max_evaluations = 300;
    let started = Instant::now();
    let constant = periodic.best_constant_phi(&search).unwrap();
    let free = periodic.free_phi(&search, &constant).unwrap();
    report(
        "circle, periodic (period)",
        &constant,
        &free,
        started.elapsed().as_secs_f64(),
    );
    assert!(free.value <= constant.value);
    assert!(free.orientation.on(&circle).unwrap().is_closed());
    recheck_free(&machine, &circle, &free, &search);
}

#[test]
fn the_paper_circle_at_20_hz_compresses_every_link_at_every_constant_orientation() {
    // The paper's 20 Hz circle at 45 deg compresses link 1 to 43 % of its Euler load. The
    // orientation that minimises the largest compression, for both axial-force models, and a
    // buckling margin that 45 deg breaks and the best constant keeps.
    let machine = common::machine();
    let circle = common::circle();
    let schedule = Schedule::revolution(circle.length(), 20.0);
    let joint = JointReactionAxialForce;
    let paper = PaperAxialForce;
    for (name, model) in [
        ("joint-reaction", &joint as &dyn AxialForceModel),
        ("paper (eq. 12)", &paper),
    ] {
        let planner = Planner::new(&machine, &circle, Settings::default()).axial_model(model);
        let mut search = PhiSearch::new(
            deg(-180.0),
            deg(180.0),
            PhiObjective::MaxMargin(schedule.clone()),
        )
        .unwrap();
        search.max_evaluations = 400;
        let started = Instant::now();
        let at45 = planner.compression(&schedule, 1000).unwrap();
        let constant = planner.best_constant_phi(&search).unwrap();
        let constant_time = started.elapsed();
        let free = planner.free_phi(&search, &constant).unwrap();
        let c = constant.compression.as_ref().unwrap();
        let feasible: Vec<f64> = constant
            .scan
            .iter()
            .filter_map(|p| p.value.clone().ok())
            .collect();
        let least = feasible.iter().copied().fold(f64::INFINITY, f64::min);
        println!(
            "{name}: 45 deg: link {} at {} compressed to {:.4} of its critical load; best constant phi {:.3} deg: {:.4} (links {:.4} {:.4} {:.4}), {} of {} scanned orientations reachable, least compression {:.4}; free ({:.1}..{:.1} deg): {:.4}; {:.2?} and {:.2?}",
            at45.link + 1,
            at45.end,
            at45.ratio,
            constant.phi.to_degrees(),
            constant.value,
            c.links[0],
            c.links[1],
            c.links[2],
            feasible.len(),
            constant.scan.len(),
            least,
            free.range.0.to_degrees(),
            free.range.1.to_degrees(),
            free.value,
            constant_time,
            started.elapsed() - constant_time
        );
        // Independent: the scene's circle at both orientations.
        let independent = |phi: f64| {
            independent_ratio(&machine, &paper_circle_at(phi), (0.0, 0.05), 20_000, model)
        };
        assert!((independent(deg(45.0)) - at45.ratio).abs() <= 1e-5);
        assert!((independent(constant.phi) - constant.value).abs() <= 1e-5);
        // No constant orientation keeps every link in tension on this circle.
        assert!(least > 0.0 && !c.in_tension(0.0));
        assert!(constant.value < at45.ratio && free.value <= constant.value);
        // The free orientation, run as a trajectory at the circle's speed.
        let oriented = free.orientation.on(&circle).unwrap();
        let speed = circle.length() * 20.0;
        let timing = Timing::new(vec![0.0, circle.length()], vec![speed, speed], true).unwrap();
        let trajectory = PlannedTrajectory::new(&oriented, timing, 0.0).unwrap();
        let run = independent_ratio(&machine, &trajectory, (0.0, 0.05), 20_000, model);
        assert!((run - free.value).abs() <= 1e-5, "{run} vs {}", free.value);
        // A buckling margin between the two: broken at 45 deg, kept at the best constant.
        let margin = 0.5 * (constant.value + at45.ratio);
        let check = |path: &CirclePath| {
            Planner::new(&machine, path, Settings::default())
                .axial_model(model)
                .constraint(Buckling::new(&machine, margin).unwrap())
                .check_timing(
                    &[],
                    (0.0, 0.05),
                    10_000,
                    |t| schedule.state(circle.length(), t),
                    None,
                )
                .unwrap()
                .max_usage
        };
        let best_path = CirclePath::new([-0.05, 0.0], 0.05, constant.phi, 0.0, false).unwrap();
        assert!(check(&circle) > 1.0 && check(&best_path) < 1.0);
    }
}

#[test]
fn orientation_keys_are_checked() {
    for (text, key) in [
        ("slider_speed = 1.0\nphi_min_deg = 10.0", "plan.phi_min_deg"),
        (
            "slider_speed = 1.0\nphi = \"free\"\nphi_min_deg = 10.0\nphi_max_deg = 5.0",
            "plan.phi_max_deg",
        ),
        (
            "slider_speed = 1.0\nphi = \"free\"\nphi_min_deg = -200.0\nphi_max_deg = 200.0",
            "plan.phi_max_deg",
        ),
        (
            "slider_speed = 1.0\nphi = \"best_constant\"\nphi_ends = \"fixed\"",
            "plan.phi_ends",
        ),
        (
            "slider_speed = 1.0\nphi = \"free\"\nphi_ends = \"fixed\"\nboundary = \"periodic\"",
            "plan.phi_ends",
        ),
        (
            "slider_speed = 1.0\nphi = \"free\"\nphi_spline_points = 3",
            "plan.phi_spline_points",
        ),
        (
            "slider_speed = 1.0\nphi = \"free\"\nphi_harmonics = 0",
            "plan.phi_harmonics",
        ),
        (
            "slider_speed = 1.0\nphi = \"free\"\nphi_scan_step_deg = 0.0",
            "plan.phi_scan_step_deg",
        ),
        (
            "slider_speed = 1.0\nphi_objective = \"max_margin\"",
            "plan.phi_objective",
        ),
    ] {
        let spec: PlanSpec = toml::from_str(text).unwrap();
        let error = spec.validate().unwrap_err();
        assert!(error.to_string().starts_with(key), "{text}: {error}");
    }
    let bad = toml::from_str::<PlanSpec>("phi = \"constant\"").unwrap_err();
    assert!(bad.to_string().contains("constant"), "{bad}");
    // One key per line, as a scene would write it.
    let spec: PlanSpec = toml::from_str(
        "slider_speed = 1.0\nslider_force = 400.0\nphi = \"free\"\nphi_min_deg = -30.0\nphi_max_deg = 60.0\nphi_objective = \"max_margin\"\nphi_ends = \"fixed\"",
    )
    .unwrap();
    let error = spec.phi_search(None).unwrap_err();
    assert!(
        error.to_string().starts_with("plan.phi_objective"),
        "{error}"
    );
    let schedule = Schedule::revolution(0.3, 20.0);
    let search = spec.phi_search(Some(schedule.clone())).unwrap().unwrap();
    assert!((search.min - deg(-30.0)).abs() <= 1e-15 && (search.max - deg(60.0)).abs() <= 1e-15);
    assert_eq!(search.objective, PhiObjective::MaxMargin(schedule));
    assert_eq!(search.ends, PhiEnds::Fixed);
    assert!(PlanSpec::default().phi_search(None).unwrap().is_none());
}

#[test]
fn an_orientation_search_says_why_nothing_is_feasible() {
    let machine = common::machine();
    let segment = common::pick_and_place();
    let planner = limits(Planner::new(&machine, &segment, Settings::default()));
    // phi = 0 is a type-II singular orientation of this machine everywhere near the path.
    let search = PhiSearch::new(deg(-0.1), deg(0.1), PhiObjective::MinTime).unwrap();
    let error = planner.best_constant_phi(&search).unwrap_err();
    let text = error.to_string();
    assert!(
        text.starts_with("no constant orientation in [-0.100, 0.100] deg"),
        "{text}"
    );
    assert!(text.contains("type-II"), "{text}");
    // A free law that leaves the bounds is refused by name.
    let search = PhiSearch::new(deg(25.0), deg(35.0), PhiObjective::MinTime).unwrap();
    let wide = Orientation {
        relative: true,
        law: flexprr_kinematics::PhiLaw::Spline(
            flexprr_kinematics::PhiSpline::new(vec![0.0, 0.3, 0.3, 0.0]).unwrap(),
        ),
    };
    let error = planner.phi_objective(&search, &wide).unwrap_err();
    assert!(error.to_string().contains("phi_max_deg"), "{error}");
}

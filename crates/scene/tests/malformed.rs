//! Malformed scenes: every error must name the key, point at `file:line:column` and say what
//! was expected, and it must come before anything is integrated.
//!
//! Each case edits one line of a small valid scene. The expected location is found by a plain
//! text search for the offending key in the edited scene (independent of the crate's own
//! locator); the expected key path and the words describing the expectation are written by
//! hand from the scene reference (`docs/scenes.md`).

use flexprr_scene::{ScenarioError, Scene};

const FILE: &str = "scene.toml";

/// A valid, quick scene (frequencies only) that the cases below break one line at a time.
const BASE: &str = r#"name = "base"

[machine]
layout = "radial"
alpha_deg = [150.0, 270.0, 30.0]
platform_side = 0.1
half_travel = 0.2
platform_mass = 0.2
slider_mass = 0.5

[links]
length = 0.2
modes = 3
material = { youngs_modulus = 7.3e10, density = 2770.0 }
section = { kind = "uniform", thickness = 0.002, height = 0.03 }
basis = { kind = "sine" }

[trajectory]
kind = "circle"
centre = [-0.05, 0.0]
radius = 0.05
frequency = 2.0
phi_deg = 45.0

[model]
formulation = "consistent"
damping = [0.01]

[integrator]
method = "abm"
rtol = 1e-8
atol = 1e-12
max_steps = 100000

[time]
start = 0.0
end = 0.1
output_step = 0.01

[output]
requests = ["frequencies"]
deflection_xi = [0.5]
plots = false
"#;

/// `BASE` with the line `old` (exactly one occurrence) replaced by `new`.
fn edit(old: &str, new: &str) -> String {
    assert_eq!(
        BASE.matches(old).count(),
        1,
        "the base scene must contain `{old}` exactly once"
    );
    BASE.replacen(old, new, 1)
}

/// 1-based line and column of the first occurrence of `needle` in `text` (byte columns; the
/// scenes are ASCII).
fn position_of(text: &str, needle: &str) -> (usize, usize) {
    let offset = text
        .find(needle)
        .unwrap_or_else(|| panic!("`{needle}` not in the scene:\n{text}"));
    let line = text[..offset].matches('\n').count() + 1;
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    (line, offset - line_start + 1)
}

/// Loads `text`, expects bad input, and checks the message: `scene.toml:line:col` where
/// `at` first occurs, the dotted `key`, and every phrase of `expected`.
#[track_caller]
fn rejects(text: &str, at: &str, key: &str, expected: &[&str]) {
    let err = match Scene::from_text(FILE, "scene", text) {
        Ok(_) => panic!("accepted a malformed scene:\n{text}"),
        Err(e) => e,
    };
    assert!(err.is_input(), "not reported as bad input: {err}");
    let ScenarioError::Input {
        location,
        key: reported_key,
        ..
    } = &err
    else {
        unreachable!("is_input checked above")
    };
    let message = err.to_string();
    let (line, column) = position_of(text, at);
    let place = format!("{FILE}:{line}:{column}");
    assert!(
        message.starts_with(&format!("{place}: ")),
        "expected the message to start at {place}: {message}"
    );
    let loc = location.as_ref().expect("a location");
    assert_eq!((loc.line, loc.column), (line, column), "{message}");
    assert_eq!(reported_key, key, "{message}");
    assert!(message.contains(key), "key `{key}` not named in: {message}");
    for phrase in expected {
        assert!(
            message.contains(phrase),
            "`{phrase}` missing from: {message}"
        );
    }
    assert!(
        !message.contains('\n'),
        "the message must be one line: {message}"
    );
}

#[test]
fn the_base_scene_is_valid() {
    let scene = Scene::from_text(FILE, "scene", BASE).expect("the base scene is valid");
    assert_eq!(scene.name, "base");
    assert_eq!(scene.output_times.len(), 11);
    assert!(!scene.needs_integration());
}

// ---------------------------------------------------------------------------------------
// Syntax

#[test]
fn syntax_error_unterminated_table_header() {
    let text = edit("[integrator]\n", "[integrator\n");
    rejects(
        &text,
        "\nmethod",
        "integrator",
        &["unclosed table", "expected `]`"],
    );
}

#[test]
fn syntax_error_unclosed_array_names_its_own_key() {
    // The parser only notices on the next line; the array's key is the one to blame.
    let text = edit(
        "alpha_deg = [150.0, 270.0, 30.0]\n",
        "alpha_deg = [150.0, 270.0, 30.0\n",
    );
    rejects(
        &text,
        "[150.0",
        "machine.alpha_deg",
        &["opened on line 5", "not closed"],
    );
    // Also at the end of a table, before the next header.
    let text = edit("deflection_xi = [0.5]\n", "deflection_xi = [0.5\n");
    rejects(&text, "[0.5", "output.deflection_xi", &["not closed"]);
}

#[test]
fn syntax_error_in_a_closed_array_stays_on_its_line() {
    let text = edit("centre = [-0.05, 0.0]\n", "centre = [-0.05 0.0]\n");
    let err = Scene::from_text(FILE, "scene", &text).expect_err("a missing comma");
    let ScenarioError::Input { key, .. } = &err else {
        panic!("not bad input: {err}")
    };
    assert_eq!(key, "trajectory.centre", "{err}");
    assert!(!err.to_string().contains("not closed"), "{err}");
}

#[test]
fn the_sine_basis_refuses_keys_of_other_bases() {
    let text = edit(
        "basis = { kind = \"sine\" }\n",
        "basis = { kind = \"sine\", ends = \"clamped-free\" }\n",
    );
    rejects(
        &text,
        "ends =",
        "links.basis.ends",
        &["unknown field `ends`", "no keys besides its kind"],
    );
}

#[test]
fn syntax_error_missing_value() {
    let text = edit("half_travel = 0.2\n", "half_travel = \n");
    rejects(
        &text,
        "\nplatform_mass",
        "machine.half_travel",
        &["expected a value after `=`"],
    );
}

// ---------------------------------------------------------------------------------------
// Unknown keys

#[test]
fn unknown_top_level_key() {
    let text = edit("name = \"base\"\n", "name = \"base\"\ntitle = \"oops\"\n");
    rejects(
        &text,
        "title",
        "title",
        &["unknown field `title`", "expected one of", "`name`"],
    );
}

#[test]
fn unknown_key_in_the_machine_table() {
    let text = edit("slider_mass = 0.5\n", "slider_mas = 0.5\n");
    rejects(
        &text,
        "slider_mas",
        "machine.slider_mas",
        &["unknown field `slider_mas`", "`slider_mass`"],
    );
}

#[test]
fn unknown_key_in_an_inline_section_table() {
    let text = edit("height = 0.03 }", "height = 0.03, width = 0.01 }");
    rejects(
        &text,
        "width",
        "links.section.width",
        &["unknown field `width`", "`thickness`", "`height`"],
    );
}

#[test]
fn unknown_key_in_the_trajectory_table() {
    let text = edit("radius = 0.05\n", "radius = 0.05\nspeed = 1.0\n");
    rejects(
        &text,
        "speed",
        "trajectory.speed",
        &["unknown field `speed`", "`radius`", "`frequency`"],
    );
}

// ---------------------------------------------------------------------------------------
// Wrong types

#[test]
fn string_where_a_number_is_expected() {
    let text = edit("end = 0.1\n", "end = \"0.1\"\n");
    rejects(&text, "\"0.1\"", "time.end", &["string", "expected f64"]);
}

#[test]
fn number_where_a_list_is_expected() {
    let text = edit("deflection_xi = [0.5]\n", "deflection_xi = 0.5\n");
    rejects(
        &text,
        "0.5\nplots",
        "output.deflection_xi",
        &["floating point", "expected a sequence"],
    );
}

#[test]
fn negative_integer_for_a_count() {
    let text = edit("max_steps = 100000\n", "max_steps = -5\n");
    rejects(
        &text,
        "-5",
        "integrator.max_steps",
        &["-5", "expected usize"],
    );
}

// ---------------------------------------------------------------------------------------
// Missing tables and keys

#[test]
fn missing_time_table() {
    let text = edit("[time]\nstart = 0.0\nend = 0.1\noutput_step = 0.01\n", "");
    rejects(&text, "name", "time", &["missing field `time`"]);
}

#[test]
fn missing_circle_frequency() {
    let text = edit("frequency = 2.0\n", "");
    rejects(
        &text,
        "[trajectory]",
        "trajectory.frequency",
        &["missing field `frequency`"],
    );
}

// ---------------------------------------------------------------------------------------
// Values out of range

#[test]
fn negative_platform_mass() {
    let text = edit("platform_mass = 0.2\n", "platform_mass = -0.2\n");
    rejects(
        &text,
        "platform_mass",
        "machine.platform_mass",
        &["expected a non-negative number (kg)", "got -0.2"],
    );
}

#[test]
fn zero_modes() {
    let text = edit("modes = 3\n", "modes = 0\n");
    rejects(
        &text,
        "modes",
        "links.modes",
        &["expected at least 1 mode", "got 0"],
    );
}

#[test]
fn zero_rtol() {
    let text = edit("rtol = 1e-8\n", "rtol = 0.0\n");
    rejects(
        &text,
        "rtol",
        "integrator.rtol",
        &["expected a positive relative tolerance below 1", "got 0"],
    );
}

#[test]
fn negative_rtol() {
    let text = edit("rtol = 1e-8\n", "rtol = -1e-6\n");
    rejects(
        &text,
        "rtol",
        "integrator.rtol",
        &[
            "expected a positive relative tolerance below 1",
            "got -1e-6",
        ],
    );
}

#[test]
fn negative_atol() {
    let text = edit("atol = 1e-12\n", "atol = -1e-12\n");
    rejects(
        &text,
        "atol",
        "integrator.atol",
        &["expected a non-negative number", "got -1e-12"],
    );
}

#[test]
fn end_time_not_after_start() {
    let text = edit("end = 0.1\n", "end = 0.0\n");
    rejects(
        &text,
        "end = 0.0",
        "time.end",
        &["must be after time.start = 0 s", "got 0 s"],
    );
}

#[test]
fn negative_output_step() {
    let text = edit("output_step = 0.01\n", "output_step = -0.01\n");
    rejects(
        &text,
        "output_step",
        "time.output_step",
        &["expected a positive number (s)", "got -0.01"],
    );
}

#[test]
fn negative_thickness() {
    let text = edit("thickness = 0.002", "thickness = -0.002");
    rejects(
        &text,
        "thickness",
        "links.section.thickness",
        &["expected a positive number (m)", "got -0.002"],
    );
}

#[test]
fn zero_link_length() {
    let text = edit("length = 0.2\n", "length = 0.0\n");
    rejects(
        &text,
        "length",
        "links.length",
        &["expected a positive number (m)", "got 0"],
    );
}

#[test]
fn deflection_position_outside_the_link() {
    let text = edit("deflection_xi = [0.5]\n", "deflection_xi = [0.5, 1.5]\n");
    rejects(
        &text,
        "1.5",
        "output.deflection_xi.1",
        &["expected a position xi in [0, 1]", "got 1.5"],
    );
}

#[test]
fn damping_list_of_the_wrong_length() {
    let text = edit("damping = [0.01]\n", "damping = [0.01, 0.02]\n");
    rejects(
        &text,
        "damping",
        "model.damping",
        &["one ratio for all modes or one per mode (3)", "got 2"],
    );
}

#[test]
fn negative_damping_ratio() {
    let text = edit("damping = [0.01]\n", "damping = [0.01, -0.02, 0.01]\n");
    rejects(
        &text,
        "-0.02",
        "model.damping.1",
        &["expected a non-negative number", "got -0.02"],
    );
}

#[test]
fn zero_max_steps() {
    let text = edit("max_steps = 100000\n", "max_steps = 0\n");
    rejects(
        &text,
        "max_steps",
        "integrator.max_steps",
        &["expected at least 1"],
    );
}

// ---------------------------------------------------------------------------------------
// Unknown choices

#[test]
fn unknown_formulation() {
    let text = edit(
        "formulation = \"consistent\"\n",
        "formulation = \"exact\"\n",
    );
    rejects(
        &text,
        "\"exact\"",
        "model.formulation",
        &["unknown variant `exact`", "`paper`", "`consistent`"],
    );
}

#[test]
fn unknown_output_request() {
    let text = edit(
        "requests = [\"frequencies\"]\n",
        "requests = [\"frequencies\", \"stresses\"]\n",
    );
    rejects(
        &text,
        "\"stresses\"",
        "output.requests.1",
        &["unknown variant `stresses`", "deflections", "frequencies"],
    );
}

#[test]
fn unknown_integrator_method() {
    let text = edit("method = \"abm\"\n", "method = \"ode45\"\n");
    rejects(
        &text,
        "\"ode45\"",
        "integrator.method",
        &[
            "unknown value \"ode45\"",
            "\"abm\", \"auto\", \"bdf\", \"generalized_alpha\", \"magnus4\", \"magnus6\", \"rk45\"",
        ],
    );
}

#[test]
fn unknown_basis_kind() {
    let text = edit(
        "basis = { kind = \"sine\" }",
        "basis = { kind = \"legendre\" }",
    );
    rejects(
        &text,
        "\"legendre\"",
        "links.basis.kind",
        &[
            "unknown basis kind \"legendre\"",
            "\"sine\"",
            "\"classical\"",
            "\"hermite\"",
        ],
    );
}

#[test]
fn unknown_end_conditions() {
    let text = edit(
        "basis = { kind = \"sine\" }",
        "basis = { kind = \"classical\", ends = \"clamped-sliding\" }",
    );
    rejects(
        &text,
        "\"clamped-sliding\"",
        "links.basis.ends",
        &["unknown variant `clamped-sliding`", "`clamped-free`"],
    );
}

#[test]
fn unknown_layout() {
    let text = edit("layout = \"radial\"\n", "layout = \"star\"\n");
    rejects(
        &text,
        "\"star\"",
        "machine.layout",
        &["unknown variant `star`", "`radial` or `general`"],
    );
}

#[test]
fn unknown_point_to_point_profile() {
    let text = edit(
        "kind = \"circle\"\ncentre = [-0.05, 0.0]\nradius = 0.05\nfrequency = 2.0\nphi_deg = 45.0\n",
        "kind = \"point-to-point\"\nfrom = [-0.02, 0.0, 10.0]\nto = [0.02, 0.01, 10.0]\n\
         duration = 0.05\nprofile = \"trapezoidal\"\n",
    );
    rejects(
        &text,
        "\"trapezoidal\"",
        "trajectory.profile",
        &["unknown variant `trapezoidal`", "`quintic`", "`cycloidal`"],
    );
}

// ---------------------------------------------------------------------------------------
// Bases and layouts

#[test]
fn hermite_basis_with_modes() {
    let text = edit(
        "basis = { kind = \"sine\" }",
        "basis = { kind = \"hermite\", elements = 8 }",
    );
    rejects(
        &text,
        "modes",
        "links.modes",
        &[
            "hermite basis takes its size from its own keys",
            "remove modes",
        ],
    );
}

#[test]
fn too_many_modes() {
    let text = edit("modes = 3\n", "modes = 61\n");
    rejects(&text, "modes", "links.modes", &["61 modes", "supported 60"]);
}

#[test]
fn general_layout_with_two_legs() {
    let legs = "layout = \"general\"\n\
        legs = [\n\
          { anchor = [0.0, -0.3], direction_deg = 0.0, travel = [-0.2, 0.2], attachment = [0.0, -0.05] },\n\
          { anchor = [0.3, 0.0], direction_deg = 90.0, travel = [-0.2, 0.2], attachment = [0.05, 0.0] },\n\
        ]\n";
    let text = edit("layout = \"radial\"\n", legs)
        .replace("alpha_deg = [150.0, 270.0, 30.0]\n", "")
        .replace("platform_side = 0.1\n", "")
        .replace("half_travel = 0.2\n", "");
    rejects(
        &text,
        "legs",
        "machine.legs",
        &["expected 3 [[machine.legs]] tables", "got 2"],
    );
}

// ---------------------------------------------------------------------------------------
// Trajectories outside the usable workspace (caught before integrating)

#[test]
fn circle_too_large_to_reach() {
    let text = edit("radius = 0.05\n", "radius = 0.5\n");
    rejects(
        &text,
        "trajectory]",
        "trajectory",
        &[
            "leaves the usable workspace",
            "expected every pose from 0 s to 0.1 s",
            "unreachable",
        ],
    );
}

#[test]
fn circle_shifted_beyond_the_slider_travel() {
    let text = edit("centre = [-0.05, 0.0]\n", "centre = [-0.1, 0.18]\n");
    rejects(
        &text,
        "trajectory]",
        "trajectory",
        &[
            "leaves the usable workspace",
            "expected every pose from 0 s to 0.1 s",
            "outside travel",
        ],
    );
}

#[test]
fn point_to_point_into_the_singular_home_pose() {
    let text = edit(
        "kind = \"circle\"\ncentre = [-0.05, 0.0]\nradius = 0.05\nfrequency = 2.0\nphi_deg = 45.0\n",
        "kind = \"point-to-point\"\nfrom = [-0.05, 0.02, 30.0]\nto = [0.0, 0.0, 0.0]\n\
         duration = 0.05\n",
    );
    rejects(
        &text,
        "trajectory]",
        "trajectory",
        &[
            "leaves the usable workspace",
            "expected every pose from 0 s to 0.1 s",
            "singularity",
        ],
    );
}

#[test]
fn waypoints_with_decreasing_times() {
    let text = edit(
        "kind = \"circle\"\ncentre = [-0.05, 0.0]\nradius = 0.05\nfrequency = 2.0\nphi_deg = 45.0\n",
        "kind = \"waypoints\"\npoints = [[0.0, -0.05, 0.0, 30.0], [0.08, -0.04, 0.01, 30.0], \
         [0.05, -0.03, 0.0, 30.0]]\n",
    );
    rejects(
        &text,
        "points =",
        "trajectory.points",
        &["times must increase"],
    );
}

#[test]
fn zero_duration_move() {
    let text = edit(
        "kind = \"circle\"\ncentre = [-0.05, 0.0]\nradius = 0.05\nfrequency = 2.0\nphi_deg = 45.0\n",
        "kind = \"point-to-point\"\nfrom = [-0.02, 0.0, 10.0]\nto = [0.02, 0.01, 10.0]\n\
         duration = 0.0\n",
    );
    rejects(
        &text,
        "duration",
        "trajectory.duration",
        &["expected a positive number (s)", "got 0"],
    );
}

#[test]
fn unknown_key_in_a_leg_of_a_general_layout() {
    let legs = "layout = \"general\"\n\
        [[machine.legs]]\n\
        anchor = [0.2232, -0.1289]\n\
        direction_deg = 150.0\n\
        travel = [-0.2, 0.2]\n\
        attachment = [0.05, -0.0289]\n\
        stiffness = 1e6\n";
    let text = edit(
        "[machine]\nlayout = \"radial\"\nalpha_deg = [150.0, 270.0, 30.0]\nplatform_side = 0.1\n\
         half_travel = 0.2\nplatform_mass = 0.2\nslider_mass = 0.5\n",
        &format!("[machine]\n{legs}"),
    );
    rejects(
        &text,
        "stiffness",
        "machine.legs.0.stiffness",
        &["unknown field `stiffness`", "`anchor`", "`branch`"],
    );
}

#[test]
fn boolean_where_a_number_is_expected() {
    let text = edit("frequency = 2.0\n", "frequency = true\n");
    rejects(
        &text,
        "frequency",
        "trajectory.frequency",
        &["invalid type: boolean `true`", "expected f64"],
    );
}

#[test]
fn stepped_section_not_reaching_the_platform_end() {
    let text = edit(
        "section = { kind = \"uniform\", thickness = 0.002, height = 0.03 }",
        "section = { kind = \"stepped\", steps = [{ end = 0.5, thickness = 0.002, height = 0.03 }, \
         { end = 0.9, thickness = 0.003, height = 0.03 }] }",
    );
    rejects(
        &text,
        "steps",
        "links.section.steps",
        &["end = 0.9", "must be 1"],
    );
}

#[test]
fn string_for_a_number_inside_an_inline_section_table() {
    let text = edit("height = 0.03 }", "height = \"0.03\" }");
    rejects(
        &text,
        "height",
        "links.section.height",
        &["invalid type: string \"0.03\"", "expected f64"],
    );
}

#[test]
fn spectral_radius_of_a_method_without_one() {
    let text = edit(
        "max_steps = 100000\n",
        "max_steps = 100000\nspectral_radius = 0.5\n",
    );
    rejects(
        &text,
        "spectral_radius",
        "integrator.spectral_radius",
        &["generalized_alpha", "integrated by abm"],
    );
}

/// The nonlinear model under generalized-alpha takes the key in `[0, 1]` into its options.
#[test]
fn spectral_radius_of_generalized_alpha() {
    let nonlinear = |rho: &str| {
        edit("method = \"abm\"\n", "method = \"generalized_alpha\"\n")
            .replace(
                "damping = [0.01]\n",
                "coupling = \"nonlinear\"\nelements = 4\n",
            )
            .replace(
                "max_steps = 100000\n",
                &format!("max_steps = 100000\nspectral_radius = {rho}\n"),
            )
    };
    rejects(
        &nonlinear("1.5"),
        "spectral_radius",
        "integrator.spectral_radius",
        &["from 0", "to 1", "got 1.5"],
    );
    let scene = Scene::from_text(FILE, "scene", &nonlinear("0.25")).unwrap();
    assert_eq!(scene.options.spectral_radius, Some(0.25));
    // `auto` picks generalized-alpha for this model, so the key is its.
    let auto = nonlinear("0.25").replace("method = \"generalized_alpha\"\n", "method = \"auto\"\n");
    let scene = Scene::from_text(FILE, "scene", &auto).unwrap();
    assert_eq!(scene.method.name(), "generalized_alpha");
    assert_eq!(scene.options.spectral_radius, Some(0.25));
}

//! Study files: every bad value is reported with `file:line:column` and its dotted key, where
//! line and column are those of the offending text in the file (found here independently,
//! by searching the text); input files must be regular files of bounded size; a study is
//! told apart from a scene.

use std::path::{Path, PathBuf};

use flexprr_studies::study::{MAX_INPUT_BYTES, Study, StudyError};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

const HEAD: &str = "base = \"paper_f20.toml\"\n";

/// The error of a study made of `HEAD` and `body`.
fn error(body: &str) -> StudyError {
    Study::from_text("bad.toml", "bad", &format!("{HEAD}{body}"), &configs()).unwrap_err()
}

/// `bad.toml:<line>:<column>` of the `occurrence`-th (0-based) match of `needle` in the
/// study text.
fn at(body: &str, needle: &str, occurrence: usize) -> String {
    let text = format!("{HEAD}{body}");
    let offset = text
        .match_indices(needle)
        .nth(occurrence)
        .unwrap_or_else(|| panic!("{needle} not in the text"))
        .0;
    let line = text[..offset].matches('\n').count() + 1;
    let column = offset - text[..offset].rfind('\n').map_or(0, |i| i + 1) + 1;
    format!("bad.toml:{line}:{column}: ")
}

/// Asserts that the error is located at `location`, names `key` and says `what`.
fn assert_located(e: &StudyError, location: &str, key: &str, what: &str) {
    let message = e.to_string();
    assert!(
        matches!(e, StudyError::Input { .. }),
        "not an input error: {message}"
    );
    assert!(e.is_input());
    assert!(
        message.starts_with(&format!("{location}{key}: ")),
        "expected {location}{key}: ..., got {message}"
    );
    assert!(message.contains(what), "{message}");
    assert!(!message.contains('\n'), "{message}");
}

#[test]
fn a_bad_choice_is_located_by_the_parser() {
    let body = "combine = \"diagonal\"\n";
    assert_located(
        &error(body),
        &at(body, "\"diagonal\"", 0),
        "combine",
        "unknown variant `diagonal`",
    );
    let body = "[[axis]]\nkey = \"trajectory.frequency\"\nrange = { start = 1.0, end = 2.0, count = 3, spacing = \"cubic\" }\n";
    assert_located(
        &error(body),
        &at(body, "\"cubic\"", 0),
        "axis.0.range.spacing",
        "unknown variant `cubic`",
    );
    let body = "quantities = [{ kind = \"peak_speed\", link = 1 }]\n";
    let e = error(body);
    assert!(e.to_string().contains("peak_speed"), "{e}");
    assert!(e.to_string().starts_with("bad.toml:2:"), "{e}");
}

#[test]
fn an_unknown_field_is_located_with_its_key() {
    let body = "[[axis]]\nkey = \"trajectory.frequency\"\nvalues = [1.0]\n[[axis]]\nkey = \"machine.platform_mass\"\nvalue = [1.0]\n";
    assert_located(
        &error(body),
        &at(body, "value ", 0),
        "axis.1.value",
        "unknown field `value`",
    );
}

#[test]
fn checks_after_parsing_are_located_at_their_key() {
    let body = "quantities = [{ kind = \"buckling\", link = 4 }]\n";
    assert_located(
        &error(body),
        &at(body, "link", 0),
        "quantities.0.link",
        "link must be 1, 2 or 3, got 4",
    );
    let body = "quantities = [{ kind = \"frequency_range\", link = 1, mode = 0 }]\n";
    assert_located(
        &error(body),
        &at(body, "mode", 0),
        "quantities.0.mode",
        "numbered from 1",
    );
    let body =
        "[[axis]]\nkey = \"trajectory.frequency\"\nrange = { start = 1.0, end = 2.0, count = 0 }\n";
    assert_located(
        &error(body),
        &at(body, "count", 0),
        "axis.0.range.count",
        "at least 1",
    );
    let body = "[[axis]]\nkey = \"trajectory.frequency\"\nrange = { start = 0.0, end = 2.0, count = 3, spacing = \"log\" }\n";
    assert_located(
        &error(body),
        &at(body, "range", 0),
        "axis.0.range",
        "positive start and end",
    );
    let body = "[[axis]]\nkey = \"trajectory.frequency\"\nvalues = [1.0]\n[[axis]]\nkey = \"trajectory.frequency\"\nvalues = [2.0]\n";
    assert_located(
        &error(body),
        &at(body, "key", 1),
        "axis.1.key",
        "appears twice",
    );
    let body = "[[axis]]\nkey = \"trajectory.frequency.hz\"\nvalues = [1.0]\n";
    assert_located(
        &error(body),
        &at(body, "key", 0),
        "axis.0.key",
        "is not inside a table or an array",
    );
    let body = "[[axis]]\nkey = \"trajectory.frequency\"\nvalues = []\n";
    assert_located(
        &error(body),
        &at(body, "values", 0),
        "axis.0.values",
        "has no values",
    );
}

#[test]
fn plot_keys_and_columns_are_checked_and_located() {
    let axis = "quantities = [{ kind = \"buckling\", link = 1 }]\n[[axis]]\nkey = \"trajectory.frequency\"\nvalues = [1.0]\n";
    let body = format!(
        "{axis}[[plot]]\nfile = \"p.svg\"\nx = \"machine.platform_mass\"\ny = [\"buckles_1\"]\n"
    );
    assert_located(
        &error(&body),
        &at(&body, "x = ", 0),
        "plot.0.x",
        "\"machine.platform_mass\" is not an axis key (axes: trajectory.frequency)",
    );
    let body = format!(
        "{axis}[[plot]]\nfile = \"p.svg\"\nx = \"trajectory.frequency\"\ny = [\"buckles_1\", \"P_max_1_N\"]\n"
    );
    assert_located(
        &error(&body),
        &at(&body, "\"P_max_1_N\"", 0),
        "plot.0.y.1",
        "not a quantity column (columns: buckles_1, buckling_start_1_s)",
    );
}

#[test]
fn base_and_inline_scene_are_exclusive_and_one_is_required() {
    let both = Study::from_text(
        "bad.toml",
        "bad",
        "base = \"paper_f20.toml\"\n[scene]\nname = \"x\"\n",
        &configs(),
    )
    .unwrap_err();
    assert_located(&both, "bad.toml:1:1: ", "base", "not both");
    let none = Study::from_text("bad.toml", "bad", "name = \"x\"\n", &configs()).unwrap_err();
    let message = none.to_string();
    assert!(message.starts_with("bad.toml: base: missing"), "{message}");
}

#[test]
fn a_broken_base_scene_is_located_in_the_scene_file() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("scene.toml"), "[links]\nlength = = 0.2\n").unwrap();
    let e = Study::from_text("s.toml", "s", "base = \"scene.toml\"\n", tmp.path()).unwrap_err();
    assert!(matches!(e, StudyError::Scene(_)), "{e}");
    let message = e.to_string();
    let scene = tmp.path().join("scene.toml").display().to_string();
    assert!(
        message.starts_with(&format!("base scene: {scene}:2:")),
        "{message}"
    );
}

#[test]
fn input_files_must_be_regular_and_small() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = Study::load(tmp.path()).unwrap_err();
    assert!(matches!(dir, StudyError::InputFile { .. }), "{dir}");
    assert!(dir.to_string().contains("is a directory"), "{dir}");
    assert!(dir.is_input());

    #[cfg(unix)]
    {
        // Refused from its metadata: nothing is read, so this cannot hang or fill memory.
        let zero = Study::load(Path::new("/dev/zero")).unwrap_err();
        assert!(
            zero.to_string()
                .contains("is a device, pipe or socket, not a regular file"),
            "{zero}"
        );
    }

    let big = tmp.path().join("big.toml");
    let size = MAX_INPUT_BYTES as usize + 1;
    std::fs::write(&big, "#".repeat(size)).unwrap();
    let e = Study::load(&big).unwrap_err();
    assert!(
        e.to_string()
            .contains(&format!("is {size} bytes, more than the 4 MiB")),
        "{e}"
    );

    // The base scene gets the same check.
    std::fs::create_dir(tmp.path().join("scene.toml")).unwrap();
    let e = Study::from_text("s.toml", "s", "base = \"scene.toml\"\n", tmp.path()).unwrap_err();
    assert!(e.to_string().contains("is a directory"), "{e}");
}

#[test]
fn studies_are_told_apart_from_scenes() {
    for study in ["study_speed_sweep.toml", "study_thickness_payload.toml"] {
        let text = std::fs::read_to_string(configs().join(study)).unwrap();
        assert!(Study::looks_like_study(&text), "{study}");
    }
    for scene in ["paper_f20.toml", "pick_and_place.toml", "link_paper.toml"] {
        let path = configs().join(scene);
        if let Ok(text) = std::fs::read_to_string(&path) {
            assert!(!Study::looks_like_study(&text), "{scene}");
        }
    }
    assert!(!Study::looks_like_study("not = = toml"));
}

#[test]
fn a_missing_study_or_base_scene_is_bad_input() {
    let tmp = tempfile::tempdir().unwrap();
    let e = Study::load(&tmp.path().join("nowhere.toml")).unwrap_err();
    assert!(e.is_input(), "{e}");
    assert!(
        e.to_string().contains("nowhere.toml: cannot be read"),
        "{e}"
    );
    let e = Study::from_text("s.toml", "s", "base = \"absent.toml\"\n", tmp.path()).unwrap_err();
    assert!(e.is_input(), "{e}");
    assert!(e.to_string().contains("absent.toml: cannot be read"), "{e}");
}

#[test]
fn an_unknown_output_quantity_is_located_at_its_name_with_the_names_offered() {
    let body = "quantities = [{ kind = \"output\", name = \"tip_speed\" }]\n\n[[axis]]\nkey = \"trajectory.frequency\"\nvalues = [10.0]\n";
    // The built-in outputs offer no quantity by name: the message says so.
    assert_located(
        &error(body),
        &at(body, "name = ", 0),
        "quantities.0.name",
        "unknown output quantity `tip_speed`, no output offers quantities",
    );
}

#[test]
fn a_quantity_parameter_is_refused_at_its_key_or_value() {
    // A value of the wrong type: at the value, with the parameter's key.
    let body = "quantities = [{ kind = \"buckling\", link = \"a\" }]\n";
    assert_located(
        &error(body),
        &at(body, "\"a\"", 0),
        "quantities.0.link",
        "invalid type: string \"a\", expected usize",
    );
    // A missing parameter: at its table.
    let body = "quantities = [{ kind = \"frequency_range\", link = 1 }]\n";
    assert_located(
        &error(body),
        &at(body, "{", 0),
        "quantities.0",
        "missing field `mode`",
    );
    // A key the kind does not take, also on a kind without parameters.
    let body = "quantities = [{ kind = \"patch_voltage\", link = 1 }]\n";
    assert_located(
        &error(body),
        &at(body, "link", 0),
        "quantities.0.link",
        "unknown field `link`, there are no fields",
    );
    // An unknown kind lists the registered ones.
    let body = "quantities = [{ kind = \"peak_speed\" }]\n";
    assert_located(
        &error(body),
        &at(body, "\"peak_speed\"", 0),
        "quantities.0.kind",
        "unknown variant `peak_speed`, expected one of `frequency_range`, `stiffness_ratio`",
    );
}

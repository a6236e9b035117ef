//! Study plots: axis labels and units from the quantity columns and the scene-key table,
//! legends `key words = value unit`, and failed cases drawn (and counted), not dropped.

use std::path::{Path, PathBuf};

use flexprr_studies::keys::{key_label, key_value_label};
use flexprr_studies::study::{Study, StudyOptions, run_study};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

#[test]
fn plots_have_labels_with_units_legends_and_failed_cases() {
    let text = r#"
base = "paper_f20.toml"
quantities = [{ kind = "frequency_range", link = 1, mode = 1 }]
[set.output]
requests = ["frequencies"]
compare_without_axial_force = false
plots = false
[set.time]
end = 0.05
output_step = 1e-3
[[axis]]
key = "trajectory.frequency"
values = [5.0, 10.0, 15.0]
[[axis]]
key = "links.section.thickness"
values = [0.002, -0.001]
[[plot]]
file = "range.svg"
x = "trajectory.frequency"
y = ["f_min_1_1_Hz"]
series = "links.section.thickness"
"#;
    let study = Study::from_text("plot.toml", "plot", text, &configs()).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let options = StudyOptions {
        threads: Some(2),
        ..StudyOptions::default()
    };
    run_study(&study, tmp.path(), &options, &|_, _| {}).unwrap();
    let svg = std::fs::read_to_string(tmp.path().join("range.svg")).unwrap();
    // The drawn words, one text element after the other (a long axis label is drawn in
    // lines).
    let words = svg
        .split("<text ")
        .skip(1)
        .map(|t| &t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()])
        .collect::<Vec<_>>()
        .join(" ");
    for text in [
        "circle frequency f (Hz)",
        "lowest frequency of link 1, mode 1 (Hz)",
        // Legend values with an SI prefix chosen from the value.
        "link thickness = 2 mm",
        "link thickness = −1 mm",
        // The three invalid cases (negative thickness) are drawn and counted.
        "failed cases (3)",
    ] {
        assert!(words.contains(text), "{text} missing from {words}");
    }
    assert!(
        !svg.contains("f_min_1_1_Hz"),
        "raw column name used as a label"
    );
    // Each failed case is a hollow red circle (white fill, red stroke) in the strip along
    // the lower edge: three of them, at the three frequencies.
    let hollow_red = svg.matches("fill=\"white\" stroke=\"#dc0000\"").count();
    assert_eq!(hollow_red, 3 + 1, "three cases and the legend sample");
}

/// The units of the key table agree with the unit column of the scene-file reference.
#[test]
fn key_units_agree_with_the_scene_reference() {
    let reference =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scenes.md"))
            .unwrap();
    for (key, unit) in [
        ("machine.platform_mass", "kg"),
        ("trajectory.frequency", "Hz"),
        ("links.length", "m"),
    ] {
        let name = key.rsplit('.').next().unwrap();
        // A row `| `name` | type | unit | ...` (the trajectory table has a kind column first).
        let row = reference
            .lines()
            .find(|l| l.contains(&format!("| `{name}` |")))
            .unwrap_or_else(|| panic!("{name} not in docs/scenes.md"));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let at = cells
            .iter()
            .position(|c| *c == format!("`{name}`"))
            .unwrap();
        assert_eq!(cells[at + 2], unit, "{row}");
        assert!(key_label(key).ends_with(&format!("({unit})")), "{key}");
        assert!(
            key_value_label(key, "1").ends_with(&format!("= 1 {unit}")),
            "{key}"
        );
    }
    assert_eq!(key_label("model.formulation"), "formulation");
    assert_eq!(key_label("some.unknown_key"), "some.unknown_key");
}

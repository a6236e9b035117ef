//! Every CSV value is written as docs/scenes.md states: scientific notation with ten
//! decimals, `-?D.DDDDDDDDDDe-?X` (Rust's `{:.10e}`: `1.0000000000e-4`, `0.0000000000e0`),
//! both by `flexprr run` and by `flexprr kinematics`, whose table is the run's
//! `kinematics.csv` to the byte.

use std::path::Path;
use std::process::Command;

/// Whether `v` is `-?D.DDDDDDDDDDe-?X` with one leading digit, ten decimals and an exponent
/// without sign `+` or leading zeros.
fn documented_format(v: &str) -> bool {
    let v = v.strip_prefix('-').unwrap_or(v);
    let Some((mantissa, exponent)) = v.split_once('e') else {
        return false;
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let Some((int, frac)) = mantissa.split_once('.') else {
        return false;
    };
    let exponent = exponent.strip_prefix('-').unwrap_or(exponent);
    int.len() == 1
        && digits(int)
        && frac.len() == 10
        && digits(frac)
        && digits(exponent)
        && (exponent == "0" || !exponent.starts_with('0'))
}

fn check_csv(name: &str, text: &str) {
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    assert!(header.starts_with("t_s,"), "{name}: {header}");
    let columns = header.split(',').count();
    let mut rows = 0;
    for line in lines {
        let values: Vec<&str> = line.split(',').collect();
        assert_eq!(values.len(), columns, "{name}: {line}");
        for v in values {
            assert!(
                documented_format(v),
                "{name}: {v:?} is not in the documented format"
            );
            assert!(v.parse::<f64>().unwrap().is_finite());
        }
        rows += 1;
    }
    assert!(rows > 0, "{name} is empty");
}

#[test]
fn csv_values_have_the_documented_format() {
    assert!(documented_format("1.0000000000e-4") && documented_format("-2.5000000000e0"));
    assert!(!documented_format("1.000000000e-4") && !documented_format("1.0000000000e-04"));
    assert!(!documented_format("1.0000000000e+4") && !documented_format("1e-4"));

    let tmp = tempfile::tempdir().unwrap();
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/paper_f20.toml");
    let out = tmp.path().join("paper_f20");
    let run = Command::new(env!("CARGO_BIN_EXE_flexprr"))
        .args(["run", "--quiet"])
        .arg(&config)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let mut checked = 0;
    for entry in std::fs::read_dir(&out).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        // table1.csv is a summary table (link, mode, rounded frequencies), not a series.
        if name.ends_with(".csv") && name != "table1.csv" {
            check_csv(&name, &std::fs::read_to_string(&path).unwrap());
            checked += 1;
        }
    }
    assert!(checked >= 8, "{checked} CSV files");

    let kinematics = Command::new(env!("CARGO_BIN_EXE_flexprr"))
        .arg("kinematics")
        .arg(&config)
        .output()
        .unwrap();
    assert!(kinematics.status.success());
    let text = String::from_utf8(kinematics.stdout).unwrap();
    check_csv("flexprr kinematics", &text);
    assert_eq!(
        text,
        std::fs::read_to_string(out.join("kinematics.csv")).unwrap(),
        "flexprr kinematics and the run's kinematics.csv differ"
    );
}

//! Helpers shared by the command-line tests: the binary under test, its error output, the
//! CSV tables it writes (read by `flexprr_testkit::csv`), a scene that runs in
//! milliseconds and a snapshot of a directory tree.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `flexprr` binary built for these tests.
pub fn flexprr() -> Command {
    Command::new(env!("CARGO_BIN_EXE_flexprr"))
}

/// The workspace's `configs/` directory.
pub fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs")
}

/// A shipped scene or study file of `configs/` by name.
pub fn config(name: &str) -> PathBuf {
    configs().join(name)
}

/// What a finished command printed on standard error.
pub fn stderr_of(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// A numeric CSV table written by `flexprr`: its header and rows.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    flexprr_testkit::csv::read_numeric(path)
}

/// A KED scene that runs in milliseconds (10 ms of the 10 Hz circle, frequencies and
/// deflections, no plots).
pub const TINY: &str = r#"name = "tiny"
[trajectory]
kind = "circle"
frequency = 10.0
[time]
end = 0.01
output_step = 1e-3
[output]
requests = ["frequencies", "deflections"]
plots = false
"#;

/// Every file and directory under `root` (relative paths) with its contents; directories
/// map to an empty content and a `/` suffix, anything else (a link, a pipe) to
/// `<special>`.
pub fn tree(root: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.strip_prefix(root).unwrap().display().to_string();
            let meta = std::fs::symlink_metadata(&path).unwrap();
            if meta.is_dir() {
                out.insert(format!("{name}/"), Vec::new());
                stack.push(path);
            } else if meta.is_file() {
                out.insert(name, std::fs::read(&path).unwrap());
            } else {
                out.insert(name, b"<special>".to_vec());
            }
        }
    }
    out
}

/// `flexprr check <path>`: asserts it succeeds and returns what it printed on standard
/// output and standard error.
pub fn check_ok(path: &Path) -> (String, String) {
    let output = flexprr().arg("check").arg(path).output().unwrap();
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}: {}",
        path.display(),
        stderr_of(&output)
    );
    (
        String::from_utf8_lossy(&output.stdout).into_owned(),
        stderr_of(&output),
    )
}

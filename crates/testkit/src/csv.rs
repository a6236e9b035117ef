//! The CSV tables flexprr writes, read back for tests: a header row and rows of numbers.

use std::path::Path;

/// Reads a numeric CSV table: its header and its rows (cells trimmed, blank lines skipped,
/// as external validation data may have them). Panics (this is a test helper) with the
/// file, row and cell when the file cannot be read or a cell is not a number, so a failing
/// test names what it could not read.
pub fn read_numeric(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap_or_else(|| panic!("{} is empty", path.display()))
        .split(',')
        .map(|name| name.trim().to_string())
        .collect();
    let rows = lines
        .enumerate()
        .filter(|(_, line)| !line.trim().is_empty())
        .map(|(row, line)| {
            line.split(',')
                .map(|cell| {
                    cell.trim().parse().unwrap_or_else(|_| {
                        panic!(
                            "{} row {}: {cell:?} is not a number",
                            path.display(),
                            row + 2
                        )
                    })
                })
                .collect()
        })
        .collect();
    (header, rows)
}

#[cfg(test)]
mod tests {
    #[test]
    fn reads_header_and_rows() {
        let dir = std::env::temp_dir().join(format!("flexprr-testkit-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.csv");
        std::fs::write(&path, "t,x\n0,1.5\n0.1,-2e-3\n").unwrap();
        let (header, rows) = super::read_numeric(&path);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(header, ["t", "x"]);
        assert_eq!(rows.len(), 2);
        assert!((rows[1][1] + 2e-3).abs() < 1e-18);
    }
}

//! `flexprr beam <link.toml> [--json]`: natural frequencies of a single link under an axial
//! load `P(x) = p0 + p1 x + p2 x^2` (model.md section 7).
//!
//! The link file (see `configs/link_paper.toml` and `docs/beam.md`) gives the material, the
//! section, the length, the assumed-mode basis, the number of modes, the coupling and the load.
//! The material, section and basis tables are the scenarios layer's ([`flexprr_scene::link`]),
//! shared with scene files.

use std::sync::Arc;

use super::Failure;
use flexprr_beam::{AxialLoad, Basis, Coupling, LinkFrequencies, ModalIntegrals, frequencies};
use flexprr_scene::link::{MaterialConfig, SectionConfig, build_section, check_link};
use flexprr_scene::{BasisParams, BasisTable, ModeCount, Registry, ScenarioError};
use serde::Deserialize;

/// Arguments of `flexprr beam`.
#[derive(Debug, clap::Args)]
pub struct BeamArgs {
    /// Link file (TOML).
    pub file: std::path::PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// A single-link file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkFile {
    /// Link length `l` (m).
    pub length: f64,
    /// Number of basis functions `r` for `sine` and `classical` bases; for `hermite`, the
    /// number of modes reported (at most the number of free nodal unknowns).
    pub modes: usize,
    /// `"full"` (default) or `"diagonal"` (the paper's eq. 22).
    #[serde(default)]
    pub coupling: CouplingConfig,
    /// Material of the link.
    pub material: MaterialConfig,
    /// Cross-section along the link.
    pub section: SectionConfig,
    /// Assumed-mode basis (`kind` and its keys, as in scene files).
    pub basis: BasisTable,
    /// Axial force, tension positive (default: none).
    #[serde(default)]
    pub load: LoadConfig,
}

/// Frequency coupling.
#[derive(Debug, Clone, Copy, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CouplingConfig {
    /// Generalized eigenproblem with the full matrices.
    #[default]
    Full,
    /// Diagonals only (eq. 22).
    Diagonal,
}

/// `P(x) = p0 + p1 x + p2 x^2`, `x` in metres from the slider end, tension positive.
#[derive(Debug, Clone, Copy, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct LoadConfig {
    /// Constant part (N).
    #[serde(default)]
    pub p0: f64,
    /// Linear coefficient (N/m).
    #[serde(default)]
    pub p1: f64,
    /// Quadratic coefficient (N/m^2).
    #[serde(default)]
    pub p2: f64,
}

/// Parses a link file; errors say where (`file:line:column`), which key and what was expected
/// (the same reporting as scene files).
pub fn parse_link_file(file: &str, text: &str) -> Result<LinkFile, String> {
    flexprr_scene::parse_toml(file, text).map_err(|e| e.to_string())
}

/// A link built from a file: basis, section and its integrals.
struct Link {
    basis: Arc<dyn Basis>,
    ei_at_start: f64,
    rho_a_at_start: f64,
    integrals: ModalIntegrals,
    reported: usize,
}

/// A bad-input error at `key` of the link file, located in `text`.
fn input_error(path: &str, text: &str, key: &str, message: impl Into<String>) -> String {
    ScenarioError::Input {
        location: flexprr_scene::locate(path, text, key),
        key: key.to_string(),
        message: message.into(),
    }
    .to_string()
}

fn build_link(path: &str, text: &str, file: &LinkFile) -> Result<Link, String> {
    check_link(&file.material, &file.section, file.length)
        .map_err(|(key, message)| input_error(path, text, &key, message))?;
    for (key, value) in [
        ("load.p0", file.load.p0),
        ("load.p1", file.load.p1),
        ("load.p2", file.load.p2),
    ] {
        if !value.is_finite() {
            return Err(input_error(
                path,
                text,
                key,
                format!("expected a finite number, got {value:?}"),
            ));
        }
    }
    let section = build_section(&file.material, &file.section)
        .map_err(|(key, message)| input_error(path, text, &key, message))?;
    let registry = Registry::default();
    let params = BasisParams::new(path, text, "basis", &file.basis.params);
    // For a basis sized by its own keys, `modes` is only how many modes are reported.
    let sized_by_modes = registry
        .basis(&file.basis.kind)
        .is_none_or(|f| f.mode_count() == ModeCount::FromModes);
    let basis = registry
        .build_basis(
            &params,
            &file.basis.kind,
            "modes",
            sized_by_modes.then_some(file.modes),
        )
        .map_err(|e| e.to_string())?;
    if file.modes == 0 || file.modes > basis.len() {
        return Err(input_error(
            path,
            text,
            "modes",
            format!(
                "modes = {} must be between 1 and the {} functions of the {} basis",
                file.modes,
                basis.len(),
                basis.name()
            ),
        ));
    }
    let integrals = ModalIntegrals::compute(basis.as_ref(), section.as_ref(), file.length)
        .map_err(|e| format!("modal integrals: {e}"))?;
    Ok(Link {
        ei_at_start: section.bending_stiffness(0.0),
        rho_a_at_start: section.mass_per_length(0.0),
        basis,
        integrals,
        reported: file.modes,
    })
}

/// Runs the command.
pub fn run(args: BeamArgs) -> Result<(), Failure> {
    let path = args.file.display().to_string();
    let text = flexprr_scene::read_input_file(&args.file).map_err(Failure::bad_input)?;
    let file = parse_link_file(&path, &text).map_err(Failure::bad_input)?;
    let link = build_link(&path, &text, &file).map_err(Failure::bad_input)?;
    let load = AxialLoad {
        p0: file.load.p0,
        p1: file.load.p1,
        p2: file.load.p2,
    };
    let coupling = match file.coupling {
        CouplingConfig::Full => Coupling::Full,
        CouplingConfig::Diagonal => Coupling::Diagonal,
    };
    // The link file is the only input: an eigenproblem that cannot be formed (a load so
    // large that the stiffness overflows) is bad input, placed at the load.
    let result = frequencies(&link.integrals, &load, coupling).map_err(|e| {
        Failure::bad_input(input_error(
            &path,
            &text,
            "load",
            format!("the eigenproblem of this link and load cannot be solved: {e}; check the load's size"),
        ))
    })?;
    let report = if args.json {
        json_report(&file, &link, &load, &result) + "\n"
    } else {
        table_report(&file, &link, &load, &result)
    };
    write_stdout(&report)
}

/// Writes to standard output; a closed pipe (e.g. `| head`) is not an error.
fn write_stdout(text: &str) -> Result<(), Failure> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Failure::run(format!("cannot write output: {e}"))),
    }
}

fn json_report(file: &LinkFile, link: &Link, load: &AxialLoad, result: &LinkFrequencies) -> String {
    let modes: Vec<_> = result.modes[..link.reported]
        .iter()
        .map(|m| {
            serde_json::json!({
                "mode": m.mode,
                "frequency_hz": m.frequency_hz,
                "omega_squared": m.omega_squared,
                "state": m.state.name(),
            })
        })
        .collect();
    let value = serde_json::json!({
        "basis": link.basis.name(),
        "r": link.integrals.r(),
        "coupling": result.coupling.name(),
        "length": file.length,
        "total_mass": link.integrals.total_mass,
        "bending_stiffness_at_slider": link.ei_at_start,
        "mass_per_length_at_slider": link.rho_a_at_start,
        "quadrature": {
            "points_per_panel": link.integrals.points_per_panel,
            "panels": link.integrals.panels,
        },
        "load": { "p0": load.p0, "p1": load.p1, "p2": load.p2 },
        "buckled": result.is_buckled(),
        "lowest_eigenvalue": result.lowest_eigenvalue(),
        "critical_load_factor": result.critical_load_factor,
        "modes": modes,
    });
    serde_json::to_string_pretty(&value).unwrap_or_else(|_| value.to_string())
}

fn table_report(
    file: &LinkFile,
    link: &Link,
    load: &AxialLoad,
    result: &LinkFrequencies,
) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let mi = &link.integrals;
    let _ = writeln!(
        s,
        "link: l = {} m, mass = {:.6} kg, EI(0) = {:.6e} N m^2, rhoA(0) = {:.6e} kg/m",
        file.length, mi.total_mass, link.ei_at_start, link.rho_a_at_start
    );
    let _ = writeln!(
        s,
        "basis: {}; coupling: {}; quadrature: {} Gauss points x {} panel(s)",
        link.basis.name(),
        result.coupling.name(),
        mi.points_per_panel,
        mi.panels
    );
    let _ = writeln!(
        s,
        "load: P(x) = {} + {} x + {} x^2 N (tension positive)",
        load.p0, load.p1, load.p2
    );
    let _ = writeln!(
        s,
        "{:>5}  {:>16}  {:>20}  state",
        "mode", "frequency (Hz)", "omega^2 (rad^2/s^2)"
    );
    for m in &result.modes[..link.reported] {
        let _ = writeln!(
            s,
            "{:>5}  {:>16.6}  {:>20.9e}  {}",
            m.mode,
            m.frequency_hz,
            m.omega_squared,
            m.state.name()
        );
    }
    match result.critical_load_factor {
        Some(factor) => {
            let _ = writeln!(
                s,
                "critical load factor: {} (the link buckles at {} x this load)",
                significant(factor, 10),
                significant(factor, 7)
            );
        }
        None => {
            let _ = writeln!(
                s,
                "critical load factor: none (no positive multiple of this load buckles the link)"
            );
        }
    }
    if result.is_buckled() {
        let _ = writeln!(
            s,
            "BUCKLED: lowest eigenvalue {:.6e} rad^2/s^2 (stiffness not positive definite)",
            result.lowest_eigenvalue()
        );
    }
    s
}

/// `value` with `digits` significant digits: fixed-point between 1e-3 and 1e7
/// (`2.345678901`, `1234.568`), scientific notation outside (`4.567890123e-7`), so that a tiny
/// or a huge factor keeps its digits instead of reading `0.000000000`.
fn significant(value: f64, digits: usize) -> String {
    let digits = digits.max(1);
    let magnitude = value.abs();
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    if (1e-3..1e7).contains(&magnitude) {
        let exponent = magnitude.log10().floor() as i64;
        let decimals = (digits as i64 - 1 - exponent).max(0) as usize;
        format!("{value:.decimals$}")
    } else {
        format!("{value:.prec$e}", prec = digits - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors_keep_their_significant_digits() {
        assert_eq!(significant(2.345678901234, 10), "2.345678901");
        assert_eq!(significant(1234.5678, 7), "1234.568");
        assert_eq!(significant(4.567890123456e-7, 10), "4.567890123e-7");
        assert_eq!(significant(3.0e9, 7), "3.000000e9");
        assert_eq!(significant(0.00123456789, 4), "0.001235");
        // The value read back equals the factor to the digits shown.
        let tiny: f64 = significant(1.234567890123e-12, 10).parse().unwrap();
        assert!((tiny / 1.234567890123e-12 - 1.0).abs() < 1e-9);
    }

    #[test]
    fn unknown_key_is_reported_with_line_and_column() {
        let text = "length = 0.2\nmodes = 3\nlenght = 1\n";
        let err = parse_link_file("link.toml", text).unwrap_err();
        assert!(err.contains("link.toml:3:1"), "{err}");
        assert!(err.contains("lenght"), "{err}");
    }

    #[test]
    fn unknown_key_inside_a_tagged_table_is_rejected() {
        let text = "length = 0.2\nmodes = 3\n[material]\nyoungs_modulus = 7e10\ndensity = 2770.0\n\
                    [section]\nkind = \"uniform\"\nthickness = 0.002\nheight = 0.03\nwidth = 1\n\
                    [basis]\nkind = \"sine\"\n";
        let err = parse_link_file("link.toml", text).unwrap_err();
        assert!(err.contains("section.width"), "{err}");
    }
}

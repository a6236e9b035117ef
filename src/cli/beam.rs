//! `flexprr beam <link.toml> [--json]`: natural frequencies of a single link under an axial
//! load `P(x) = p0 + p1 x + p2 x^2` (model.md section 7).
//!
//! The link file (see `configs/link_paper.toml` and `docs/beam.md`) gives the material, the
//! section, the length, the assumed-mode basis, the number of modes, the coupling and the load.
//! The material, section and basis tables are the scenarios layer's ([`flexprr_scene::link`]),
//! shared with scene files.

use super::Failure;
use flexprr_beam::{AxialLoad, LinkFrequencies, frequencies};
use flexprr_scene::link_file::{BuiltLink as Link, LinkFile};

/// Arguments of `flexprr beam`.
#[derive(Debug, clap::Args)]
pub struct BeamArgs {
    /// Link file (TOML).
    pub file: std::path::PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs the command.
pub fn run(args: BeamArgs) -> Result<(), Failure> {
    let path = args.file.display().to_string();
    let (file, text) = LinkFile::load(&args.file).map_err(Failure::bad_input)?;
    let link = file.build(&path, &text).map_err(Failure::bad_input)?;
    let load = file.load.axial_load();
    let coupling = file.coupling.coupling();
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
        "bending_stiffness_at_slider": link.bending_stiffness_at_start,
        "mass_per_length_at_slider": link.mass_per_length_at_start,
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
        "link: l = {} m, mass = {} kg, EI(0) = {:.6e} N m^2, rhoA(0) = {:.6e} kg/m",
        super::short(file.length, 7),
        super::short(mi.total_mass, 7),
        link.bending_stiffness_at_start,
        link.mass_per_length_at_start
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
        super::short(load.p0, 10),
        super::short(load.p1, 10),
        super::short(load.p2, 10)
    );
    let _ = writeln!(
        s,
        "{:>5}  {:>16}  {:>20}  state",
        "mode", "frequency (Hz)", "omega^2 (rad^2/s^2)"
    );
    for m in &result.modes[..link.reported] {
        let _ = writeln!(
            s,
            "{:>5}  {:>16}  {:>20.9e}  {}",
            m.mode,
            fixed_or_scientific(m.frequency_hz, 6),
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

/// A bad-input message located at `key` of the link file.
fn input_error(path: &str, text: &str, key: &str, message: impl Into<String>) -> String {
    flexprr_scene::ScenarioError::Input {
        location: flexprr_scene::locate(path, text, key),
        key: key.to_string(),
        message: message.into(),
    }
    .to_string()
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

/// `value` with `decimals` decimals between 1e-3 and 1e7 (the table's usual range), else in
/// scientific notation with as many digits after the point, so a frequency of a tiny link is
/// not printed as twenty digits, nor a slow one as `0.000000`.
fn fixed_or_scientific(value: f64, decimals: usize) -> String {
    let magnitude = value.abs();
    if value == 0.0 || !value.is_finite() || (1e-3..1e7).contains(&magnitude) {
        format!("{value:.decimals$}")
    } else {
        format!("{value:.decimals$e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_numbers_stay_short_at_any_scale() {
        assert_eq!(fixed_or_scientific(116.41234567, 6), "116.412346");
        assert_eq!(fixed_or_scientific(2.124296443310437e18, 6), "2.124296e18");
        assert_eq!(fixed_or_scientific(3.2e-5, 6), "3.200000e-5");
        assert_eq!(fixed_or_scientific(0.0, 6), "0.000000");
        // Lengths and masses as a person writes them, without binary noise.
        assert_eq!(crate::cli::short(0.3 / 10.0, 7), "0.03");
        assert_eq!(crate::cli::short(0.2, 7), "0.2");
        assert_eq!(crate::cli::short(1e-9, 7), "1e-9");
        assert_eq!(crate::cli::short(2.770000000000001e-18, 7), "2.77e-18");
        assert_eq!(crate::cli::short(0.004986123456, 7), "0.004986123");
        assert_eq!(crate::cli::short(-1e12, 10), "-1e12");
        assert_eq!(crate::cli::short(50.0, 10), "50");
    }

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
}

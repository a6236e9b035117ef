//! Units with SI prefixes, "nice" tick positions and tick labels.
//!
//! The prefix of an axis is chosen from the largest magnitude it shows, in engineering
//! notation (the exponent a multiple of three, so the scaled magnitude lies in `[1, 1000)`;
//! BIPM, *The International System of Units*, 9th ed., 2019, section 3). Tick steps are
//! `1, 2, 5 x 10^k` (Heckbert, "Nice numbers for graph labels", *Graphics Gems*, 1990), and
//! a label shows exactly the decimals its step needs, without trailing zeros and never `-0`.

/// SI prefixes from pico to giga: (exponent, symbol).
const PREFIXES: [(i32, &str); 8] = [
    (-12, "p"),
    (-9, "n"),
    (-6, "µ"),
    (-3, "m"),
    (0, ""),
    (3, "k"),
    (6, "M"),
    (9, "G"),
];

/// Base units that take a prefix on their first symbol (`m` -> `mm`, `m/s²` -> `mm/s²`).
/// `kg` (already prefixed), `deg` and compound units such as `kg m²` do not.
const PREFIXABLE: [&str; 9] = ["m", "N", "s", "Hz", "J", "Pa", "rad", "W", "V"];

/// How an axis shows its values: multiply data by [`Scaled::factor`] and write the unit as
/// [`Scaled::unit`].
#[derive(Debug, Clone, PartialEq)]
pub struct Scaled {
    /// Factor from the SI value to the shown value (`1e3` for `m` -> `mm`).
    pub factor: f64,
    /// The unit as shown (`mm`, `kN`, `×10⁻³` for a quantity without a prefixable unit, or
    /// empty).
    pub unit: String,
}

/// The engineering exponent of `max_abs`: a multiple of three `e` with
/// `1 <= max_abs / 10^e < 1000`, clamped to the prefixes pico to giga. Zero for zero or a
/// value that is not finite.
pub fn engineering_exponent(max_abs: f64) -> i32 {
    if !(max_abs.is_finite() && max_abs > 0.0) {
        return 0;
    }
    // A value that rounds up to the next power of 1000 in four significant digits belongs
    // to the next prefix (999.99 m -> 1 km), so the scaled value never shows as 1000.
    let rounded: f64 = format!("{max_abs:.3e}").parse().unwrap_or(max_abs);
    let e = (rounded.log10() + 1e-12).floor() as i32;
    (e.div_euclid(3) * 3).clamp(-12, 9)
}

/// The prefix symbol of an engineering exponent (`-3` -> `m`), if it is one of pico to giga.
pub fn prefix_symbol(exponent: i32) -> Option<&'static str> {
    PREFIXES
        .iter()
        .find(|(e, _)| *e == exponent)
        .map(|(_, s)| *s)
}

/// How to show values of magnitude up to `max_abs` in `unit`: a prefixed unit where the unit
/// takes one (`2e-4 m` -> `µm`, `1500 N` -> `kN`), the unit unchanged for magnitudes in
/// `[1, 1000)`; a unit without prefixes (`kg`, `deg`, none) is kept for magnitudes in
/// `[0.01, 10⁴)` and takes a power-of-ten factor outside (`×10⁻⁶`, `×10⁻³ kg`).
pub fn scale_for(max_abs: f64, unit: &str) -> Scaled {
    let e = engineering_exponent(max_abs);
    if e == 0 {
        return Scaled {
            factor: 1.0,
            unit: unit.to_string(),
        };
    }
    let factor = 10f64.powi(-e);
    let (first, rest) = split_first_unit(unit);
    if !PREFIXABLE.contains(&first) && (1e-2..1e4).contains(&max_abs) {
        // Ratios near one (a stiffness ratio of 0.98) and masses in kg read best as they are.
        return Scaled {
            factor: 1.0,
            unit: unit.to_string(),
        };
    }
    if PREFIXABLE.contains(&first) {
        let prefix = prefix_symbol(e).unwrap_or_default();
        return Scaled {
            factor,
            unit: format!("{prefix}{first}{rest}"),
        };
    }
    let power = format!("×10{}", superscript(&e.to_string()));
    Scaled {
        factor,
        unit: if unit.is_empty() {
            power
        } else {
            format!("{power} {unit}")
        },
    }
}

/// The first unit symbol and the rest: `m/s²` -> (`m`, `/s²`), `kg m²` -> (`kg`, ` m²`).
fn split_first_unit(unit: &str) -> (&str, &str) {
    let end = unit.find(['/', ' ', '²', '³', '·']).unwrap_or(unit.len());
    unit.split_at(end)
}

/// `s` with digits and signs as Unicode superscripts (`-6` -> `⁻⁶`).
pub fn superscript(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '-' => '⁻',
            '+' => '⁺',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            '9' => '⁹',
            other => other,
        })
        .collect()
}

/// The step of the form `1, 2 or 5 x 10^k` nearest to `raw` (Heckbert's rounding: mantissa
/// below 1.5 -> 1, below 3 -> 2, below 7 -> 5, else 10).
pub fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let k = raw.log10().floor();
    let base = 10f64.powf(k);
    let mantissa = raw / base;
    let m = if mantissa < 1.5 {
        1.0
    } else if mantissa < 3.0 {
        2.0
    } else if mantissa < 7.0 {
        5.0
    } else {
        10.0
    };
    m * base
}

/// Ticks of a linear axis on `[lo, hi]`: multiples of a nice step, about `target` of them
/// (at least two when the interval is not empty). Returns the ticks and the step.
pub fn linear_ticks(lo: f64, hi: f64, target: usize) -> (Vec<f64>, f64) {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return (vec![lo], 1.0);
    }
    let mut step = nice_step((hi - lo) / target.max(2) as f64);
    loop {
        let first = (lo / step - 1e-9).ceil() as i64;
        let last = (hi / step + 1e-9).floor() as i64;
        if last - first >= 1 || step <= f64::MIN_POSITIVE {
            // Integer multiples: no accumulated rounding, and zero is exactly zero.
            let ticks = (first..=last).map(|k| k as f64 * step).collect();
            return (ticks, step);
        }
        step = nice_step(step / 2.5);
    }
}

/// The number of decimals a label on a grid of `step` needs (`0.05` -> 2, `20` -> 0).
pub fn decimals(step: f64) -> usize {
    if !(step.is_finite() && step > 0.0) {
        return 0;
    }
    let d = -(step.log10() + 1e-9).floor();
    if d > 0.0 { d as usize } else { 0 }
}

/// The label of tick `v` on a grid of `step`: as many decimals as the step needs, trailing
/// zeros (and a bare point) removed, a minus sign as `−` (U+2212), and never `−0`.
pub fn tick_label(v: f64, step: f64) -> String {
    let d = decimals(step);
    let mut s = format!("{v:.d$}");
    if s.contains('.') {
        let trimmed = s.trim_end_matches('0').trim_end_matches('.').len();
        s.truncate(trimmed);
    }
    if s.chars().all(|c| c == '-' || c == '0' || c == '.') {
        return "0".to_string();
    }
    s.replace('-', "−")
}

/// A value with its unit and an SI prefix chosen from the value itself, with up to four
/// significant digits and a minus sign as `−`: `0.002 m` -> `2 mm`, `0.2 kg` -> `0.2 kg`,
/// `1e-3` -> `0.001`, `-0.001 m` -> `−1 mm`.
pub fn value_label(v: f64, unit: &str) -> String {
    let scaled = if unit.is_empty() || !PREFIXABLE.contains(&split_first_unit(unit).0) {
        Scaled {
            factor: 1.0,
            unit: unit.to_string(),
        }
    } else {
        scale_for(v.abs(), unit)
    };
    let shown = v * scaled.factor;
    let number = format!("{}", format!("{shown:.4}").parse::<f64>().unwrap_or(shown));
    let number = shorten(number, shown).replace('-', "−");
    if scaled.unit.is_empty() {
        number
    } else {
        format!("{number} {}", scaled.unit)
    }
}

/// Four significant digits for numbers written without a prefix (`0.0001234`).
fn shorten(fixed: String, v: f64) -> String {
    if v.abs() >= 1e-3 || v.abs() < f64::MIN_POSITIVE {
        return fixed;
    }
    let r: f64 = format!("{v:.3e}").parse().unwrap_or(v);
    format!("{r}")
}

/// Ticks of a logarithmic axis on `[lo, hi]` (both positive): the powers of ten inside, every
/// second or more when there are many, as exponents; and the minor ticks `2..9 x 10^k` (as
/// values) when few decades are shown.
pub fn log_ticks(lo: f64, hi: f64) -> (Vec<i32>, Vec<f64>) {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return (Vec::new(), Vec::new());
    }
    let (a, b) = (
        (lo.log10() - 1e-9).ceil() as i32,
        (hi.log10() + 1e-9).floor() as i32,
    );
    let decades = (b - a).max(0) as usize;
    let every = decades.div_ceil(7).max(1) as i32;
    let major: Vec<i32> = (a..=b).filter(|e| e.rem_euclid(every) == 0).collect();
    let mut minor = Vec::new();
    if every == 1 {
        for e in (a - 1)..=b {
            for m in 2..=9 {
                let v = f64::from(m) * 10f64.powi(e);
                if v > lo && v < hi {
                    minor.push(v);
                }
            }
        }
    }
    (major, minor)
}

/// The label of the power of ten `10^e`: `10⁻⁶`, and `1`, `10` for `e = 0, 1`.
pub fn power_label(e: i32) -> String {
    match e {
        0 => "1".to_string(),
        1 => "10".to_string(),
        _ => format!("10{}", superscript(&e.to_string())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn prefixes_by_hand() {
        // (largest magnitude, unit) -> shown unit and factor, worked by hand.
        for (max, unit, shown, factor) in [
            (6e-5, "m", "µm", 1e6),
            (1.5e-4, "m", "µm", 1e6),
            (2.5e-3, "m", "mm", 1e3),
            (0.2, "s", "ms", 1e3),
            (1.0, "s", "s", 1.0),
            (999.0, "N", "N", 1.0),
            (1500.0, "N", "kN", 1e-3),
            (999.9999, "N", "kN", 1e-3),
            (2e-3, "m/s²", "mm/s²", 1e3),
            (0.05, "rad", "mrad", 1e3),
            (7e-7, "J", "nJ", 1e9),
            (2e11, "Pa", "GPa", 1e-9),
            (0.5, "kg", "kg", 1.0),
            (2e-3, "kg", "×10⁻³ kg", 1e3),
            (3e-6, "", "×10⁻⁶", 1e6),
            (0.98, "", "", 1.0),
            (2e4, "", "×10³", 1e-3),
            (40.0, "Hz", "Hz", 1.0),
            (0.0, "m", "m", 1.0),
        ] {
            let s = scale_for(max, unit);
            assert_eq!(s.unit, shown, "{max} {unit}");
            assert!((s.factor / factor - 1.0).abs() < 1e-12, "{max} {unit}");
        }
    }

    #[test]
    fn ticks_by_hand() {
        let (t, step) = linear_ticks(0.0, 0.2, 5);
        assert!((step - 0.05).abs() < 1e-15);
        let labels: Vec<String> = t.iter().map(|v| tick_label(*v, step)).collect();
        assert_eq!(labels, ["0", "0.05", "0.1", "0.15", "0.2"]);
        let (t, step) = linear_ticks(-63.0, 61.0, 5);
        let labels: Vec<String> = t.iter().map(|v| tick_label(*v, step)).collect();
        assert_eq!(labels, ["−60", "−40", "−20", "0", "20", "40", "60"]);
        let (t, step) = linear_ticks(-1.2, 1.3, 5);
        let labels: Vec<String> = t.iter().map(|v| tick_label(*v, step)).collect();
        assert_eq!(labels, ["−1", "−0.5", "0", "0.5", "1"]);
        assert_eq!(tick_label(-1e-17, 0.1), "0");
        assert_eq!(tick_label(2.0, 0.5), "2");
        assert_eq!(log_ticks(1e-4, 2e-1).0, [-4, -3, -2, -1]);
        assert_eq!(power_label(-12), "10⁻¹²");
        assert_eq!(value_label(0.002, "m"), "2 mm");
        assert_eq!(value_label(0.2, "kg"), "0.2 kg");
        assert_eq!(value_label(20.0, "Hz"), "20 Hz");
        assert_eq!(value_label(1e-3, ""), "0.001");
        assert_eq!(value_label(-1e-3, "m"), "−1 mm");
        assert_eq!(value_label(1.2346e-5, ""), "0.00001235");
    }

    proptest! {
        /// The shown magnitude lies in [1, 1000) for every value the prefixes reach.
        #[test]
        fn scaled_magnitude_is_engineering(m in -11.9f64..11.9, unit in prop::sample::select(vec!["m", "N", "Hz", "deg"])) {
            let unit = if unit == "deg" && (-2.0..4.0).contains(&m) { "m" } else { unit };
            let v = 10f64.powf(m);
            let s = scale_for(v, unit);
            let shown = v * s.factor;
            prop_assert!((1.0 - 1e-9..1000.0).contains(&shown) || (shown - 1000.0).abs() < 1.0, "{v} -> {shown} {}", s.unit);
        }

        /// Every label parses back to its tick within half the shown precision, has no
        /// trailing zero after a point, is not `-0`, and neighbouring labels differ.
        #[test]
        fn labels_parse_back(lo in -1e6f64..1e6, span_exp in -6.0f64..6.0, target in 3usize..8) {
            let hi = lo + 10f64.powf(span_exp);
            let (ticks, step) = linear_ticks(lo, hi, target);
            prop_assert!(ticks.len() >= 2);
            let labels: Vec<String> = ticks.iter().map(|v| tick_label(*v, step)).collect();
            let precision = 10f64.powi(-(decimals(step) as i32));
            for (v, l) in ticks.iter().zip(&labels) {
                let back: f64 = l.replace('−', "-").parse().unwrap();
                prop_assert!((back - v).abs() <= 0.5 * precision + 1e-9 * v.abs(), "{v} -> {l}");
                prop_assert!(!(l.contains('.') && l.ends_with('0')), "{l}");
                prop_assert!(l != "−0" && l != "-0", "{l}");
                prop_assert!(*v >= lo - 1e-9 * lo.abs() && *v <= hi + 1e-9 * hi.abs());
            }
            for w in labels.windows(2) {
                prop_assert_ne!(&w[0], &w[1]);
            }
        }
    }
}

//! SVG pieces shared by every figure of the module: the document's head, text with
//! subscripts, lines, markers and the sizes of the house style (fonts, line width). The
//! [`crate::Figure`] renderer and custom drawings with [`crate::axes::Axes`] (the viewer's
//! machine figures) are both written with these.

use std::fmt::Write as _;

use crate::{Color, Dash, Marker, Style};

/// Width of a figure (px): one paper column of 8.5 cm.
pub const WIDTH: f64 = 420.0;
/// Font size of tick labels (px).
pub const FONT_TICK: f64 = 13.0;
/// Font size of axis titles (px).
pub const FONT_LABEL: f64 = 14.0;
/// Font size of legend entries (px).
pub const FONT_LEGEND: f64 = 12.5;
/// Font size of figure titles (px).
pub const FONT_TITLE: f64 = 15.0;
/// Average advance of a character as a fraction of the font size (DejaVu Sans and
/// Helvetica run about 0.55; the extra margin keeps estimated boxes on the safe side).
pub const CHAR_WIDTH: f64 = 0.6;
/// Width of data lines (px).
pub const LINE_WIDTH: f64 = 1.6;
/// The font families of every figure.
pub const FONT_FAMILY: &str = "DejaVu Sans, Helvetica, Arial, sans-serif";

/// Opens an SVG document of `width x height` px on `out`: the root element in the house
/// font, `<title>` (`name`), `<desc>` (`description`, when given) and a white background.
pub fn open(out: &mut String, width: f64, height: f64, name: &str, description: Option<&str>) {
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" \
         viewBox=\"0 0 {width} {height}\" font-family=\"{FONT_FAMILY}\">"
    );
    let _ = writeln!(out, "<title>{}</title>", escape(name));
    if let Some(d) = description {
        let _ = writeln!(out, "<desc>{}</desc>", escape(d));
    }
    let _ = writeln!(out, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
}

/// Closes the document opened by [`open`].
pub fn close(out: &mut String) {
    out.push_str("</svg>\n");
}

/// `text` with XML special characters escaped (no subscript markup).
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        push_escaped(&mut out, c);
    }
    out
}

/// Text with `_{xy}` subscripts as SVG content: Unicode subscripts where every character
/// has one, otherwise a lowered smaller `tspan`; XML special characters escaped. A `_`
/// without `{` is an underscore (scene names such as `paper_f20`).
pub fn markup(text: &str, font: f64) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(at) = rest.find("_{") {
        let Some(close) = rest[at..].find('}') else {
            break;
        };
        for c in rest[..at].chars() {
            push_escaped(&mut out, c);
        }
        let sub = &rest[at + 2..at + close];
        rest = &rest[at + close + 1..];
        match sub.chars().map(subscript).collect::<Option<String>>() {
            Some(unicode) => out.push_str(&unicode),
            None => {
                let shift = 0.3 * font;
                let _ = write!(
                    out,
                    "<tspan dy=\"{shift:.1}\" font-size=\"{:.1}\">",
                    0.72 * font
                );
                for c in sub.chars() {
                    push_escaped(&mut out, unsubscript(c).unwrap_or(c));
                }
                let _ = write!(out, "</tspan><tspan dy=\"{:.1}\"></tspan>", -shift);
            }
        }
    }
    for c in rest.chars() {
        push_escaped(&mut out, c);
    }
    out
}

/// Appends `c` to `out`, XML special characters escaped.
fn push_escaped(out: &mut String, c: char) {
    match c {
        '&' => out.push_str("&amp;"),
        '<' => out.push_str("&lt;"),
        '>' => out.push_str("&gt;"),
        '"' => out.push_str("&quot;"),
        _ => out.push(c),
    }
}

const SUBSCRIPTS: [(char, char); 33] = [
    ('0', '₀'),
    ('1', '₁'),
    ('2', '₂'),
    ('3', '₃'),
    ('4', '₄'),
    ('5', '₅'),
    ('6', '₆'),
    ('7', '₇'),
    ('8', '₈'),
    ('9', '₉'),
    ('a', 'ₐ'),
    ('e', 'ₑ'),
    ('o', 'ₒ'),
    ('x', 'ₓ'),
    ('h', 'ₕ'),
    ('k', 'ₖ'),
    ('l', 'ₗ'),
    ('m', 'ₘ'),
    ('n', 'ₙ'),
    ('p', 'ₚ'),
    ('s', 'ₛ'),
    ('t', 'ₜ'),
    ('i', 'ᵢ'),
    ('r', 'ᵣ'),
    ('u', 'ᵤ'),
    ('v', 'ᵥ'),
    ('j', 'ⱼ'),
    ('β', 'ᵦ'),
    ('ρ', 'ᵨ'),
    ('φ', 'ᵩ'),
    (',', ','),
    ('+', '₊'),
    ('=', '₌'),
];

/// The Unicode subscript of `c` (an existing subscript is kept).
fn subscript(c: char) -> Option<char> {
    if unsubscript(c).is_some() {
        return Some(c);
    }
    SUBSCRIPTS.iter().find(|(p, _)| *p == c).map(|(_, s)| *s)
}

/// The plain character of a Unicode subscript.
fn unsubscript(c: char) -> Option<char> {
    SUBSCRIPTS
        .iter()
        .find(|(p, s)| *s == c && *p != c)
        .map(|(p, _)| *p)
}

/// Estimated width of `text` at `font` (px), subscript markup not counted.
pub fn text_width(text: &str, font: f64) -> f64 {
    let n = text
        .chars()
        .filter(|c| !matches!(c, '_' | '{' | '}'))
        .count();
    n as f64 * CHAR_WIDTH * font
}

/// `text` in lines of at most `width` px at `font`, broken between words.
pub fn wrap(text: &str, width: f64, font: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        match lines.last_mut() {
            Some(line) if text_width(&format!("{line} {word}"), font) <= width => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// `label (unit)`, or the label alone.
pub(crate) fn axis_title(label: &str, unit: &str) -> String {
    if unit.is_empty() {
        label.to_string()
    } else {
        format!("{label} ({unit})")
    }
}

/// The colour as `#rrggbb`.
pub fn color(c: Color) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

/// The `stroke-dasharray` attribute of a dash (with its leading space; empty when solid).
pub fn dasharray(d: Dash) -> &'static str {
    match d {
        Dash::Solid => "",
        Dash::Dashed => " stroke-dasharray=\"6 3\"",
        Dash::Dotted => " stroke-dasharray=\"1.5 2.5\"",
        Dash::DashDot => " stroke-dasharray=\"7 3 1.5 3\"",
    }
}

/// Radius of a marker (px).
pub const MARKER: f64 = 3.4;

/// A marker `m` of colour `c` centred on `(x, y)` (px).
pub fn marker(out: &mut String, m: Marker, c: Color, (x, y): (f64, f64)) {
    let c = color(c);
    let r = MARKER;
    let _ = match m {
        Marker::Disc => writeln!(
            out,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"{r}\" fill=\"{c}\"/>"
        ),
        Marker::Ring => writeln!(
            out,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"{r}\" fill=\"white\" stroke=\"{c}\" stroke-width=\"1.4\"/>"
        ),
        Marker::Square => writeln!(
            out,
            "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"{c}\"/>",
            x - 0.85 * r,
            y - 0.85 * r,
            1.7 * r,
            1.7 * r
        ),
        Marker::Triangle => writeln!(
            out,
            "<path d=\"M{:.1} {:.1}L{:.1} {:.1}L{:.1} {:.1}Z\" fill=\"{c}\"/>",
            x,
            y - 1.15 * r,
            x + r,
            y + 0.75 * r,
            x - r,
            y + 0.75 * r
        ),
        Marker::TriangleDown => writeln!(
            out,
            "<path d=\"M{:.1} {:.1}L{:.1} {:.1}L{:.1} {:.1}Z\" fill=\"{c}\"/>",
            x,
            y + 1.15 * r,
            x + r,
            y - 0.75 * r,
            x - r,
            y - 0.75 * r
        ),
        Marker::Diamond => writeln!(
            out,
            "<path d=\"M{:.1} {:.1}L{:.1} {:.1}L{:.1} {:.1}L{:.1} {:.1}Z\" fill=\"{c}\"/>",
            x,
            y - 1.2 * r,
            x + r,
            y,
            x,
            y + 1.2 * r,
            x - r,
            y
        ),
    };
}

/// A polyline through `points` (px) in the line of style `s` (colour, dash, [`LINE_WIDTH`]);
/// nothing for fewer than two points.
pub fn polyline(out: &mut String, points: &[(f64, f64)], s: Style) {
    if points.len() < 2 {
        return;
    }
    let _ = write!(out, "<polyline points=\"");
    for (k, (x, y)) in points.iter().enumerate() {
        let sep = if k == 0 { "" } else { " " };
        let _ = write!(out, "{sep}{x:.1},{y:.1}");
    }
    let _ = writeln!(
        out,
        "\" fill=\"none\" stroke=\"{}\" stroke-width=\"{LINE_WIDTH}\" stroke-linejoin=\"round\"{}/>",
        color(s.color),
        dasharray(s.dash)
    );
}

/// `text` (with `_{..}` subscripts, see [`markup`]) at `(x, y)` (px, the baseline) in `font`
/// px, anchored `start`, `middle` or `end`.
pub fn text(out: &mut String, (x, y): (f64, f64), font: f64, anchor: &str, text: &str) {
    let _ = writeln!(
        out,
        "<text x=\"{x:.1}\" y=\"{y:.1}\" font-size=\"{font}\" text-anchor=\"{anchor}\">{}</text>",
        markup(text, font)
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subscripts() {
        assert_eq!(markup("F_{a1}", 14.0), "Fₐ₁");
        assert_eq!(markup("δ_{max}", 14.0), "δₘₐₓ");
        assert_eq!(markup("M_{ρ} ρ̈", 14.0), "Mᵨ ρ̈");
        assert_eq!(markup("paper_f20", 14.0), "paper_f20");
        let p = markup("P_{B1} (N)", 10.0);
        assert!(
            p.starts_with("P<tspan dy=\"3.0\" font-size=\"7.2\">B1</tspan>"),
            "{p}"
        );
        assert!(p.ends_with(" (N)"), "{p}");
        assert_eq!(markup("a<b & c", 14.0), "a&lt;b &amp; c");
    }
}

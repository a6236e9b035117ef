//! Figures for papers: the one plot module of flexprr, for runs, studies, work-precision
//! diagrams and the viewer's machine figures. It knows no simulation: it draws numbers.
//!
//! A [`Figure`] is a stack of [`Panel`]s sharing one x [`Axis`]; a panel has its own y axis
//! and [`Series`] drawn in a [`Style`] (colour, dash, marker). [`Figure::to_svg`] writes a
//! plain SVG sized for one column of a paper (8.5 cm at about 420 px, so 13-15 px text reads
//! as 7-8 pt), following these conventions (`docs/plots.md`):
//!
//! * every axis shows its values with an SI prefix chosen from its largest magnitude
//!   ([`ticks::scale_for`]: `mm`, `µm`, `kN`), one prefix per axis;
//! * ticks are multiples of `1, 2, 5 x 10^k`, labelled with exactly the decimals the step
//!   needs, no trailing zeros and no `−0` ([`ticks::tick_label`]); logarithmic axes are
//!   labelled `10⁻⁶`;
//! * labels take `_{xy}` for subscripts, written as Unicode subscripts where they exist
//!   (`F_{a1}` -> `Fₐ₁`) and as lowered smaller text where they do not (`P_{B}`); a bare `_`
//!   stays an underscore;
//! * the legend goes into the corner of the plot area that no line or marker touches, or
//!   above the plot area when every corner is taken, so it never covers data; its samples
//!   are drawn with the series' own colour, dash and marker;
//! * series longer than four points a pixel column are decimated to the first, lowest,
//!   highest and last point of every pixel column ([`decimate::decimate`]), which draws the
//!   same at the figure's size and keeps each series' extremes;
//! * failed cases ([`Series::failed`]) are hollow red circles in a strip along the lower
//!   edge of the plot area, below all data, at their x (one circle per x, with the count
//!   `×n` beside it where several cases failed there), with a legend entry.
//!
//! ```
//! use flexprr_plot::{Axis, Figure, Panel, Series, Style};
//! let t = [0.0, 0.1, 0.2];
//! let w = [0.0, 1.5e-4, -0.5e-4];
//! let figure = Figure::new(Axis::new("t", "s"))
//!     .title("Deflection at ξ = 0.5")
//!     .panel(Panel::new(Axis::new("w_{1}", "m")).series(Series::new(
//!         "with axial force",
//!         &t,
//!         &w,
//!         Style::nth(0),
//!     )));
//! let svg = figure.to_svg().unwrap();
//! assert!(svg.contains("(µm)") && svg.contains("(ms)") && svg.contains("w₁"));
//! ```

pub mod axes;
pub mod decimate;
mod legend;
mod render;
pub mod svg;
pub mod ticks;

use std::path::Path;

/// An RGB colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Color(pub u8, pub u8, pub u8);

/// Line colours, in turn (Okabe & Ito's colour-blind-safe set, "Color Universal Design",
/// 2002, without its yellow, which is too light on white).
pub const PALETTE: [Color; 7] = [
    Color(0, 114, 178),
    Color(230, 159, 0),
    Color(0, 158, 115),
    Color(204, 121, 167),
    Color(86, 180, 233),
    Color(0, 0, 0),
    Color(213, 94, 0),
];

/// The colour of failed cases.
pub const FAILED_COLOR: Color = Color(220, 0, 0);

/// How a line is dashed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dash {
    /// Continuous.
    Solid,
    /// Long dashes.
    Dashed,
    /// Dots.
    Dotted,
    /// Dash and dot.
    DashDot,
}

/// A point marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Disc,
    /// Hollow circle.
    Ring,
    /// Filled square.
    Square,
    /// Filled triangle, apex up.
    Triangle,
    /// Filled diamond.
    Diamond,
    /// Filled triangle, apex down.
    TriangleDown,
}

impl Marker {
    /// Markers in turn, one per line, so lines drawn on top of each other stay apart (the
    /// hollow [`Marker::Ring`] is kept for failed cases).
    pub const CYCLE: [Marker; 5] = [
        Marker::Disc,
        Marker::Square,
        Marker::Triangle,
        Marker::Diamond,
        Marker::TriangleDown,
    ];
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Style {
    /// Colour of line and marker.
    pub color: Color,
    /// Dash of the line.
    pub dash: Dash,
    /// Marker on every point, if any.
    pub marker: Option<Marker>,
    /// Whether the points are joined by a line.
    pub line: bool,
}

impl Style {
    /// The `k`-th colour of [`PALETTE`], solid, without markers.
    pub fn nth(k: usize) -> Self {
        Self {
            color: PALETTE[k % PALETTE.len()],
            dash: Dash::Solid,
            marker: None,
            line: true,
        }
    }
    /// The same style with dash `dash`.
    pub fn dash(mut self, dash: Dash) -> Self {
        self.dash = dash;
        self
    }
    /// The same style with markers `marker` on the points.
    pub fn marker(mut self, marker: Marker) -> Self {
        self.marker = Some(marker);
        self
    }
}

/// Linear or logarithmic axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear, with an SI prefix on the unit.
    Linear,
    /// Base-10 logarithmic (non-positive values are not drawn), unit without prefix.
    Log,
}

/// An axis: what it shows (with `_` subscripts) and the SI unit of the data.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Symbol or words, `_{..}` for subscripts, e.g. `w_{1}`, `platform mass`.
    pub label: String,
    /// SI unit of the data (`m`, `N`, `rad/s²`; empty for ratios).
    pub unit: String,
    /// Linear or logarithmic.
    pub scale: Scale,
}

impl Axis {
    /// A linear axis.
    pub fn new(label: impl Into<String>, unit: impl Into<String>) -> Self {
        Self {
            label: label.into(),
            unit: unit.into(),
            scale: Scale::Linear,
        }
    }
    /// A logarithmic axis.
    pub fn log(label: impl Into<String>, unit: impl Into<String>) -> Self {
        Self {
            scale: Scale::Log,
            ..Self::new(label, unit)
        }
    }
}

/// Where a series' points are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// At their values.
    Data,
    /// In a strip along the lower edge of the plot area, below the data, at their x (failed
    /// cases: they have no y).
    LowerEdge,
}

/// One series: points, legend label and style.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label (empty: no legend entry).
    pub label: String,
    /// Abscissae, SI units.
    pub x: Vec<f64>,
    /// Ordinates, SI units (not finite: a gap).
    pub y: Vec<f64>,
    /// How it is drawn.
    pub style: Style,
    /// Where it is drawn.
    pub placement: Placement,
}

impl Series {
    /// A series of points `(x[k], y[k])`.
    pub fn new(label: impl Into<String>, x: &[f64], y: &[f64], style: Style) -> Self {
        Self {
            label: label.into(),
            x: x.to_vec(),
            y: y.to_vec(),
            style,
            placement: Placement::Data,
        }
    }
    /// Failed cases at abscissae `x`: hollow red circles in the strip along the lower edge,
    /// no line.
    pub fn failed(label: impl Into<String>, x: Vec<f64>) -> Self {
        Self {
            label: label.into(),
            y: vec![f64::NAN; x.len()],
            x,
            style: Style {
                color: FAILED_COLOR,
                dash: Dash::Solid,
                marker: Some(Marker::Ring),
                line: false,
            },
            placement: Placement::LowerEdge,
        }
    }
}

/// One panel: a y axis and its series.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// The y axis.
    pub y: Axis,
    /// The series, drawn in order.
    pub series: Vec<Series>,
}

impl Panel {
    /// A panel without series.
    pub fn new(y: Axis) -> Self {
        Self {
            y,
            series: Vec::new(),
        }
    }
    /// The panel with one more series.
    pub fn series(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }
}

/// A figure: panels stacked vertically, sharing the x axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Title drawn above the panels (none for a figure with a caption in the paper).
    pub title: Option<String>,
    /// A description stored in the SVG (`<desc>`), not drawn: scene, source.
    pub description: Option<String>,
    /// The shared x axis.
    pub x: Axis,
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
}

impl Figure {
    /// A figure without panels.
    pub fn new(x: Axis) -> Self {
        Self {
            title: None,
            description: None,
            x,
            panels: Vec::new(),
        }
    }
    /// The figure with a title.
    pub fn title(mut self, title: impl Into<String>) -> Self {
        self.title = Some(title.into());
        self
    }
    /// The figure with a description stored in the file.
    pub fn description(mut self, description: impl Into<String>) -> Self {
        self.description = Some(description.into());
        self
    }
    /// The figure with one more panel.
    pub fn panel(mut self, panel: Panel) -> Self {
        self.panels.push(panel);
        self
    }

    /// The figure as SVG text.
    ///
    /// # Errors
    /// A one-line message naming the figure and the series if a series has different
    /// numbers of x and y values, or the figure has no panel.
    pub fn to_svg(&self) -> Result<String, String> {
        render::render(self)
    }

    /// Writes the figure as an SVG file.
    ///
    /// # Errors
    /// As [`Figure::to_svg`], or the file cannot be written (the message names it).
    pub fn write_svg(&self, path: &Path) -> Result<(), String> {
        let text = self
            .to_svg()
            .map_err(|e| format!("plot {}: {e}", path.display()))?;
        std::fs::write(path, text).map_err(|e| format!("plot {}: {e}", path.display()))
    }
}

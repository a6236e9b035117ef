//! The named inputs and outputs of a linear model, and their spelling on the command line
//! and in files (`slider_force:2`, `point_force:1@0.125`, `deflection:1@0.5`).

use std::fmt;
use std::str::FromStr;

use crate::LinearError;

/// An input of a linear model: a force (N).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Input {
    /// A force on slider `i` (0-based) along its guide.
    SliderForce(usize),
    /// A transverse point force on link `link` (0-based) at `xi` along it, along the
    /// chord normal `n` (the impact of a modal hammer).
    PointForce {
        /// The link (0-based).
        link: usize,
        /// Where along it (0..1).
        xi: f64,
    },
}

/// A platform coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// `x` (m).
    X,
    /// `y` (m).
    Y,
    /// `phi` (rad).
    Phi,
}

/// An output of a linear model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Output {
    /// Slider `i`'s position `rho_i` (m).
    SliderPosition(usize),
    /// A platform coordinate (m or rad).
    Platform(Axis),
    /// The transverse deflection `w` of link `link` at `xi`, from its chord (m).
    Deflection {
        /// The link (0-based).
        link: usize,
        /// Where along it (0..1).
        xi: f64,
    },
    /// The slope `dw/dx` of link `link` at `xi` (rad).
    Slope {
        /// The link (0-based).
        link: usize,
        /// Where along it (0..1).
        xi: f64,
    },
    /// The absolute acceleration of the point of link `link` at `xi` along the chord normal
    /// (m/s^2): what an accelerometer on the link reads.
    Acceleration {
        /// The link (0-based).
        link: usize,
        /// Where along it (0..1).
        xi: f64,
    },
}

/// `link@xi` with a 1-based link and `xi` in `[0, 1]`.
fn link_point(text: &str, what: &str) -> Result<(usize, f64), LinearError> {
    let bad = |rule: &str| LinearError::Channel(format!("{what}:{text}: {rule}"));
    let (link, xi) = text
        .split_once('@')
        .ok_or_else(|| bad("expected LINK@XI, e.g. 1@0.5 (link 1, 2 or 3; xi from 0 to 1)"))?;
    let link: usize = link
        .trim()
        .parse()
        .map_err(|_| bad("the link must be 1, 2 or 3"))?;
    if !(1..=3).contains(&link) {
        return Err(bad("the link must be 1, 2 or 3"));
    }
    let xi: f64 = xi
        .trim()
        .parse()
        .map_err(|_| bad("xi must be a number from 0 to 1"))?;
    if !(0.0..=1.0).contains(&xi) {
        return Err(bad("xi must be a number from 0 to 1"));
    }
    Ok((link - 1, xi))
}

/// A 1-based slider number.
fn slider(text: &str, what: &str) -> Result<usize, LinearError> {
    match text.trim().parse::<usize>() {
        Ok(i @ 1..=3) => Ok(i - 1),
        _ => Err(LinearError::Channel(format!(
            "{what}:{text}: the slider must be 1, 2 or 3"
        ))),
    }
}

impl FromStr for Input {
    type Err = LinearError;
    /// `slider_force:I` or `point_force:LINK@XI` (1-based slider and link).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().split_once(':') {
            Some(("slider_force", i)) => Ok(Input::SliderForce(slider(i, "slider_force")?)),
            Some(("point_force", p)) => {
                let (link, xi) = link_point(p, "point_force")?;
                Ok(Input::PointForce { link, xi })
            }
            _ => Err(LinearError::Channel(format!(
                "unknown input {s:?}: expected slider_force:I or point_force:LINK@XI"
            ))),
        }
    }
}

impl FromStr for Output {
    type Err = LinearError;
    /// `slider:I`, `platform:x|y|phi`, `deflection:LINK@XI`, `slope:LINK@XI` or
    /// `acceleration:LINK@XI`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let unknown = || {
            LinearError::Channel(format!(
                "unknown output {s:?}: expected slider:I, platform:x|y|phi, deflection:LINK@XI, \
                 slope:LINK@XI or acceleration:LINK@XI"
            ))
        };
        let (kind, rest) = s.trim().split_once(':').ok_or_else(unknown)?;
        Ok(match kind {
            "slider" => Output::SliderPosition(slider(rest, "slider")?),
            "platform" => Output::Platform(match rest.trim() {
                "x" => Axis::X,
                "y" => Axis::Y,
                "phi" => Axis::Phi,
                _ => return Err(unknown()),
            }),
            "deflection" | "slope" | "acceleration" => {
                let (link, xi) = link_point(rest, kind)?;
                match kind {
                    "deflection" => Output::Deflection { link, xi },
                    "slope" => Output::Slope { link, xi },
                    _ => Output::Acceleration { link, xi },
                }
            }
            _ => return Err(unknown()),
        })
    }
}

impl fmt::Display for Input {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Input::SliderForce(i) => write!(f, "slider_force:{}", i + 1),
            Input::PointForce { link, xi } => write!(f, "point_force:{}@{xi}", link + 1),
        }
    }
}

impl fmt::Display for Output {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Output::SliderPosition(i) => write!(f, "slider:{}", i + 1),
            Output::Platform(Axis::X) => f.write_str("platform:x"),
            Output::Platform(Axis::Y) => f.write_str("platform:y"),
            Output::Platform(Axis::Phi) => f.write_str("platform:phi"),
            Output::Deflection { link, xi } => write!(f, "deflection:{}@{xi}", link + 1),
            Output::Slope { link, xi } => write!(f, "slope:{}@{xi}", link + 1),
            Output::Acceleration { link, xi } => write!(f, "acceleration:{}@{xi}", link + 1),
        }
    }
}

impl Input {
    /// The unit (`N`).
    pub fn unit(&self) -> &'static str {
        "N"
    }
}

impl Output {
    /// The SI unit.
    pub fn unit(&self) -> &'static str {
        match self {
            Output::SliderPosition(_) | Output::Deflection { .. } => "m",
            Output::Platform(Axis::Phi) | Output::Slope { .. } => "rad",
            Output::Platform(_) => "m",
            Output::Acceleration { .. } => "m/s^2",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_parse_and_print_back() {
        for text in [
            "slider_force:2",
            "point_force:1@0.125",
            "slider:3",
            "platform:phi",
            "deflection:2@0.5",
            "slope:3@0",
            "acceleration:1@1",
        ] {
            let printed = match text.parse::<Input>() {
                Ok(input) => input.to_string(),
                Err(_) => text.parse::<Output>().unwrap().to_string(),
            };
            assert_eq!(printed, text);
        }
        for bad in [
            "slider_force:4",
            "point_force:1@1.5",
            "deflection:0@0.5",
            "platform:z",
            "x",
        ] {
            let e = bad
                .parse::<Output>()
                .err()
                .zip(bad.parse::<Input>().err())
                .expect("refused");
            assert!(!e.0.to_string().is_empty() && !e.1.to_string().contains('\n'));
        }
    }
}

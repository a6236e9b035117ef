//! Typed identities of what a model reports: a [`Column`] is a quantity with its link, mode
//! and position along the link, and a [`Table`] is a time series of such columns. The CSV
//! header is rendered from the identity once; nothing parses a header back. They live here,
//! beside the models, so that a model produces its own tables
//! ([`crate::SceneModel::tables`]) and the run layer writes them without knowing the model.

use std::fmt;

/// What a column holds. Each quantity knows its header stem, unit and plot symbol.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Quantity {
    /// Time (s).
    Time,
    /// Platform position x (m).
    PlatformX,
    /// Platform position y (m).
    PlatformY,
    /// Platform orientation phi (rad).
    PlatformPhi,
    /// Slider position rho (m).
    SliderPosition,
    /// Slider velocity (m/s).
    SliderVelocity,
    /// Slider acceleration (m/s^2).
    SliderAcceleration,
    /// Link angle beta (rad).
    LinkAngle,
    /// Link angular velocity (rad/s).
    LinkAngularVelocity,
    /// Link angular acceleration (rad/s^2).
    LinkAngularAcceleration,
    /// Driving force of the rigid inverse dynamics (N).
    DrivingForceRigid,
    /// Driving force with the links' elastic inertia (N).
    DrivingForceFlexible,
    /// Flexible minus rigid driving force (N).
    DrivingForceDifference,
    /// Force of the slider on the link at B, x (N).
    ReactionBx,
    /// Force of the slider on the link at B, y (N).
    ReactionBy,
    /// Force of the platform on the link at C, x (N).
    ReactionCx,
    /// Force of the platform on the link at C, y (N).
    ReactionCy,
    /// Axial force at end B (N, tension positive).
    AxialForceB,
    /// Axial force at end C (N, tension positive).
    AxialForceC,
    /// Driving force of the coupled model (N).
    CoupledDrivingForce,
    /// Natural frequency along the motion (Hz).
    Frequency,
    /// Modal coordinate eta (m).
    ModalCoordinate,
    /// Transverse deflection w at xi (m).
    Deflection,
    /// Transverse deflection w at xi without axial force (m).
    DeflectionWithoutAxialForce,
    /// Modal force from the slider acceleration (N).
    ModalForceRho,
    /// Modal force from the link's angular acceleration (N).
    ModalForceBeta,
    /// The paper's coupling modal force F_fg (N).
    ModalForceFg,
    /// Rigid-body kinetic energy (J).
    RigidKineticEnergy,
    /// Strain energy of a link (J).
    StrainEnergy,
    /// Elastic kinetic energy of a link (J).
    ElasticKineticEnergy,
    /// Platform deviation from its nominal path, x (m).
    DeviationX,
    /// Platform deviation, y (m).
    DeviationY,
    /// Platform deviation, phi (rad).
    DeviationPhi,
    /// Platform deviation with the quasi-static axial stretch, x (m).
    DeviationXWithStretch,
    /// Platform deviation with the quasi-static axial stretch, y (m).
    DeviationYWithStretch,
    /// Platform deviation with the quasi-static axial stretch, phi (rad).
    DeviationPhiWithStretch,
    /// Largest chord shortening over the links (m).
    MaxChordShortening,
    /// Kinetic energy of the whole moving machine model (links and platform, J).
    KineticEnergy,
    /// Type-II measure of the (deflected) chords (dimensionless).
    TypeIIMeasure,
    /// Slider tracking error `rho_ref - rho` (m): commanded minus actual slider position.
    SliderError,
    /// Platform tracking error, x: commanded minus actual (m).
    PlatformErrorX,
    /// Platform tracking error, y: commanded minus actual (m).
    PlatformErrorY,
    /// Platform tracking error, phi: commanded minus actual (rad).
    PlatformErrorPhi,
    /// The controller's force command to a slider's actuator (N).
    ForceCommand,
    /// The force an actuator exerts on its slider along the guide (N).
    ActuatorForce,
    /// A quantity defined by a layer above (a motor's torque, a patch's voltage, a
    /// whole-machine frequency, or one registered from outside): its own spelling.
    Named(NamedQuantity),
}

/// A quantity defined outside this crate, with how it is written: header stem, optional
/// suffix after the indices, unit in the header, plot symbol and SI unit.
///
/// ```
/// use flexprr_dynamics::{Column, NamedQuantity, Quantity};
///
/// const TIP_SPEED: Quantity = Quantity::Named(NamedQuantity::new("tip_speed", "m_s", "v", "m/s"));
/// assert_eq!(Column::link(TIP_SPEED, 0).header(), "tip_speed_1_m_s");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NamedQuantity {
    /// Header stem (`motor_torque`).
    pub stem: &'static str,
    /// Suffix after the indices (`uncontrolled` in `w_1_xi0.5_uncontrolled_m`).
    pub suffix: Option<&'static str>,
    /// Unit as written in the header (`N_m`).
    pub header_unit: &'static str,
    /// Plot symbol (`τ`).
    pub symbol: &'static str,
    /// SI unit in plot labels (`N·m`).
    pub unit: &'static str,
}

impl NamedQuantity {
    /// A quantity without a suffix.
    pub const fn new(
        stem: &'static str,
        header_unit: &'static str,
        symbol: &'static str,
        unit: &'static str,
    ) -> Self {
        Self {
            stem,
            suffix: None,
            header_unit,
            symbol,
            unit,
        }
    }

    /// The same quantity with `suffix` after the indices.
    pub const fn with_suffix(self, suffix: &'static str) -> Self {
        Self {
            suffix: Some(suffix),
            ..self
        }
    }
}

/// How a quantity is written: header stem, optional suffix after the indices, unit, and the
/// plot symbol with its SI unit.
struct Spelling {
    stem: &'static str,
    suffix: Option<&'static str>,
    header_unit: &'static str,
    symbol: &'static str,
    unit: &'static str,
}

const fn sp(
    stem: &'static str,
    suffix: Option<&'static str>,
    header_unit: &'static str,
    symbol: &'static str,
    unit: &'static str,
) -> Spelling {
    Spelling {
        stem,
        suffix,
        header_unit,
        symbol,
        unit,
    }
}

impl Quantity {
    fn spelling(self) -> Spelling {
        use Quantity as Q;
        match self {
            Q::Time => sp("t", None, "s", "t", "s"),
            Q::PlatformX => sp("x", None, "m", "x", "m"),
            Q::PlatformY => sp("y", None, "m", "y", "m"),
            Q::PlatformPhi => sp("phi", None, "rad", "φ", "rad"),
            Q::SliderPosition => sp("rho", None, "m", "ρ", "m"),
            Q::SliderVelocity => sp("rho_dot", None, "m_s", "ρ̇", "m/s"),
            Q::SliderAcceleration => sp("rho_ddot", None, "m_s2", "ρ̈", "m/s²"),
            Q::LinkAngle => sp("beta", None, "rad", "β", "rad"),
            Q::LinkAngularVelocity => sp("beta_dot", None, "rad_s", "β̇", "rad/s"),
            Q::LinkAngularAcceleration => sp("beta_ddot", None, "rad_s2", "β̈", "rad/s²"),
            Q::DrivingForceRigid => sp("F_a", Some("rigid"), "N", "F_a", "N"),
            Q::DrivingForceFlexible => sp("F_a", Some("flexible"), "N", "F_a", "N"),
            Q::DrivingForceDifference => sp("F_a", Some("difference"), "N", "ΔF_a", "N"),
            Q::ReactionBx => sp("F_B", Some("x"), "N", "F_Bx", "N"),
            Q::ReactionBy => sp("F_B", Some("y"), "N", "F_By", "N"),
            Q::ReactionCx => sp("F_C", Some("x"), "N", "F_Cx", "N"),
            Q::ReactionCy => sp("F_C", Some("y"), "N", "F_Cy", "N"),
            Q::AxialForceB => sp("P_B", None, "N", "P_B", "N"),
            Q::AxialForceC => sp("P_C", None, "N", "P_C", "N"),
            Q::CoupledDrivingForce => sp("F_a", None, "N", "F_a", "N"),
            Q::Frequency => sp("f", None, "Hz", "f", "Hz"),
            Q::ModalCoordinate => sp("eta", None, "m", "η", "m"),
            Q::Deflection => sp("w", None, "m", "w", "m"),
            Q::DeflectionWithoutAxialForce => sp("w", Some("no_axial"), "m", "w", "m"),
            Q::ModalForceRho => sp("F_rho", None, "N", "F_ρ", "N"),
            Q::ModalForceBeta => sp("F_beta", None, "N", "F_β", "N"),
            Q::ModalForceFg => sp("F_fg", None, "N", "F_fg", "N"),
            Q::RigidKineticEnergy => sp("rigid_kinetic", None, "J", "T_rigid", "J"),
            Q::StrainEnergy => sp("strain", None, "J", "U", "J"),
            Q::ElasticKineticEnergy => sp("elastic_kinetic", None, "J", "T_elastic", "J"),
            Q::DeviationX => sp("dx", None, "m", "Δx", "m"),
            Q::DeviationY => sp("dy", None, "m", "Δy", "m"),
            Q::DeviationPhi => sp("dphi", None, "rad", "Δφ", "rad"),
            Q::DeviationXWithStretch => sp("dx", Some("with_stretch"), "m", "Δx", "m"),
            Q::DeviationYWithStretch => sp("dy", Some("with_stretch"), "m", "Δy", "m"),
            Q::DeviationPhiWithStretch => sp("dphi", Some("with_stretch"), "rad", "Δφ", "rad"),
            Q::MaxChordShortening => sp("max_chord_shortening", None, "m", "δ_max", "m"),
            Q::KineticEnergy => sp("kinetic", None, "J", "T", "J"),
            Q::TypeIIMeasure => sp("type_ii", None, "measure", "μ_II", "1"),
            Q::SliderError => sp("slider_error", None, "m", "e_ρ", "m"),
            Q::PlatformErrorX => sp("platform_error_x", None, "m", "e_x", "m"),
            Q::PlatformErrorY => sp("platform_error_y", None, "m", "e_y", "m"),
            Q::PlatformErrorPhi => sp("platform_error_phi", None, "rad", "e_φ", "rad"),
            Q::Named(n) => sp(n.stem, n.suffix, n.header_unit, n.symbol, n.unit),
            Q::ForceCommand => sp("force_command", None, "N", "F_c", "N"),
            Q::ActuatorForce => sp("actuator_force", None, "N", "F", "N"),
        }
    }

    /// The SI unit, as written in plot labels (`m`, `N`, `rad/s²`).
    pub fn unit(self) -> &'static str {
        self.spelling().unit
    }

    /// The symbol used in plot labels (Unicode Greek: `ρ`, `β`, `η`).
    pub fn symbol(self) -> &'static str {
        self.spelling().symbol
    }
}

/// One output column: a quantity, and where it applies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    /// What it holds.
    pub quantity: Quantity,
    /// Link, 0-based.
    pub link: Option<usize>,
    /// Mode, 0-based.
    pub mode: Option<usize>,
    /// Position along the link (0..1).
    pub xi: Option<f64>,
}

impl Column {
    /// A column of a machine-wide quantity.
    pub const fn of(quantity: Quantity) -> Self {
        Self {
            quantity,
            link: None,
            mode: None,
            xi: None,
        }
    }
    /// A column of link `link` (0-based).
    pub const fn link(quantity: Quantity, link: usize) -> Self {
        Self {
            quantity,
            link: Some(link),
            mode: None,
            xi: None,
        }
    }
    /// A column of mode `mode` of link `link` (both 0-based).
    pub const fn mode(quantity: Quantity, link: usize, mode: usize) -> Self {
        Self {
            quantity,
            link: Some(link),
            mode: Some(mode),
            xi: None,
        }
    }
    /// A column at position `xi` along link `link`.
    pub const fn at(quantity: Quantity, link: usize, xi: f64) -> Self {
        Self {
            quantity,
            link: Some(link),
            mode: None,
            xi: Some(xi),
        }
    }

    /// The CSV header: `stem[_link][_mode][_xi<xi>][_suffix]_unit`, links and modes
    /// 1-based (`rho_1_m`, `f_1_2_Hz`, `w_3_xi0.5_no_axial_m`).
    pub fn header(&self) -> String {
        let s = self.quantity.spelling();
        let mut h = String::from(s.stem);
        if let Some(i) = self.link {
            h.push_str(&format!("_{}", i + 1));
        }
        if let Some(j) = self.mode {
            h.push_str(&format!("_{}", j + 1));
        }
        if let Some(xi) = self.xi {
            h.push_str(&format!("_xi{xi}"));
        }
        if let Some(suffix) = s.suffix {
            h.push('_');
            h.push_str(suffix);
        }
        h.push('_');
        h.push_str(s.header_unit);
        h
    }

    /// A label for plots and messages, with Unicode symbols and 1-based subscripts:
    /// `ρ₁`, `f₁,₂`, `w₂(ξ = 0.5)`.
    pub fn label(&self) -> String {
        let mut l = String::from(self.quantity.symbol());
        let sub = |n: usize| -> String {
            n.to_string()
                .chars()
                .map(|c| char::from_u32(0x2080 + c.to_digit(10).unwrap_or(0)).unwrap_or(c))
                .collect()
        };
        match (self.link, self.mode) {
            (Some(i), Some(j)) => l.push_str(&format!("{},{}", sub(i + 1), sub(j + 1))),
            (Some(i), None) => l.push_str(&sub(i + 1)),
            _ => {}
        }
        if let Some(xi) = self.xi {
            l.push_str(&format!("(ξ = {xi})"));
        }
        l
    }
}

impl fmt::Display for Column {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.header())
    }
}

/// A time-series table: the time column first, then typed columns.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// File stem (`kinematics`, `deflections`, ...).
    pub name: String,
    /// Column identities, time first.
    pub columns: Vec<Column>,
    /// Column data, `data[column][row]`.
    pub data: Vec<Vec<f64>>,
}

impl Table {
    /// A table with only the time column.
    pub fn new(name: &str, t: &[f64]) -> Self {
        Self {
            name: name.to_string(),
            columns: vec![Column::of(Quantity::Time)],
            data: vec![t.to_vec()],
        }
    }
    /// Appends a column.
    pub fn push(&mut self, column: Column, values: Vec<f64>) {
        self.columns.push(column);
        self.data.push(values);
    }
    /// The values of `column`.
    pub fn get(&self, column: &Column) -> Option<&[f64]> {
        self.columns
            .iter()
            .position(|c| c == column)
            .map(|i| self.data[i].as_slice())
    }
    /// The values of the column whose CSV header is `header` (for readers of the files).
    pub fn column(&self, header: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .position(|c| c.header() == header)
            .map(|i| self.data[i].as_slice())
    }
    /// The CSV headers, rendered from the column identities.
    pub fn headers(&self) -> Vec<String> {
        self.columns.iter().map(Column::header).collect()
    }
    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }
    /// The time column.
    pub fn time(&self) -> &[f64] {
        &self.data[0]
    }
}

#[cfg(test)]
mod tests {
    use super::{Column, Quantity as Q};

    #[test]
    fn headers_follow_the_documented_pattern() {
        assert_eq!(Column::of(Q::Time).header(), "t_s");
        assert_eq!(Column::link(Q::SliderVelocity, 0).header(), "rho_dot_1_m_s");
        assert_eq!(
            Column::link(Q::DrivingForceRigid, 2).header(),
            "F_a_3_rigid_N"
        );
        assert_eq!(Column::link(Q::ReactionCy, 1).header(), "F_C_2_y_N");
        assert_eq!(Column::mode(Q::Frequency, 0, 1).header(), "f_1_2_Hz");
        assert_eq!(
            Column::at(Q::DeflectionWithoutAxialForce, 2, 0.5).header(),
            "w_3_xi0.5_no_axial_m"
        );
        assert_eq!(
            Column::of(Q::DeviationPhiWithStretch).header(),
            "dphi_with_stretch_rad"
        );
        assert_eq!(Column::mode(Q::ModalCoordinate, 1, 2).label(), "η₂,₃");
        assert_eq!(Column::link(Q::SliderError, 0).header(), "slider_error_1_m");
        assert_eq!(
            Column::of(Q::PlatformErrorPhi).header(),
            "platform_error_phi_rad"
        );
    }
}

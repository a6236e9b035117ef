//! What a model with axially rigid chords gives a linear analysis at rest so that its chords
//! become the links' axial springs `EA / l`: the platform then has three coordinates of its
//! own, its deviation from the pose the rigid chords impose (docs/linear.md, "Elastic
//! chords").

use faer::Mat;

/// Axial coordinates per link that the relaxed chords add beyond the platform's deviation:
/// the links' fixed-fixed axial modes `sin(k pi xi)`, `k = 1 ..`, which distribute their
/// axial inertia (docs/linear.md, "Elastic chords"). Three put the platform modes within
/// 0.05 % of an axially exact reference where one puts them within 0.2 % and none within
/// 0.9 %.
pub const AXIAL_MODES: usize = 3;

/// The relaxation of a model's rigid chords into axial springs, at a state at rest.
///
/// With `z` the model's coordinates ([`crate::SceneModel::modes`]) and `p` the platform
/// pose, the rigid chords impose `p = P z` (to first order at rest). Relaxed, the platform's
/// deviation `d = p - P z` is free, the chords stretch by `e = G d` (`G` the rows
/// `e_i^T dC_i/dp` of the chord directions at the platform joints) and store
/// `e^T diag(EA_i / l_i) e / 2`. The kinetic energy of the whole machine (sliders,
/// platform, and the links with their axial and transverse rigid motion interpolated
/// linearly between the joints plus the bending `w`) in `(z, d)` is
///
/// ```text
/// T = z'^T M z' / 2 + z'^T X d' + d'^T M_d d' / 2
/// ```
///
/// where `M` is the rigid model's own mass matrix. A linear model `M z'' = F(z, z', c) + B u`
/// becomes `[M X; X^T M_d] [z''; d''] = [F + B u; -K_d d + B_d u]` with `K_d = G^T diag(EA/l)
/// G`, and it returns to the rigid one as `EA -> infinity`.
#[derive(Debug, Clone)]
pub struct ChordCompliance {
    /// `M`: the mass matrix of the model's coordinates at the state (`n x n`).
    pub mass: Mat<f64>,
    /// `X`: the kinetic coupling of the coordinates' rates with the platform deviation's
    /// (`n x 3`).
    pub coupling: Mat<f64>,
    /// `M_d`: the mass of the platform deviation: the platform's, plus the links' seen at
    /// their platform joints (`3 x 3`).
    pub deviation_mass: Mat<f64>,
    /// `K_d = G^T diag(EA_i / l_i) G` (`3 x 3`; N/m, N, N m).
    pub stiffness: Mat<f64>,
    /// Damping of the added coordinates (the same size as the stiffness): each damped in its
    /// own motion at the scene's modal damping ratio of the links' highest bending mode,
    /// `c_qq = 2 zeta sqrt(k_qq m_qq)` (zero without damping).
    pub damping: Mat<f64>,
    /// For each link, `dC_i/dp^T n_i`: the generalized force on the deviation of a unit
    /// force at the platform joint along the link's chord normal. A transverse force at
    /// `xi` along the link contributes `xi` times it (the linear interpolation of the
    /// joints' motion); the acceleration of that point along the normal has `xi` times it
    /// as its gradient in `d''`.
    pub joint_normal: [[f64; 3]; 3],
}

impl ChordCompliance {
    /// Number of coordinates the relaxation adds.
    pub fn size(&self) -> usize {
        self.deviation_mass.nrows()
    }
}

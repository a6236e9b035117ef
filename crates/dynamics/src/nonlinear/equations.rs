//! The equations of motion of [`NonlinearSystem`] in its generalized coordinates `z`:
//!
//! ```text
//! M(z) z'' = F(t, z, z'),   M = M_own + sum_e A_e^T M_e A_e,
//! F = f_own - sum_e A_e^T (f_e + M_e abar_e + h_e)
//! ```
//!
//! Each element's coordinates `x_e = (x1, y1, psi1, x2, y2, psi2)` move with the generalized
//! ones as `x_e'' = A_e z'' + abar_e`: a free node's coordinates are generalized coordinates;
//! the first node's position is the slider's, prescribed (`abar = B''(t)`) or an actuated
//! slider's coordinate `rho` (`A = u`); the last node's position is the platform point
//! `p + R(phi) c` (`A = [I | perp(r)]`, `abar = -phi'^2 r`). `M_e` and `h_e` are the element's
//! inertia ([`NodalMass`]), `f_e` its internal, damping and external nodal forces; `M_own`
//! holds the platform's mass and inertia and the sliders' masses, `f_own` the actuator
//! forces. `M` is banded per link with a border of the platform's (and the sliders')
//! coordinates ([`BorderedBanded`]).

// Index loops below mirror the formulas (rows and columns of small matrices).
#![allow(clippy::needless_range_loop)]

use super::banded::BorderedBanded;
use super::inertia::NodalMass;
use super::system::{Frame, NonlinearSystem, perp};
use crate::DynamicsError;

/// How one element coordinate moves with the generalized coordinates: up to two
/// `(coordinate, coefficient)` pairs (`usize::MAX` for none).
pub(super) type CoordinateMap = [(usize, f64); 2];

/// No generalized coordinate.
pub(super) const NONE: usize = usize::MAX;

/// The block rows of an element's six coordinates when each is one link coordinate with
/// coefficient 1 (an element between two free nodes), `None` otherwise.
#[allow(
    clippy::float_cmp,
    reason = "a free node's coordinates enter element_map with the exact coefficient 1"
)]
fn interior_rows(places: &[[(MassPlace, f64); 2]; 6]) -> Option<[usize; 6]> {
    let mut rows = [0; 6];
    for (row, slot) in rows.iter_mut().zip(places) {
        match slot {
            [(MassPlace::Block(_, j), a), (MassPlace::None, _)] if *a == 1.0 => *row = *j,
            _ => return None,
        }
    }
    Some(rows)
}

/// Where a generalized coordinate sits in the [`BorderedBanded`] mass.
#[derive(Debug, Clone, Copy)]
enum MassPlace {
    /// No coordinate.
    None,
    /// Row `j` of link block `b`.
    Block(usize, usize),
    /// Border index.
    Border(usize),
}

impl NonlinearSystem {
    /// Generalized index of link `i`'s local coordinate `j`.
    #[inline]
    pub(super) fn link_index(&self, i: usize, j: usize) -> usize {
        3 + i * self.per_link + j
    }

    /// The map `A_e` of element `e` of link `i` (rows: the element's six coordinates) and the
    /// known part `abar_e` of its acceleration.
    pub(super) fn element_map(
        &self,
        frame: &Frame,
        y: &[f64],
        i: usize,
        e: usize,
    ) -> ([CoordinateMap; 6], [f64; 6]) {
        let ne = self.options.elements;
        let n = self.coordinates();
        let mut map = [[(NONE, 0.0); 2]; 6];
        let mut known = [0.0; 6];
        for (slot, node) in [(0usize, e), (3, e + 1)] {
            if node == 0 {
                map[slot + 2][0] = (self.link_index(i, 0), 1.0);
                if self.actuated.is_some() {
                    let u = self.machine.geometry.legs[i].guide.direction.into_inner();
                    let s = self.slider_index(i);
                    map[slot][0] = (s, u.x);
                    map[slot + 1][0] = (s, u.y);
                } else {
                    known[slot] = frame.b[i][2].x;
                    known[slot + 1] = frame.b[i][2].y;
                }
            } else if node == ne {
                let r = frame.r[i];
                let rp = perp(&r);
                map[slot] = [(0, 1.0), (2, rp.x)];
                map[slot + 1] = [(1, 1.0), (2, rp.y)];
                map[slot + 2][0] = (self.link_index(i, 3 * ne - 2), 1.0);
                let omega = y[n + 2];
                known[slot] = -omega * omega * r.x;
                known[slot + 1] = -omega * omega * r.y;
            } else {
                for c in 0..3 {
                    map[slot + c][0] = (self.link_index(i, 3 * node - 2 + c), 1.0);
                }
            }
        }
        (map, known)
    }

    /// Where coordinate `g` of an element of link `i` sits in the mass: a row of the link's
    /// block, or the border (the platform's three coordinates, then the sliders');
    /// [`MassPlace::None`] for [`NONE`].
    #[inline]
    fn mass_place(&self, i: usize, g: usize) -> MassPlace {
        let links_end = 3 + 3 * self.per_link;
        if g == NONE {
            MassPlace::None
        } else if g < 3 {
            MassPlace::Border(g)
        } else if g < links_end {
            MassPlace::Block(i, g - self.link_index(i, 0))
        } else {
            MassPlace::Border(3 + g - links_end)
        }
    }

    /// Adds `v` at `(p1, p2)` of the symmetric generalized matrix `mass` (every ordered pair
    /// is offered by the caller; each stored entry is taken once).
    #[inline]
    fn add_mass(mass: &mut BorderedBanded, p1: MassPlace, p2: MassPlace, v: f64) {
        match (p1, p2) {
            (MassPlace::Block(b1, j1), MassPlace::Block(b2, j2)) => {
                debug_assert_eq!(b1, b2, "links are not coupled directly");
                if j1 >= j2 {
                    mass.add_block(b1, j1, j2, v);
                }
            }
            (MassPlace::Block(b, j), MassPlace::Border(c)) => mass.add_coupling(b, j, c, v),
            (MassPlace::Border(c1), MassPlace::Border(c2)) => mass.add_border(c1, c2, v),
            _ => {}
        }
    }

    /// The element's coordinates and rates `(x_e, x_e')`.
    #[inline]
    pub(super) fn element_state(
        &self,
        y: &[f64],
        frame: &Frame,
        i: usize,
        e: usize,
    ) -> ([f64; 6], [f64; 6]) {
        let (q1, v1) = self.node(y, frame, i, e);
        let (q2, v2) = self.node(y, frame, i, e + 1);
        (
            [q1[0], q1[1], q1[2], q2[0], q2[1], q2[2]],
            [v1[0], v1[1], v1[2], v2[0], v2[1], v2[2]],
        )
    }

    /// Assembles `M` into `self.mass` and `F` into `self.generalized` (`self.forces` must hold
    /// the nodal internal, damping and external forces; `self.slider_forces` the actuators').
    pub(super) fn assemble_equations(&mut self, y: &[f64], frame: &Frame) {
        let ne = self.options.elements;
        let stride = 3 * (ne + 1);
        let mut mass = std::mem::take(&mut self.mass);
        let mut rhs = std::mem::take(&mut self.generalized);
        mass.clear();
        rhs.fill(0.0);
        let model = self.options.mass;
        for i in 0..3 {
            let link = self.links[i];
            // The angle of the last element's second node and its sine and cosine: the next
            // element's first node.
            let mut shared = (f64::NAN, (0.0, 1.0));
            for e in 0..ne {
                let (q, v) = self.element_state(y, frame, i, e);
                let first = if q[2].to_bits() == shared.0.to_bits() {
                    shared.1
                } else {
                    q[2].sin_cos()
                };
                shared = (q[5], q[5].sin_cos());
                let inertia = model.inertia_with_ends(
                    link.element_mass,
                    link.element.length,
                    &v,
                    [first, shared.1],
                );
                let f = &self.forces[i * stride..(i + 1) * stride];
                if e > 0 && e + 1 < ne {
                    // An element inside the link: its six coordinates are rows
                    // 3e - 2 .. 3e + 4 of the link's block, nothing of its acceleration is
                    // known, and its second node's forces are its own (the same as the
                    // general path below, without the maps).
                    let base = 3 * e - 2;
                    let g0 = self.link_index(i, base);
                    for c in 0..6 {
                        let mut force = inertia.velocity_terms[c];
                        if c >= 3 {
                            force += f[3 * (e + 1) + c - 3];
                        }
                        rhs[g0 + c] -= force;
                    }
                    for c1 in 0..6 {
                        for c2 in 0..=c1 {
                            mass.add_block(i, base + c1, base + c2, inertia.mass[c1][c2]);
                        }
                    }
                    continue;
                }
                let (map, known) = self.element_map(frame, y, i, e);
                // Known force: the nodal forces of the element's nodes are added once per node
                // (by the element that owns the node's slot: its first element, or the last
                // element for node N), the inertia of the known accelerations per element.
                let mut known_force = inertia.velocity_terms;
                for (a, row) in inertia.mass.iter().enumerate() {
                    known_force[a] += row.iter().zip(&known).map(|(m, k)| m * k).sum::<f64>();
                }
                for c in 0..6 {
                    let node = e + c / 3;
                    let owns = if c < 3 { e == 0 } else { true };
                    if owns {
                        known_force[c] += f[3 * node + c % 3];
                    }
                }
                for (c, m) in map.iter().enumerate() {
                    for &(g, coef) in m.iter().filter(|(g, _)| *g != NONE) {
                        rhs[g] -= coef * known_force[c];
                    }
                }
                // Where each slot's coordinates sit in the mass, found once per element.
                let mut places = [[(MassPlace::None, 0.0); 2]; 6];
                for (slot, m) in places.iter_mut().zip(&map) {
                    for (place, &(g, a)) in slot.iter_mut().zip(m) {
                        *place = (self.mass_place(i, g), a);
                    }
                }
                if let Some(rows) = interior_rows(&places) {
                    // An element inside the link: its coordinates are rows of the block.
                    for (c1, &j1) in rows.iter().enumerate() {
                        for (c2, &j2) in rows.iter().enumerate() {
                            if j1 >= j2 {
                                mass.add_block(i, j1, j2, inertia.mass[c1][c2]);
                            }
                        }
                    }
                    continue;
                }
                for (c1, m1) in places.iter().enumerate() {
                    for (c2, m2) in places.iter().enumerate() {
                        let v = inertia.mass[c1][c2];
                        if v == 0.0 {
                            continue;
                        }
                        for &(p1, a1) in m1 {
                            for &(p2, a2) in m2 {
                                Self::add_mass(&mut mass, p1, p2, a1 * a2 * v);
                            }
                        }
                    }
                }
            }
        }
        // The platform's own mass and the sliders'.
        let (mp, ip) = (self.machine.platform_mass, self.machine.platform_inertia);
        for (c, v) in [(0, mp), (1, mp), (2, ip)] {
            mass.add_border(c, c, v);
        }
        if self.actuated.is_some() {
            let masses = self.slider_masses();
            for i in 0..3 {
                let g = self.slider_index(i);
                mass.add_border(3 + i, 3 + i, masses[i]);
                rhs[g] += self.slider_forces[i] + self.slider_loads[i];
            }
        }
        self.mass = mass;
        self.generalized = rhs;
    }

    /// Solves `M z'' = F` (after [`NonlinearSystem::assemble_equations`]) into `acc`.
    ///
    /// # Errors
    /// A mass matrix that is not positive definite (a bug or a non-finite state).
    pub(super) fn solve_equations(&mut self, t: f64, acc: &mut [f64]) -> Result<(), DynamicsError> {
        self.mass
            .factor()
            .map_err(|_| DynamicsError::MassNotPositive { t })?;
        let links = 3 * self.per_link;
        acc.copy_from_slice(&self.generalized[..acc.len()]);
        let k = self.mass.border_size();
        let mut border = [0.0; 6];
        border[..3].copy_from_slice(&acc[..3]);
        if k > 3 {
            border[3..k].copy_from_slice(&acc[3 + links..3 + links + 3]);
        }
        self.mass.solve(&mut acc[3..3 + links], &mut border[..k]);
        acc[..3].copy_from_slice(&border[..3]);
        if k > 3 {
            acc[3 + links..3 + links + 3].copy_from_slice(&border[3..k]);
        }
        Ok(())
    }

    /// The residual `M acc - F` of the equations of motion (after
    /// [`NonlinearSystem::assemble_equations`], before a solve) into `out`.
    pub(super) fn equations_residual(&self, acc: &[f64], out: &mut [f64]) {
        let links = 3 * self.per_link;
        let k = self.mass.border_size();
        let (mut border_x, mut border_out) = ([0.0; 6], [0.0; 6]);
        border_x[..3].copy_from_slice(&acc[..3]);
        if k > 3 {
            border_x[3..k].copy_from_slice(&acc[3 + links..3 + links + 3]);
        }
        self.mass.multiply(
            &acc[3..3 + links],
            &border_x[..k],
            &mut out[3..3 + links],
            &mut border_out[..k],
        );
        out[..3].copy_from_slice(&border_out[..3]);
        if k > 3 {
            out[3 + links..3 + links + 3].copy_from_slice(&border_out[3..k]);
        }
        for (r, f) in out.iter_mut().zip(&self.generalized) {
            *r -= f;
        }
    }

    /// The accelerations `x_e''` of element `e` of link `i` from the generalized `acc`.
    pub(super) fn element_acceleration(
        &self,
        frame: &Frame,
        y: &[f64],
        acc: &[f64],
        i: usize,
        e: usize,
    ) -> [f64; 6] {
        let (map, mut a) = self.element_map(frame, y, i, e);
        for (c, m) in map.iter().enumerate() {
            for &(g, coef) in m.iter().filter(|(g, _)| *g != NONE) {
                a[c] += coef * acc[g];
            }
        }
        a
    }

    /// Inertia force `M_e x_e'' + h_e` of element `e` of link `i` at the accelerations `acc`.
    pub(super) fn element_inertia_force(
        &self,
        frame: &Frame,
        y: &[f64],
        acc: &[f64],
        i: usize,
        e: usize,
    ) -> [f64; 6] {
        let link = self.links[i];
        let (q, v) = self.element_state(y, frame, i, e);
        let a = self.element_acceleration(frame, y, acc, i, e);
        let inertia = self
            .options
            .mass
            .inertia(link.element_mass, link.element.length, &q, &v);
        let mut f = inertia.velocity_terms;
        for (k, row) in inertia.mass.iter().enumerate() {
            f[k] += row.iter().zip(&a).map(|(m, x)| m * x).sum::<f64>();
        }
        f
    }

    /// Kinetic energy of link `i`'s elements, `sum_e x_e'^T M_e x_e' / 2`.
    pub(super) fn link_kinetic_energy(&self, y: &[f64], frame: &Frame, i: usize) -> f64 {
        let link = self.links[i];
        (0..self.options.elements)
            .map(|e| {
                let (q, v) = self.element_state(y, frame, i, e);
                let m = NodalMass::inertia(
                    self.options.mass,
                    link.element_mass,
                    link.element.length,
                    &q,
                    &v,
                )
                .mass;
                let mut t = 0.0;
                for a in 0..6 {
                    for b in 0..6 {
                        t += 0.5 * v[a] * m[a][b] * v[b];
                    }
                }
                t
            })
            .sum()
    }
}

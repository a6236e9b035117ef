//! The geometry of the deflected links at one `(t, y)`: the frame of the prescribed sliders
//! and the platform, the nodes, the centre line between them and what is read from it
//! (deflection, slope, mid-point deflections, the chords' type-II measure).

use super::*;

impl NonlinearSystem {
    /// Transverse deflection (m) of link `link` (0-based) at `xi` (0..1 of the undeformed
    /// length) from its chord `B_i -> C_i`, along the chord normal, at `(t, y)`. Between
    /// nodes the element's centre line is the cubic Hermite curve through its end positions
    /// and tangents `(cos psi, sin psi)` (the co-rotational element's own interpolation of
    /// the transverse displacement, Crisfield 1991, section 7.3, to the order of the local
    /// rotations).
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure.
    pub fn deflection_at(
        &self,
        t: f64,
        link: usize,
        xi: f64,
        y: &[f64],
    ) -> Result<f64, DynamicsError> {
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        Ok(self.deflection_in(&frame, y, link.min(2), xi))
    }
    /// [`NonlinearSystem::deflection_at`] in a computed frame.
    pub(super) fn deflection_in(&self, frame: &Frame, y: &[f64], i: usize, xi: f64) -> f64 {
        let (point, _) = self.centre_line(frame, y, i, xi);
        let b = frame.b[i][0];
        let chord = (frame.c[i][0] - b).normalize();
        (point - b).dot(&perp(&chord))
    }
    /// The slope `dw/dx` (rad) of link `link`'s deflection from its chord at `xi`, at
    /// `(t, y)`: the tangent of the element's cubic Hermite centre line in the chord's frame,
    /// `(T . n) / (T . e)`.
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure.
    pub fn slope_at(&self, t: f64, link: usize, xi: f64, y: &[f64]) -> Result<f64, DynamicsError> {
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        let i = link.min(2);
        let (_, tangent) = self.centre_line(&frame, y, i, xi);
        let chord = (frame.c[i][0] - frame.b[i][0]).normalize();
        Ok(tangent.dot(&perp(&chord)) / tangent.dot(&chord))
    }
    /// The point at `xi` of link `i`'s centre line and its tangent `d r / d xi`: the cubic
    /// Hermite curve through the element's end positions and tangents `(cos psi, sin psi)`.
    pub(super) fn centre_line(
        &self,
        frame: &Frame,
        y: &[f64],
        i: usize,
        xi: f64,
    ) -> (Vector2<f64>, Vector2<f64>) {
        let ne = self.options.elements;
        let s = xi.clamp(0.0, 1.0) * ne as f64;
        let e = (s.floor() as usize).min(ne - 1);
        let a = s - e as f64;
        let (q1, _) = self.node(y, frame, i, e);
        let (q2, _) = self.node(y, frame, i, e + 1);
        let le = self.links[i].element.length;
        let (p1, p2) = (Vector2::new(q1[0], q1[1]), Vector2::new(q2[0], q2[1]));
        let (t1, t2) = (
            Vector2::new(q1[2].cos(), q1[2].sin()) * le,
            Vector2::new(q2[2].cos(), q2[2].sin()) * le,
        );
        let (h00, h10) = (
            2.0 * a * a * a - 3.0 * a * a + 1.0,
            a * a * a - 2.0 * a * a + a,
        );
        let (h01, h11) = (-2.0 * a * a * a + 3.0 * a * a, a * a * a - a * a);
        let point = p1 * h00 + t1 * h10 + p2 * h01 + t2 * h11;
        let (d00, d10) = (6.0 * a * a - 6.0 * a, 3.0 * a * a - 4.0 * a + 1.0);
        let (d01, d11) = (-6.0 * a * a + 6.0 * a, 3.0 * a * a - 2.0 * a);
        let tangent = p1 * d00 + t1 * d10 + p2 * d01 + t2 * d11;
        (point, tangent)
    }
    /// Sliders from the rigid inverse kinematics of the nominal motion, platform points from
    /// the state.
    pub(in crate::nonlinear) fn frame(&self, t: f64, y: &[f64]) -> Result<Frame, DynamicsError> {
        let n = self.coordinates();
        let nominal = self.trajectory.motion(t);
        let rigid = self
            .machine
            .geometry
            .inverse_kinematics_unchecked(&nominal)
            .map_err(|source| DynamicsError::Kinematics { t, source })?;
        let (phi, omega) = (y[2], y[n + 2]);
        let (sin, cos) = phi.sin_cos();
        let p = Vector2::new(y[0], y[1]);
        let v = Vector2::new(y[n], y[n + 1]);
        let mut frame = Frame {
            t,
            nominal,
            rigid,
            rho: [[0.0; 3]; 3],
            b: [[Vector2::zeros(); 3]; 3],
            r: [Vector2::zeros(); 3],
            c: [[Vector2::zeros(); 2]; 3],
        };
        let measured = self.actuated.as_ref().map(|a| a.measured(y));
        for (i, leg) in self.machine.geometry.legs.iter().enumerate() {
            let s = &frame.rigid.legs[i];
            let u = leg.guide.direction.into_inner();
            // Actuated sliders: from the state, their acceleration still unknown.
            frame.rho[i] = match measured {
                Some(m) => [m[i].position, m[i].velocity, 0.0],
                None => [s.rho, s.rho_dot, s.rho_ddot],
            };
            let [rho, rho_dot, rho_ddot] = frame.rho[i];
            frame.b[i] = [leg.guide.anchor.coords + rho * u, rho_dot * u, rho_ddot * u];
            let a = leg.attachment;
            let r = Vector2::new(cos * a.x - sin * a.y, sin * a.x + cos * a.y);
            frame.r[i] = r;
            frame.c[i] = [p + r, v + omega * perp(&r)];
        }
        Ok(frame)
    }
    /// Coordinates and rates `(x, y, psi)` of node `k` of link `i`.
    #[inline]
    pub(in crate::nonlinear) fn node(
        &self,
        y: &[f64],
        frame: &Frame,
        i: usize,
        k: usize,
    ) -> ([f64; 3], [f64; 3]) {
        let n = self.coordinates();
        let ne = self.options.elements;
        let off = 3 + i * self.per_link;
        if k == 0 {
            let [b, bd, _] = frame.b[i];
            ([b.x, b.y, y[off]], [bd.x, bd.y, y[n + off]])
        } else if k == ne {
            let [c, cd] = frame.c[i];
            let j = off + 3 * ne - 2;
            ([c.x, c.y, y[j]], [cd.x, cd.y, y[n + j]])
        } else {
            let j = off + 3 * k - 2;
            (
                [y[j], y[j + 1], y[j + 2]],
                [y[n + j], y[n + j + 1], y[n + j + 2]],
            )
        }
    }
    /// The angle of link `i`'s centre line at position `a` of element `e`, and its rate.
    pub(super) fn tangent_angle(
        &self,
        y: &[f64],
        frame: &Frame,
        i: usize,
        (e, a): (usize, f64),
    ) -> (f64, f64) {
        let (q1, v1) = self.node(y, frame, i, e);
        let (q2, v2) = self.node(y, frame, i, e + 1);
        let le = self.links[i].element.length;
        let (d00, d10) = (6.0 * a * a - 6.0 * a, 3.0 * a * a - 4.0 * a + 1.0);
        let (d01, d11) = (-6.0 * a * a + 6.0 * a, 3.0 * a * a - 2.0 * a);
        let (c1, s1) = (q1[2].cos(), q1[2].sin());
        let (c2, s2) = (q2[2].cos(), q2[2].sin());
        let tangent = Vector2::new(q1[0], q1[1]) * d00
            + Vector2::new(c1, s1) * (le * d10)
            + Vector2::new(q2[0], q2[1]) * d01
            + Vector2::new(c2, s2) * (le * d11);
        let rate = Vector2::new(v1[0], v1[1]) * d00
            + Vector2::new(-s1, c1) * (le * v1[2] * d10)
            + Vector2::new(v2[0], v2[1]) * d01
            + Vector2::new(-s2, c2) * (le * v2[2] * d11);
        (
            tangent.y.atan2(tangent.x),
            cross(&tangent, &rate) / tangent.norm_squared(),
        )
    }
    /// Positions of every node of link `link` (0-based) at `(t, y)` (allocating; for plots).
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure.
    pub fn node_positions(
        &self,
        t: f64,
        y: &[f64],
        link: usize,
    ) -> Result<Vec<[f64; 2]>, DynamicsError> {
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        Ok((0..=self.options.elements)
            .map(|k| {
                let (q, _) = self.node(y, &frame, link.min(2), k);
                [q[0], q[1]]
            })
            .collect())
    }
    /// Type-II measure of the chords `B_i -> C_i` (as [`crate::equilibrium_measure`]).
    pub(super) fn measure(&self, frame: &Frame) -> f64 {
        let centroid = (frame.r[0] + frame.r[1] + frame.r[2]) / 3.0;
        let radius = frame
            .r
            .iter()
            .map(|r| (r - centroid).norm())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut m = Matrix3::zeros();
        for i in 0..3 {
            let e = (frame.c[i][0] - frame.b[i][0]).normalize();
            let moment = cross(&(frame.r[i] - centroid), &e) / radius;
            let col = Vector3::new(e.x, e.y, moment);
            m.set_column(i, &(col / col.norm()));
        }
        m.determinant().abs()
    }
    /// Mid-point deflections from the chords (m).
    pub(super) fn midpoint_deflections(&self, y: &[f64], frame: &Frame) -> [f64; 3] {
        let mid = self.options.elements / 2;
        std::array::from_fn(|i| {
            let (q, _) = self.node(y, frame, i, mid);
            let b = frame.b[i][0];
            let e = (frame.c[i][0] - b).normalize();
            (Vector2::new(q[0], q[1]) - b).dot(&perp(&e))
        })
    }
}

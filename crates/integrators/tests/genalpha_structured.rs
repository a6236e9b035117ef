//! The generalized-alpha method on a system that declares a [`BlockBanded`] structure and a
//! residual form ([`SecondOrderForm::structure`], [`SecondOrderForm::residual`]):
//! * with and without the structure, the same steps and the same solution to round-off (the
//!   banded-bordered LU solves the same Newton systems as the dense one);
//! * with the residual `M a - F` instead of `a - M^-1 F`, the same accuracy against an
//!   independent solution (RK45 at a tolerance 1e6 times tighter);
//! * no allocation per step on either path;
//! * a form whose matrices break the structure it declared is refused with a message.

use faer::MatMut;
use flexprr_integrators::{
    BlockBanded, GeneralizedAlpha, Integrator, IntegratorError, OdeSystem, Options, Rk45,
    SecondOrderForm, Stepper,
};
use flexprr_testkit::alloc::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Two chains of `m` masses between a wall and a shared mass (coordinate 0; chain 1 is
/// coordinates `1..=m`, chain 2 `m+1..=2m`, each from the wall to the shared mass), joined by
/// springs of force `k d + k3 d^3` for an elongation `d` and dampers `c d'`. `M` is diagonal,
/// `K` and `C` tridiagonal per chain with the shared mass as the border.
struct Chains {
    m: usize,
    mass: [f64; 2],
    k: f64,
    k3: f64,
    c: f64,
    /// Declare the structure.
    structured: bool,
    /// Offer the residual form.
    residual: bool,
    /// Write an entry outside the declared structure (a faulty form).
    faulty: bool,
    /// Spring forces on each coordinate (work).
    force: Vec<f64>,
}

impl Chains {
    fn new(m: usize) -> Self {
        Self {
            m,
            mass: [0.5, 3.0],
            k: 400.0,
            k3: 2e5,
            c: 0.4,
            structured: false,
            residual: false,
            faulty: false,
            force: vec![0.0; 2 * m + 1],
        }
    }

    fn n(&self) -> usize {
        2 * self.m + 1
    }

    fn mass_of(&self, i: usize) -> f64 {
        if i == 0 { self.mass[1] } else { self.mass[0] }
    }

    /// The springs as pairs `(left, right)` of coordinates, `None` for the wall.
    fn springs(&self) -> impl Iterator<Item = (Option<usize>, usize)> + '_ {
        (0..2).flat_map(move |chain| {
            let first = 1 + chain * self.m;
            (0..=self.m).map(move |s| {
                let left = if s == 0 { None } else { Some(first + s - 1) };
                let right = if s == self.m { 0 } else { first + s };
                (left, right)
            })
        })
    }

    /// `F(q, v)` into `self.force`.
    fn forces(&mut self, q: &[f64], v: &[f64]) {
        let mut force = std::mem::take(&mut self.force);
        force.fill(0.0);
        for (left, right) in self.springs() {
            let (ql, vl) = left.map_or((0.0, 0.0), |l| (q[l], v[l]));
            let (d, dd) = (q[right] - ql, v[right] - vl);
            let f = self.k * d + self.k3 * d * d * d + self.c * dd;
            force[right] -= f;
            if let Some(l) = left {
                force[l] += f;
            }
        }
        self.force = force;
    }
}

impl OdeSystem for Chains {
    fn dim(&self) -> usize {
        2 * self.n()
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let n = self.n();
        self.forces(&y[..n], &y[n..]);
        dy[..n].copy_from_slice(&y[n..]);
        for i in 0..n {
            dy[n + i] = self.force[i] / self.mass_of(i);
        }
    }
    fn second_order_form(&mut self) -> Option<&mut dyn SecondOrderForm> {
        Some(self)
    }
}

impl SecondOrderForm for Chains {
    fn coordinates(&self) -> usize {
        self.n()
    }
    fn matrices(
        &mut self,
        _t: f64,
        y: &[f64],
        mut mass: MatMut<'_, f64>,
        mut damping: MatMut<'_, f64>,
        mut stiffness: MatMut<'_, f64>,
    ) {
        let n = self.n();
        for i in 0..n {
            mass[(i, i)] = self.mass_of(i);
        }
        for (left, right) in self.springs() {
            let ql = left.map_or(0.0, |l| y[l]);
            let d = y[right] - ql;
            let kt = self.k + 3.0 * self.k3 * d * d;
            stiffness[(right, right)] += kt;
            damping[(right, right)] += self.c;
            if let Some(l) = left {
                stiffness[(l, l)] += kt;
                stiffness[(l, right)] -= kt;
                stiffness[(right, l)] -= kt;
                damping[(l, l)] += self.c;
                damping[(l, right)] -= self.c;
                damping[(right, l)] -= self.c;
            }
        }
        if self.faulty {
            stiffness[(1, self.m + 1)] = 1e-3;
        }
    }
    fn structure(&self) -> Option<BlockBanded> {
        let (m, n) = (self.m, self.n());
        self.structured
            .then(|| BlockBanded::new(n, vec![1..m + 1, m + 1..n], 1).unwrap())
    }
    fn has_residual(&self) -> bool {
        self.residual
    }
    fn residual(&mut self, _t: f64, y: &[f64], acc: &[f64], residual: &mut [f64]) {
        let n = self.n();
        self.forces(&y[..n], &y[n..]);
        for i in 0..n {
            residual[i] = self.mass_of(i) * acc[i] - self.force[i];
        }
    }
}

/// A start off equilibrium: a smooth displacement of every mass, the shared one moving.
fn start(s: &Chains) -> Vec<f64> {
    let n = s.n();
    let mut y = vec![0.0; 2 * n];
    for (i, q) in y[..n].iter_mut().enumerate() {
        *q = 0.02 * ((i as f64) * 0.9).sin();
    }
    y[n] = 1.0;
    y
}

const TIMES: [f64; 3] = [0.1, 0.25, 0.5];

#[test]
fn the_structure_takes_the_same_steps_as_the_dense_algebra() {
    let ga = GeneralizedAlpha::new(Options::default().rtol(1e-6).atol(1e-9));
    let mut dense = Chains::new(6);
    let y0 = start(&dense);
    let a = ga.solve(&mut dense, 0.0, &y0, &TIMES).unwrap();
    let mut structured = Chains::new(6);
    structured.structured = true;
    let b = ga.solve(&mut structured, 0.0, &y0, &TIMES).unwrap();
    println!(
        "dense: {} steps ({} rejected, {} LU); structured: {} ({}, {})",
        a.stats.accepted_steps,
        a.stats.rejected_steps,
        a.stats.lu_decompositions,
        b.stats.accepted_steps,
        b.stats.rejected_steps,
        b.stats.lu_decompositions
    );
    assert!(a.stats.accepted_steps > 100);
    assert_eq!(a.stats.accepted_steps, b.stats.accepted_steps);
    assert_eq!(a.stats.rejected_steps, b.stats.rejected_steps);
    assert_eq!(a.stats.newton_iterations, b.stats.newton_iterations);
    assert_eq!(a.stats.lu_decompositions, b.stats.lu_decompositions);
    for k in 0..TIMES.len() {
        for (x, y) in a.y(k).iter().zip(b.y(k)) {
            assert!((x - y).abs() < 1e-10 * (1.0 + x.abs()), "{x} vs {y}");
        }
    }
}

#[test]
fn the_residual_form_is_as_accurate_as_the_right_hand_side() {
    let mut reference = Chains::new(6);
    let y0 = start(&reference);
    let exact = Rk45::new(Options::default().rtol(1e-12).atol(1e-15))
        .solve(&mut reference, 0.0, &y0, &TIMES)
        .unwrap();
    let n = reference.n();
    let error = |residual: bool, rtol: f64| {
        let mut s = Chains::new(6);
        s.structured = true;
        s.residual = residual;
        let ga = GeneralizedAlpha::new(Options::default().rtol(rtol).atol(rtol * 1e-3));
        let sol = ga.solve(&mut s, 0.0, &y0, &TIMES).unwrap();
        let err = (0..TIMES.len())
            .flat_map(|k| (0..n).map(move |i| (k, i)))
            .map(|(k, i)| (sol.y(k)[i] - exact.y(k)[i]).abs())
            .fold(0.0, f64::max);
        (err, sol.stats.accepted_steps)
    };
    for rtol in [1e-4, 1e-6] {
        let (e_rhs, steps_rhs) = error(false, rtol);
        let (e_res, steps_res) = error(true, rtol);
        println!(
            "rtol {rtol:e}: a - M^-1 F {e_rhs:.3e} ({steps_rhs} steps), M a - F {e_res:.3e} \
             ({steps_res} steps)"
        );
        // Both are the same discretisation; Newton's iterates differ within its tolerance.
        assert!(
            e_res < 1.5 * e_rhs && e_rhs < 1.5 * e_res,
            "{e_res} vs {e_rhs}"
        );
        assert!(steps_res.abs_diff(steps_rhs) * 10 <= steps_rhs);
    }
}

#[test]
fn structured_steps_do_not_allocate() {
    for residual in [false, true] {
        let mut s = Chains::new(6);
        s.structured = true;
        s.residual = residual;
        let y0 = start(&s);
        let ga = GeneralizedAlpha::new(Options::default().rtol(1e-6).atol(1e-9));
        let mut stepper = ga.start(&mut s, 0.0, &y0, 0.3).unwrap();
        let mut out = vec![0.0; y0.len()];
        let before = allocations();
        while stepper.t() < 0.3 {
            stepper.step(&mut s).unwrap();
            let tm = 0.5 * (stepper.t() + stepper.t_previous());
            stepper.interpolate(tm, &mut out);
        }
        assert_eq!(allocations(), before, "residual form {residual}");
        assert!(stepper.stats().lu_decompositions > 10);
    }
}

#[test]
fn matrices_outside_the_declared_structure_are_refused() {
    let mut s = Chains::new(4);
    s.structured = true;
    s.faulty = true;
    let y0 = start(&s);
    let err = GeneralizedAlpha::new(Options::default())
        .solve(&mut s, 0.0, &y0, &[0.1])
        .unwrap_err();
    println!("{err}");
    assert!(
        matches!(&err, IntegratorError::InvalidInput(m) if m.contains("(1, 5)") && m.contains("outside")),
        "{err}"
    );
}

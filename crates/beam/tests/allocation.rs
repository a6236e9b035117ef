//! The frequency solver's hot path allocates nothing after construction (counted with a
//! wrapping global allocator; this test binary holds only this test so nothing else runs
//! concurrently while counting).

use faer::Mat;
use flexprr_beam::{
    AxialLoad, Coupling, FrequencySolver, HermiteBasis, ModalIntegrals, UniformSection,
};
use flexprr_testkit::alloc::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn eigenvalues_and_geometric_stiffness_do_not_allocate() {
    let section = UniformSection::rectangle(7.3e10, 2770.0, 0.002, 0.03).unwrap();
    // r = 20 unknowns (10 elements) so faer's blocked paths are exercised too.
    let mi =
        ModalIntegrals::compute(&HermiteBasis::pinned_pinned(10).unwrap(), &section, 0.2).unwrap();
    let r = mi.r();
    for coupling in [Coupling::Full, Coupling::Diagonal] {
        let mut solver = FrequencySolver::new(&mi, coupling).unwrap();
        let mut stiffness = Mat::zeros(r, r);
        let mut out = vec![0.0; r];
        let before = allocations();
        for step in 0..50 {
            let load = AxialLoad {
                p0: -100.0 + 4.0 * step as f64,
                p1: 10.0,
                p2: -3.0,
            };
            mi.total_stiffness_into(&load, stiffness.as_mut());
            solver.eigenvalues(stiffness.as_ref(), &mut out).unwrap();
        }
        let after = allocations();
        assert_eq!(
            after - before,
            0,
            "{coupling:?}: {} allocations",
            after - before
        );
        assert!(out.iter().all(|w| w.is_finite()));
    }
}

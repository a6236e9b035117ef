//! The inverse kinematics is called inside ODE right-hand sides: it must not allocate.
//! A counting global allocator (per thread) checks that.

use flexprr_kinematics::{Circle, Geometry, MachineKinematics, Trajectory};

use flexprr_testkit::alloc::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn inverse_kinematics_does_not_allocate() {
    let geometry = Geometry::paper();
    let circle = Circle::paper(20.0).unwrap();
    let mut in_place = MachineKinematics::default();
    let before = allocations();
    let mut checksum = 0.0;
    for k in 0..1000 {
        let motion = circle.motion(k as f64 * 5e-5);
        let checked = geometry.inverse_kinematics(&motion).unwrap();
        let unchecked = geometry.inverse_kinematics_unchecked(&motion).unwrap();
        let positions = geometry.inverse_position(&motion.pose).unwrap();
        let measures = geometry.singularity(&motion.pose).unwrap();
        geometry
            .inverse_kinematics_into(&motion, &mut in_place)
            .unwrap();
        checksum += in_place.legs[2].rho_ddot;
        geometry
            .inverse_kinematics_unchecked_into(&motion, &mut in_place)
            .unwrap();
        checksum += in_place.legs[0].beta_ddot + in_place.legs[1].beta();
        let closure = geometry.closure(
            &motion.pose,
            [positions[0].rho, positions[1].rho, positions[2].rho],
            geometry.link_lengths(),
        );
        checksum += checked.legs[0].rho_ddot
            + unchecked.legs[1].beta_ddot
            + measures.type_ii
            + closure.residual.x;
    }
    let after = allocations();
    assert!(checksum.is_finite());
    assert_eq!(after - before, 0, "inverse kinematics allocated");
    // The counter does see allocations on this thread.
    let probe: Vec<u8> = std::hint::black_box(Vec::with_capacity(16));
    assert!(allocations() > after);
    drop(probe);
}

//! `FrictionCompensator::step` makes no heap allocation (it runs in a 200 Hz loop).
//! A counting global allocator, alone in this test binary, counts every allocation made
//! by the test's own thread (the harness's other threads, such as its slow-test notice
//! on a loaded machine, may allocate meanwhile and are not counted).

use era::friction::compensator::{ChannelConfig, FrictionCompensator};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    // `try_with`: during thread teardown the slot may be gone; nothing to count then.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn step_allocates_nothing() {
    // Table 5.1's adjusted coefficients, thesis settings, 8 channels.
    let coefficients = [0.0325, 0.05, 0.025, 0.01, 0.015, 0.05, 0.0325, 0.0175];
    let comp = FrictionCompensator::new(
        coefficients
            .iter()
            .map(|c| ChannelConfig::thesis(*c))
            .collect(),
    )
    .unwrap();
    let mut velocities = [0.0f64; 8];
    let mut outputs = [0.0f64; 8];
    let before = allocations();
    let mut checksum = 0.0;
    for k in 0..100_000 {
        for (ch, v) in velocities.iter_mut().enumerate() {
            *v = ((k * (ch + 3)) as f64 * 0.001).sin() * 2.0;
        }
        comp.step(&velocities, &mut outputs).unwrap();
        checksum += outputs.iter().sum::<f64>();
        // An error path too: wrong length, reported without allocating.
        assert!(comp.step(&velocities[..7], &mut outputs).is_err());
    }
    let after = allocations();
    assert_eq!(after - before, 0, "step allocated {} times", after - before);
    assert!(checksum.is_finite());
}

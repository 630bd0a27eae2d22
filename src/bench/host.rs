//! How much parallel CPU the host lends a run, measured rather than assumed.
//!
//! On a CPU implementation of Vulkan (lavapipe) every kernel runs on the host's cores,
//! while the single-thread CPU references run on one, so a GPU-vs-CPU ratio depends on
//! whether the other cores were really there. The probe runs the same compute-bound
//! work (registers only, no memory traffic) on one thread and split over all of rayon's
//! threads; the ratio of the two times is the number of cores the run effectively had.
//! Where it reads full and the kernels are still slow, the cause is elsewhere: on the
//! shared 2-vCPU VM this was written on, the 4M-pair sort's median was 108–124 ms in
//! three runs and 73 ms in another, with the probe at 1.94–2.00 in all of them, so what
//! came and went was not the cores (what it was is still open: docs/PERFORMANCE.md,
//! "What the slow phase looks like").

use std::time::Instant;

use rayon::prelude::*;

/// Iterations of the probe's integer loop per thread-share: about 15 ms on one core.
const PROBE_STEPS: u64 = 15_000_000;

/// A dependent chain of integer operations that stays in registers (no memory traffic,
/// so the probe measures cores, not bandwidth).
fn spin(seed: u64, steps: u64) -> u64 {
    let mut x = seed | 1;
    for _ in 0..steps {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
    }
    x
}

/// Effective parallel cores right now: time of the work on one thread over its time
/// split across `rayon::current_num_threads()` threads (at most that many; near 1 when
/// the other cores are busy or withheld). The best of three tries of each side.
pub fn effective_cores() -> f64 {
    let threads = rayon::current_num_threads().max(1) as u64;
    let total = PROBE_STEPS * threads;
    let best_of = |f: &dyn Fn() -> u64| {
        (0..3)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(f());
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let serial = best_of(&|| spin(1, total));
    let parallel = best_of(&|| {
        (0..threads)
            .into_par_iter()
            .map(|i| spin(i + 1, PROBE_STEPS))
            .reduce(|| 0, |a, b| a ^ b)
    });
    serial / parallel
}

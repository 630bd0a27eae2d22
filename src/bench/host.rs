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
//! "Why medians swing").

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

/// The host's processor as `/proc/cpuinfo` names it, with its family and model numbers
/// and its widest x86 vector extension, e.g. `AMD EPYC (family 25, model 1; AVX2)`.
/// lavapipe's figures and the CPU references both move with the processor (the sort
/// target has been met on some of the VMs this project ran on and missed by far on
/// others: docs/PERFORMANCE.md), so every benchmark report names it. "unknown CPU"
/// where `/proc/cpuinfo` cannot be read.
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| describe_cpuinfo(&text, vector_extension()))
        .unwrap_or_else(|| "unknown CPU".to_string())
}

/// The widest x86 vector extension the processor offers: what lavapipe's LLVM back end
/// may emit for its 8-lane vectors (AVX-512 brings gather and scatter instructions that
/// changed which memory accesses were fastest: docs/PERFORMANCE.md).
fn vector_extension() -> Option<&'static str> {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            return Some("AVX-512");
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            return Some("AVX2");
        }
    }
    None
}

/// The first processor's `model name`, `cpu family` and `model` from the text of
/// `/proc/cpuinfo`, and `vector` after them where given. None without a model name.
fn describe_cpuinfo(text: &str, vector: Option<&str>) -> Option<String> {
    let first = text.split("\n\n").next()?;
    let field = |key: &str| {
        first.lines().find_map(|line| {
            let (k, v) = line.split_once(':')?;
            (k.trim() == key).then(|| v.trim().to_string())
        })
    };
    let name = field("model name").filter(|n| !n.is_empty())?;
    let mut details = [("family", "cpu family"), ("model", "model")]
        .into_iter()
        .filter_map(|(label, key)| field(key).map(|v| format!("{label} {v}")))
        .collect::<Vec<_>>()
        .join(", ");
    if let Some(v) = vector {
        if !details.is_empty() {
            details.push_str("; ");
        }
        details.push_str(v);
    }
    Some(if details.is_empty() {
        name
    } else {
        format!("{name} ({details})")
    })
}

#[cfg(test)]
mod tests {
    use super::describe_cpuinfo;

    const EPYC: &str = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\n\
                        model\t\t: 1\nmodel name\t: AMD EPYC\nstepping\t: 1\n\n\
                        processor\t: 1\nmodel name\t: Other\n";

    #[test]
    fn names_the_first_processor_with_family_model_and_vectors() {
        assert_eq!(
            describe_cpuinfo(EPYC, Some("AVX2")).as_deref(),
            Some("AMD EPYC (family 25, model 1; AVX2)")
        );
        assert_eq!(
            describe_cpuinfo(EPYC, None).as_deref(),
            Some("AMD EPYC (family 25, model 1)")
        );
    }

    #[test]
    fn without_a_model_name_there_is_no_description() {
        assert_eq!(
            describe_cpuinfo("processor\t: 0\ncpu family\t: 6\n", None),
            None
        );
        assert_eq!(describe_cpuinfo("", Some("AVX2")), None);
        // No family or model lines: the name alone.
        assert_eq!(
            describe_cpuinfo("model name\t: Neoverse\n", None).as_deref(),
            Some("Neoverse")
        );
    }
}

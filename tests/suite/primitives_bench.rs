//! The primitives benchmark: a quick run under validation (checks that every primitive
//! is verified and timed, not how fast), and the full measurement, ignored by default:
//!
//! ```text
//! cargo test --release --test suite -- --ignored --nocapture primitives_bench::bench_primitives_full
//! ```
//! (`SPLITRAY_BENCH_JSON=out.json` also writes the report as JSON.)

use crate::common;

use splitray::bench::primitives::{run, PrimitivesBenchOptions};
use splitray::vk::{Gpu, GpuDesc, InstanceDesc, StreamPlacement};

#[test]
fn bench_primitives_smoke() {
    let gpu = common::gpu();
    let report = run(
        &gpu,
        &PrimitivesBenchOptions {
            n: 100_003,
            scan_n: 200_003,
            runs: 5,
            tuning: None,
        },
    )
    .unwrap();
    report.print();
    assert_eq!(report.rows.len(), 10);
    assert!(report
        .rows
        .iter()
        .all(|r| r.gpu_ms > 0.0 && r.wall_ms > 0.0));
    serde_json::to_string(&report).unwrap();
    common::assert_clean(&gpu);
}

#[test]
#[ignore = "measurement: run in release with --ignored --nocapture"]
fn bench_primitives_full() {
    let gpu = Gpu::new(&GpuDesc {
        instance: InstanceDesc {
            validation: false,
            sync_validation: false,
        },
        device: None,
        placement: StreamPlacement::Spread,
        ..Default::default()
    })
    .unwrap();
    let mut opts = PrimitivesBenchOptions::default();
    if let Ok(n) = std::env::var("SPLITRAY_BENCH_N") {
        opts.n = n.parse().unwrap();
    }
    if let Ok(n) = std::env::var("SPLITRAY_BENCH_SCAN_N") {
        opts.scan_n = n.parse().unwrap();
    }
    let report = run(&gpu, &opts).unwrap();
    report.print();
    if let Ok(path) = std::env::var("SPLITRAY_BENCH_JSON") {
        std::fs::write(path, serde_json::to_string_pretty(&report).unwrap()).unwrap();
    }
}

/// Times the sort and scan under several tunings (the measurements behind
/// `Tuning::for_device`):
/// `cargo test --release --test suite -- --ignored --nocapture primitives_bench::tuning_sweep`
#[test]
#[ignore = "measurement: run in release with --ignored --nocapture"]
fn tuning_sweep() {
    use splitray::bench::primitives::{time_copy, time_cpu_sort, time_scan, time_sort};
    use splitray::primitives::Tuning;
    let gpu = Gpu::new(&GpuDesc {
        instance: InstanceDesc {
            validation: false,
            sync_validation: false,
        },
        device: None,
        placement: StreamPlacement::Spread,
        ..Default::default()
    })
    .unwrap();
    let n: usize = std::env::var("SPLITRAY_SWEEP_N").map_or(1 << 20, |s| s.parse().unwrap());
    let base = Tuning::for_device(gpu.info());
    let sg = gpu.info().limits.subgroup_size;
    println!(
        "device {}, subgroup {sg}, default {}",
        gpu.info().name,
        base.describe()
    );
    let cpu_device = gpu.info().is_cpu();
    let only_scan = std::env::var_os("SPLITRAY_SWEEP_SCAN_ONLY").is_some();
    let sorts: Vec<Tuning> = if cpu_device {
        // (workgroup, keys per invocation, digit bits, subgroup rows, barrier-free
        // segments, interleaved pairs, 64-bit accesses)
        vec![
            (sg / 2, 32768, 11, false, true, true, true),
            (sg / 2, 32768, 11, false, true, true, false),
            (sg / 2, 16384, 11, false, true, true, true),
            (sg / 2, 65536, 11, false, true, true, true),
            (sg / 4, 32768, 11, false, true, true, true),
            (sg / 2, 16384, 11, false, true, false, true),
            (sg, 16384, 8, false, true, false, true),
            (sg, 16384, 8, false, false, false, false),
        ]
        .into_iter()
        .map(|(w, k, bits, rows, segments, pairs, wide)| Tuning {
            sort_workgroup_size: w,
            sort_keys_per_invocation: k,
            radix_bits: bits,
            sort_rows: rows,
            sort_segments: segments,
            sort_pairs: pairs,
            wide_accesses: wide,
            ..base
        })
        .collect()
    } else {
        // Multisplit tiles (workgroup, keys per invocation), then the fallback of GPUs
        // without subgroup ballots for the ratio between the two.
        let multisplit = Tuning::gpu(sg);
        [
            (128, 16),
            (128, 24),
            (256, 8),
            (256, 12),
            (256, 15),
            (256, 16),
            (256, 18),
            (384, 10),
            (512, 7),
        ]
        .into_iter()
        .map(|(w, k)| Tuning {
            sort_workgroup_size: w,
            sort_keys_per_invocation: k,
            ..multisplit
        })
        .chain([Tuning::gpu_runs(sg)])
        .collect()
    };
    let sorts: Vec<Tuning> = sorts
        .into_iter()
        .filter(|_| !only_scan)
        .map(|t| t.fit(gpu.info()))
        .collect();
    // Rounds interleave the tunings (and the CPU reference) so that a change of load on
    // a shared machine hits them alike; each reports its minimum over all rounds.
    let rounds: usize = std::env::var("SPLITRAY_SWEEP_ROUNDS").map_or(3, |s| s.parse().unwrap());
    let mut best = vec![f64::INFINITY; sorts.len()];
    let mut cpu_best = f64::INFINITY;
    for _ in 0..rounds.min(if sorts.is_empty() { 0 } else { rounds }) {
        if cpu_device {
            cpu_best = cpu_best.min(time_cpu_sort(n, 2));
        }
        for (t, b) in sorts.iter().zip(&mut best) {
            *b = b.min(time_sort(&gpu, t, n, 2).unwrap());
        }
    }
    if !sorts.is_empty() && cpu_device {
        println!("sort {n}: {cpu_best:>9.2} ms  cpu sort_unstable_by_key (single thread)");
    }
    for (t, ms) in sorts.iter().zip(best) {
        println!(
            "sort {n}: {:>9.2} ms {:>7.1} Mkeys/s {:>5.2}x cpu  {}",
            ms,
            n as f64 / ms / 1e3,
            cpu_best / ms,
            t.describe()
        );
    }
    let only_sort = std::env::var_os("SPLITRAY_SWEEP_SORT_ONLY").is_some();
    // (workgroup, items per invocation, subgroup rows, segment-scan items per invocation,
    // 64-bit accesses)
    let scan_shapes: &[(u32, u32, bool, u32, bool)] = if cpu_device {
        &[
            (sg, 256, true, 1024, true),
            (sg, 256, true, 2048, true),
            (sg, 256, true, 2048, false),
            (sg, 256, true, 2064, true),
            (sg, 256, true, 4096, true),
            (sg, 256, true, 4112, true),
            (sg, 256, true, 8208, true),
            (sg, 256, true, 0, false),
        ]
    } else {
        &[
            (128, 16, false, 0, false),
            (256, 8, false, 0, false),
            (256, 16, false, 0, false),
            (512, 8, false, 0, false),
        ]
    };
    let scans: Vec<Tuning> = scan_shapes
        .iter()
        .copied()
        .filter(|_| !only_sort)
        .map(|(w, k, rows, seg, wide)| {
            Tuning {
                workgroup_size: w,
                items_per_invocation: k,
                subgroup_rows: rows,
                scan_segment: seg,
                wide_accesses: wide,
                ..base
            }
            .fit(gpu.info())
        })
        .collect();
    // Interleaved rounds as for the sort, with a copy of the same bytes as the yardstick.
    let mut best = vec![f64::INFINITY; scans.len()];
    let mut copy_best = f64::INFINITY;
    for _ in 0..if scans.is_empty() { 0 } else { rounds } {
        copy_best = copy_best.min(time_copy(&gpu, 4 * n, 1).unwrap());
        for (t, b) in scans.iter().zip(&mut best) {
            *b = b.min(time_scan(&gpu, t, 4 * n, 1).unwrap());
        }
    }
    if !scans.is_empty() {
        println!(
            "scan {}: {copy_best:>9.2} ms  vkCmdCopyBuffer of the same bytes",
            4 * n
        );
    }
    for (t, ms) in scans.iter().zip(best) {
        println!(
            "scan {}: {:>9.2} ms {:>7.1} Mkeys/s {:>5.2} of copy  segment {}, {}",
            4 * n,
            ms,
            4.0 * n as f64 / ms / 1e3,
            copy_best / ms,
            t.scan_segment,
            t.describe()
        );
    }
}

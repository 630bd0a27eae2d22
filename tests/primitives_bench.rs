//! The primitives benchmark: a quick run under validation (checks that every primitive
//! is verified and timed, not how fast), and the full measurement, ignored by default:
//!
//! ```text
//! cargo test --release --test primitives_bench -- --ignored --nocapture bench_primitives_full
//! ```
//! (`SPLITRAY_BENCH_JSON=out.json` also writes the report as JSON.)

mod common;

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

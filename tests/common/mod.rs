//! Shared test harness: every GPU test runs with the validation layer on, and any
//! validation error or warning fails it.
#![allow(dead_code)]

use splitray::vk::{Gpu, GpuDesc, InstanceDesc, StreamPlacement};

/// Opens the default device with validation (and synchronization validation if `sync`).
pub fn gpu_with(placement: StreamPlacement, sync: bool) -> Gpu {
    let _ = env_logger::builder().is_test(true).try_init();
    Gpu::new(&GpuDesc {
        instance: InstanceDesc {
            validation: true,
            sync_validation: sync,
        },
        device: None,
        placement,
    })
    .expect("a Vulkan device with the validation layer (run `make deps`)")
}

pub fn gpu() -> Gpu {
    gpu_with(StreamPlacement::Spread, false)
}

/// Waits for the device, then fails the test on any validation message.
pub fn assert_clean(gpu: &Gpu) {
    gpu.wait_idle().expect("wait idle");
    let messages = gpu.validation_messages();
    assert!(
        messages.is_empty(),
        "{} validation message(s):\n{}",
        messages.len(),
        messages
            .iter()
            .map(|m| format!("  {} [{}] {}", m.severity, m.id_name, m.text))
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// Deterministic pseudo-random u32s (SplitMix64) for test data.
pub fn random_u32s(n: usize, seed: u64) -> Vec<u32> {
    let mut state = seed;
    (0..n)
        .map(|_| {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as u32
        })
        .collect()
}

//! The CPU twin of `glsl/common/random.glsl` (src/bidir/random.rs) against the GLSL
//! function on the device, bit for bit: the bidirectional integrators' random numbers
//! are the GPU methods' random numbers.
use crate::common;

use bytemuck::{Pod, Zeroable};
use splitray::bidir::random::random01;
use splitray::shaders;
use splitray::vk::{ComputePipeline, PipelineDesc, StreamKind};

/// `Query` in glsl/test/random_echo.comp.
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
#[repr(C)]
struct Query {
    index: u32,
    sample: u32,
    dimension: u32,
    seed: u32,
}

#[test]
fn random01_matches_the_glsl_function_bit_for_bit() {
    let gpu = common::gpu();
    let pipeline = ComputePipeline::new(
        &gpu,
        &PipelineDesc {
            kernel: shaders::TEST_RANDOM_ECHO,
            bindings: 2,
            push_constant_bytes: 4,
            spec: &[64],
        },
    )
    .unwrap();
    // Random words, plus the edges: zeros, all ones, the light subpaths' dimensions.
    let words = common::random_u32s(4 * 100_003, 9);
    let mut queries: Vec<Query> = words
        .chunks_exact(4)
        .map(|w| Query {
            index: w[0],
            sample: w[1] % 4096,
            dimension: w[2],
            seed: w[3],
        })
        .collect();
    queries.push(Query::default());
    queries.push(Query {
        index: u32::MAX,
        sample: u32::MAX,
        dimension: u32::MAX,
        seed: u32::MAX,
    });
    queries.push(Query {
        dimension: splitray::bidir::random::dims::LIGHT_BASE,
        ..Default::default()
    });
    let n = queries.len();
    let input = gpu.upload("random-queries", &queries).unwrap();
    let output = gpu.zeroed::<u32>("random-bits", n).unwrap();
    let mut rec = gpu.recorder(StreamKind::Main).unwrap();
    rec.dispatch_items(
        &pipeline,
        &[(&input).into(), (&output).into()],
        &(n as u32),
        n as u64,
    )
    .unwrap();
    gpu.wait(&rec.submit(&[]).unwrap()).unwrap();
    let bits = output.read::<u32>().unwrap();
    let mismatches: Vec<_> = queries
        .iter()
        .zip(&bits)
        .filter(|(q, &b)| random01(q.index, q.sample, q.dimension, q.seed).to_bits() != b)
        .take(4)
        .collect();
    assert!(mismatches.is_empty(), "CPU and GPU differ: {mismatches:?}");
    common::assert_clean(&gpu);
}

//! The integration tests, one binary: each module is one area of splitray.
//!
//! nextest runs each test in a process of its own, but `cargo test` (what `make test`
//! falls back to without nextest) runs them all in one process, on parallel threads. So
//! a test changes nothing process-wide that another test relies on: no global `tracing`
//! subscriber (the timeline's capture installs one; a test that needs its own runs in a
//! child process: common/process.rs), no environment variables, and the GPU tests take
//! turns on their devices (common/turn.rs).

mod common;

mod animation;
mod bdpt_bench;
mod bidir_mis;
mod bidir_random;
mod bpt_agreement;
mod bpt_analytic;
mod bpt_mitsuba;
mod bsdf_chi2;
mod bsdf_gpu;
mod cbpt_gpu;
mod cbpt_mis;
mod cbpt_mitsuba;
mod cbpt_pipeline;
mod cbpt_render;
mod checkpoint;
mod cli;
mod cli_long_renders;
mod display_server;
mod display_tonemap;
mod eye_kernels;
mod far_from_origin;
mod film_io;
mod input_fuzz;
mod integrator_interface;
mod lvc_accumulate;
mod lvc_analytic;
mod lvc_determinism;
mod lvc_kernels;
mod lvc_mis;
mod lvc_mitsuba;
mod past_one_binding;
mod preview_window;
mod primitives_bench;
mod primitives_compact;
mod primitives_reduce;
mod primitives_scan;
mod primitives_sort;
mod primitives_sync;
mod pt_analytic;
mod pt_kernels;
mod pt_materials;
mod pt_mitsuba;
mod ray_offset;
mod reference_compare;
mod render;
mod scene_load;
mod shader_build;
mod shards;
mod timeline;
mod trace_brute_force;
mod trace_cpu_bvh;
mod trace_pdacrt;
mod trace_tracers;
mod trace_watertight;
mod vk_runtime;

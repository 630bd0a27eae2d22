//! splitray: a Vulkan-native ray tracing and light transport engine.
//!
//! Layers, bottom to top:
//! - [`vk`]: the only place with `unsafe` and raw `ash` — instance, device, streams,
//!   buffers, pipelines, command recording, profiling.
//! - [`shaders`]: SPIR-V compiled from `glsl/` at build time.
//! - [`primitives`]: GPU scan, radix sort, reduce-by-key, compaction, gather/scatter.
//! - [`bsdf`]: BSDFs and layered materials, with GLSL twins in `glsl/common/bsdf.glsl`.
//! - [`scene`], [`film`]: scene input and image output (CPU only); [`input`]: opening
//!   the files a command reads (regular files only).
//! - [`trace`]: the `Tracer` interface and its implementations.
//! - [`integrator`]: what is computed along the rays; [`bidir`]: the CPU bidirectional
//!   path tracer's machinery (vertices, walks, connections, MIS and its oracle).
//! - [`render`]: ties a scene, a tracer and an integrator into a film.
//! - [`display`]: watching a render converge (the preview's tone mapping, tev streaming);
//!   `preview`: the preview window (the `window` feature, on X11 systems).
//! - [`scene_export`]: the resolved scene as JSON, for reference renderers.
//! - [`bench`](mod@bench): the measurements behind `splitray bench`.
//! - [`timeline`]: per-stream and per-thread timelines (Chrome trace-event JSON, SVG).
//! - [`console`]: what the command line prints, never fatal to it.

pub mod bench;
pub mod bidir;
pub mod bsdf;
pub mod console;
pub mod display;
pub mod film;
pub mod input;
pub mod integrator;
#[cfg(x11_preview)]
pub mod preview;
pub mod primitives;
pub mod render;
pub mod scene;
pub mod scene_export;
pub mod shaders;
pub mod timeline;
pub mod trace;
pub mod vk;

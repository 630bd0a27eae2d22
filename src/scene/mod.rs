//! Scenes: geometry, materials, lights and camera, from TOML, OBJ or built-in generators.
pub mod camera;
pub use camera::{Camera, CameraFrame};

//! [`Fingerprint`]: what decides an image, so that a checkpoint is continued and shards
//! are merged only with the scene and settings they were rendered from.
//!
//! It covers the scene's content (triangles, their shading normals and materials, the
//! materials, point lights and camera), the film size, seed, integrator, samples per pass
//! and every setting the integrator reports ([`crate::integrator::Integrator::settings`]).
//! Left out on purpose:
//! - names (scene, materials): renaming a file changes no pixel;
//! - the tracer and the device: every tracer returns the same hits (tests/suite/trace_tracers.rs)
//!   and devices differ only in floating-point rounding, so shards of one image may be
//!   rendered by different tracers on different machines. Both are recorded in the image
//!   header all the same. (A resumed render is bit-identical to an uninterrupted one on
//!   the same tracer and device.)
//! - the samples asked for: a checkpoint can be continued to more of them, and which
//!   passes each shard took is recorded by pass index instead.
//!
//! Hashes are SHA-256 over an explicit little-endian byte stream (never `std`'s
//! `Hasher`, which may change between Rust releases), so fingerprints agree across
//! machines and builds.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::scene::{Material, Scene};

/// The scene content's digest and the settings that decide an image besides it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fingerprint {
    /// SHA-256 of the scene content, hex ([`scene_digest`]).
    pub scene_digest: String,
    /// `(key, value)` in a fixed order: film size, seed, integrator, samples per pass,
    /// then the integrator's own settings.
    pub settings: Vec<(String, String)>,
}

impl Fingerprint {
    /// The fingerprint of `scene` rendered at `width × height` with `seed` by `integrator`,
    /// whose passes add `samples_per_pass` samples and which reports `integrator_settings`.
    pub fn new(
        scene: &Scene,
        width: u32,
        height: u32,
        seed: u64,
        integrator: &str,
        samples_per_pass: u32,
        integrator_settings: Vec<(String, String)>,
    ) -> Self {
        let mut settings = vec![
            ("width".to_string(), width.to_string()),
            ("height".to_string(), height.to_string()),
            ("seed".to_string(), seed.to_string()),
            ("integrator".to_string(), integrator.to_string()),
            ("samples_per_pass".to_string(), samples_per_pass.to_string()),
        ];
        settings.extend(integrator_settings);
        Self {
            scene_digest: scene_digest(scene),
            settings,
        }
    }

    /// SHA-256 of the digest and settings, hex: equal for images that may be merged.
    pub fn hash(&self) -> String {
        let mut h = Sha256::new();
        h.update(b"splitray-fingerprint-1\n");
        h.update(self.scene_digest.as_bytes());
        for (key, value) in &self.settings {
            h.update(b"\n");
            h.update(key.as_bytes());
            h.update(b"=");
            h.update(value.as_bytes());
        }
        hex(&h.finalize())
    }

    /// What differs from `other`, in words (empty when the two are equal), e.g.
    /// `["seed 7 in a.exr, 8 in b.exr"]` where `this` and `that` name the two.
    pub fn differences(&self, other: &Fingerprint, this: &str, that: &str) -> Vec<String> {
        let mut out = Vec::new();
        if self.scene_digest != other.scene_digest {
            out.push("the scene's geometry, materials, lights or camera".to_string());
        }
        let value = |list: &[(String, String)], key: &str| {
            list.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone())
        };
        let mut keys: Vec<&String> = self.settings.iter().map(|(k, _)| k).collect();
        for (k, _) in &other.settings {
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
        for key in keys {
            let (a, b) = (value(&self.settings, key), value(&other.settings, key));
            if a != b {
                let show = |v: Option<String>| v.unwrap_or_else(|| "unset".into());
                out.push(format!("{key} {} {this}, {} {that}", show(a), show(b)));
            }
        }
        out
    }

    /// The settings as one header value: `key=value;key=value`.
    /// The value of setting `key`, if the fingerprint has it.
    pub fn setting(&self, key: &str) -> Option<&str> {
        self.settings
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    pub fn settings_string(&self) -> String {
        self.settings
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(";")
    }

    /// Parses [`Fingerprint::settings_string`].
    pub fn parse_settings(text: &str) -> Option<Vec<(String, String)>> {
        if text.is_empty() {
            return Some(Vec::new());
        }
        text.split(';')
            .map(|pair| {
                let (k, v) = pair.split_once('=')?;
                Some((k.to_string(), v.to_string()))
            })
            .collect()
    }
}

/// SHA-256 (hex) of everything in `scene` that changes its image: the triangles in soup
/// order (vertices, shading normals, material index), the materials (all parameters but
/// the name), the point lights and the camera. Floats enter by their bit patterns.
pub fn scene_digest(scene: &Scene) -> String {
    let mut h = Sha256::new();
    h.update(b"splitray-scene-1");
    h.update((scene.triangles.len() as u64).to_le_bytes());
    for t in &scene.triangles {
        for p in t.p {
            update_vec3(&mut h, p);
        }
        match t.n {
            Some(n) => {
                h.update([1u8]);
                for v in n {
                    update_vec3(&mut h, v);
                }
            }
            None => h.update([0u8]),
        }
        h.update(t.material.to_le_bytes());
    }
    // Materials, lights and camera through serde_json: finite floats print as the
    // shortest string that reads back to the same bits, so the text is as exact.
    let unnamed: Vec<Material> = scene
        .materials
        .iter()
        .map(|m| Material {
            name: String::new(),
            ..m.clone()
        })
        .collect();
    let json = serde_json::to_vec(&(&unnamed, &scene.point_lights, &scene.camera))
        .expect("scene parts serialise to JSON");
    h.update((json.len() as u64).to_le_bytes());
    h.update(json);
    hex(&h.finalize())
}

fn update_vec3(h: &mut Sha256, v: glam::Vec3) {
    for c in v.to_array() {
        h.update(c.to_bits().to_le_bytes());
    }
}

/// Lower-case hex of `bytes`.
pub(crate) fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    fn fingerprint(scene: &Scene, seed: u64) -> Fingerprint {
        Fingerprint::new(
            scene,
            24,
            16,
            seed,
            "pt",
            1,
            vec![("max_depth".into(), "-1".into())],
        )
    }

    #[test]
    fn equal_inputs_give_equal_hashes_and_no_differences() {
        let scene = builtin("cornell-box").unwrap();
        let (a, b) = (fingerprint(&scene, 7), fingerprint(&scene, 7));
        assert_eq!(a.hash(), b.hash());
        assert!(a.differences(&b, "a", "b").is_empty());
        assert_eq!(a.hash().len(), 64);
    }

    #[test]
    fn every_part_of_the_scene_and_settings_changes_the_hash() {
        let scene = builtin("cornell-box").unwrap();
        let base = fingerprint(&scene, 7);
        let mut changed = Vec::new();
        let mut s = scene.clone();
        s.triangles[3].p[1].x += 1e-3;
        changed.push(fingerprint(&s, 7));
        let mut s = scene.clone();
        s.triangles[0].material = 1;
        changed.push(fingerprint(&s, 7));
        let mut s = scene.clone();
        s.materials[0].diffuse.y *= 0.5;
        changed.push(fingerprint(&s, 7));
        let mut s = scene.clone();
        s.camera.fov_y += 0.1;
        changed.push(fingerprint(&s, 7));
        let mut s = scene.clone();
        s.point_lights.push(crate::scene::PointLight {
            position: glam::Vec3::ONE,
            intensity: glam::Vec3::ONE,
        });
        changed.push(fingerprint(&s, 7));
        changed.push(fingerprint(&scene, 8));
        let mut other_depth = fingerprint(&scene, 7);
        other_depth.settings.last_mut().unwrap().1 = "5".into();
        changed.push(other_depth);
        for c in &changed {
            assert_ne!(c.hash(), base.hash());
            assert!(!base.differences(c, "a", "b").is_empty());
        }
        assert_eq!(
            base.differences(&fingerprint(&scene, 8), "here", "there"),
            ["seed 7 here, 8 there"]
        );
        // Names alone change no pixel.
        let mut renamed = scene.clone();
        renamed.name = "other".into();
        renamed.materials[0].name = "other".into();
        assert_eq!(fingerprint(&renamed, 7).hash(), base.hash());
    }

    #[test]
    fn settings_string_round_trips() {
        let scene = builtin("cornell-box").unwrap();
        let f = fingerprint(&scene, 7);
        let text = f.settings_string();
        assert_eq!(Fingerprint::parse_settings(&text).unwrap(), f.settings);
        assert_eq!(Fingerprint::parse_settings("a").as_deref(), None);
    }
}

//! Scenes several tests share.

use glam::Vec3;
use splitray::scene::{builtin, MaterialBsdf, MaterialLayer, PointLight, Scene};

/// The Cornell box with a mirror tall block, a short block of mixed diffuse and mirror
/// layers, tilted shading normals on the floor, and a point light beside the area light.
pub fn tricky_cornell_box() -> Scene {
    let mut scene = builtin("cornell-box").unwrap();
    let layer = |kind: &str, r: f32, weight: f32| MaterialLayer {
        kind: splitray::scene::BsdfKind::from_name(kind).unwrap(),
        reflectance: Vec3::splat(r),
        roughness: 0.3,
        distribution: splitray::scene::MicrofacetModel::Ggx,
        ior: 1.5,
        weight,
    };
    let mirror = scene.materials.len() as u32;
    let mut m = scene.materials[0].clone();
    m.name = "mirror".into();
    m.bsdf = Some(MaterialBsdf {
        layers: vec![layer("mirror", 0.9, 1.0)],
    });
    scene.materials.push(m.clone());
    m.name = "mixed".into();
    m.bsdf = Some(MaterialBsdf {
        layers: vec![
            layer("lambert", 0.7, 0.5),
            layer("mirror", 0.9, 0.3),
            layer("conductor", 0.8, 0.2),
        ],
    });
    scene.materials.push(m);
    // Triangles 10..20 are the short block, 20..30 the tall one (scene::builtin).
    for (i, t) in scene.triangles.iter_mut().enumerate() {
        match i {
            10..20 => t.material = mirror + 1,
            20..30 => t.material = mirror,
            _ => {}
        }
        let ng = t.geometric_normal();
        if ng.y > 0.9 && t.centroid().y < 1.0 {
            // Floor: vertex normals tilted differently at each corner.
            let tilt = |k: usize| (ng + Vec3::new(0.2 * k as f32 - 0.2, 0.0, 0.15)).normalize();
            t.n = Some([tilt(0), tilt(1), tilt(2)]);
        }
    }
    scene.point_lights.push(PointLight {
        position: Vec3::new(278.0, 400.0, 279.0),
        intensity: Vec3::splat(3e4),
    });
    scene
}

/// The scene `factor` times as large (a power of two, so every length scales exactly):
/// triangles, camera and point lights move; a point light's intensity scales by
/// factor² so that the light reaching each surface stays the same.
pub fn scaled(scene: &Scene, factor: f32) -> Scene {
    let mut s = scene.clone();
    for t in &mut s.triangles {
        t.p = t.p.map(|p| p * factor);
    }
    s.camera.position *= factor;
    s.camera.look_at *= factor;
    for l in &mut s.point_lights {
        l.position *= factor;
        l.intensity *= factor * factor;
    }
    s
}

/// The scene with every emitter `factor` times as bright.
pub fn brighter(scene: &Scene, factor: f32) -> Scene {
    let mut s = scene.clone();
    for m in &mut s.materials {
        m.emission *= factor;
    }
    for l in &mut s.point_lights {
        l.intensity *= factor;
    }
    s
}

/// Whether squaring some pixel's mean in f32 overflows or vanishes: films whose second
/// moments were sums of such squares lost those pixels' standard error.
pub fn squares_leave_f32(mean: &[[f32; 3]]) -> bool {
    mean.iter()
        .flatten()
        .any(|&m| m > 0.0 && (m * m == 0.0 || (m * m).is_infinite()))
}

/// Asserts that `got`, rendered with the lights `factor` (a power of two) as bright as
/// `expected`'s, is `expected` scaled exactly: sums by `factor`, second moments by its
/// square, and every pixel's standard error by `factor`, finite.
pub fn assert_scaled_exactly(
    got: &splitray::film::FilmSums,
    expected: &splitray::film::FilmSums,
    factor: f32,
    what: &str,
) {
    let scaled = |sums: &[[f64; 3]], by: f64| -> Vec<[f64; 3]> {
        sums.iter().map(|p| p.map(|v| v * by)).collect()
    };
    assert_eq!(got.sum, scaled(&expected.sum, factor as f64), "{what}");
    assert_eq!(
        got.sum_sq.as_deref().unwrap(),
        scaled(expected.sum_sq.as_deref().unwrap(), (factor as f64).powi(2)),
        "{what}: second moments"
    );
    let expected_se = expected.stderr().unwrap();
    for (p, (g, e)) in got.stderr().unwrap().iter().zip(&expected_se).enumerate() {
        assert_eq!(
            *g,
            e.map(|v| v * factor),
            "{what}: pixel {p}'s standard error"
        );
        assert!(g.iter().all(|v| v.is_finite()), "{what}: pixel {p}: {g:?}");
    }
}

//! Checks that a scene can be rendered; every error names the scene's source file.

use glam::Vec3;

use super::{Camera, FilmSize, Location, Scene, SceneError, SceneStats};

/// What [`super::Triangle::is_degenerate`] finds, in words.
const DEGENERATE: &str = "degenerate (zero area, or an area past 32-bit floating point)";

/// Largest accepted film width or height, in pixels.
pub const MAX_FILM_DIM: u32 = 16384;

/// Position, look-at and up finite; look_at ≠ position, and their distance's square
/// finite; up non-zero and not parallel to the view direction; 0 < fov_y < 180.
pub fn validate_camera(camera: &Camera, at: &Location) -> Result<(), SceneError> {
    let err = |message: String| SceneError::Camera {
        at: at.clone(),
        message,
    };
    for (what, v) in [
        ("position", camera.position),
        ("look_at", camera.look_at),
        ("up", camera.up),
    ] {
        if !v.is_finite() {
            return Err(err(format!("{what} {v} is not finite")));
        }
    }
    if !camera.fov_y.is_finite() || camera.fov_y <= 0.0 || camera.fov_y >= 180.0 {
        return Err(err(format!(
            "fov_y {} is outside (0, 180) degrees",
            camera.fov_y
        )));
    }
    let forward = camera.look_at - camera.position;
    let distance2 = forward.length_squared();
    // Past about 1.8e19 the squared distance overflows f32: the view direction would
    // normalise to zero and every ray of the camera would be NaN.
    if !distance2.is_finite() {
        return Err(err(format!(
            "look_at {} is too far from position {} for 32-bit floating point",
            camera.look_at, camera.position
        )));
    }
    if distance2 <= f32::MIN_POSITIVE {
        return Err(err(format!(
            "look_at {} is the same point as position",
            camera.look_at
        )));
    }
    // Within about eight float steps of position, the view direction is mostly rounding.
    if forward.length() <= 1e-6 * camera.position.abs().max_element() {
        return Err(err(format!(
            "look_at {} is too close to position {} for 32-bit floating point so far \
             from the origin: move it farther along the view direction",
            camera.look_at, camera.position
        )));
    }
    if camera.up.length_squared() <= f32::MIN_POSITIVE {
        return Err(err("up is the zero vector".to_string()));
    }
    let f = forward.normalize();
    let u = camera.up.normalize();
    if f.cross(u).length() < 1e-4 {
        return Err(err(format!(
            "up {} is parallel to the view direction {}",
            camera.up, f
        )));
    }
    Ok(())
}

/// Whether `pixels` is a film side splitray renders: 1 ..= [`MAX_FILM_DIM`].
pub fn is_film_side(pixels: u32) -> bool {
    (1..=MAX_FILM_DIM).contains(&pixels)
}

/// 1 ≤ width, height ≤ [`MAX_FILM_DIM`].
pub fn validate_film(film: &FilmSize, at: &Location) -> Result<(), SceneError> {
    for (what, v) in [("width", film.width), ("height", film.height)] {
        if !is_film_side(v) {
            return Err(SceneError::Film {
                at: at.clone(),
                message: format!("{what} {v} is outside 1..={MAX_FILM_DIM}"),
            });
        }
    }
    Ok(())
}

pub(super) fn check_finite(
    v: Vec3,
    at: &Location,
    what: impl FnOnce() -> String,
) -> Result<(), SceneError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(SceneError::NonFinite {
            at: at.clone(),
            what: what(),
            value: v.to_string(),
        })
    }
}

/// Radiance, reflectances and intensities are never negative: a negative channel would
/// make the integrators' pdfs and weights meaningless rather than just dim the image.
pub(super) fn check_non_negative(
    v: Vec3,
    at: &Location,
    what: impl FnOnce() -> String,
) -> Result<(), SceneError> {
    if v.min_element() < 0.0 {
        return Err(SceneError::Invalid {
            at: at.clone(),
            message: format!("{} {v} is negative", what()),
        });
    }
    Ok(())
}

/// Why a reflectance channel above 1 is refused.
pub(super) const ABOVE_ONE: &str =
    "is more than 1: a surface cannot reflect more light than it receives";

/// A reflectance (`diffuse`, `specular`): each channel in [0, 1]. One above 1 would make
/// every bounce add energy, so that a closed room's radiance grows without bound.
pub(super) fn check_reflectance(
    v: Vec3,
    at: &Location,
    what: impl Fn() -> String,
) -> Result<(), SceneError> {
    check_non_negative(v, at, &what)?;
    if v.max_element() > 1.0 {
        return Err(SceneError::Invalid {
            at: at.clone(),
            message: format!("{} {v} {ABOVE_ONE}", what()),
        });
    }
    Ok(())
}

/// Full check of a scene loaded from `at`: camera, film, non-empty geometry, finite
/// vertices / normals / material and light parameters, material indices in range.
/// Degenerate triangles are allowed (counted and logged as a warning) unless every
/// triangle is degenerate.
pub fn validate_scene(scene: &Scene, at: &Location) -> Result<SceneStats, SceneError> {
    validate_camera(&scene.camera, at)?;
    validate_film(&scene.film, at)?;
    if scene.triangles.is_empty() {
        return Err(SceneError::Empty {
            at: at.clone(),
            message: format!("scene '{}' has no triangles", scene.name),
        });
    }
    for (i, t) in scene.triangles.iter().enumerate() {
        for (k, p) in t.p.iter().enumerate() {
            check_finite(*p, at, || format!("triangle {i} vertex {k}"))?;
        }
        if let Some(n) = &t.n {
            for (k, v) in n.iter().enumerate() {
                check_finite(*v, at, || format!("triangle {i} normal {k}"))?;
            }
        }
        if t.material as usize >= scene.materials.len() {
            return Err(SceneError::Invalid {
                at: at.clone(),
                message: format!(
                    "triangle {i} uses material {} but the scene has {} materials",
                    t.material,
                    scene.materials.len()
                ),
            });
        }
    }
    for m in &scene.materials {
        for (what, v, reflectance) in [
            ("diffuse", m.diffuse, true),
            ("specular", m.specular, true),
            ("emission", m.emission, false),
        ] {
            let what = || format!("material '{}' {what}", m.name);
            check_finite(v, at, what)?;
            if reflectance {
                check_reflectance(v, at, what)?;
            } else {
                check_non_negative(v, at, what)?;
            }
        }
        for (what, v) in [
            ("shininess", m.shininess),
            ("ior", m.ior),
            ("dissolve", m.dissolve),
        ] {
            if !v.is_finite() {
                return Err(SceneError::NonFinite {
                    at: at.clone(),
                    what: format!("material '{}' {what}", m.name),
                    value: v.to_string(),
                });
            }
        }
    }
    for (i, l) in scene.point_lights.iter().enumerate() {
        check_finite(l.position, at, || format!("point light {i} position"))?;
        check_finite(l.intensity, at, || format!("point light {i} intensity"))?;
        check_non_negative(l.intensity, at, || format!("point light {i} intensity"))?;
    }
    let stats = scene.stats();
    if stats.degenerate_triangles == stats.triangles {
        return Err(SceneError::Empty {
            at: at.clone(),
            message: format!(
                "all {} triangles of scene '{}' are {DEGENERATE}",
                stats.triangles, scene.name
            ),
        });
    }
    if stats.degenerate_triangles > 0 {
        log::warn!(
            "{at}: {} of {} triangles are {DEGENERATE}; kept",
            stats.degenerate_triangles,
            stats.triangles
        );
    }
    if stats.emissive_triangles == 0 && stats.point_lights == 0 {
        log::warn!("{at}: scene '{}' has no lights", scene.name);
    }
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at() -> Location {
        Location::file("x.toml")
    }

    fn cam() -> Camera {
        Camera {
            position: Vec3::new(0.0, 0.0, -5.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 45.0,
        }
    }

    #[test]
    fn camera_errors() {
        assert!(validate_camera(&cam(), &at()).is_ok());
        let bad = [
            (
                Camera {
                    look_at: Vec3::new(0.0, 0.0, -5.0),
                    ..cam()
                },
                "same point",
            ),
            (
                Camera {
                    up: Vec3::ZERO,
                    ..cam()
                },
                "zero vector",
            ),
            (
                Camera {
                    up: Vec3::Z,
                    ..cam()
                },
                "parallel",
            ),
            (
                Camera {
                    fov_y: 180.0,
                    ..cam()
                },
                "outside (0, 180)",
            ),
            (
                Camera {
                    fov_y: 0.0,
                    ..cam()
                },
                "outside (0, 180)",
            ),
            (
                Camera {
                    position: Vec3::new(f32::NAN, 0.0, 0.0),
                    ..cam()
                },
                "not finite",
            ),
            (
                Camera {
                    position: Vec3::new(0.0, 0.0, 1e38),
                    ..cam()
                },
                "too far from position",
            ),
        ];
        for (c, want) in bad {
            let e = validate_camera(&c, &at()).unwrap_err().to_string();
            assert!(e.starts_with("x.toml: invalid camera"), "{e}");
            assert!(e.contains(want), "{e} should contain {want}");
        }
    }

    #[test]
    fn film_errors() {
        let ok = FilmSize {
            width: 16384,
            height: 1,
        };
        assert!(validate_film(&ok, &at()).is_ok());
        for (w, h) in [(0, 10), (10, 0), (16385, 10)] {
            let e = validate_film(
                &FilmSize {
                    width: w,
                    height: h,
                },
                &at(),
            )
            .unwrap_err()
            .to_string();
            assert!(e.contains("x.toml: invalid film size"), "{e}");
        }
    }
}

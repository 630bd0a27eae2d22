//! Vertex animation from a numbered sequence of OBJ files (`wave_0000.obj`,
//! `wave_0001.obj`, …): file `first + k` is the mesh's shape at time `k / fps`; between
//! two files every vertex (and shading normal) moves linearly; before the first file and
//! after the last the shape is held.
//!
//! Every file of a sequence must have the same triangles in the same order (the same
//! face count after triangulation, so each vertex has a partner in every file), and
//! either all or none of them vertex normals. Materials come from the first file.

use std::path::Path;

use glam::Vec3;

use crate::scene::obj::{check_referenced_file, load_obj_mesh, ObjMesh};
use crate::scene::{Location, SceneError, Triangle};

/// A file name with one frame number in it: `{}` (the number as is) or `{:0N}` (zero-
/// padded to N digits), e.g. `wave_{:04}.obj`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SequencePattern {
    prefix: String,
    suffix: String,
    /// Zero-padded width; 0 for none.
    width: usize,
}

impl SequencePattern {
    /// The pattern in `path`, `Ok(None)` when `path` has no `{`, or why it is not one.
    pub fn parse(path: &str) -> Result<Option<Self>, String> {
        let Some(open) = path.find('{') else {
            return Ok(None);
        };
        let Some(close) = path[open..].find('}').map(|c| open + c) else {
            return Err(format!("'{path}': '{{' without a closing '}}'"));
        };
        let spec = &path[open + 1..close];
        let width = match spec {
            "" => 0,
            _ => spec
                .strip_prefix(":0")
                .and_then(|w| w.parse::<usize>().ok())
                .filter(|w| (1..=9).contains(w))
                .ok_or_else(|| {
                    format!(
                        "'{path}': the frame number is written {{}} or {{:0N}} (N digits, \
                         zero-padded, 1 to 9), not {{{spec}}}"
                    )
                })?,
        };
        let suffix = &path[close + 1..];
        if suffix.contains('{') || suffix.contains('}') {
            return Err(format!("'{path}': only one {{…}} frame number is allowed"));
        }
        Ok(Some(Self {
            prefix: path[..open].to_string(),
            suffix: suffix.to_string(),
            width,
        }))
    }

    /// The file name of frame `number`.
    pub fn file(&self, number: u32) -> String {
        format!(
            "{}{:0width$}{}",
            self.prefix,
            number,
            self.suffix,
            width = self.width
        )
    }
}

/// The positions (and shading normals) of one file of a sequence, per triangle.
#[derive(Clone, Debug, PartialEq)]
struct Shape {
    p: Vec<[Vec3; 3]>,
    n: Option<Vec<[Vec3; 3]>>,
}

/// The shapes of a mesh over time.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexSequence {
    fps: f64,
    shapes: Vec<Shape>,
}

/// Fractions this close to a whole frame count as that frame, so that a frame time
/// rounded to f32 poses the file itself.
const SNAP: f64 = 1e-4;

impl VertexSequence {
    /// Files in the sequence.
    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// Seconds from the first file to the last.
    pub fn duration(&self) -> f64 {
        (self.shapes.len().saturating_sub(1)) as f64 / self.fps
    }

    /// The file before time `t` (index from 0) and the fraction of the way to the next.
    pub fn segment(&self, t: f32) -> (usize, f32) {
        let last = self.shapes.len() - 1;
        let u = (t as f64 * self.fps).clamp(0.0, last as f64);
        if u.is_nan() {
            return (0, 0.0);
        }
        let (i, w) = (u.floor(), u - u.floor());
        let i = i as usize;
        if w < SNAP || i == last {
            (i, 0.0)
        } else if w > 1.0 - SNAP {
            (i + 1, 0.0)
        } else {
            (i, w as f32)
        }
    }

    /// Vertex `k` of triangle `j` (and its normal, if the files have normals) at the
    /// place `(i, w)` of [`Self::segment`].
    pub fn vertex(&self, (i, w): (usize, f32), j: usize) -> ([Vec3; 3], Option<[Vec3; 3]>) {
        let a = &self.shapes[i];
        if w == 0.0 {
            return (a.p[j], a.n.as_ref().map(|n| n[j]));
        }
        let b = &self.shapes[i + 1];
        let p = std::array::from_fn(|k| a.p[j][k].lerp(b.p[j][k], w));
        let n = match (&a.n, &b.n) {
            (Some(na), Some(nb)) => Some(std::array::from_fn(|k| {
                na[j][k].lerp(nb[j][k], w).normalize_or_zero()
            })),
            _ => None,
        };
        (p, n)
    }
}

/// Loads files `first..=last` of `pattern` (relative to `dir`) at `fps` files per
/// second: the first file's mesh (triangles and materials) and the sequence. `at` is the
/// scene file's place that names the pattern; `shown` is the pattern as written there.
pub fn load_sequence(
    dir: &Path,
    pattern: &SequencePattern,
    shown: &str,
    (first, last, fps): (u32, u32, f64),
    at: &Location,
) -> Result<(ObjMesh, VertexSequence), SceneError> {
    let invalid = |message: String| SceneError::Invalid {
        at: at.clone(),
        message: format!("mesh sequence '{shown}': {message}"),
    };
    if last < first {
        return Err(invalid(format!(
            "last file {last} comes before first file {first}"
        )));
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(invalid(format!("fps {fps} must be a positive number")));
    }
    // Every file must exist before any is parsed: a missing one is named at once. The
    // names are made one at a time, so a mistyped `last` costs no memory.
    for n in first..=last {
        let name = pattern.file(n);
        check_referenced_file(&dir.join(&name), at, "mesh sequence file", &name)?;
    }
    let first_name = pattern.file(first);
    let mut first_mesh: Option<ObjMesh> = None;
    let mut shapes = Vec::with_capacity((last - first) as usize + 1);
    for n in first..=last {
        let name = pattern.file(n);
        // Every file's positions measured from the first file's origin (`ObjMesh::origin`).
        let mut mesh = load_obj_mesh(&dir.join(&name))?;
        if let Some(first) = &first_mesh {
            mesh = mesh.measured_from(first.origin);
        }
        let shape = shape_of(&mesh.triangles);
        if let Some(m) = &first_mesh {
            check_same_topology(m, &mesh, (&first_name, &name)).map_err(&invalid)?;
        } else {
            if mesh.triangles.is_empty() {
                return Err(invalid(format!("'{name}' has no faces")));
            }
            first_mesh = Some(mesh);
        }
        shapes.push(shape);
    }
    let mesh = first_mesh.expect("first <= last: at least one file");
    Ok((mesh, VertexSequence { fps, shapes }))
}

fn shape_of(triangles: &[Triangle]) -> Shape {
    let all_normals = triangles.iter().all(|t| t.n.is_some());
    Shape {
        p: triangles.iter().map(|t| t.p).collect(),
        n: all_normals.then(|| triangles.iter().map(|t| t.n.unwrap()).collect()),
    }
}

/// The same triangle count, the same faces over the vertices and the same normals (all
/// or none per triangle) as the first file: frames blend triangle by triangle, so a file
/// whose faces join other vertices would tear the mesh apart between frames.
fn check_same_topology(
    first: &ObjMesh,
    other: &ObjMesh,
    (first_name, name): (&str, &str),
) -> Result<(), String> {
    let (a, b) = (first.triangles.len(), other.triangles.len());
    if a != b {
        return Err(format!(
            "'{name}' has {b} triangles ({} vertices) but '{first_name}' has {a} ({} \
             vertices): every file of a sequence needs the same faces in the same order",
            3 * b,
            3 * a
        ));
    }
    if first.connectivity != other.connectivity {
        return Err(format!(
            "'{name}' joins its vertices into faces otherwise than '{first_name}': every \
             file of a sequence needs the same faces in the same order"
        ));
    }
    let with_normals = |m: &ObjMesh| m.triangles.iter().filter(|t| t.n.is_some()).count();
    let (na, nb) = (with_normals(first), with_normals(other));
    if na != nb {
        return Err(format!(
            "'{name}' has vertex normals on {nb} triangles but '{first_name}' on {na}: \
             every file of a sequence needs normals on the same faces, or none"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns() {
        let p = SequencePattern::parse("wave_{:04}.obj").unwrap().unwrap();
        assert_eq!(p.file(7), "wave_0007.obj");
        assert_eq!(p.file(12345), "wave_12345.obj");
        let p = SequencePattern::parse("f{}.obj").unwrap().unwrap();
        assert_eq!(p.file(7), "f7.obj");
        assert_eq!(SequencePattern::parse("plain.obj").unwrap(), None);
        for bad in ["a{.obj", "a{:4}.obj", "a{:0}.obj", "a{x}.obj", "a{}{}.obj"] {
            assert!(SequencePattern::parse(bad).is_err(), "{bad}");
        }
    }

    fn sequence(xs: &[f32], fps: f64) -> VertexSequence {
        VertexSequence {
            fps,
            shapes: xs
                .iter()
                .map(|&x| Shape {
                    p: vec![[Vec3::new(x, 0.0, 0.0), Vec3::Y, Vec3::Z]],
                    n: None,
                })
                .collect(),
        }
    }

    #[test]
    fn files_are_frames_at_fps_and_vertices_move_linearly() {
        let s = sequence(&[0.0, 10.0, 30.0], 2.0);
        assert_eq!(s.duration(), 1.0);
        assert_eq!(s.segment(0.0), (0, 0.0));
        assert_eq!(s.segment(0.5), (1, 0.0));
        assert_eq!(s.segment(0.25), (0, 0.5));
        assert_eq!(s.vertex(s.segment(0.25), 0).0[0].x, 5.0);
        assert_eq!(s.vertex(s.segment(0.75), 0).0[0].x, 20.0);
        // Held outside the files' span.
        assert_eq!(s.segment(-1.0), (0, 0.0));
        assert_eq!(s.segment(9.0), (2, 0.0));
        // A frame time rounded to f32 is the file itself.
        let s = sequence(&[0.0, 1.0, 2.0, 3.0], 24.0);
        assert_eq!(s.segment((2.0f64 / 24.0) as f32), (2, 0.0));
        assert_eq!(s.segment(f32::NAN), (0, 0.0));
    }
}

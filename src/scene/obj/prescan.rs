//! The pre-scan of OBJ and MTL text: every number parses and is finite and every face
//! index is inside the file, reported with its line, before `tobj` sees the text (so that
//! inputs on which `tobj` would panic never reach it). It also notes what the text needs
//! rewritten for `tobj` ([`super::for_tobj`]) and how the faces join the vertices.

use std::collections::hash_map::DefaultHasher;
use std::hash::Hasher;

use super::{Location, SceneError};

/// What the OBJ pre-scan learnt besides "no errors".
#[derive(Debug, Default)]
pub(super) struct ObjScan {
    /// The rest of each `mtllib` line (one or more library names) and its line number.
    pub mtllibs: Vec<(String, usize)>,
    /// Each `usemtl` name and its line number.
    pub usemtl: Vec<(String, usize)>,
    /// A `mtllib` line comes after a `usemtl`: `tobj` resolves a `usemtl` against the
    /// libraries loaded so far, so the libraries must move to the top.
    pub mtllib_after_usemtl: bool,
    /// Some data line (`v`, `vt`, `vn`, `f`) needs rewriting for `tobj`: it ends in a
    /// comment, is a one-number `vt`, or is a coloured `v` among plain ones.
    pub data_lines_need_rewrite: bool,
    /// Some vertices carry colours (`v x y z r g b`) and others do not. splitray ignores
    /// vertex colours; `tobj` refuses a file that mixes them, so they are dropped.
    pub mixed_vertex_colours: bool,
    /// A hash of how the faces join the vertices: each face's size and its position
    /// indices renumbered in order of first use. Files with the same faces over vertices
    /// listed in any order hash alike; texture and normal indices do not count.
    pub connectivity: u64,
}

fn rest_of_line<'a>(line: &'a str, keyword: &str) -> &'a str {
    line.trim_start()[keyword.len()..].trim()
}

/// The keyword of an OBJ line and the line without a trailing comment where the keyword
/// is a data line's (`v`, `vt`, `vn`, `f`: a `#` can be nothing else there). Other lines
/// keep their `#`: it may belong to a material or object name.
pub(super) fn data_of(line: &str) -> (Option<&str>, &str) {
    let keyword = line.split_whitespace().next();
    match keyword {
        Some("v" | "vt" | "vn" | "f") => {
            (keyword, line.split_once('#').map_or(line, |(data, _)| data))
        }
        _ => (keyword, line),
    }
}

fn parse_floats(
    words: &[&str],
    n: usize,
    at: &Location,
    what: &str,
) -> Result<Vec<f32>, SceneError> {
    if words.len() < n {
        return Err(SceneError::Syntax {
            at: at.clone(),
            message: format!("{what} needs {n} numbers, found {}", words.len()),
        });
    }
    words[..n]
        .iter()
        .map(|w| {
            w.parse::<f32>().map_err(|_| SceneError::Syntax {
                at: at.clone(),
                message: format!("{what}: '{w}' is not a number"),
            })
        })
        .collect()
}

fn require_finite(vals: &[f32], at: &Location, what: String) -> Result<(), SceneError> {
    if vals.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        let value = vals
            .iter()
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(" ");
        Err(SceneError::NonFinite {
            at: at.clone(),
            what,
            value,
        })
    }
}

/// Line-by-line check of OBJ text: vertex / normal numbers parse and are finite, face
/// indices are non-zero integers inside the file's vertex / texcoord / normal counts.
pub(super) fn prescan_obj(text: &str, file: &str) -> Result<ObjScan, SceneError> {
    let totals = count_elements(text);
    let mut seen = [0usize; 3];
    let mut face = 0usize;
    let mut coloured = 0usize;
    let mut scan = ObjScan::default();
    let mut joins = Connectivity::new(totals[0]);
    for (i, line) in text.lines().enumerate() {
        let (Some(keyword), data) = data_of(line) else {
            continue;
        };
        let words: Vec<&str> = data.split_whitespace().collect();
        let at = || Location::line(file, i + 1);
        scan.data_lines_need_rewrite |= data.len() != line.len();
        match keyword {
            "v" => {
                seen[0] += 1;
                let numbers = check_vertex(&words[1..], seen[0], &at())?;
                coloured += usize::from(numbers == 6);
            }
            "vt" => {
                seen[1] += 1;
                // `vt u [v [w]]`: v defaults to 0 (the OBJ specification).
                parse_floats(&words[1..], 1, &at(), "texture coordinate")?;
                scan.data_lines_need_rewrite |= words.len() == 2;
            }
            "vn" => {
                seen[2] += 1;
                let n = parse_floats(&words[1..], 3, &at(), "vertex normal")?;
                require_finite(&n, &at(), format!("normal {}", seen[2]))?;
            }
            "f" => {
                face += 1;
                check_face(&words[1..], face, &seen, &totals, &at, &mut joins)?;
            }
            "mtllib" => {
                // Without a name, the library's path would be the OBJ's folder.
                let names = rest_of_line(line, "mtllib");
                if names.is_empty() {
                    return Err(SceneError::Syntax {
                        at: at(),
                        message: "mtllib without a material library name".to_string(),
                    });
                }
                scan.mtllib_after_usemtl |= !scan.usemtl.is_empty();
                scan.mtllibs.push((names.to_string(), i + 1));
            }
            "usemtl" => {
                let name = rest_of_line(line, "usemtl");
                if name.is_empty() {
                    return Err(SceneError::Syntax {
                        at: at(),
                        message: "usemtl without a material name".to_string(),
                    });
                }
                scan.usemtl.push((name.to_string(), i + 1));
            }
            _ => {}
        }
    }
    scan.mixed_vertex_colours = coloured != 0 && coloured != totals[0];
    scan.data_lines_need_rewrite |= scan.mixed_vertex_colours;
    scan.connectivity = joins.hash.finish();
    Ok(scan)
}

/// Builds [`ObjScan::connectivity`] face by face.
struct Connectivity {
    /// The renumbered index of each position, `u32::MAX` until a face uses it.
    renumbered: Vec<u32>,
    used: u32,
    hash: DefaultHasher,
}

impl Connectivity {
    fn new(positions: usize) -> Self {
        Self {
            renumbered: vec![u32::MAX; positions],
            used: 0,
            hash: DefaultHasher::new(),
        }
    }

    /// Adds a face by the 0-based indices of its positions.
    fn add_face(&mut self, positions: &[usize]) {
        self.hash.write_usize(positions.len());
        for &p in positions {
            let id = &mut self.renumbered[p];
            if *id == u32::MAX {
                *id = self.used;
                self.used += 1;
            }
            self.hash.write_u32(*id);
        }
    }
}

/// The kinds of element a face refers to, in the order of a face vertex's `v/vt/vn`.
const FACE_INDEX_KINDS: [&str; 3] = ["vertex", "texcoord", "normal"];

/// The file's vertices, texture coordinates and normals ([`FACE_INDEX_KINDS`]).
fn count_elements(text: &str) -> [usize; 3] {
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => nv += 1,
            Some("vt") => nvt += 1,
            Some("vn") => nvn += 1,
            _ => {}
        }
    }
    [nv, nvt, nvn]
}

/// Checks the numbers of vertex `index` (`x y z`, `x y z w` or `x y z r g b`): finite,
/// and a weight that is not 0. Returns how many numbers the vertex has.
fn check_vertex(numbers: &[&str], index: usize, at: &Location) -> Result<usize, SceneError> {
    let xyz = parse_floats(numbers, 3, at, "vertex position")?;
    require_finite(&xyz, at, format!("vertex {index}"))?;
    match numbers.len() {
        3 => {}
        4 => {
            let w = parse_floats(&numbers[3..], 1, at, "vertex w")?[0];
            if w == 0.0 || !w.is_finite() {
                return Err(SceneError::Syntax {
                    at: at.clone(),
                    message: format!("vertex {index} has weight w = {w}"),
                });
            }
        }
        6 => {
            parse_floats(&numbers[3..], 3, at, "vertex colour")?;
        }
        n => {
            return Err(SceneError::Syntax {
                at: at.clone(),
                message: format!(
                    "vertex {index} has {n} numbers: expected x y z, x y z w or x y z r g b"
                ),
            })
        }
    }
    Ok(numbers.len())
}

/// Checks face `face`'s vertex references against the elements `seen` before it and
/// the file's `totals`.
fn check_face(
    vertices: &[&str],
    face: usize,
    seen: &[usize; 3],
    totals: &[usize; 3],
    at: &dyn Fn() -> Location,
    joins: &mut Connectivity,
) -> Result<(), SceneError> {
    if vertices.len() < 3 {
        return Err(SceneError::Syntax {
            at: at(),
            message: format!(
                "face {face} has {} vertices; a face needs at least 3",
                vertices.len()
            ),
        });
    }
    let mut positions = Vec::with_capacity(vertices.len());
    for w in vertices {
        let parts: Vec<&str> = w.split('/').collect();
        if parts.len() > 3 || parts[0].is_empty() {
            return Err(SceneError::Syntax {
                at: at(),
                message: format!("face {face}: malformed vertex reference '{w}'"),
            });
        }
        for (k, part) in parts.iter().enumerate() {
            if part.is_empty() {
                continue;
            }
            let idx: i64 = part.parse().map_err(|_| SceneError::Syntax {
                at: at(),
                message: format!("face {face}: '{part}' in '{w}' is not an index"),
            })?;
            check_face_index(idx, k, face, seen[k], totals[k], at)?;
            if k == 0 {
                // Checked: 1 ≤ idx ≤ total, or −seen ≤ idx ≤ −1.
                positions.push(match idx {
                    i if i > 0 => i as usize - 1,
                    i => seen[0] - i.unsigned_abs() as usize,
                });
            }
        }
    }
    joins.add_face(&positions);
    Ok(())
}

/// Checks index `idx` of kind `k` ([`FACE_INDEX_KINDS`]) in face `face`, where `seen`
/// elements of that kind come before the face and the file has `total`.
fn check_face_index(
    idx: i64,
    k: usize,
    face: usize,
    seen: usize,
    total: usize,
    at: &dyn Fn() -> Location,
) -> Result<(), SceneError> {
    // Relative (negative) indices count back from the elements seen so far; absolute
    // ones may point anywhere in the file.
    let ok = match idx {
        0 => {
            return Err(SceneError::Syntax {
                at: at(),
                message: format!(
                    "face {face}: {} index 0 is invalid (OBJ indices start at 1)",
                    FACE_INDEX_KINDS[k]
                ),
            })
        }
        i if i < 0 => i.unsigned_abs() <= seen as u64,
        i => i as u64 <= total as u64,
    };
    if !ok {
        return Err(SceneError::IndexOutOfRange {
            at: at(),
            face,
            kind: FACE_INDEX_KINDS[k],
            index: idx,
            count: if idx < 0 { seen } else { total },
        });
    }
    Ok(())
}

/// Line-by-line check of MTL text: colour and scalar parameters parse and are finite.
pub(super) fn prescan_mtl(text: &str, file: &str) -> Result<(), SceneError> {
    for (i, line) in text.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some(&keyword) = words.first() else {
            continue;
        };
        let at = Location::line(file, i + 1);
        match keyword {
            "Ka" | "Kd" | "Ks" | "Ke" => {
                let v = parse_floats(&words[1..], 3, &at, keyword)?;
                require_finite(&v, &at, keyword.to_string())?;
                // As `validate_scene` refuses a negative colour and a reflectance above
                // 1, but said at its line (Ka, which splitray does not use, may be
                // anything finite).
                let colour = format!("{keyword} [{}, {}, {}]", v[0], v[1], v[2]);
                let problem = if keyword != "Ka" && v.iter().any(|c| *c < 0.0) {
                    Some("is negative")
                } else if matches!(keyword, "Kd" | "Ks") && v.iter().any(|c| *c > 1.0) {
                    Some(crate::scene::validate::ABOVE_ONE)
                } else {
                    None
                };
                if let Some(problem) = problem {
                    return Err(SceneError::Invalid {
                        at,
                        message: format!("{colour} {problem}"),
                    });
                }
            }
            "Ns" | "Ni" | "d" | "Tr" => {
                let v = parse_floats(&words[1..], 1, &at, keyword)?;
                require_finite(&v, &at, keyword.to_string())?;
            }
            "illum" => {
                let ok = words.get(1).is_some_and(|w| w.parse::<u8>().is_ok());
                if !ok {
                    return Err(SceneError::Syntax {
                        at,
                        message: "illum needs an integer 0..=255".to_string(),
                    });
                }
            }
            "newmtl" if words.len() < 2 => {
                return Err(SceneError::Syntax {
                    at,
                    message: "newmtl without a material name".to_string(),
                })
            }
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prescan_catches_bad_indices_with_line() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 99\n";
        let e = prescan_obj(text, "m.obj").unwrap_err().to_string();
        assert_eq!(
            e,
            "m.obj:5: face 2 references vertex 99 but the file has 3 vertices"
        );
        let e = prescan_obj("v 0 0 0\nf -1 -2 -3\n", "m.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains("m.obj:2: face 1 references vertex -2"), "{e}");
        let e = prescan_obj("v 0 0 0\nf 1/1 1/1 1/1\n", "m.obj")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("references texcoord 1 but the file has 0"),
            "{e}"
        );
        let e = prescan_obj("v 0 0 0\nf 0 1 1\n", "m.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains("index 0 is invalid"), "{e}");
    }

    #[test]
    fn prescan_catches_non_finite() {
        let e = prescan_obj("v 0 0 0\nv 1 nan 0\n", "m.obj")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("m.obj:2: vertex 2 is not finite"), "{e}");
        let e = prescan_mtl("newmtl a\nKd 0.5\n", "m.mtl")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("m.mtl:2: Kd needs 3 numbers"), "{e}");
    }
}

//! The OBJ text `tobj` is given: the file's own text where `tobj` reads it as the OBJ
//! format means, else a copy rewritten into the subset `tobj` reads alike. Line numbers
//! stay the pre-scan's business ([`super::prescan`]), so the copy may move lines.

use std::borrow::Cow;
use std::fmt::Write as _;
use std::path::Path;

use super::prescan::{data_of, ObjScan};

/// One material library a `mtllib` line names, and that line.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Library {
    pub name: String,
    pub line: usize,
}

/// The libraries of the file's `mtllib` lines. A line may name several, separated by
/// spaces (the OBJ specification); a line whose whole rest names a file in `dir` is
/// taken as one name, since names with spaces exist too.
pub(super) fn libraries(scan: &ObjScan, dir: &Path) -> Vec<Library> {
    let mut out = Vec::new();
    for (rest, line) in &scan.mtllibs {
        let whole = !rest.contains(char::is_whitespace) || dir.join(rest).is_file();
        if whole {
            out.push(Library {
                name: rest.clone(),
                line: *line,
            });
        } else {
            out.extend(rest.split_whitespace().map(|name| Library {
                name: name.to_string(),
                line: *line,
            }));
        }
    }
    out
}

/// The text to give `tobj` for `text`, which `scan` pre-scanned and whose `mtllib` lines
/// name `libraries`:
/// - every library is named on a line of its own at the top where a line named several
///   or came after a `usemtl` (`tobj` takes a line's rest as one file name, and looks up
///   a `usemtl` only among the libraries read before it; OBJ materials are global);
/// - trailing comments of data lines go;
/// - a `vt u` gets its default v of 0;
/// - vertex colours go where some vertices have them and others do not.
pub(super) fn text_for_tobj<'a>(
    text: &'a str,
    scan: &ObjScan,
    libraries: &[Library],
) -> Cow<'a, str> {
    let hoist = scan.mtllib_after_usemtl || libraries.len() != scan.mtllibs.len();
    if !hoist && !scan.data_lines_need_rewrite {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 64);
    if hoist {
        for library in libraries {
            let _ = writeln!(out, "mtllib {}", library.name);
        }
    }
    for line in text.lines() {
        match data_of(line) {
            (Some("mtllib"), _) if hoist => continue,
            (Some("v"), data) if scan.mixed_vertex_colours => {
                let words: Vec<&str> = data.split_whitespace().collect();
                // `v x y z r g b` → `v x y z`; `v x y z [w]` stays.
                let keep = if words.len() == 7 { 4 } else { words.len() };
                out.push_str(&words[..keep].join(" "));
            }
            (Some("vt"), data) if data.split_whitespace().count() == 2 => {
                out.push_str(data.trim_end());
                out.push_str(" 0");
            }
            (_, data) => out.push_str(data),
        }
        out.push('\n');
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::super::prescan::prescan_obj;
    use super::*;

    fn rewritten(text: &str) -> String {
        let scan = prescan_obj(text, "t.obj").unwrap();
        let libraries = libraries(&scan, Path::new("/nonexistent"));
        text_for_tobj(text, &scan, &libraries).into_owned()
    }

    #[test]
    fn plain_text_is_given_as_it_is() {
        let text = "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 0.5\nusemtl a\nf 1 2 3\n";
        let scan = prescan_obj(text, "t.obj").unwrap();
        let libraries = libraries(&scan, Path::new("."));
        assert!(matches!(
            text_for_tobj(text, &scan, &libraries),
            Cow::Borrowed(_)
        ));
    }

    #[test]
    fn libraries_move_to_the_top_one_a_line() {
        let text = "usemtl a\nv 0 0 0\nmtllib a.mtl b.mtl\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        assert_eq!(
            rewritten(text),
            "mtllib a.mtl\nmtllib b.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
        );
    }

    #[test]
    fn data_lines_are_rewritten_into_what_tobj_reads() {
        let text =
            "v 0 0 0 1 0 0 # red\nv 1 0 0\nv 0 1 0 2\nvt 0.5\nf 1/1 2/1 3/1 # one\no a # b\n";
        assert_eq!(
            rewritten(text),
            "v 0 0 0\nv 1 0 0\nv 0 1 0 2\nvt 0.5 0\nf 1/1 2/1 3/1 \no a # b\n"
        );
    }
}

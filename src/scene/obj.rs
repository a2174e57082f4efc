//! Line-by-line checks of an OBJ (and its MTL libraries) before `tobj` parses it: `tobj` reports
//! problems without a line, accepts 1- and 2-vertex faces as degenerate triangles, reads `l`
//! polylines of three or more points as faces, and panics on a one-value `Kd`. The scan finds
//! these with their line, and maps every triangle `tobj` makes back to its face's line.

use super::files;
use crate::error::{Error, Result};
use std::collections::HashMap;
use std::path::Path;

/// What the scan of an OBJ learned, for checks after `tobj` has parsed it.
#[derive(Debug, Default)]
pub struct ObjScan {
    /// Position (as `tobj` parses it: float32, divided by `w`) and line of every `v`.
    pub vertices: Vec<([f32; 3], u32)>,
    /// Line of each triangle `tobj` makes, in its order (a face of `k` vertices is fanned
    /// into `k − 2`).
    pub triangle_lines: Vec<u32>,
    /// `usemtl` names that faces follow, each with the line of its first such `usemtl`.
    pub usemtl: Vec<(String, u32)>,
    /// True when some face comes before any `usemtl`.
    pub faces_without_usemtl: bool,
    /// `mtllib` file names with their line.
    pub mtllibs: Vec<(String, u32)>,
    /// Lines of `l` (polyline) elements, left out of the text `tobj` reads.
    pub polylines: Vec<u32>,
    /// The text for `tobj`: the file with `l` lines blanked (so it is the file unless there are
    /// polylines).
    pub text: String,
    /// Faces that repeat an earlier face (the same corner positions in the same cyclic order,
    /// whatever vertex they start from): line → line of the earlier face.
    pub repeated_faces: HashMap<u32, u32>,
    /// Every `vn`, as `tobj` parses it (float32), in file order.
    pub normals: Vec<[f32; 3]>,
    /// Per triangle `tobj` makes (as [`ObjScan::triangle_lines`]): the `vn` of its corners
    /// (indices into [`ObjScan::normals`]), or `None` when a corner has none. `tobj` drops
    /// normals misaligned when only some faces have them, so they are taken from the scan.
    pub triangle_normals: Vec<Option<[u32; 3]>>,
}

/// Parses one number as `tobj` does (float32).
fn number(w: &str) -> Option<f32> {
    w.parse::<f32>().ok()
}

/// The rest of `line` after its keyword, as `tobj` reads `usemtl` and `mtllib` arguments.
fn argument(line: &str) -> &str {
    line.split_once(' ').unwrap_or_default().1.trim()
}

/// Scans `text` (the OBJ at `path`), failing on the first line `tobj` would misread or reject.
pub fn scan_obj(text: &str, path: &Path) -> Result<ObjScan> {
    let err = |line: usize, message: String| Error::Mesh {
        path: path.into(),
        message: format!("line {line}: {message}"),
    };
    let mut s = ObjScan::default();
    let mut counts = [0usize; 3];
    const NAMES: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    // Face corners: (line, kind, index resolved as `tobj` does, as written), checked at the
    // end: `tobj` checks bounds against the whole file, and ignores texture coordinate and
    // normal indices when the file has none.
    let mut corners: Vec<(u32, usize, isize, isize)> = Vec::new();
    // Each face's line and its vertex corners (a range of `corners`).
    let mut faces: Vec<(u32, std::ops::Range<usize>)> = Vec::new();
    // The `usemtl` in force: its entry in `s.usemtl` and its line.
    let mut material: Option<(usize, u32)> = None;
    for (n, line) in text.lines().enumerate() {
        let no = n + 1;
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let xyz: Vec<f32> = words.by_ref().take(3).map_while(number).collect();
                if xyz.len() < 3 {
                    return Err(err(
                        no,
                        format!("malformed vertex `{}`: expected 3 numbers", line.trim()),
                    ));
                }
                let mut p = [xyz[0], xyz[1], xyz[2]];
                let extra: Vec<&str> = words.collect();
                match extra.len() {
                    0 | 3 => {}
                    1 => match number(extra[0]) {
                        Some(w) if w != 0.0 => p = p.map(|c| c / w),
                        _ => {
                            return Err(err(
                                no,
                                format!("vertex weight `{}` must be a non-zero number", extra[0]),
                            ))
                        }
                    },
                    k => {
                        return Err(err(
                            no,
                            format!(
                                "malformed vertex `{}`: {} values (3, 4 with a weight, or 6 with a colour)",
                                line.trim(),
                                3 + k
                            ),
                        ))
                    }
                }
                s.vertices.push((p, no as u32));
                counts[0] += 1;
            }
            Some(k @ ("vt" | "vn")) => {
                let (kind, want) = if k == "vt" { (1, 2) } else { (2, 3) };
                let values: Vec<f32> = words.take(want).map_while(number).collect();
                if values.len() < want {
                    return Err(err(
                        no,
                        format!("malformed `{}`: expected {want} numbers", line.trim()),
                    ));
                }
                if kind == 2 {
                    s.normals.push([values[0], values[1], values[2]]);
                }
                counts[kind] += 1;
            }
            Some("f") => {
                let refs: Vec<&str> = words.collect();
                if refs.len() < 3 {
                    return Err(err(
                        no,
                        format!(
                            "face `{}` has {} {}: a face needs at least 3",
                            line.trim(),
                            refs.len(),
                            if refs.len() == 1 {
                                "vertex"
                            } else {
                                "vertices"
                            }
                        ),
                    ));
                }
                let first_corner = corners.len();
                // Each corner's `vn` as resolved (None without one), for the fanned triangles.
                let mut corner_normals: Vec<Option<isize>> = Vec::with_capacity(refs.len());
                for r in &refs {
                    let parts: Vec<&str> = r.split('/').collect();
                    let bad = || {
                        err(
                            no,
                            format!("malformed face vertex `{r}` in `{}`", line.trim()),
                        )
                    };
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(bad());
                    }
                    for (kind, part) in parts.iter().enumerate().filter(|(_, p)| !p.is_empty()) {
                        let x: isize = part.parse().map_err(|_| bad())?;
                        let at = if x < 0 {
                            counts[kind] as isize + x
                        } else {
                            x - 1
                        };
                        corners.push((no as u32, kind, at, x));
                    }
                    corner_normals.push(
                        parts
                            .get(2)
                            .filter(|p| !p.is_empty())
                            .and_then(|p| p.parse::<isize>().ok())
                            .map(|x| if x < 0 { counts[2] as isize + x } else { x - 1 }),
                    );
                }
                faces.push((no as u32, first_corner..corners.len()));
                // tobj fans a face from its first corner: (0, k, k + 1). Indices are checked
                // below; an out-of-range one fails the scan before these are used.
                for k in 1..refs.len() - 1 {
                    let tri = [0, k, k + 1].map(|i| corner_normals[i]);
                    s.triangle_normals.push(match tri {
                        [Some(a), Some(b), Some(c)] => Some([a, b, c].map(|i| i.max(0) as u32)),
                        _ => None,
                    });
                }
                s.triangle_lines
                    .extend(std::iter::repeat_n(no as u32, refs.len() - 2));
                match material {
                    Some((m, at)) => s.usemtl[m].1 = s.usemtl[m].1.min(at),
                    None => s.faces_without_usemtl = true,
                }
            }
            Some("l") => s.polylines.push(no as u32),
            Some("usemtl") => {
                let name = argument(line);
                if name.is_empty() {
                    return Err(err(no, "`usemtl` without a material name".into()));
                }
                // Entered with an impossible line until a face follows it.
                let m = match s.usemtl.iter().position(|(m, _)| m == name) {
                    Some(m) => m,
                    None => {
                        s.usemtl.push((name.to_string(), u32::MAX));
                        s.usemtl.len() - 1
                    }
                };
                material = Some((m, no as u32));
            }
            Some("mtllib") => s.mtllibs.push((argument(line).to_string(), no as u32)),
            _ => {}
        }
    }
    for &(no, kind, at, x) in &corners {
        let (name, count) = (NAMES[kind], counts[kind]);
        if kind > 0 && count == 0 {
            continue;
        }
        if x == 0 {
            return Err(err(
                no as usize,
                format!("{name} index 0: OBJ indices start at 1 (or count back from -1)"),
            ));
        }
        if at < 0 {
            return Err(err(
                no as usize,
                format!("relative {name} index {x} reaches before the first {name}"),
            ));
        }
        if at as usize >= count {
            return Err(err(
                no as usize,
                format!("{name} index {x} is out of range: the file has {count}"),
            ));
        }
        if kind == 0 {
            let (p, vline) = s.vertices[at as usize];
            if !p.iter().all(|c| c.is_finite()) {
                return Err(err(
                    vline as usize,
                    format!("vertex {p:?} (used by the face at line {no}) is not finite"),
                ));
            }
        }
    }
    // Positions, not indices: a face written again with its own copies of the vertices (as
    // the Cornell box's bottom faces are) is the same surface.
    let mut first_of: HashMap<Vec<[u32; 3]>, u32> = HashMap::new();
    for (no, range) in &faces {
        let mut key: Vec<[u32; 3]> = corners[range.clone()]
            .iter()
            .filter(|c| c.1 == 0)
            .map(|c| s.vertices[c.2 as usize].0.map(f32::to_bits))
            .collect();
        let start = (0..key.len()).min_by_key(|&k| key[k]).unwrap_or(0);
        key.rotate_left(start);
        match first_of.get(&key) {
            Some(&earlier) => {
                s.repeated_faces.insert(*no, earlier);
            }
            None => {
                first_of.insert(key, *no);
            }
        }
    }
    if s.normals.is_empty() {
        // As tobj: normal indices in a file without `vn` are ignored.
        s.triangle_normals.iter_mut().for_each(|t| *t = None);
    }
    s.usemtl.retain(|(_, line)| *line != u32::MAX);
    s.text = if s.polylines.is_empty() {
        text.to_string()
    } else {
        text.lines()
            .map(|l| match l.split_whitespace().next() {
                Some("l") => "",
                _ => l,
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    Ok(s)
}

/// Checks an MTL's colour lines (a one-number `Kd` is grey, as the MTL format allows, and is
/// written out as three for `tobj`, which would panic on it) and returns the text `tobj` reads.
pub fn prepare_mtl(text: &str, path: &Path) -> Result<String> {
    let mut out = String::with_capacity(text.len());
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if let Some(key @ ("Ka" | "Kd" | "Ks" | "Ke")) = words.next() {
            let values: Vec<&str> = words.take_while(|w| !w.starts_with('#')).collect();
            let numeric = |k: usize| values.iter().take(k).all(|w| number(w).is_some());
            match values.len() {
                // tobj reads the first three and ignores the rest (a comment, say).
                k if k >= 3 && numeric(3) => {}
                1 if numeric(1) => {
                    let v = values[0];
                    out += &format!("{key} {v} {v} {v}\n");
                    continue;
                }
                _ => {
                    return Err(Error::Mesh {
                        path: path.into(),
                        message: format!(
                            "line {}: `{}`: {key} needs 3 numbers (or 1 for grey)",
                            n + 1,
                            line.trim()
                        ),
                    })
                }
            }
        }
        out += line;
        out.push('\n');
    }
    Ok(out)
}

/// The first line of `text` that makes `parse` fail: a prefix fails exactly when it contains a
/// bad line, so the shortest failing prefix ends at it (binary search).
pub fn failing_line<T, E>(
    text: &str,
    parse: impl Fn(&str) -> std::result::Result<T, E>,
) -> Option<usize> {
    let ends: Vec<usize> = text
        .char_indices()
        .filter(|(_, c)| *c == '\n')
        .map(|(i, _)| i + 1)
        .chain([text.len()])
        .collect();
    if parse(text).is_ok() {
        return None;
    }
    let (mut lo, mut hi) = (0, ends.len() - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if parse(&text[..ends[mid]]).is_err() {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    Some(lo + 1)
}

/// Reads an MTL library (checked and prepared for `tobj`), with messages naming the file and
/// the OBJ line of its `mtllib`.
pub fn read_mtl(path: &Path, obj: &Path, line: u32) -> Result<String> {
    let text = files::read_text(path, "MTL").map_err(|p| match p {
        files::FileProblem::Path(m) => Error::Mesh {
            path: obj.into(),
            message: format!("line {line}: MTL library {}: {m}", path.display()),
        },
        files::FileProblem::Content(m) => Error::Mesh {
            path: path.into(),
            message: format!(
                "{m} (the MTL library named at line {line} of {})",
                obj.display()
            ),
        },
    })?;
    prepare_mtl(&text, path).map_err(|e| match e {
        Error::Mesh { path, message } => Error::Mesh {
            path,
            message: format!(
                "{message} (the MTL library named at line {line} of {})",
                obj.display()
            ),
        },
        e => e,
    })
}

/// Parses `text` (the MTL at `path`, named at `line` of `obj`) with `parse`; an error names the
/// line that caused it.
pub fn parse_mtl<T, E: std::fmt::Display>(
    text: &str,
    path: &Path,
    obj: &Path,
    line: u32,
    parse: impl Fn(&str) -> std::result::Result<T, E>,
) -> Result<T> {
    parse(text).map_err(|e| Error::Mesh {
        path: path.into(),
        message: format!(
            "line {}: cannot parse MTL: {e} (the MTL library named at line {line} of {})",
            failing_line(text, &parse).unwrap_or(0),
            obj.display()
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(text: &str) -> std::result::Result<ObjScan, String> {
        scan_obj(text, Path::new("t.obj")).map_err(|e| e.to_string())
    }

    #[test]
    fn faces_map_to_their_lines() {
        let s = scan(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\r\nv 0 1 0\nusemtl a\nf -4 -3 -2 -1\nf 1 2 3\nl 1 2 3\n",
        )
        .unwrap();
        assert_eq!(s.triangle_lines, vec![6, 6, 7]);
        assert_eq!(s.usemtl, vec![("a".to_string(), 5)]);
        assert!(!s.faces_without_usemtl);
        assert_eq!(s.polylines, vec![8]);
        assert!(!s.text.contains("l 1 2 3"));
        assert!(s.repeated_faces.is_empty());
        // Repeated from another start vertex (and with its own copies of the vertices): the
        // same face. Reversed: a different one.
        let s = scan("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 3 4 1 2\nf 4 3 2 1\nv 1 1 0\nf 1 2 -1 4\n")
            .unwrap();
        assert_eq!(s.repeated_faces, HashMap::from([(6, 5), (9, 5)]));
    }

    #[test]
    fn normals_follow_the_fanned_triangles() {
        // A quad with normals on every corner (fanned as tobj does), a triangle without, one
        // with relative indices, and one where a corner lacks its normal.
        let s = scan(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0.6 0.8\n\
             f 1//1 2//2 3//1 4//2\nf 1 2 3\nf 1/ 2//-1 3//-2\nf 1//1 2 3//1\n",
        )
        .unwrap();
        assert_eq!(s.normals, vec![[0.0, 0.0, 1.0], [0.0, 0.6, 0.8]]);
        assert_eq!(
            s.triangle_normals,
            vec![Some([0, 1, 0]), Some([0, 0, 1]), None, None, None]
        );
        // Normal indices in a file without `vn` are ignored (as tobj does).
        let s = scan("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n").unwrap();
        assert_eq!(s.triangle_normals, vec![None]);
    }

    #[test]
    fn bad_lines_are_named() {
        for (text, want) in [
            ("v 0 0 0\nf 1\n", "line 2: face `f 1` has 1 vertex"),
            (
                "v 0 0 0\nv 1 0 0\nf 1 2\n",
                "line 3: face `f 1 2` has 2 vertices",
            ),
            ("v 0 0 0\nv 1 0 zero\n", "line 2: malformed vertex"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
                "line 4: vertex index 9 is out of range: the file has 3",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n",
                "line 4: relative vertex index -4 reaches before",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
                "line 4: vertex index 0",
            ),
            (
                "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
                "line 2: vertex [1.0, NaN, 0.0] (used by the face at line 4) is not finite",
            ),
            ("v 0 0 0 0\n", "line 1: vertex weight `0`"),
            ("usemtl\n", "line 1: `usemtl` without a material name"),
        ] {
            let e = scan(text).unwrap_err();
            assert!(e.contains(want), "{text:?}: {e}");
        }
        // An unused non-finite vertex is not an error.
        assert!(scan("v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\nf 1 2 3\n").is_ok());
    }

    #[test]
    fn one_value_colours_are_grey_and_bad_ones_named() {
        let t = prepare_mtl(
            "newmtl a\r\nKd 0.5 # grey\nKs 0.1 0.2 0.3 # comment\n",
            Path::new("a.mtl"),
        )
        .unwrap();
        let (m, _) = tobj::load_mtl_buf(&mut t.as_bytes()).unwrap();
        assert_eq!(m[0].diffuse, Some([0.5; 3]));
        assert_eq!(m[0].specular, Some([0.1, 0.2, 0.3]));
        let e = prepare_mtl("newmtl a\nKd 0.5 0.2\n", Path::new("a.mtl")).unwrap_err();
        assert!(
            e.to_string()
                .contains("line 2: `Kd 0.5 0.2`: Kd needs 3 numbers"),
            "{e}"
        );
        let bad = "newmtl a\nKd 1 1 1\nNs x\nd 1\n";
        let parse = |t: &str| tobj::load_mtl_buf(&mut t.as_bytes());
        assert_eq!(failing_line(bad, parse), Some(3));
    }
}

//! PLY meshes (Mitsuba's `ply` shape): ASCII and binary (little- and big-endian), `vertex`
//! with `x y z` and optional `nx ny nz`, `face` with a `vertex_indices` (or `vertex_index`)
//! list, polygons fanned into triangles; other elements and properties are read past.

/// What a PLY file holds, in its own frame.
#[derive(Debug, Default)]
pub struct Ply {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Vertex normals (empty when the file has none).
    pub normals: Vec<[f64; 3]>,
    /// Triangles (polygons fanned from their first corner).
    pub triangles: Vec<[u32; 3]>,
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

#[derive(Clone, Copy)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(t: &str) -> Option<Scalar> {
        Some(match t {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

struct Property {
    name: String,
    /// `Some(count type)` for a list.
    list: Option<Scalar>,
    kind: Scalar,
}

struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// Reads a value at a time from the body, in any of the three formats.
struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    format: Format,
    tokens: std::str::SplitAsciiWhitespace<'a>,
}

impl Body<'_> {
    fn next(&mut self, s: Scalar) -> Result<f64, String> {
        if self.format == Format::Ascii {
            let t = self
                .tokens
                .next()
                .ok_or("the file ends before its elements do")?;
            return t
                .parse::<f64>()
                .map_err(|_| format!("`{t}` is not a number"));
        }
        let n = s.size();
        let b = self
            .bytes
            .get(self.at..self.at + n)
            .ok_or("the file ends before its elements do (truncated?)")?;
        self.at += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(b);
        if self.format == Format::Big {
            a[..n].reverse();
        }
        Ok(match s {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }
}

/// Parses a PLY file's bytes; the error says what is wrong (the caller names the file).
pub fn parse(bytes: &[u8]) -> Result<Ply, String> {
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or("not a PLY file: no `end_header`")?;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| "the PLY header is not text")?;
    let mut lines = header.lines().map(str::trim);
    if lines.next() != Some("ply") {
        return Err("not a PLY file: it does not start with `ply`".into());
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for line in lines {
        let w: Vec<&str> = line.split_ascii_whitespace().collect();
        match w.as_slice() {
            ["format", f, _] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    _ => return Err(format!("unknown PLY format `{f}`")),
                })
            }
            ["element", name, count] => elements.push(Element {
                name: name.to_string(),
                count: count
                    .parse()
                    .map_err(|_| format!("element {name}: count `{count}` is not a number"))?,
                properties: Vec::new(),
            }),
            ["property", "list", c, t, name] => {
                let e = elements.last_mut().ok_or("a property before any element")?;
                let (c, t) = (Scalar::parse(c), Scalar::parse(t));
                let (Some(c), Some(t)) = (c, t) else {
                    return Err(format!("property {name}: unknown type"));
                };
                e.properties.push(Property {
                    name: name.to_string(),
                    list: Some(c),
                    kind: t,
                });
            }
            ["property", t, name] => {
                let e = elements.last_mut().ok_or("a property before any element")?;
                let kind = Scalar::parse(t)
                    .ok_or_else(|| format!("property {name}: unknown type `{t}`"))?;
                e.properties.push(Property {
                    name: name.to_string(),
                    list: None,
                    kind,
                });
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            _ => return Err(format!("unreadable header line `{line}`")),
        }
    }
    let format = format.ok_or("the PLY header has no `format` line")?;
    // The body starts after `end_header` and its line end.
    let mut start = end + 10;
    while start < bytes.len() && (bytes[start] == b'\r' || bytes[start] == b'\n') {
        start += 1;
        if bytes[start - 1] == b'\n' {
            break;
        }
    }
    let body_text = if format == Format::Ascii {
        std::str::from_utf8(&bytes[start..]).map_err(|_| "the ASCII body is not text")?
    } else {
        ""
    };
    let mut body = Body {
        bytes,
        at: start,
        format,
        tokens: body_text.split_ascii_whitespace(),
    };
    let mut ply = Ply::default();
    for e in &elements {
        // At least one byte per entry in binary: a count beyond the file is refused before any
        // allocation it would ask for.
        if format != Format::Ascii && e.count > bytes.len() {
            return Err(format!(
                "element {} claims {} entries, more than the file holds",
                e.name, e.count
            ));
        }
        let find = |n: &str| {
            e.properties
                .iter()
                .position(|p| p.name == n && p.list.is_none())
        };
        let xyz = [find("x"), find("y"), find("z")];
        let nxyz = [find("nx"), find("ny"), find("nz")];
        let faces = e.properties.iter().position(|p| {
            p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index")
        });
        let mut values = vec![0.0; e.properties.len()];
        for _ in 0..e.count {
            let mut list = Vec::new();
            for (k, p) in e.properties.iter().enumerate() {
                match p.list {
                    None => values[k] = body.next(p.kind)?,
                    Some(c) => {
                        let n = body.next(c)?;
                        if !(0.0..=1e6).contains(&n) {
                            return Err(format!("element {}: a list of {n} entries", e.name));
                        }
                        let keep = Some(k) == faces;
                        for _ in 0..n as usize {
                            let v = body.next(p.kind)?;
                            if keep {
                                list.push(v);
                            }
                        }
                    }
                }
            }
            if e.name == "vertex" {
                let [Some(x), Some(y), Some(z)] = xyz else {
                    return Err("element vertex has no x, y, z".into());
                };
                ply.positions.push([values[x], values[y], values[z]]);
                if let [Some(a), Some(b), Some(c)] = nxyz {
                    ply.normals.push([values[a], values[b], values[c]]);
                }
            } else if e.name == "face" && faces.is_some() {
                if list
                    .iter()
                    .any(|&i| !(i >= 0.0 && i < u32::MAX as f64 && i.fract() == 0.0))
                {
                    return Err("a face has a negative or non-integer vertex index".into());
                }
                for i in 2..list.len() {
                    ply.triangles
                        .push([list[0] as u32, list[i - 1] as u32, list[i] as u32]);
                }
            }
        }
    }
    let n = ply.positions.len();
    if let Some(t) = ply
        .triangles
        .iter()
        .find(|t| t.iter().any(|&i| i as usize >= n))
    {
        return Err(format!(
            "face {t:?}: a vertex index is out of range ({n} vertices)"
        ));
    }
    if ply.triangles.is_empty() {
        return Err("no faces".into());
    }
    Ok(ply)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_and_binary_agree() {
        let ascii = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let a = parse(ascii).unwrap();
        assert_eq!(a.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
        for p in &a.positions {
            for x in p {
                bin.extend_from_slice(&(*x as f32).to_le_bytes());
            }
        }
        bin.push(4);
        for i in [0i32, 1, 2, 3] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let b = parse(&bin).unwrap();
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.triangles, b.triangles);
        assert!(parse(&bin[..bin.len() - 2])
            .unwrap_err()
            .contains("truncated"));
        assert!(parse(
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n"
        )
        .is_err());
    }
}

//! A glTF file's JSON validated and its buffers read; every accessor checked against them
//! before the reader touches it.

use crate::error::Result;
use crate::scene::load::mesh_err;
use base64::Engine as _;
use gltf::accessor::{DataType, Dimensions};
use std::path::Path;

/// The document and its binary chunk, validated by the crate's rules but for POSITION's
/// `min`/`max`, which other loaders do not require either. The crate's validation indexes the
/// POSITION accessor without a check, so that index is checked first.
pub(super) fn parse(bytes: &[u8]) -> std::result::Result<gltf::Gltf, String> {
    use gltf::json::validation::{Checked, Validate};
    let g = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let root = g.document.as_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let pos = prim
                .attributes
                .get(&Checked::Valid(gltf::json::mesh::Semantic::Positions));
            if let Some(i) = pos.filter(|i| i.value() >= root.accessors.len()) {
                return Err(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {} does not exist ({} accessors)",
                    i.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().as_str().to_string();
        let optional = matches!(error, gltf::json::validation::Error::Missing)
            && path.contains("\"POSITION\"]")
            && (path.ends_with(".min") || path.ends_with(".max"));
        if !optional {
            errors.push(format!("{path}: {error}"));
        }
    });
    if errors.is_empty() {
        Ok(g)
    } else {
        let more = errors.len().saturating_sub(3);
        errors.truncate(3);
        Err(format!(
            "{}{}",
            errors.join("; "),
            if more > 0 {
                format!(" (and {more} more)")
            } else {
                String::new()
            }
        ))
    }
}

/// Every buffer's bytes: the GLB's binary chunk, a `data:` URI or a file beside `path`.
pub(super) fn read_buffers(g: &gltf::Gltf, path: &Path) -> Result<Vec<Vec<u8>>> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut out = Vec::new();
    for b in g.buffers() {
        let i = b.index();
        let data = match b.source() {
            gltf::buffer::Source::Bin => g.blob.clone().ok_or_else(|| {
                mesh_err(
                    path,
                    format!("buffers[{i}] is the binary chunk, which the file does not have"),
                )
            })?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, data) = rest.split_once(";base64,").ok_or_else(|| {
                        mesh_err(path, format!("buffers[{i}]: a data URI that is not base64"))
                    })?;
                    base64::engine::general_purpose::STANDARD
                        .decode(data)
                        .map_err(|e| mesh_err(path, format!("buffers[{i}]: bad base64: {e}")))?
                } else {
                    let file = dir.join(percent_decode(uri));
                    crate::scene::files::read_bytes(&file).map_err(|p| {
                        mesh_err(
                            path,
                            format!("buffers[{i}]: its file {} {p}", file.display()),
                        )
                    })?
                }
            }
        };
        if data.len() < b.length() {
            return Err(mesh_err(
                path,
                format!(
                    "buffers[{i}] holds {} bytes, fewer than its byteLength {} (truncated?)",
                    data.len(),
                    b.length()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// `%20` and the like in a relative URI.
pub(super) fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Checks that `acc` has the type asked for and lies inside its buffer view and buffer (and so
/// its sparse parts), so that the reader cannot fail halfway or overrun.
pub(super) fn check_accessor(
    acc: &gltf::Accessor,
    what: &str,
    dims: Dimensions,
    types: &[DataType],
    buffers: &[Vec<u8>],
) -> std::result::Result<(), String> {
    let i = acc.index();
    if acc.dimensions() != dims || !types.contains(&acc.data_type()) {
        return Err(format!(
            "accessors[{i}] ({what}) is {:?} {:?}; {what} must be {dims:?} of {types:?}",
            acc.dimensions(),
            acc.data_type()
        ));
    }
    if acc.count() == 0 {
        return Err(format!("accessors[{i}] ({what}) has count 0"));
    }
    let size = acc.size();
    let in_view = |view: &gltf::buffer::View, offset: usize, count: usize, size: usize| {
        let stride = view.stride().unwrap_or(size);
        let buffer_len = buffers.get(view.buffer().index()).map_or(0, Vec::len);
        let view_end = view.offset().checked_add(view.length());
        let end = stride
            .checked_mul(count - 1)
            .and_then(|s| s.checked_add(offset))
            .and_then(|s| s.checked_add(size));
        match (view_end, end) {
            (Some(ve), Some(e)) if stride >= size && ve <= buffer_len && e <= view.length() => {
                Ok(())
            }
            _ => Err(format!(
                "accessors[{i}] ({what}) reaches past bufferViews[{}] or its buffer",
                view.index()
            )),
        }
    };
    match acc.view() {
        Some(v) => in_view(&v, acc.offset(), acc.count(), size)?,
        None if acc.sparse().is_none() => {
            return Err(format!("accessors[{i}] ({what}) has no bufferView"))
        }
        None => {}
    }
    if let Some(s) = acc.sparse() {
        if s.count() == 0 || s.count() > acc.count() {
            return Err(format!(
                "accessors[{i}] ({what}): sparse count {}",
                s.count()
            ));
        }
        let idx = s.indices();
        in_view(
            &idx.view(),
            idx.offset(),
            s.count(),
            idx.index_type().size(),
        )?;
        let val = s.values();
        in_view(&val.view(), val.offset(), s.count(), size)?;
    }
    Ok(())
}

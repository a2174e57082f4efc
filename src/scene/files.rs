//! Reading a scene's text files (TOML, OBJ, MTL) so that every way a path can be wrong gets its
//! own message, and nothing that is not a regular file is ever read (a FIFO would block the
//! open, `/dev/zero` would never end).

use std::io::Read;
use std::path::Path;

/// Why a path cannot be read as a text file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FileProblem {
    /// The path is absent, a directory, a device, a link loop...: it was not opened.
    Path(String),
    /// The file was read but is not UTF-8 text.
    Content(String),
}

impl std::fmt::Display for FileProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            FileProblem::Path(m) | FileProblem::Content(m) => f.write_str(m),
        }
    }
}

/// `errno` for "too many levels of symbolic links".
#[cfg(any(target_os = "macos", target_os = "ios", target_os = "freebsd"))]
const ELOOP: i32 = 62;
#[cfg(not(any(target_os = "macos", target_os = "ios", target_os = "freebsd")))]
const ELOOP: i32 = 40;

/// What kind of non-regular file `t` is, in words.
fn kind_of(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a named pipe (FIFO)";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}

/// Checks that `path` names a regular file (following symbolic links) without opening it.
pub fn check_regular_file(path: &Path) -> Result<u64, FileProblem> {
    let meta = std::fs::metadata(path).map_err(|e| {
        let is_link = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
        FileProblem::Path(if e.raw_os_error() == Some(ELOOP) {
            "is a symbolic link loop (too many levels of symbolic links)".to_string()
        } else if is_link && e.kind() == std::io::ErrorKind::NotFound {
            match std::fs::read_link(path) {
                Ok(to) => format!(
                    "is a symbolic link to {}, which does not exist",
                    to.display()
                ),
                Err(_) => "is a dangling symbolic link".to_string(),
            }
        } else if e.kind() == std::io::ErrorKind::NotFound {
            "not found".to_string()
        } else if e.kind() == std::io::ErrorKind::PermissionDenied {
            "cannot be read: permission denied".to_string()
        } else {
            format!("cannot be read: {e}")
        })
    })?;
    let t = meta.file_type();
    if t.is_dir() {
        return Err(FileProblem::Path("is a directory, not a file".into()));
    }
    if !t.is_file() {
        return Err(FileProblem::Path(format!(
            "is {}, not a regular file",
            kind_of(t)
        )));
    }
    Ok(meta.len())
}

/// Reads a regular file's bytes (glTF binaries and buffers), at most what its metadata says.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, FileProblem> {
    let len = check_regular_file(path)?;
    let file = std::fs::File::open(path).map_err(|e| {
        FileProblem::Path(if e.kind() == std::io::ErrorKind::PermissionDenied {
            "cannot be read: permission denied".to_string()
        } else {
            format!("cannot be opened: {e}")
        })
    })?;
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(len)
        .read_to_end(&mut bytes)
        .map_err(|e| FileProblem::Path(format!("cannot be read: {e}")))?;
    Ok(bytes)
}

/// Reads a regular file as UTF-8 text. `what` names the format in messages ("OBJ", "MTL",
/// "scene"). A file with NUL bytes is binary; a file that is not UTF-8 says where.
pub fn read_text(path: &Path, what: &str) -> Result<String, FileProblem> {
    let len = check_regular_file(path)?;
    let mut file = std::fs::File::open(path).map_err(|e| {
        FileProblem::Path(if e.kind() == std::io::ErrorKind::PermissionDenied {
            "cannot be read: permission denied".to_string()
        } else {
            format!("cannot be opened: {e}")
        })
    })?;
    // Read at most what the metadata announced (plus one byte to see growth), whatever the file
    // turns out to be by the time it is open.
    let mut bytes = Vec::with_capacity(len as usize);
    (&mut file)
        .take(len.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| FileProblem::Path(format!("cannot be read: {e}")))?;
    let line_at = |offset: usize| bytes[..offset].iter().filter(|&&b| b == b'\n').count() + 1;
    if let Some(nul) = bytes.iter().position(|&b| b == 0) {
        return Err(FileProblem::Content(format!(
            "is a binary file (a NUL byte at line {}), not {what} text",
            line_at(nul)
        )));
    }
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        FileProblem::Content(format!(
            "is not UTF-8 text: byte 0x{:02x} at line {} is not valid UTF-8 ({what} files must be UTF-8 or ASCII)",
            bytes[at],
            bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir() -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("antiradiance-files-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn every_wrong_path_says_what_it_is() {
        let d = dir();
        let f = |p: &Path| read_text(p, "OBJ").unwrap_err().to_string();
        assert_eq!(f(&d.join("absent.obj")), "not found");
        assert!(f(&d).contains("is a directory"), "{}", f(&d));
        #[cfg(unix)]
        {
            assert!(f(Path::new("/dev/zero")).contains("a character device"));
            let a = d.join("loop-a.obj");
            let b = d.join("loop-b.obj");
            let _ = std::fs::remove_file(&a);
            let _ = std::fs::remove_file(&b);
            std::os::unix::fs::symlink(&b, &a).unwrap();
            std::os::unix::fs::symlink(&a, &b).unwrap();
            assert!(f(&a).contains("symbolic link loop"), "{}", f(&a));
            let dangling = d.join("dangling.obj");
            let _ = std::fs::remove_file(&dangling);
            std::os::unix::fs::symlink(d.join("nowhere.obj"), &dangling).unwrap();
            assert!(
                f(&dangling).contains("which does not exist"),
                "{}",
                f(&dangling)
            );
        }
        std::fs::write(d.join("bin.obj"), b"v 0 0 0\n\x00\x01\x02").unwrap();
        assert!(f(&d.join("bin.obj")).contains("binary file (a NUL byte at line 2)"));
        std::fs::write(d.join("latin1.obj"), b"# caf\xe9\nv 0 0 0\n").unwrap();
        let e = f(&d.join("latin1.obj"));
        assert!(
            e.contains("not UTF-8") && e.contains("0xe9 at line 1"),
            "{e}"
        );
        std::fs::write(d.join("ok.obj"), "v 0 0 0\r\n").unwrap();
        assert_eq!(read_text(&d.join("ok.obj"), "OBJ").unwrap(), "v 0 0 0\r\n");
        std::fs::remove_dir_all(&d).unwrap();
    }
}

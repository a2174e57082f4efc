//! The shaders as SPIR-V, compiled from `glsl/` by `build.rs` (glslc) and embedded: nothing is
//! compiled at run time, and a GLSL error fails the build naming `file:line`.

/// Every compiled shader: (file name under `glsl/`, SPIR-V bytes).
pub const SPIRV: &[(&str, &[u8])] = include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// The SPIR-V words of the shader `file` (a name under `glsl/`, e.g. `global.vert`).
///
/// # Panics
/// If `file` is not a shader of `glsl/`: the names are fixed in the code, so this is a bug.
pub fn spirv(file: &str) -> Vec<u32> {
    let bytes = SPIRV
        .iter()
        .find(|s| s.0 == file)
        .unwrap_or_else(|| panic!("no compiled shader named {file}"))
        .1;
    ash::util::read_spv(&mut std::io::Cursor::new(bytes)).expect("glslc writes valid SPIR-V")
}

#[cfg(test)]
mod tests {
    use super::*;

    include!("../../build/glsl.rs");

    #[test]
    fn every_shader_is_embedded() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl");
        for e in std::fs::read_dir(dir).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            if name.ends_with(".vert") || name.ends_with(".frag") || name.ends_with(".comp") {
                let words = spirv(&name);
                assert_eq!(words[0], 0x0723_0203, "{name}: SPIR-V magic");
            }
        }
    }

    #[test]
    fn errors_name_file_and_line() {
        let dir = std::env::temp_dir().join(format!("ar-glsl-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("broken.frag");
        std::fs::write(
            &bad,
            "#version 450\nvoid main() {\n  undefined_thing = 1;\n}\n",
        )
        .unwrap();
        let e = compile_glsl(&bad, &dir, &dir.join("broken.spv")).unwrap_err();
        assert!(e.contains("broken.frag:3"), "{e}");
        let inc = dir.join("inc.vert");
        std::fs::write(
            &inc,
            "#version 450\n#include \"nope.glsl\"\nvoid main() {}\n",
        )
        .unwrap();
        let e = compile_glsl(&inc, &dir, &dir.join("inc.spv")).unwrap_err();
        assert!(e.contains("inc.vert:2") && e.contains("nope.glsl"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

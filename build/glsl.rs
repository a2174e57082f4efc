// GLSL → SPIR-V with glslc (Debian's `glslc` package, installed by scripts/setup.sh), shared by
// build.rs and the test that checks error messages. Included with `include!`, so no `use` of
// crate items here.

/// Compiles `path` (stage from its extension, includes from `include_dir`) to SPIR-V bytes, or
/// returns the compiler's messages, which name `file:line`.
pub fn compile_glsl(
    path: &std::path::Path,
    include_dir: &std::path::Path,
    out: &std::path::Path,
) -> Result<Vec<u8>, String> {
    // Compute shaders for Vulkan 1.3 get LocalSizeId, which needs the maintenance4 feature;
    // the 1.2 environment keeps the plain workgroup size.
    let compute = path.extension().is_some_and(|e| e == "comp");
    let env = if compute { "--target-env=vulkan1.2" } else { "--target-env=vulkan1.3" };
    let output = std::process::Command::new(std::env::var("GLSLC").unwrap_or("glslc".into()))
        .arg(env)
        .arg("-O")
        .arg("-g")
        .arg("-I")
        .arg(include_dir)
        .arg(path)
        .arg("-o")
        .arg(out)
        .output()
        .map_err(|e| {
            format!("cannot run glslc ({e}); install it with `bash scripts/setup.sh` (Debian package glslc)")
        })?;
    if !output.status.success() {
        return Err(String::from_utf8_lossy(&output.stderr).trim().to_string());
    }
    std::fs::read(out).map_err(|e| format!("{}: {e}", out.display()))
}

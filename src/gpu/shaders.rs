//! GLSL → SPIR-V with shaderc. Sources are embedded from `glsl/`; `#include "common.glsl"`
//! resolves against the same set, and every compiler message names the file and line.

use crate::error::{Error, Result};

/// Every shader source under `glsl/`, by file name.
pub const SOURCES: &[(&str, &str)] = &[
    ("bins.glsl", include_str!("../../glsl/bins.glsl")),
    ("common.glsl", include_str!("../../glsl/common.glsl")),
    ("global.vert", include_str!("../../glsl/global.vert")),
    ("global.frag", include_str!("../../glsl/global.frag")),
    ("quad.vert", include_str!("../../glsl/quad.vert")),
    ("push.frag", include_str!("../../glsl/push.frag")),
    ("local.glsl", include_str!("../../glsl/local.glsl")),
    (
        "local_irradiance.frag",
        include_str!("../../glsl/local_irradiance.frag"),
    ),
    ("local.frag", include_str!("../../glsl/local.frag")),
    ("pull.vert", include_str!("../../glsl/pull.vert")),
    ("pull.frag", include_str!("../../glsl/pull.frag")),
    ("coverage.frag", include_str!("../../glsl/coverage.frag")),
    ("probe.frag", include_str!("../../glsl/probe.frag")),
    ("frame.glsl", include_str!("../../glsl/frame.glsl")),
    ("shadow.vert", include_str!("../../glsl/shadow.vert")),
    ("shadow.frag", include_str!("../../glsl/shadow.frag")),
    ("gbuffer.vert", include_str!("../../glsl/gbuffer.vert")),
    ("gbuffer.frag", include_str!("../../glsl/gbuffer.frag")),
    ("splat.vert", include_str!("../../glsl/splat.vert")),
    ("splat.frag", include_str!("../../glsl/splat.frag")),
    ("compose.vert", include_str!("../../glsl/compose.vert")),
    ("compose.frag", include_str!("../../glsl/compose.frag")),
];

/// Looks up an embedded source.
pub fn source(file: &str) -> Option<&'static str> {
    SOURCES.iter().find(|s| s.0 == file).map(|s| s.1)
}

/// Compiles the embedded shader `file` (stage from its extension).
pub fn compile(file: &str) -> Result<Vec<u32>> {
    let src = source(file).ok_or_else(|| Error::Shader {
        file: file.into(),
        message: "no such embedded shader".into(),
    })?;
    compile_source(file, src)
}

/// Compiles GLSL text named `file`; includes resolve against the embedded sources.
pub fn compile_source(file: &str, text: &str) -> Result<Vec<u32>> {
    let err = |message: String| Error::Shader {
        file: file.into(),
        message,
    };
    let kind = match file.rsplit('.').next() {
        Some("vert") => shaderc::ShaderKind::Vertex,
        Some("frag") => shaderc::ShaderKind::Fragment,
        _ => return Err(err("unknown shader stage (expected .vert or .frag)".into())),
    };
    let compiler = shaderc::Compiler::new()
        .map_err(|e| err(format!("cannot create the shaderc compiler: {e}")))?;
    let mut opts = shaderc::CompileOptions::new()
        .map_err(|e| err(format!("cannot create shaderc options: {e}")))?;
    opts.set_target_env(
        shaderc::TargetEnv::Vulkan,
        shaderc::EnvVersion::Vulkan1_3 as u32,
    );
    opts.set_optimization_level(shaderc::OptimizationLevel::Performance);
    opts.set_generate_debug_info();
    opts.set_include_callback(|name, _ty, _from, _depth| {
        source(name)
            .map(|content| shaderc::ResolvedInclude {
                resolved_name: name.to_string(),
                content: content.to_string(),
            })
            .ok_or_else(|| format!("include `{name}` is not an embedded shader source"))
    });
    compiler
        .compile_into_spirv(text, kind, file, "main", Some(&opts))
        .map(|a| a.as_binary().to_vec())
        .map_err(|e| err(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shader_compiles() {
        for (name, _) in SOURCES {
            if name.ends_with(".vert") || name.ends_with(".frag") {
                compile(name).unwrap_or_else(|e| panic!("{e}"));
            }
        }
    }

    #[test]
    fn errors_name_file_and_line() {
        let bad = "#version 450\nvoid main() {\n  undefined_thing = 1;\n}\n";
        let e = compile_source("broken.frag", bad).unwrap_err().to_string();
        assert!(e.contains("broken.frag:3"), "{e}");
        let bad_inc = "#version 450\n#include \"nope.glsl\"\nvoid main() {}\n";
        let e = compile_source("inc.vert", bad_inc).unwrap_err().to_string();
        assert!(e.contains("inc.vert:2") && e.contains("nope.glsl"), "{e}");
    }
}

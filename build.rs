//! Compiles every shader under `glsl/` to SPIR-V at build time (no shader compiler at run time):
//! a GLSL error fails the build with glslc's `glsl/FILE:LINE: error: ...` message. The SPIR-V is
//! embedded by `src/gpu/shaders.rs` from `$OUT_DIR/shaders.rs`.

include!("build/glsl.rs");

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=build/glsl.rs");
    println!("cargo:rerun-if-changed=glsl");
    println!("cargo:rerun-if-env-changed=GLSLC");
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let dir = std::path::Path::new("glsl");
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("glsl/ exists")
        .map(|e| {
            e.expect("readable glsl/")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    let mut table = String::from("&[\n");
    let mut failures = Vec::new();
    for name in names {
        println!("cargo:rerun-if-changed=glsl/{name}");
        if !(name.ends_with(".vert") || name.ends_with(".frag") || name.ends_with(".comp")) {
            continue;
        }
        let spv = out.join(format!("{name}.spv"));
        match compile_glsl(&dir.join(&name), dir, &spv) {
            Ok(_) => table += &format!("    ({name:?}, include_bytes!({:?})),\n", spv),
            Err(e) => failures.push(e),
        }
    }
    if !failures.is_empty() {
        for f in &failures {
            println!("cargo:warning={}", f.lines().next().unwrap_or(""));
        }
        panic!("GLSL compilation failed:\n{}", failures.join("\n"));
    }
    table += "]\n";
    std::fs::write(out.join("shaders.rs"), table).expect("writing shaders.rs");
}

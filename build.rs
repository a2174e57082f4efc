//! Links Debian's static glslang/SPIRV-Tools after shaderc_combined (../shared/BUILD-NOTES.md):
//! Debian's libshaderc_combined.a lacks them, and building shaderc from source takes 15 minutes.
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!(
        "cargo:rustc-link-arg=-Wl,--push-state,-Bstatic,--start-group,-lglslang,-lMachineIndependent,\
         -lGenericCodeGen,-lOSDependent,-lOGLCompiler,-lHLSL,-lSPIRV,-lSPIRV-Tools-opt,-lSPIRV-Tools,\
         -lglslang-default-resource-limits,--end-group,--pop-state,-lstdc++"
    );
}

//! Host mirrors of everything the shaders read: push constants, per-instance vertex data,
//! storage-buffer records and descriptor bindings. `glsl/common.glsl` is the GLSL side; the tests
//! below check sizes, offsets and that both files name the same fields and bindings in order.

/// Push constants shared by every pass (`PassConstants` in common.glsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PassConstants {
    /// Bins per row `m`.
    pub bins: u32,
    /// Rows stored per column block (`rows_per_column ≤ maxImageDimension2D`).
    pub rows_per_column: u32,
    /// Width of the bound render target, texels.
    pub target_width: u32,
    /// Height of the bound render target, texels.
    pub target_height: u32,
    /// Width of one row in the target: `m` for tables, 1 for per-row images.
    pub quad_width: u32,
    /// Line endpoint offset for the line rasterization mode in use.
    pub line_offset: f32,
    /// Bin solid angle `4π/m`.
    pub omega: f32,
    /// Bit 0: a direct-light table is bound; bit 1: tables are float16.
    pub flags: u32,
    /// Constant environment radiance times the source scale (rgb); the source scale (a), a
    /// power of two that every emitted radiance is multiplied by to centre values in float16's range.
    pub environment: [f32; 4],
}

/// `PassConstants::flags` bit: the direct-light table is valid.
pub const FLAG_DIRECT: u32 = 1;
/// `PassConstants::flags` bit: tables are float16; shaders round stores to nearest.
pub const FLAG_HALF: u32 = 2;

/// One link as the global pass's per-instance vertex data (20 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuLink {
    /// Receiver row.
    pub receiver: u32,
    /// Sender row.
    pub sender: u32,
    /// Central bin (low 16 bits) and filter-table layer (high 16 bits).
    pub bin_layer: u32,
    /// Receiver bins covered: first (low 16 bits) and one past the last (high 16 bits).
    pub span: u32,
    /// Form factor (eq. 17 with the exact-leaf calibration).
    pub form_factor: f32,
}

/// A quad covering whole rows `[first, end)` of one column block; `source` is the row the push
/// pass reads (unused by the local pass).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct QuadInstance {
    /// Row read by the fragment shader (push).
    pub source: u32,
    /// First covered row.
    pub first: u32,
    /// One past the last covered row (same column block as `first`).
    pub end: u32,
}

/// One pull line: the leaf's row is added to the ancestor's.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PullLine {
    /// Leaf row read.
    pub leaf: u32,
    /// Ancestor row written.
    pub ancestor: u32,
}

/// A material in the storage buffer (std430, `Material` in common.glsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuMaterial {
    /// Diffuse albedo (rgb), a unused.
    pub kd: [f32; 4],
    /// Specular albedo (rgb) and Phong exponent (a).
    pub ks_ns: [f32; 4],
    /// Emitted radiance (rgb), a unused.
    pub ke: [f32; 4],
}

/// Descriptor bindings of the solver's one set layout (`AR_BINDING_*` in common.glsl).
pub mod binding {
    /// Leaves' I_ex, current (read by global and local).
    pub const LEAF_EX: u32 = 0;
    /// Clusters' I_ex (written by pull, read by global).
    pub const CLUSTER_EX: u32 = 1;
    /// Cone-filter tables, one m×m layer per used class.
    pub const FILTER: u32 = 2;
    /// Gathered incident radiance L_in.
    pub const L_IN: u32 = 3;
    /// Pushed incident radiance.
    pub const L_PUSH: u32 = 4;
    /// Irradiance from links and environment, one texel per row.
    pub const IRRADIANCE_T: u32 = 5;
    /// Irradiance from direct light, one texel per row.
    pub const IRRADIANCE_D: u32 = 6;
    /// Attributes: normal (rgb), area (a).
    pub const ATTR_NORMAL_AREA: u32 = 7;
    /// Attributes: cosine normalization, material index, leaf flag.
    pub const ATTR_LEAF: u32 = 8;
    /// Direct incident radiance table.
    pub const DIRECT: u32 = 9;
    /// Leaves' I_ex just written by the local pass (read by pull).
    pub const LEAF_EX_NEXT: u32 = 10;
    /// Materials storage buffer.
    pub const MATERIALS: u32 = 11;
    /// Bin center directions storage buffer (vec4 per bin).
    pub const BIN_CENTERS: u32 = 12;
    /// Number of bindings.
    pub const COUNT: u32 = 13;
    /// Storage-buffer bindings (the rest are combined image samplers).
    pub const BUFFERS: [u32; 2] = [MATERIALS, BIN_CENTERS];
}

/// Local-pass mode specialization constant (`AR_MODE` in common.glsl, constant_id 0).
pub mod mode {
    /// Reflection and antiradiance (symmetric scheme).
    pub const BOTH: u32 = 0;
    /// Reflection only (asymmetric step, eq. 13).
    pub const REFLECT: u32 = 1;
    /// Antiradiance only (asymmetric step, eq. 14).
    pub const ANTIRADIANCE: u32 = 2;
}

/// Views a slice of plain `#[repr(C)]` records as bytes for upload.
pub fn as_bytes<T: Copy>(v: &[T]) -> &[u8] {
    // SAFETY: the layout types are repr(C) with only u32/f32 fields and no padding.
    unsafe { std::slice::from_raw_parts(v.as_ptr() as *const u8, std::mem::size_of_val(v)) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    const COMMON: &str = include_str!("../../glsl/common.glsl");

    /// Field names of a GLSL block/struct `name { ... }` in common.glsl, in order.
    fn glsl_fields(name: &str) -> Vec<String> {
        let start = COMMON
            .find(&format!("{name} {{"))
            .unwrap_or_else(|| panic!("{name} missing"));
        let body = &COMMON[start..];
        let body = &body[body.find('{').unwrap() + 1..body.find('}').unwrap()];
        let code: String = body
            .lines()
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect::<Vec<_>>()
            .join("\n");
        code.split(';')
            .filter_map(|f| f.split_whitespace().last().map(str::to_string))
            .collect()
    }

    #[test]
    fn push_constants_match_glsl() {
        assert_eq!(size_of::<PassConstants>(), 48);
        assert_eq!(offset_of!(PassConstants, omega), 24);
        assert_eq!(offset_of!(PassConstants, environment), 32);
        assert_eq!(
            glsl_fields("PassConstants"),
            [
                "bins",
                "rows_per_column",
                "target_width",
                "target_height",
                "quad_width",
                "line_offset",
                "omega",
                "flags",
                "environment"
            ]
        );
    }

    #[test]
    fn vertex_and_buffer_records() {
        assert_eq!(size_of::<GpuLink>(), 20);
        assert_eq!(offset_of!(GpuLink, form_factor), 16);
        assert_eq!(size_of::<QuadInstance>(), 12);
        assert_eq!(size_of::<PullLine>(), 8);
        assert_eq!(size_of::<GpuMaterial>(), 48);
        assert_eq!(offset_of!(GpuMaterial, ke), 32);
        assert_eq!(glsl_fields("Material"), ["kd", "ks_ns", "ke"]);
    }

    #[test]
    fn bindings_match_glsl() {
        let consts = [
            ("LEAF_EX", binding::LEAF_EX),
            ("CLUSTER_EX", binding::CLUSTER_EX),
            ("FILTER", binding::FILTER),
            ("L_IN", binding::L_IN),
            ("L_PUSH", binding::L_PUSH),
            ("IRRADIANCE_T", binding::IRRADIANCE_T),
            ("IRRADIANCE_D", binding::IRRADIANCE_D),
            ("ATTR_NORMAL_AREA", binding::ATTR_NORMAL_AREA),
            ("ATTR_LEAF", binding::ATTR_LEAF),
            ("DIRECT", binding::DIRECT),
            ("LEAF_EX_NEXT", binding::LEAF_EX_NEXT),
            ("MATERIALS", binding::MATERIALS),
            ("BIN_CENTERS", binding::BIN_CENTERS),
        ];
        assert_eq!(consts.len() as u32, binding::COUNT);
        for (name, value) in consts {
            let line = format!("#define AR_BINDING_{name} {value}\n");
            assert!(
                COMMON.contains(&line),
                "common.glsl lacks `{}`",
                line.trim()
            );
        }
        for (name, value) in [
            ("BOTH", mode::BOTH),
            ("REFLECT", mode::REFLECT),
            ("ANTIRADIANCE", mode::ANTIRADIANCE),
        ] {
            let line = format!("#define AR_MODE_{name} {value}u\n");
            assert!(
                COMMON.contains(&line),
                "common.glsl lacks `{}`",
                line.trim()
            );
        }
        assert!(COMMON.contains(&format!("#define AR_FLAG_DIRECT {FLAG_DIRECT}u\n")));
        assert!(COMMON.contains(&format!("#define AR_FLAG_HALF {FLAG_HALF}u\n")));
    }
}

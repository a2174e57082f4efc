//! Tests of the parent module.

use super::*;
use std::mem::{offset_of, size_of};

const COMMON: &str = include_str!("../../../glsl/common.glsl");

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
    assert_eq!(offset_of!(PassConstants, omega), 16);
    assert_eq!(offset_of!(PassConstants, sender), 24);
    assert_eq!(offset_of!(PassConstants, environment), 32);
    assert_eq!(
        glsl_fields("PassConstants"),
        [
            "target_width",
            "target_height",
            "quad_width",
            "line_offset",
            "omega",
            "flags",
            "sender",
            "keep",
            "environment"
        ]
    );
}

#[test]
fn specialization_ids_match_glsl() {
    for (name, id) in [
        ("AR_SPEC_MODE", spec::MODE),
        ("AR_SPEC_GLOSSY", spec::GLOSSY),
        ("AR_SPEC_ANTIRADIANCE", spec::ANTIRADIANCE),
        ("AR_SPEC_DIRECT", spec::DIRECT),
        ("AR_SPEC_ENVIRONMENT", spec::ENVIRONMENT),
        ("AR_SPEC_EMISSION", spec::EMISSION),
        ("AR_SPEC_SPLAT", spec::SPLAT),
        ("AR_SPEC_VERTEX", spec::VERTEX),
        ("AR_SPEC_BINS", spec::BINS),
        ("AR_SPEC_GRID_ROWS", spec::GRID_ROWS),
        ("AR_SPEC_ROWS_PER_COLUMN", spec::ROWS_PER_COLUMN),
        ("AR_SPEC_TILE_NODES", spec::TILE_NODES),
        ("AR_SPEC_ROUND_WIDTH", spec::ROUND_WIDTH),
    ] {
        assert!(
            COMMON.contains(&format!("#define {name} {id}\n")),
            "{name} is not {id} in common.glsl"
        );
    }
    let t = crate::gpu::tables::TableLayout::with_column_height(100, 32, 4096, 40)
        .unwrap()
        .with_grid(4, 4096)
        .unwrap();
    let v = spec::solver_values(&crate::plan::Features::ALL, mode::REFLECT, true, &t, false);
    assert_eq!(
        v[..spec::COUNT],
        spec::values(&crate::plan::Features::ALL, mode::REFLECT, true)
    );
    assert_eq!(
        [
            v[spec::BINS as usize],
            v[spec::GRID_ROWS as usize],
            v[spec::ROWS_PER_COLUMN as usize],
            v[spec::TILE_NODES as usize]
        ],
        [32, 4, 40, 10]
    );
    assert_eq!(v[spec::ROUND_WIDTH as usize], 0);
    let r = spec::solver_values(&crate::plan::Features::ALL, mode::REFLECT, true, &t, true);
    assert_eq!(r[spec::ROUND_WIDTH as usize], t.tile_extent().0);
}

#[test]
fn vertex_and_buffer_records() {
    assert_eq!(size_of::<GpuLink>(), 12);
    assert_eq!(offset_of!(GpuLink, form_factor), 8);
    assert_eq!(size_of::<GpuCombo>(), 16);
    assert_eq!(size_of::<QuadInstance>(), 12);
    assert_eq!(size_of::<RowPair>(), 8);
    for (r, s, c) in [
        (0, 0, 0),
        (LINK_MAX_ROWS - 1, 7, LINK_MAX_COMBOS - 1),
        (5, LINK_MAX_ROWS - 1, 1234),
    ] {
        assert_eq!(GpuLink::new(r, s, c, 1.5).unpack(), (r, s, c));
    }
    let common = COMMON;
    assert!(common.contains(&format!("#define AR_LINK_ROW_BITS {LINK_ROW_BITS}u\n")));
    assert_eq!(size_of::<GpuMaterial>(), 48);
    assert_eq!(offset_of!(GpuMaterial, ke), 32);
    assert_eq!(glsl_fields("Material"), ["kd", "ks_ns", "ke"]);
}

#[test]
fn frame_records_match_glsl() {
    assert_eq!(size_of::<FrameConstants>(), 128);
    assert_eq!(offset_of!(FrameConstants, eye), 64);
    assert_eq!(offset_of!(FrameConstants, misc), 112);
    assert_eq!(
        glsl_fields("FrameConstants"),
        ["view_proj", "eye", "environment", "sizes", "misc"]
    );
    assert_eq!(size_of::<GpuShadowView>(), 144);
    assert_eq!(
        glsl_fields("ShadowView"),
        ["view_proj", "origin", "forward", "atlas", "right", "up"]
    );
    assert_eq!(size_of::<GpuLight>(), 128);
    assert_eq!(offset_of!(GpuLight, cell), 80);
    assert_eq!(
        glsl_fields("Light"),
        [
            "kind_views",
            "position",
            "direction",
            "power",
            "params",
            "cell[3]"
        ]
    );
    assert_eq!(size_of::<GpuEmitterTriangle>(), 64);
    assert_eq!(glsl_fields("EmitterTriangle"), ["c0", "c1", "c2", "ke"]);
    assert_eq!(size_of::<GpuFrameElement>(), 80);
    assert_eq!(
        glsl_fields("FrameElement"),
        [
            "center_radius",
            "normal_area",
            "ids",
            "cos_norm",
            "face_normal"
        ]
    );
    assert_eq!(size_of::<CornerVertex>(), 32);
    assert_eq!(offset_of!(CornerVertex, vertex), 16);
    assert_eq!(offset_of!(CornerVertex, normal), 20);
    assert_eq!(size_of::<GpuAdjEntry>(), 20);
    assert_eq!(glsl_fields("AdjEntry"), ["leaf", "nx", "ny", "nz", "w"]);
    let names = [
        "I_TOTAL",
        "MATERIALS",
        "BIN_CENTERS",
        "ELEMENTS",
        "ADJ_OFFSETS",
        "ADJ_LIST",
        "LIGHTS",
        "SHADOW_VIEWS",
        "SHADOW_MAP",
        "GBUF_POSITION",
        "GBUF_VERTEX",
        "SPLAT",
        "EMITTERS",
        "GBUF_NORMAL",
        "SPLAT_BINS",
        "DIRECT_BLOCKS",
        "VERTEX_POSITIONS",
        "VERTEX_VALUES",
    ];
    assert_eq!(names.len() as u32, frame_binding::COUNT);
    for (value, name) in names.iter().enumerate() {
        let line = format!("#define AR_FRAME_{name} {value}\n");
        assert!(
            COMMON.contains(&line),
            "common.glsl lacks `{}`",
            line.trim()
        );
    }
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
        ("ATTR_NORMAL_AREA", binding::ATTR_NORMAL_AREA),
        ("ATTR_LEAF", binding::ATTR_LEAF),
        ("DIRECT", binding::DIRECT),
        ("LEAF_EX_NEXT", binding::LEAF_EX_NEXT),
        ("MATERIALS", binding::MATERIALS),
        ("BIN_CENTERS", binding::BIN_CENTERS),
        ("LOBE_NORM", binding::LOBE_NORM),
        ("CLUSTER_EX_ODD", binding::CLUSTER_EX_ODD),
        ("COMBOS", binding::COMBOS),
        ("LOBE_BINS", binding::LOBE_BINS),
        ("LINKS", binding::LINKS),
        ("ENVIRONMENT", binding::ENVIRONMENT),
        ("ROUNDED", binding::ROUNDED),
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
    for (name, value) in [
        ("MODE", spec::MODE),
        ("GLOSSY", spec::GLOSSY),
        ("ANTIRADIANCE", spec::ANTIRADIANCE),
        ("DIRECT", spec::DIRECT),
        ("ENVIRONMENT", spec::ENVIRONMENT),
        ("EMISSION", spec::EMISSION),
        ("SPLAT", spec::SPLAT),
        ("VERTEX", spec::VERTEX),
    ] {
        let line = format!("#define AR_SPEC_{name} {value}\n");
        assert!(
            COMMON.contains(&line),
            "common.glsl lacks `{}`",
            line.trim()
        );
    }
    assert_eq!(spec::COUNT, 8);
    assert!(COMMON.contains(&format!("#define AR_FLAG_HALF {FLAG_HALF}u\n")));
    use crate::gpu::tables::{SENDER_EVEN, SENDER_LEAF, SENDER_ODD};
    for (name, value) in [
        ("LEAF", SENDER_LEAF),
        ("EVEN", SENDER_EVEN),
        ("ODD", SENDER_ODD),
    ] {
        let line = format!("#define AR_SENDER_{name} {value}u\n");
        assert!(
            COMMON.contains(&line),
            "common.glsl lacks `{}`",
            line.trim()
        );
    }
    assert!(COMMON.contains(&format!(
        "#define AR_LOBE_REFINE {}u\n",
        crate::gpu::pack::LOBE_REFINE
    )));
}

//! Tests of the parent module.

use super::*;
use std::mem::{offset_of, size_of};

const COMMON: &str = include_str!("../../../../glsl/pr_common.glsl");

fn glsl_fields(name: &str) -> Vec<String> {
    let start = COMMON
        .find(&format!("{name} {{"))
        .unwrap_or_else(|| panic!("{name} missing"));
    let body = &COMMON[start..];
    let body = &body[body.find('{').unwrap() + 1..body.find('}').unwrap()];
    body.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
        .split(';')
        .filter_map(|f| f.split_whitespace().last().map(str::to_string))
        .collect()
}

#[test]
fn records_match_glsl() {
    assert_eq!(size_of::<PrConstants>(), 32);
    assert_eq!(offset_of!(PrConstants, gradient), 16);
    assert_eq!(
        glsl_fields("PrConstants"),
        [
            "leaves",
            "face",
            "size",
            "subdivision",
            "gradient",
            "eps",
            "near",
            "slot"
        ]
    );
    assert_eq!(size_of::<PrLeaf>(), 96);
    assert_eq!(
        glsl_fields("PrLeaf"),
        ["c0_area", "c1", "c2", "normal", "albedo", "center"]
    );
    assert_eq!(size_of::<PrState>(), 48);
    assert_eq!(glsl_fields("PrState"), ["gathered", "unshot", "base"]);
    assert_eq!(size_of::<PrShot>(), 32);
    assert_eq!(offset_of!(PrShot, unshot), 16);
    assert_eq!(
        glsl_fields("PrShot"),
        ["shooter", "pad0", "pad1", "pad2", "unshot"]
    );
    assert_eq!(size_of::<PrVertex>(), 16);
    for (name, value) in [
        ("LEAVES", binding::LEAVES),
        ("STATE", binding::STATE),
        ("SHOT", binding::SHOT),
        ("FIGURES", binding::FIGURES),
        ("ITEM_ID", binding::ITEM_ID),
        ("ITEM_DIST", binding::ITEM_DIST),
    ] {
        let line = format!("#define PR_BINDING_{name} {value}\n");
        assert!(
            COMMON.contains(&line),
            "pr_common.glsl lacks `{}`",
            line.trim()
        );
    }
    assert!(COMMON.contains(&format!("#define PR_NONE {NONE:#x}u\n")));
}

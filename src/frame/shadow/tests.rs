//! Tests of the shadow maps' views and lookup constants.

use super::*;

/// Uniform numbers in [−1, 1) from a linear congruential generator seeded with `seed`.
fn uniform_from(seed: u64) -> impl FnMut() -> f64 {
    let mut rng = seed;
    move || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// A sphere is seen where it stands in front of a view, not behind it or far to its side;
/// one around the light always is. Orthographic views take the square widened by the radius.
#[test]
fn views_see_spheres_in_front() {
    let v = ShadowView::perspective(DVec3::ZERO, DVec3::NEG_Y, 45f64.to_radians(), 0.1, 10.0);
    assert!(v.may_see(DVec3::new(0.0, -2.0, 0.0), 0.1));
    assert!(v.may_see(DVec3::ZERO, 0.01));
    assert!(!v.may_see(DVec3::new(0.0, 2.0, 0.0), 0.5));
    // 45° half-angle: a point 60° off the axis is outside the square's cone (54.7°)...
    let off = DVec3::new(60f64.to_radians().sin(), -60f64.to_radians().cos(), 0.0) * 2.0;
    assert!(!v.may_see(off, 0.05));
    // ...unless its radius reaches in.
    assert!(v.may_see(off, 0.4));
    let mut o = v.clone();
    o.ortho = true;
    o.half = 1.0;
    assert!(o.may_see(DVec3::new(1.2, -3.0, 0.0), 0.3));
    assert!(!o.may_see(DVec3::new(1.5, -3.0, 0.0), 0.3));
}

#[test]
fn glsl_uses_the_same_constants() {
    let glsl = include_str!("../../../glsl/frame.glsl");
    for (name, v) in [
        ("DEPTH_BIAS", DEPTH_BIAS),
        ("RELATIVE_BIAS", RELATIVE_BIAS),
        ("FILTER_RADIUS", FILTER_RADIUS),
        ("GRAZING", GRAZING),
    ] {
        let line = format!("const float AR_SHADOW_{name} = {v:?};");
        assert!(glsl.contains(&line), "frame.glsl lacks `{line}`");
    }
    let taps = format!("const int AR_SHADOW_TAPS = {TAPS};");
    assert!(glsl.contains(&taps), "frame.glsl lacks `{taps}`");
    let mode = format!(
        "const uint AR_MODE_VERTEX = {}u;",
        crate::frame::surfaces::MODE_VERTEX
    );
    assert!(glsl.contains(&mode), "frame.glsl lacks `{mode}`");
    let gbuffer = include_str!("../../../glsl/gbuffer.vert");
    let filler = format!("const uint AR_FILLER = {:#x}u;", crate::gpu::pack::FILLER);
    assert!(gbuffer.contains(&filler), "gbuffer.vert lacks `{filler}`");
}

#[test]
fn texel_rays_project_to_their_texels() {
    let mut scene = Scene::empty();
    let m = scene.add_material(crate::scene::Material::diffuse("w", 0.5));
    scene.add_mesh(
        "t",
        vec![
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 2.0),
        ],
        vec![[0, 2, 1]],
        m,
    );
    scene.lights.push(Light::Directional {
        direction: DVec3::new(0.3, -1.0, 0.2).normalize(),
        irradiance: DVec3::ONE,
    });
    scene.lights.push(Light::Point {
        position: DVec3::new(0.5, 1.0, 0.5),
        intensity: DVec3::ONE,
    });
    let tilted = DVec3::new(0.3, -1.0, 0.1).normalize();
    scene.lights.push(Light::EmitterSample {
        position: DVec3::new(0.2, 0.9, 0.4),
        normal: tilted,
        radiance: DVec3::ONE,
        area: 0.01,
        cell: None,
    });
    let maps = ShadowMaps::new(&scene, &scene.lights, 16, 8).unwrap();
    assert_eq!(maps.light_views, vec![(0, 1), (1, 6), (7, 5)]);
    assert!(maps.views[7..].iter().all(|v| v.size == 8));
    // The atlas holds every map without overlap.
    for (a, va) in maps.views.iter().enumerate() {
        assert!(va.atlas.0 + va.size <= maps.atlas.0 && va.atlas.1 + va.size <= maps.atlas.1);
        for vb in &maps.views[a + 1..] {
            let apart = va.atlas.0 + va.size <= vb.atlas.0
                || vb.atlas.0 + vb.size <= va.atlas.0
                || va.atlas.1 + va.size <= vb.atlas.1
                || vb.atlas.1 + vb.size <= va.atlas.1;
            assert!(apart, "{va:?} overlaps {vb:?}");
        }
    }
    for v in &maps.views[..7] {
        for (i, j) in [(0, 0), (5, 9), (15, 15)] {
            let (o, d) = v.texel_ray(i, j, 16);
            let p = o + d * 0.7;
            let c = v.view_proj * p.extend(1.0);
            let tx = (c.x / c.w + 1.0) * 8.0 - 0.5;
            let ty = (c.y / c.w + 1.0) * 8.0 - 0.5;
            assert!((tx - i as f64).abs() < 1e-9 && (ty - j as f64).abs() < 1e-9);
            assert!((0.0..=1.0).contains(&(c.z / c.w)));
        }
    }
    // The face chosen for a direction covers it: the point light's −y face here, and for
    // the emitter sample one of its five faces for every direction in front of it.
    let d = DVec3::new(0.2, -0.9, 0.3);
    let f = maps.view_for(1, maps.views[1].origin + d);
    assert_eq!(f, 1 + 3);
    let covers = |f: usize, p: DVec3| {
        let c = maps.views[f].view_proj * p.extend(1.0);
        (c.x / c.w).abs() <= 1.0 + 1e-12 && (c.y / c.w).abs() <= 1.0 + 1e-12 && c.w > 0.0
    };
    assert!(covers(f, maps.views[1].origin + d));
    let mut uniform = uniform_from(1);
    let origin = maps.views[7].origin;
    for _ in 0..1000 {
        let d = DVec3::new(uniform(), uniform(), uniform());
        if d.length() > 1.0 || d.dot(tilted) <= 1e-3 {
            continue;
        }
        let f = maps.view_for(2, origin + d);
        assert!(
            (7..12).contains(&f) && covers(f, origin + d),
            "{d} → view {f}"
        );
    }
}

#[test]
fn packed_normals_keep_their_direction() {
    let mut uniform = uniform_from(7);
    let mut worst = 0.0f64;
    let random = std::iter::repeat_with(|| DVec3::new(uniform(), uniform(), uniform()));
    for n in CUBE.into_iter().chain(random.take(20000 - CUBE.len())) {
        if n.length() < 1e-3 {
            continue;
        }
        let n = n.normalize();
        let packed = pack_normal(n);
        // An integer below 2^22: a float holds it exactly.
        assert!(
            packed.fract() == 0.0 && packed < (1 << 22) as f32,
            "{packed}"
        );
        worst = worst.max(unpack_normal(packed).dot(n).clamp(-1.0, 1.0).acos());
    }
    // 11 bits per octahedral coordinate, steps of 1/1023: measured 2.04e-3 rad (0.12°) at worst.
    assert!(worst < 3e-3, "{worst}");
}

/// A floor meeting a wall, lit at a grazing angle by a point light in front of the wall, and a
/// second wall standing on the floor between the light and the floor beyond it. The floor
/// along the lit crease and the wall above it are fully lit (the taps past the crease see the
/// other face, with the point in front of it); the floor behind the second wall is dark up to
/// two texels from it.
#[test]
fn a_lit_crease_stays_lit_and_a_contact_stays_dark() {
    let mut scene = Scene::empty();
    let m = scene.add_material(crate::scene::Material::diffuse("w", 0.5));
    let p = DVec3::new;
    let quads = [
        [
            p(-1.0, 0.0, -1.0),
            p(-1.0, 0.0, 1.0),
            p(1.5, 0.0, 1.0),
            p(1.5, 0.0, -1.0),
        ],
        [
            p(-1.0, 0.0, -1.0),
            p(-1.0, 1.0, -1.0),
            p(-1.0, 1.0, 1.0),
            p(-1.0, 0.0, 1.0),
        ],
        [
            p(0.8, 0.0, -1.0),
            p(0.8, 0.5, -1.0),
            p(0.8, 0.5, 1.0),
            p(0.8, 0.0, 1.0),
        ],
    ];
    let mut triangles = Vec::new();
    for (k, q) in quads.iter().enumerate() {
        scene.add_mesh(&format!("q{k}"), q.to_vec(), vec![[0, 1, 2], [0, 2, 3]], m);
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
    }
    let light = Light::Point {
        position: p(0.5, 0.1, 0.0),
        intensity: DVec3::ONE,
    };
    let mut maps = ShadowMaps::new(&scene, std::slice::from_ref(&light), 64, 64).unwrap();
    maps.render_cpu(&RayCaster::from_triangles(triangles));
    let texel = maps.views[0].texel_size(p(-1.0, 0.0, 0.0), 64);
    // The floor's texels along x at the crease span several texels at this grazing angle.
    for d in [0.01, 0.02, 0.05, 0.1, 0.3, 0.6] {
        let v = maps.visibility(0, p(-1.0 + d, 0.0, 0.0), DVec3::Y, 0.0);
        assert_eq!(v, 1.0, "floor {d} from the lit crease (texel {texel})");
        let v = maps.visibility(0, p(-1.0, d, 0.1), DVec3::X, 0.0);
        assert_eq!(v, 1.0, "wall {d} above the lit crease");
    }
    let behind = maps.views[0].texel_size(p(0.8, 0.0, 0.0), 64);
    for d in [2.0 * behind, 0.05, 0.1, 0.3] {
        let v = maps.visibility(0, p(0.8 + d, 0.0, 0.0), DVec3::Y, 0.0);
        assert_eq!(v, 0.0, "floor {d} behind the wall (texel {behind})");
    }
}

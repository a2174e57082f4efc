//! Shading normals (OBJ `vn`): per pixel the barycentric interpolation of the triangle's vertex
//! normals replaces the face normal where light is reflected toward the eye: the cosine at the
//! receiver and the Phong lobe of direct light, and the direction whose bin of the element's
//! table is read toward the eye. The face (geometric) normal keeps deciding which side is the
//! front, the shadow-map lookup, and everything the solver does (its elements stay planar).
//! `glsl/frame.glsl` mirrors [`shading_normal`] and [`eye_direction`].

use glam::DVec3;

/// Least cosine between a shading normal and the direction to the eye, before normalization
/// (about 89.4°): the eye stays in front of the shading normal, so the bin toward the eye
/// ([`eye_direction`]) stays in front of the face and is read.
pub const MIN_EYE_COSINE: f64 = 0.01;

/// The shading normal at a pixel from the `interpolated` vertex normals (any length), for a
/// surface with unit face normal `geometric` seen along unit `wo` (toward the eye, on the front:
/// `wo·geometric > 0`). Where the interpolated normal turns (nearly) away from the eye
/// (`wo·n <` [`MIN_EYE_COSINE`], at a coarse mesh's silhouette) it is tilted toward the eye,
/// `wo` added until `wo·n` is that cosine: continuous, the lobe never looks below its own
/// horizon, and the tilt moves it toward the face normal's side. A normal that cannot be
/// normalized falls back to `geometric`.
pub fn shading_normal(interpolated: DVec3, geometric: DVec3, wo: DVec3) -> DVec3 {
    let n = interpolated.normalize_or_zero();
    let c = n.dot(wo);
    let n = if n != DVec3::ZERO && c < MIN_EYE_COSINE {
        (n + wo * (MIN_EYE_COSINE - c)).normalize_or_zero()
    } else {
        n
    };
    if n == DVec3::ZERO {
        geometric
    } else {
        n
    }
}

/// `wo` turned by the rotation that takes unit `shading` onto unit `geometric` (about their
/// common perpendicular): the direction that stands to the face as `wo` stands to the shading
/// normal, whose bin is read from the element's table (its bins are the face's). Identity
/// when the two normals are equal. The loader keeps every vertex normal within 90° of its face
/// and [`shading_normal`] only tilts toward the front, so `shading·geometric ≥ 0` and the
/// rotation is well defined.
pub fn eye_direction(wo: DVec3, shading: DVec3, geometric: DVec3) -> DVec3 {
    let v = shading.cross(geometric);
    let c = shading.dot(geometric);
    // Rodrigues' formula for the rotation from `shading` to `geometric`.
    wo * c + v.cross(wo) + v * (v.dot(wo) / (1.0 + c).max(1e-12))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glsl_uses_the_same_constant() {
        let glsl = include_str!("../../glsl/frame.glsl");
        let line = format!("const float AR_MIN_EYE_COSINE = {MIN_EYE_COSINE:?};");
        assert!(glsl.contains(&line), "frame.glsl lacks `{line}`");
    }

    #[test]
    fn eye_direction_keeps_the_angle_to_the_normal() {
        let g = DVec3::Z;
        let s = DVec3::new(0.3, -0.2, 1.0).normalize();
        for i in 0..50 {
            let a = i as f64 * 0.41;
            let wo = DVec3::new(a.cos(), a.sin(), 0.3 + 0.02 * i as f64).normalize();
            let r = eye_direction(wo, s, g);
            assert!((r.length() - 1.0).abs() < 1e-12);
            assert!((r.dot(g) - wo.dot(s)).abs() < 1e-12, "{wo} -> {r}");
        }
        // Equal normals: no rotation; the shading normal itself goes onto the face normal.
        assert_eq!(eye_direction(DVec3::X, g, g), DVec3::X);
        assert!((eye_direction(s, s, g) - g).length() < 1e-12);
    }

    #[test]
    fn shading_normals_never_face_away_from_the_eye() {
        let g = DVec3::Z;
        let wo = DVec3::new(1.0, 0.0, 0.2).normalize();
        // Tilted away from the eye: tilted until just in front of it, on the face's side, and
        // so read from a bin in front of the face.
        let n = shading_normal(DVec3::new(-0.6, 0.0, 0.8), g, wo);
        assert!(n.dot(wo) > 0.005 && n.dot(wo) < 0.02, "{}", n.dot(wo));
        assert!(n.dot(g) > 0.0 && (n.length() - 1.0).abs() < 1e-12);
        assert!(eye_direction(wo, n, g).dot(g) > 0.0);
        // Facing the eye: only normalized.
        let m = DVec3::new(0.3, 0.1, 0.9);
        assert!((shading_normal(m, g, wo) - m.normalize()).length() < 1e-15);
        assert_eq!(shading_normal(DVec3::ZERO, g, wo), g);
    }
}

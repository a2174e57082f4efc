//! Shadow maps for the lights (§3.3): one orthographic view for a directional light, one
//! perspective view for a spot light with a cut-off below 75°, six cube faces otherwise (point
//! lights, wide spots, area-emitter samples). All views share one atlas image, each at its own
//! size (emitter samples' maps are small, see [`crate::frame::emitters::SAMPLE_MAP_SIZE`]).
//! A map stores the *linear* distance to the nearest surface at each texel center (from the light
//! for perspective views, from the near plane for orthographic ones) and that surface's normal
//! (turned to the light, packed in one float: [`pack_normal`]), so the GPU (rasterized,
//! `glsl/shadow.frag`) and the CPU (ray cast at texel centers) build the same map, and one
//! filtered lookup (`visibility`, mirrored in `glsl/frame.glsl`) serves leaves and pixels.

use crate::raycast::RayCaster;
use crate::scene::{Light, Scene};
use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;

/// Value of a texel that sees no surface.
pub const EMPTY: f32 = 3.0e38;
/// One texel of a map: the distance and the packed normal of the surface it sees (both
/// [`EMPTY`] where it sees none; the GPU clears every channel to it).
pub type Texel = [f32; 2];
/// A texel that sees no surface.
pub const EMPTY_TEXEL: Texel = [EMPTY, EMPTY];
/// Steps per axis of a packed normal's octahedral coordinates (11 bits each: both fit a
/// float's 24-bit mantissa exactly, so the GPU's float target stores them without rounding).
const NORMAL_STEPS: f64 = 2047.0;

/// `n` (unit) in one float: its octahedral coordinates, 11 bits each, as the integer
/// `u·2048 + v` (mirrored in `glsl/frame.glsl` `ar_pack_normal`).
pub fn pack_normal(n: DVec3) -> f32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    let (mut u, mut v) = (n.x / l1, n.y / l1);
    if n.z < 0.0 {
        let sign = |a: f64| if a >= 0.0 { 1.0 } else { -1.0 };
        (u, v) = ((1.0 - v.abs()) * sign(u), (1.0 - u.abs()) * sign(v));
    }
    let q = |a: f64| {
        ((a * 0.5 + 0.5) * NORMAL_STEPS)
            .round()
            .clamp(0.0, NORMAL_STEPS)
    };
    (q(u) * 2048.0 + q(v)) as f32
}

/// The unit normal [`pack_normal`] packed (mirrored in `glsl/frame.glsl`).
pub fn unpack_normal(packed: f32) -> DVec3 {
    let p = packed as f64;
    let qu = (p / 2048.0).floor();
    let (u, v) = (
        qu / NORMAL_STEPS * 2.0 - 1.0,
        (p - qu * 2048.0) / NORMAL_STEPS * 2.0 - 1.0,
    );
    let z = 1.0 - u.abs() - v.abs();
    let (mut x, mut y) = (u, v);
    if z < 0.0 {
        let sign = |a: f64| if a >= 0.0 { 1.0 } else { -1.0 };
        (x, y) = ((1.0 - v.abs()) * sign(u), (1.0 - u.abs()) * sign(v));
    }
    DVec3::new(x, y, z).normalize()
}
/// Depth bias, in texels at the receiver, along the light's ray. The lookup compares each tap
/// with the receiver's own plane at that tap's texel (receiver-plane depth), so a planar
/// receiver matches its own map to rounding at any slope and needs no slope-scaled bias; what
/// is left is this tenth of a texel (rounding of the map and of the plane, a mesh's curvature within a
/// texel). Before, a fixed offset toward the light plus a slope-scaled bias of up to 13.5 texels
/// lifted a receiver past any occluder that near: a band of light along every contact (a wall
/// under a roof lit to 2 pixels below the roof at 256² maps, `tests/contact.rs`).
pub const DEPTH_BIAS: f64 = 0.1;
/// Relative depth bias: float32 map distances and the GPU's interpolated positions round at
/// about 10⁻⁷ of the distance; this covers them at any scene scale.
pub const RELATIVE_BIAS: f64 = 1e-5;
/// Radius (texels) of the tent filter of the percentage-closer lookup: one texel, so a point
/// more than one texel inside a shadow has every tap of non-zero weight inside it.
pub const FILTER_RADIUS: f64 = 1.0;
/// Texels per axis under the tent: of the 3 a radius of 1 spans, the third always weighs 0
/// (it lies a whole texel past the point), so 2×2 taps give the same lookup as 3×3.
pub const TAPS: i64 = 2;
// TAPS covers the tent only at this radius.
const _: () = assert!(FILTER_RADIUS == 1.0);
/// A tap whose texel ray meets the receiver's plane at a cosine below this (seen edge-on or
/// from behind) is compared at the receiver point's own distance.
const GRAZING: f64 = 1e-3;
/// Spot lights wider than this use a cube map.
const SPOT_SINGLE_VIEW_MAX_DEG: f64 = 75.0;

/// One rendered view of a light.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowView {
    /// Side of its map, texels.
    pub size: u32,
    /// Its map's top-left texel in the atlas.
    pub atlas: (u32, u32),
    /// World → Vulkan clip space (x right, y down, reversed depth 1..0).
    pub view_proj: DMat4,
    /// Light position (perspective) or a point on the near plane (orthographic).
    pub origin: DVec3,
    /// Unit view axis.
    pub forward: DVec3,
    /// Unit image right.
    pub right: DVec3,
    /// Unit image up.
    pub up: DVec3,
    /// `tan(fov/2)` (perspective) or half the side of the square (orthographic).
    pub half: f64,
    /// Orthographic (directional light) rather than perspective.
    pub ortho: bool,
    /// A one-sided light's normal: texels whose rays leave well behind it are never looked up,
    /// and the CPU leaves them empty rather than cast them.
    pub front: Option<DVec3>,
}

impl ShadowView {
    fn perspective(origin: DVec3, forward: DVec3, half_angle: f64, near: f64, far: f64) -> Self {
        let helper = if forward.y.abs() < 0.9 {
            DVec3::Y
        } else {
            DVec3::Z
        };
        Self::perspective_with(
            origin,
            forward,
            forward.cross(helper).normalize(),
            half_angle,
            near,
            far,
        )
    }

    /// A perspective view with the image's right given (unit, perpendicular to `forward`): the
    /// faces of a turned cube must share its edges.
    fn perspective_with(
        origin: DVec3,
        forward: DVec3,
        right: DVec3,
        half_angle: f64,
        near: f64,
        far: f64,
    ) -> Self {
        let up = right.cross(forward);
        let half = half_angle.tan();
        let view = basis(origin, forward, right, up);
        let proj = super::camera::reversed_perspective(1.0 / half, 1.0 / half, near, far);
        Self {
            size: 0,
            atlas: (0, 0),
            view_proj: proj * view,
            origin,
            forward,
            right,
            up,
            half,
            ortho: false,
            front: None,
        }
    }

    /// Unit ray (origin, direction) through the center of texel (i, j) of a `size`² map.
    pub fn texel_ray(&self, i: u32, j: u32, size: u32) -> (DVec3, DVec3) {
        let x = (i as f64 + 0.5) / size as f64 * 2.0 - 1.0;
        let y = (j as f64 + 0.5) / size as f64 * 2.0 - 1.0;
        if self.ortho {
            let o = self.origin + self.right * (x * self.half) - self.up * (y * self.half);
            (o, self.forward)
        } else {
            let d = self.forward + self.right * (x * self.half) - self.up * (y * self.half);
            (self.origin, d.normalize())
        }
    }

    /// The linear distance the map stores for a surface point `p`.
    pub fn distance(&self, p: DVec3) -> f64 {
        if self.ortho {
            (p - self.origin).dot(self.forward)
        } else {
            (p - self.origin).length()
        }
    }

    /// Whether a sphere (`center`, `radius`) may show in this view: conservative, the view's
    /// square taken as the cone around its diagonal (perspective) or its square widened by
    /// the radius (orthographic); a sphere around the origin always may.
    pub fn may_see(&self, center: DVec3, radius: f64) -> bool {
        let d = center - self.origin;
        if self.ortho {
            return d.dot(self.right).abs() <= self.half + radius
                && d.dot(self.up).abs() <= self.half + radius
                && d.dot(self.forward) >= -radius;
        }
        let len = d.length();
        if len <= radius {
            return true;
        }
        let off_axis = (d.dot(self.forward) / len).clamp(-1.0, 1.0).acos();
        off_axis <= (self.half * std::f64::consts::SQRT_2).atan() + (radius / len).asin()
    }

    /// World size of one texel at `p`.
    pub fn texel_size(&self, p: DVec3, size: u32) -> f64 {
        let scale = if self.ortho {
            1.0
        } else {
            (p - self.origin).length()
        };
        2.0 * self.half * scale / size as f64
    }
}

/// Appends the views of `light` over a scene of bounding sphere (`center`, `radius`).
fn light_views_of(light: &Light, center: DVec3, radius: f64, views: &mut Vec<ShadowView>) {
    match light {
        Light::Directional { direction, .. } => {
            let f = *direction;
            let helper = if f.y.abs() < 0.9 { DVec3::Y } else { DVec3::Z };
            let r = f.cross(helper).normalize();
            let u = r.cross(f);
            let half = radius * 1.02;
            let origin = center - f * (radius * 1.02);
            let depth = 2.0 * radius * 1.02;
            let view = basis(origin, f, r, u);
            let proj = DMat4::from_cols(
                DVec4::new(1.0 / half, 0.0, 0.0, 0.0),
                DVec4::new(0.0, 1.0 / half, 0.0, 0.0),
                DVec4::new(0.0, 0.0, -1.0 / depth, 0.0),
                DVec4::new(0.0, 0.0, 1.0, 1.0),
            );
            views.push(ShadowView {
                size: 0,
                atlas: (0, 0),
                view_proj: proj * view,
                origin,
                forward: f,
                right: r,
                up: u,
                half,
                ortho: true,
                front: None,
            });
        }
        Light::EmitterSample {
            position, normal, ..
        } => {
            // A one-sided emitter sees only its front: the cube turned to its normal, without
            // the face behind it (five faces; the sides' back halves are never looked up).
            let far = (*position - center).length() + radius * 1.02;
            let near = (far * 1e-5).max(1e-7);
            let helper = if normal.y.abs() < 0.9 {
                DVec3::Y
            } else {
                DVec3::Z
            };
            let r = normal.cross(helper).normalize();
            let u = r.cross(*normal);
            // Each face's right is another of the cube's axes, so the faces meet edge to edge.
            for (f, right) in [(*normal, r), (r, u), (-r, u), (u, r), (-u, r)] {
                let quarter = std::f64::consts::FRAC_PI_4;
                let mut v = ShadowView::perspective_with(*position, f, right, quarter, near, far);
                v.front = Some(*normal);
                views.push(v);
            }
        }
        Light::Point { position, .. } | Light::Spot { position, .. } => {
            let far = (*position - center).length() + radius * 1.02;
            let near = (far * 1e-5).max(1e-7);
            match light {
                Light::Spot { axis, cutoff, .. }
                    if cutoff.to_degrees() < SPOT_SINGLE_VIEW_MAX_DEG =>
                {
                    let half = (cutoff * 1.05 + 0.01).min(80f64.to_radians());
                    views.push(ShadowView::perspective(*position, *axis, half, near, far));
                }
                _ => {
                    for f in CUBE {
                        views.push(ShadowView::perspective(
                            *position,
                            f,
                            std::f64::consts::FRAC_PI_4,
                            near,
                            far,
                        ));
                    }
                }
            }
        }
    }
}

/// Places every view's map in an atlas, in rows (larger maps first keep the rows even), and
/// returns the atlas size, or `None` beyond [`MAX_ATLAS`] on a side.
fn pack_atlas(views: &mut [ShadowView]) -> Option<(u32, u32)> {
    let area: u64 = views.iter().map(|v| (v.size as u64).pow(2)).sum();
    let largest = views.iter().map(|v| v.size).max().unwrap_or(1).max(1);
    let width = ((area as f64).sqrt().ceil() as u32)
        .next_power_of_two()
        .clamp(largest, MAX_ATLAS.max(largest));
    let mut order: Vec<usize> = (0..views.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(views[i].size));
    let (mut x, mut y, mut row) = (0u32, 0u32, 0u32);
    for i in order {
        let s = views[i].size;
        if x + s > width {
            (x, y, row) = (0, y + row, 0);
        }
        views[i].atlas = (x, y);
        x += s;
        row = row.max(s);
    }
    let height = (y + row).max(1);
    (width <= MAX_ATLAS && height <= MAX_ATLAS).then_some((width, height))
}

/// World → view matrix for camera space x right, y down, z forward.
fn basis(o: DVec3, f: DVec3, r: DVec3, u: DVec3) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(r.x, -u.x, f.x, 0.0),
        DVec4::new(r.y, -u.y, f.y, 0.0),
        DVec4::new(r.z, -u.z, f.z, 0.0),
        DVec4::new(-r.dot(o), u.dot(o), -f.dot(o), 1.0),
    )
}

/// Cube faces in the order the lookup selects them: +X, −X, +Y, −Y, +Z, −Z.
const CUBE: [DVec3; 6] = [
    DVec3::X,
    DVec3::NEG_X,
    DVec3::Y,
    DVec3::NEG_Y,
    DVec3::Z,
    DVec3::NEG_Z,
];

/// Largest side of the atlas holding every view's map (maxImageDimension2D of lavapipe and
/// most GPUs).
pub const MAX_ATLAS: u32 = 16384;

/// The shadow maps of every light of a scene.
#[derive(Debug, Clone)]
pub struct ShadowMaps {
    /// Side of analytic lights' maps, texels.
    pub size: u32,
    /// All views, lights in order.
    pub views: Vec<ShadowView>,
    /// First view and view count (1 or 6) per light.
    pub light_views: Vec<(u32, u32)>,
    /// Width and height of the atlas image holding every view's map.
    pub atlas: (u32, u32),
    /// Where each view's map starts in [`ShadowMaps::data`].
    pub offsets: Vec<usize>,
    /// Texels (distance, packed normal), view after view, each row-major (`size × size` of its
    /// view); empty until rendered.
    pub data: Vec<Texel>,
}

impl ShadowMaps {
    /// The views for `lights` over `scene`, fitted to its bounds (no map data yet): analytic
    /// lights' maps of `size`² texels, emitter samples' of `sample_size`², packed into one atlas
    /// in rows. Returns `None` when the atlas would exceed [`MAX_ATLAS`] on a side.
    pub fn new(scene: &Scene, lights: &[Light], size: u32, sample_size: u32) -> Option<Self> {
        let sides: Vec<u32> = lights
            .iter()
            .map(|l| match l {
                Light::EmitterSample { .. } => sample_size,
                _ => size,
            })
            .collect();
        Self::with_sides(scene, lights, size, &sides)
    }

    /// [`ShadowMaps::new`] with each light's map side given (`sides[i]` for `lights[i]`;
    /// `size` is reported as the analytic lights' side): instant radiosity's VPLs get smaller
    /// maps than the emitter samples.
    pub fn with_sides(scene: &Scene, lights: &[Light], size: u32, sides: &[u32]) -> Option<Self> {
        let (lo, hi) = scene.bounds();
        let (center, radius) = ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-6));
        let mut views = Vec::new();
        let mut light_views = Vec::new();
        for (light, &side) in lights.iter().zip(sides) {
            let first = views.len();
            light_views_of(light, center, radius, &mut views);
            for v in &mut views[first..] {
                v.size = side;
            }
            light_views.push((first as u32, (views.len() - first) as u32));
        }
        let atlas = pack_atlas(&mut views)?;
        let mut offsets = Vec::with_capacity(views.len());
        let mut at = 0;
        for v in &views {
            offsets.push(at);
            at += (v.size * v.size) as usize;
        }
        Some(Self {
            size,
            views,
            light_views,
            atlas,
            offsets,
            data: Vec::new(),
        })
    }

    /// Texels of every view together.
    pub fn texels(&self) -> usize {
        self.views.iter().map(|v| (v.size * v.size) as usize).sum()
    }

    /// Fills [`ShadowMaps::data`] from the atlas image read back from the GPU (row-major,
    /// `atlas.0 × atlas.1`).
    pub fn set_from_atlas(&mut self, atlas: &[Texel]) {
        let w = self.atlas.0 as usize;
        let mut data = Vec::with_capacity(self.texels());
        for v in &self.views {
            let (x0, y0, s) = (v.atlas.0 as usize, v.atlas.1 as usize, v.size as usize);
            for y in 0..s {
                data.extend_from_slice(&atlas[(y0 + y) * w + x0..(y0 + y) * w + x0 + s]);
            }
        }
        self.data = data;
    }

    /// Fills the maps by casting a ray through every texel center (the CPU backend).
    pub fn render_cpu(&mut self, caster: &RayCaster) {
        self.render_cpu_reusing(caster, None);
    }

    /// [`ShadowMaps::render_cpu`] after objects moved: where `old` has the same views, its
    /// texels whose rays meet none of the spheres `moved` (around every moved object before and
    /// after the move) are kept, as nothing else can change along them. Returns the rays cast.
    pub fn render_cpu_reusing(
        &mut self,
        caster: &RayCaster,
        reuse: Option<(&ShadowMaps, &[(DVec3, f64)])>,
    ) -> usize {
        let reuse =
            reuse.filter(|(old, _)| old.views == self.views && old.data.len() == self.texels());
        let meets = |org: DVec3, dir: DVec3, (c, r): (DVec3, f64)| {
            let t = (c - org).dot(dir).max(0.0);
            (org + dir * t - c).length() <= r
        };
        let cast = std::sync::atomic::AtomicUsize::new(0);
        // One task per texel row of every view (rows of different views differ in length).
        let rows: Vec<(usize, u32)> = self
            .views
            .iter()
            .enumerate()
            .flat_map(|(v, view)| (0..view.size).map(move |j| (v, j)))
            .collect();
        let filled: Vec<Vec<Texel>> = rows
            .par_iter()
            .map(|&(v, j)| {
                let view = &self.views[v];
                (0..view.size)
                    .map(|i| {
                        let (org, dir) = view.texel_ray(i, j, view.size);
                        // Behind a one-sided light by more than the lookup's filter reaches.
                        if view.front.is_some_and(|n| dir.dot(n) < -0.1) {
                            return EMPTY_TEXEL;
                        }
                        if let Some((old, moved)) = reuse {
                            if !moved.iter().any(|&m| meets(org, dir, m)) {
                                let k = self.offsets[v] + (j * view.size + i) as usize;
                                return old.data[k];
                            }
                        }
                        cast.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        caster
                            .closest(org, dir, 0.0, f64::INFINITY)
                            .map_or(EMPTY_TEXEL, |h| {
                                let c = caster.corners(h.shape);
                                let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize();
                                // Turned to the light: a wall's two faces give one normal.
                                let n = if n.dot(dir) > 0.0 { -n } else { n };
                                [view.distance(org + dir * h.t) as f32, pack_normal(n)]
                            })
                    })
                    .collect()
            })
            .collect();
        self.data = filled.concat();
        cast.into_inner()
    }

    /// The view of light `light` that covers point `p`: of several (a cube's faces), the one
    /// whose axis is nearest the direction to `p` (the first of equals).
    pub fn view_for(&self, light: usize, p: DVec3) -> usize {
        let (first, count) = (
            self.light_views[light].0 as usize,
            self.light_views[light].1 as usize,
        );
        let v = p - self.views[first].origin;
        let mut best = first;
        for i in first + 1..first + count {
            if v.dot(self.views[i].forward) > v.dot(self.views[best].forward) {
                best = i;
            }
        }
        best
    }

    /// Filtered fraction of light `light` reaching `p`, a surface point with unit (face)
    /// normal `n` facing the light (`_cos`, the cosine to the light, is no longer needed: the
    /// receiver's plane gives each tap its own depth). A tap nearer than the receiver's plane
    /// votes shadow only if `p` lies behind the surface it sees: in a concave crease (a floor
    /// meeting a lit wall) the taps past the crease see the other face, with `p` in front of
    /// it; the plane beyond the crease is no receiver, so such a tap does not vote (before, it
    /// darkened every crease by up to half its light within a texel of it at grazing light).
    pub fn visibility(&self, light: usize, p: DVec3, n: DVec3, _cos: f64) -> f64 {
        if self.data.is_empty() {
            return 1.0;
        }
        let vi = self.view_for(light, p);
        let view = &self.views[vi];
        let s = view.size as i64;
        let c = view.view_proj * p.extend(1.0);
        let (x, y) = (c.x / c.w, c.y / c.w);
        let tx = (x + 1.0) * 0.5 * s as f64 - 0.5;
        let ty = (y + 1.0) * 0.5 * s as f64 - 0.5;
        let own = view.distance(p);
        let bias = view.texel_size(p, view.size) * DEPTH_BIAS + own.abs() * RELATIVE_BIAS;
        let base = &self.data[self.offsets[vi]..self.offsets[vi] + (s * s) as usize];
        let (x0, y0) = (
            (tx - FILTER_RADIUS).floor() as i64 + 1,
            (ty - FILTER_RADIUS).floor() as i64 + 1,
        );
        let stored = |kx: i64, ky: i64| {
            let (i, j) = (kx.clamp(0, s - 1), ky.clamp(0, s - 1));
            base[(j * s + i) as usize][0] as f64
        };
        // Every tap's depth is at most the point's own less the bias: where no stored depth is
        // nearer than that, every tap is lit and the lookup is exactly 1. (The GPU evaluates
        // every tap: on lavapipe the branch cost more than it saved, compose +14%.)
        let nearest = (0..TAPS * TAPS)
            .map(|k| stored(x0 + k % TAPS, y0 + k / TAPS))
            .fold(f64::INFINITY, f64::min);
        if own - bias <= nearest {
            return 1.0;
        }
        let (mut lit, mut total) = (0.0, 0.0);
        for ky in y0..y0 + TAPS {
            let wy = (1.0 - (ky as f64 - ty).abs() / FILTER_RADIUS).max(0.0);
            for kx in x0..x0 + TAPS {
                let wx = (1.0 - (kx as f64 - tx).abs() / FILTER_RADIUS).max(0.0);
                let w = wx * wy;
                if w <= 0.0 {
                    continue;
                }
                let (i, j) = (kx.clamp(0, s - 1), ky.clamp(0, s - 1));
                // Never deeper than the point itself: on a mesh rougher than a texel the plane
                // says little beyond the point, and deeper taps see the surface behind anyway.
                let d = view.plane_distance(p, n, own, i as u32, j as u32).min(own) - bias;
                let [depth, packed] = base[(j * s + i) as usize];
                if d <= depth as f64 {
                    lit += w;
                } else {
                    // The surface the tap sees, and whether p lies in front of it.
                    let (o, ray) = view.texel_ray(i as u32, j as u32, view.size);
                    let seen = o + ray * depth as f64;
                    if unpack_normal(packed).dot(p - seen) > bias {
                        continue;
                    }
                }
                total += w;
            }
        }
        if total > 0.0 {
            lit / total
        } else {
            1.0
        }
    }
}

impl ShadowView {
    /// The distance this view's map would store at texel (`i`, `j`) for the plane through `p`
    /// with unit normal `n` (receiver-plane depth); `own` (p's own distance) where the texel's
    /// ray meets the plane edge-on or from behind.
    pub fn plane_distance(&self, p: DVec3, n: DVec3, own: f64, i: u32, j: u32) -> f64 {
        let (o, d) = self.texel_ray(i, j, self.size);
        let dn = d.dot(n);
        if dn > -GRAZING {
            return own;
        }
        // Along the unit ray from the light (perspective) or from the near plane (orthographic):
        // the distance the map stores in either case.
        (p - o).dot(n) / dn
    }
}

#[cfg(test)]
mod tests;

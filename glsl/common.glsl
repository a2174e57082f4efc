// Layout constants shared by every pass; mirrors src/gpu/layout.rs (tests there compare the two).
// Tables (I_ex, I_total) hold one row per hierarchy node and one texel per bin; rows are split
// into column blocks of `rows_per_column` so the image stays within maxImageDimension2D: row r,
// bin j lives at texel ((r / H) * m + j, r % H). Per-row images (attributes, irradiance)
// use the same rows with one texel each: ((r / H), r % H). The incident tables (L_in, L_push)
// hold each node's bins as a tile of the bins' nu × nv grid (ar_in_texel), so that one wide line
// of the global pass covers a filter's footprint.
#ifndef ANTIRADIANCE_COMMON_GLSL
#define ANTIRADIANCE_COMMON_GLSL
#extension GL_GOOGLE_include_directive : require

#define AR_BINDING_LEAF_EX 0
#define AR_BINDING_CLUSTER_EX 1
#define AR_BINDING_FILTER 2
#define AR_BINDING_L_IN 3
#define AR_BINDING_L_PUSH 4
#define AR_BINDING_IRRADIANCE_T 5
#define AR_BINDING_ATTR_NORMAL_AREA 6
#define AR_BINDING_ATTR_LEAF 7
#define AR_BINDING_DIRECT 8
#define AR_BINDING_LEAF_EX_NEXT 9
#define AR_BINDING_MATERIALS 10
#define AR_BINDING_BIN_CENTERS 11
#define AR_BINDING_LOBE_NORM 12
#define AR_BINDING_CLUSTER_EX_ODD 13
#define AR_BINDING_COMBOS 14
#define AR_BINDING_LOBE_BINS 15
#define AR_BINDING_LINKS 16
#define AR_BINDING_ENVIRONMENT 17
#define AR_BINDING_ROUNDED 18

// The glossy lobes' incident-bin lists are per cell of a grid this much finer (per side) than
// the bins' (src/gpu/pack.rs LOBE_REFINE).
#define AR_LOBE_REFINE 4u

// Link records (src/gpu/layout.rs GpuLink): rows in the low bits, combo halves above.
#define AR_LINK_ROW_BITS 22u

// Which I_ex image a global draw's senders live in (src/gpu/tables.rs sender_image).
#define AR_SENDER_LEAF 0u
#define AR_SENDER_EVEN 1u
#define AR_SENDER_ODD 2u
#define AR_MODE_BOTH 0u
#define AR_MODE_REFLECT 1u
#define AR_MODE_ANTIRADIANCE 2u
#define AR_FLAG_HALF 2u

// Specialization constants (src/gpu/layout.rs `spec`): what the scene needs (src/plan).
#define AR_SPEC_MODE 0
#define AR_SPEC_GLOSSY 1
#define AR_SPEC_ANTIRADIANCE 2
#define AR_SPEC_DIRECT 3
#define AR_SPEC_ENVIRONMENT 4
#define AR_SPEC_EMISSION 5
#define AR_SPEC_SPLAT 6
#define AR_SPEC_VERTEX 7
layout(constant_id = AR_SPEC_MODE) const uint AR_MODE = 0u;
layout(constant_id = AR_SPEC_GLOSSY) const bool AR_GLOSSY = true;
layout(constant_id = AR_SPEC_ANTIRADIANCE) const bool AR_ANTIRADIANCE = true;
layout(constant_id = AR_SPEC_DIRECT) const bool AR_DIRECT = true;
layout(constant_id = AR_SPEC_ENVIRONMENT) const bool AR_ENVIRONMENT = true;
layout(constant_id = AR_SPEC_EMISSION) const bool AR_EMISSION = true;
layout(constant_id = AR_SPEC_SPLAT) const bool AR_SPLAT = true;
layout(constant_id = AR_SPEC_VERTEX) const bool AR_VERTEX = true;

struct Material {
    vec4 kd;
    vec4 ks_ns;
    vec4 ke;
};

const float AR_PI = 3.14159265358979;

#ifdef AR_FRAME_PASS
// Frame passes (shadow maps, G-buffer, splat, compose): src/gpu/frame.rs.
#define AR_FRAME_I_TOTAL 0
#define AR_FRAME_MATERIALS 1
#define AR_FRAME_BIN_CENTERS 2
#define AR_FRAME_ELEMENTS 3
#define AR_FRAME_ADJ_OFFSETS 4
#define AR_FRAME_ADJ_LIST 5
#define AR_FRAME_LIGHTS 6
#define AR_FRAME_SHADOW_VIEWS 7
#define AR_FRAME_SHADOW_MAP 8
#define AR_FRAME_GBUF_POSITION 9
#define AR_FRAME_GBUF_VERTEX 10
#define AR_FRAME_SPLAT 11
#define AR_FRAME_EMITTERS 12
#define AR_FRAME_GBUF_NORMAL 13
#define AR_FRAME_SPLAT_BINS 14
#define AR_FRAME_DIRECT_BLOCKS 15
#define AR_FRAME_VERTEX_POSITIONS 16
#define AR_FRAME_VERTEX_VALUES 17
// Texels per row of the vertex values (src/gpu/passes/vertex_values.rs WIDTH).
#define AR_VERTEX_VALUES_WIDTH 1024

layout(push_constant) uniform FrameConstants {
    mat4 view_proj;   // camera, or the shadow view being drawn
    vec4 eye;         // xyz eye; w = 1 / source scale
    vec4 environment; // rgb radiance where camera rays escape; w: exposure factor on the output
    uvec4 sizes;      // target width, height, bins, rows per column block
    uvec4 misc;       // light count, shadow view (compose: y..z the shared lights), supersampling
                      // | direct block << 8 (frame/direct.rs)
} pc;

struct ShadowView {
    mat4 view_proj;
    vec4 origin;   // w: 1 orthographic, 0 perspective
    vec4 forward;  // w: half side / tan(fov/2)
    uvec4 atlas;   // its map in the atlas: x0, y0, side
    vec4 right;    // unit image right (texel rays of the receiver-plane lookup)
    vec4 up;       // unit image up
};

struct Light {
    uvec4 kind_views;  // kind (0 directional, 1 point, 2 spot, 3 emitter sample), first view, view count, has cell
    vec4 position;
    vec4 direction;    // travel direction / spot axis / emitter normal
    vec4 power;        // rgb irradiance, intensity or radiance; w spot cut-off (radians)
    vec4 params;       // x spot beam width (radians) or emitter sample area
    vec4 cell[3];      // an emitter sample's cell corners (xyz) where kind_views.w is 1
};

struct EmitterTriangle {
    vec4 c0;
    vec4 c1;
    vec4 c2;
    vec4 ke;
};

// One face slot (src/frame/surfaces.rs Surfaces): its leaf's display data (center, splat radius,
// normal, area, row) and the face's own normal (a face cluster's faces differ from its plane).
struct FrameElement {
    vec4 center_radius;
    vec4 normal_area;  // the leaf's unit normal and area
    uvec4 ids;         // table row, surface id, mode (0 splat, 1 vertex), material
    vec4 cos_norm;     // x cosine normalization; y 1 with shading normals (OBJ vn), else 0
    vec4 face_normal;  // xyz the face's unit normal
};

// A slot whose leaf blends at a shared vertex, its shading normal there (not normalized) and its
// weight (surfaces.rs adjacency_weight); scalars keep the record 20 bytes in std430.
struct AdjEntry {
    uint leaf;
    float nx;
    float ny;
    float nz;
    float w;
};
#else
layout(push_constant) uniform PassConstants {
    uint target_width;
    uint target_height;
    uint quad_width;
    float line_offset;
    float omega;
    uint flags;
    uint sender;       // global pass: the I_ex image of the draw's senders (AR_SENDER_*)
    float keep;        // local pass: the last iterate's weight in a damped iteration (0: none)
    vec4 environment;  // rgb: environment radiance (scaled); a: source scale (a power of two)
} pc;

// The table layout (src/gpu/tables.rs TableLayout) as specialization constants, set per
// pipeline (src/gpu/layout.rs spec::solver_values): a CPU rasterizer divides by a constant with
// a multiply and a shift, by a push constant with one scalar division per lane.
#define AR_SPEC_BINS 8
#define AR_SPEC_GRID_ROWS 9
#define AR_SPEC_ROWS_PER_COLUMN 10
#define AR_SPEC_TILE_NODES 11
layout(constant_id = AR_SPEC_BINS) const uint AR_BINS = 1u;                  // bins per row, m
layout(constant_id = AR_SPEC_GRID_ROWS) const uint AR_GRID_ROWS = 1u;        // nv of the bin grid
layout(constant_id = AR_SPEC_ROWS_PER_COLUMN) const uint AR_ROWS_PER_COLUMN = 1u;
layout(constant_id = AR_SPEC_TILE_NODES) const uint AR_TILE_NODES = 1u;      // incident tiles per column
const uint AR_GRID_COLUMNS = AR_BINS / AR_GRID_ROWS;                         // nu of the bin grid

// Float16 blending rounded to nearest, emulated (src/gpu/blend16.rs): the width of the incident
// tables where the global and push passes add into the ROUNDED buffer instead of blending; 0
// where they blend (every real device).
#define AR_SPEC_ROUND_WIDTH 12
layout(constant_id = AR_SPEC_ROUND_WIDTH) const uint AR_ROUND_WIDTH = 0u;

// x rounded to the nearest float16 value, ties to even, kept in a float: finite values beyond
// float16's range become ±infinity, values below its smallest normal round on the subnormals'
// step 2^-24, as a device's float16 attachment stores them.
float ar_round_f16(float x) {
    if (isnan(x)) {
        return x;
    }
    if (abs(x) >= 65520.0) {  // at and above halfway from 65504 to 2^16: infinity
        return x > 0.0 ? 1.0 / 0.0 : -1.0 / 0.0;
    }
    // The float16 step at x: 2^(e-10) for |x| in [2^e, 2^(e+1)), and 2^-24 below 2^-14 (the
    // subnormals); x / step and its product are exact (powers of two).
    uint e = max((floatBitsToUint(x) >> 23) & 0xffu, 113u);
    float step = uintBitsToFloat((e - 10u) << 23);
    return roundEven(x / step) * step;
}

// Incident tables (src/gpu/tables.rs TableLayout::tile_texel): row r's tile has its bin 0 at
// ((r / T) * nu, (r % T) * nv), bin iv*nu + iu at offset (iu, iv).
ivec2 ar_in_origin(uint row) {
    return ivec2((row / AR_TILE_NODES) * AR_GRID_COLUMNS, (row % AR_TILE_NODES) * AR_GRID_ROWS);
}

ivec2 ar_in_texel(uint row, uint bin) {
    return ar_in_origin(row) + ivec2(bin % AR_GRID_COLUMNS, bin / AR_GRID_COLUMNS);
}

// Bin of the incident-table texel under a fragment.
uint ar_in_bin_at(ivec2 p) {
    return (uint(p.y) % AR_GRID_ROWS) * AR_GRID_COLUMNS + uint(p.x) % AR_GRID_COLUMNS;
}

ivec2 ar_texel(uint row, uint bin) {
    return ivec2((row / AR_ROWS_PER_COLUMN) * AR_BINS + bin, row % AR_ROWS_PER_COLUMN);
}

ivec2 ar_row_texel(uint row) {
    return ivec2(row / AR_ROWS_PER_COLUMN, row % AR_ROWS_PER_COLUMN);
}

// Row and bin of the table texel under a fragment.
uint ar_row_at(ivec2 p) {
    return (uint(p.x) / AR_BINS) * AR_ROWS_PER_COLUMN + uint(p.y);
}

uint ar_bin_at(ivec2 p) {
    return uint(p.x) % AR_BINS;
}

// Row of the per-row-image texel under a fragment.
uint ar_row_at_row_image(ivec2 p) {
    return uint(p.x) * AR_ROWS_PER_COLUMN + uint(p.y);
}

// Rounds to the nearest float16 (ties to even) before a store into a float16 target: some
// drivers (lavapipe) convert by truncation, a bias that antiradiance's cancellations amplify.
// Identity for float32 tables; normal float16 range only (subnormals keep truncating).
vec3 ar_store(vec3 v) {
    if ((pc.flags & AR_FLAG_HALF) == 0u) {
        return v;
    }
    uvec3 b = floatBitsToUint(v);
    return uintBitsToFloat((b + 0x0FFFu + ((b >> 13) & 1u)) & 0xFFFFE000u);
}

// Framebuffer position (texels) to clip space; Vulkan's y axis points down like the texel rows.
vec4 ar_clip(vec2 p) {
    return vec4(p / vec2(pc.target_width, pc.target_height) * 2.0 - 1.0, 0.0, 1.0);
}

// One end of a line along `row` of a table at the left edge of the texel at `position`: a line
// from position `lo` to `hi` covers exactly the texels [lo, hi) of the row (pull).
vec4 ar_line_end(uint row, uint position) {
    ivec2 t = ar_texel(row, 0u);
    return ar_clip(vec2(float(t.x) + float(position) + pc.line_offset, float(t.y) + 0.5));
}

// One end of a line that covers exactly the rectangle of `size` texels at `corner` when drawn
// `size.y` texels wide (the global pass): along the rectangle's middle row, from its left edge
// (`far` false) to its right edge. A wide line is a rectangle only in rectangular mode, where
// pc.line_offset is 0; in Bresenham mode lines are one texel wide.
vec4 ar_rect_line_end(ivec2 corner, uvec2 size, bool far) {
    float x = float(corner.x) + (far ? float(size.x) : 0.0) + pc.line_offset;
    return ar_clip(vec2(x, float(corner.y) + 0.5 * float(size.y)));
}

// A position outside the target: a line with both ends here draws nothing.
const vec4 AR_NOWHERE = vec4(-2.0, -2.0, 0.0, 1.0);
#endif  // AR_FRAME_PASS

#endif

// Progressive refinement radiosity (src/methods/progressive/gpu.rs mirrors these records; its
// tests check sizes, field names and bindings): the shooter's hemicube frame, the item buffer's
// face layout, receiver sub-triangles and the exact projected solid angle of a triangle.
#ifndef PR_COMMON_GLSL
#define PR_COMMON_GLSL

#define PR_BINDING_LEAVES 0
#define PR_BINDING_STATE 1
#define PR_BINDING_SHOT 2
#define PR_BINDING_FIGURES 3
#define PR_BINDING_ITEM_ID 4
#define PR_BINDING_ITEM_DIST 5

// No shooter (nothing left to shoot).
#define PR_NONE 0xffffffffu

const float PR_PI = 3.14159265358979;

// One element: corners (area in c0_area.w), normal, albedo, centroid.
struct PrLeaf {
    vec4 c0_area;
    vec4 c1;
    vec4 c2;
    vec4 normal;
    vec4 albedo;
    vec4 center;
};

// Per element: irradiance gathered, radiosity not yet shot, radiosity that does not change
// (emission + reflected direct light).
struct PrState {
    vec4 gathered;
    vec4 unshot;
    vec4 base;
};

// The current shooter (PR_NONE when nothing is left) and its unshot radiosity (power in w).
struct PrShot {
    uint shooter;
    uint pad0;
    uint pad1;
    uint pad2;
    vec4 unshot;
};

layout(push_constant) uniform PrConstants {
    uint leaves;      // elements
    uint face;        // hemicube face being drawn (0: along the normal, 1..4: sides)
    uint size;        // texels per face side
    uint subdivision; // deepest receiver subdivision level
    float gradient;   // relative spread of samples that triggers the next level
    float eps;        // offset of the shooter's eye off its surface
    float near;       // near plane of the hemicube faces
    uint slot;        // figures slot written by the selection
} pc;

// An orthonormal frame around unit n (Duff et al. 2017); the hemicube and its lookups share it.
void pr_basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// Axes of hemicube face f: forward, right, up (up = n on the four side faces, whose upper half
// is drawn into rows [0, size/2) of the face).
void pr_face(uint f, vec3 n, vec3 t, vec3 b, out vec3 fw, out vec3 rt, out vec3 up) {
    if (f == 0u) {
        fw = n; rt = t; up = b;
    } else if (f == 1u) {
        fw = t; rt = b; up = n;
    } else if (f == 2u) {
        fw = -t; rt = b; up = n;
    } else if (f == 3u) {
        fw = b; rt = t; up = n;
    } else {
        fw = -b; rt = t; up = n;
    }
}

// Barycentric centroid of sub-triangle k of level `level` (src/methods/progressive/mod.rs
// subtriangle_centroid).
vec3 pr_subtriangle(uint level, uint k) {
    vec3 c0 = vec3(1.0, 0.0, 0.0);
    vec3 c1 = vec3(0.0, 1.0, 0.0);
    vec3 c2 = vec3(0.0, 0.0, 1.0);
    for (int l = int(level) - 1; l >= 0; l--) {
        vec3 ab = 0.5 * (c0 + c1);
        vec3 bc = 0.5 * (c1 + c2);
        vec3 ca = 0.5 * (c2 + c0);
        uint d = (k >> (2u * uint(l))) & 3u;
        if (d == 0u) {
            c1 = ab; c2 = ca;
        } else if (d == 1u) {
            c0 = ab; c2 = bc;
        } else if (d == 2u) {
            c0 = ca; c1 = bc;
        } else {
            c0 = bc; c1 = ca; c2 = ab;
        }
    }
    return (c0 + c1 + c2) / 3.0;
}

// ∫ cos θ dω of triangle (v0, v1, v2) seen from p with normal n, clipped to the half-space in
// front of p (Lambert's polygon formula; src/linker.rs projected_solid_angle).
float pr_projected_solid_angle(vec3 p, vec3 n, vec3 v0, vec3 v1, vec3 v2) {
    vec3 tri[3] = vec3[3](v0 - p, v1 - p, v2 - p);
    vec3 poly[4];
    int k = 0;
    for (int i = 0; i < 3; i++) {
        vec3 a = tri[i];
        vec3 b = tri[(i + 1) % 3];
        float da = dot(n, a);
        float db = dot(n, b);
        if (da >= 0.0) {
            poly[k++] = a;
        }
        if ((da >= 0.0) != (db >= 0.0)) {
            poly[k++] = a + (b - a) * (da / (da - db));
        }
    }
    if (k < 3) {
        return 0.0;
    }
    float sum = 0.0;
    for (int i = 0; i < k; i++) {
        vec3 a = poly[i];
        vec3 b = poly[(i + 1) % k];
        vec3 c = cross(a, b);
        float cl = length(c);
        if (cl > 1e-30) {
            sum += atan(cl, dot(a, b)) * dot(n, c) / cl;
        }
    }
    return 0.5 * abs(sum);
}

#endif

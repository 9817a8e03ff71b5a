// The `local` model's ray caster on the GPU: one invocation per pixel, mirroring the
// CPU's reference loop (glint-volume raycast/caster.rs: Caster::ray, composite, add,
// mip) and the core's lighting (glint-core lighting: Shader::for_ray, surface_at,
// light_sums, gated; glint-lobe Lobe::eval) term by term. Values and gradients are
// the field's bricks' own (R32Float and Rgba16Sint texels, read with textureLoad):
// the 8 neighbours are interpolated here in f32, since texture units (and lavapipe)
// quantise trilinear weights to 8 bits. The tricubic filter reads the 64 taps of
// the CPU's B-spline (field/cubic.rs) from the same values; pre-integrated segments
// read the CPU's tables (classification/preint.rs) with the f64 integrals split into
// f32 pairs; clip planes and the crop box cut each ray and light its cut faces
// (clip.rs); the hw lobe reads its cosine table (glint-lobe CosTable::eval); a
// colour volume's codes replace the table's colours (ColourVolume::at).

struct Params {
    // xyz: the eye (perspective) or image centre (orthographic), index units;
    // w: 1 for perspective.
    origin: vec4<f32>,
    // The camera's forward, right, up axes in index units per mm, then in world units.
    f_index: vec4<f32>,
    r_index: vec4<f32>,
    u_index: vec4<f32>,
    f_world: vec4<f32>,
    r_world: vec4<f32>,
    u_world: vec4<f32>,
    // u0, du, v0, dv.
    plane: vec4<f32>,
    // xyz: clip box low corner; w: the step dt in mm.
    clip_lo: vec4<f32>,
    // xyz: clip box high corner; w: the termination opacity.
    clip_hi: vec4<f32>,
    // LUT lo, LUT scale, gradient scale, LUT entries.
    lut: vec4<f32>,
    // Background rgb; w: mode (0 composite, 1 MIP).
    bg: vec4<f32>,
    // ambient, diffuse, specular, shade (1 or 0).
    material: vec4<f32>,
    // gate, surface weight, geometry (0 Phong, 1 Blinn), light count.
    gate: vec4<f32>,
    // form (0 exact, 1 power, 2 Schlick, 3 Gauss, 4 table), n, a, v.
    lobe: vec4<f32>,
    // Iso threshold, pre-integrated (1) or point sampling (0), tricubic (1) or
    // trilinear (0; the pipeline's TRICUBIC decides), clip half-spaces.
    extra: vec4<f32>,
    // The cut faces' depth (mm) and strong gradient; the pre-integrated opacity
    // table's m_max and m_scale.
    cut: vec4<f32>,
    // The hw lobe's cosine table: scale (2^frac_bits), first code, entries; w: 1
    // when a colour volume's colours replace the lookup table's.
    table: vec4<f32>,
    // Rows of the matrix from the spline's index-space derivatives to the world
    // gradient (tricubic).
    gm0: vec4<f32>,
    gm1: vec4<f32>,
    gm2: vec4<f32>,
    // width, height, then the macro cells along i and j.
    size: vec4<u32>,
    // The field's dims; w: the macro cells along k.
    dims: vec4<u32>,
    // Per light: unit world direction towards it, intensity.
    lights: array<vec4<f32>, 8>,
}

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var values: texture_3d<f32>;
@group(0) @binding(2) var gradients: texture_3d<i32>;
@group(0) @binding(3) var<storage, read> lut: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> out: array<vec4<f32>>;
// Per half-space two entries: (a, b) with signed distance a·p + b (mm), then the
// unit world normal into the kept side.
@group(0) @binding(5) var<storage, read> planes: array<vec4<f32>>;
// The pre-integrated tables (PreIntegrated): per bin the point segment, then the
// integrals at the bins' lower edges as f32 pairs (high, low), the slopes, and
// (visible count, opacity table entry).
@group(0) @binding(6) var<storage, read> pre: array<vec4<f32>>;
// The hw lobe's cosine table from its first stored code.
@group(0) @binding(7) var<storage, read> spec: array<f32>;
// A colour volume's 8-bit sRGB codes, and the linear light of each code.
@group(0) @binding(8) var colours: texture_3d<u32>;
@group(0) @binding(9) var<storage, read> srgb: array<f32>;
// The empty-space map (Classification's distance), four cells a word, cell c in
// bits 8 (c mod 4) and up.
@group(0) @binding(10) var<storage, read> distance: array<u32>;
// The `shadows` model's light volumes (local.rs shadow_tables): [0] on, has
// occlusion, anisotropy, 1 / cell; [1] the occlusion's dims and first index; per
// light its axes and first index, its extents, its bias. Their values in `light`.
@group(0) @binding(11) var<storage, read> shadow: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> light: array<f32>;
// A paged field's page table (pages.rs): the page side, the pages along x and y,
// the atlas's slots along x and y, padding to 8 words, then each page's slot.
@group(0) @binding(13) var<storage, read> pages: array<u32>;

const BINS: u32 = 4096u;
const PRE_POINT: u32 = 0u;
const PRE_HI: u32 = 4096u;
const PRE_LO: u32 = 8193u;
const PRE_SLOPE: u32 = 12290u;
const PRE_AUX: u32 = 16386u;
const OPACITY_TABLE: u32 = 4096u;
const ISO_REFINE_STEPS: u32 = 8u;
const MACRO_CELL: u32 = 4u;

// The field's filter, fixed per pipeline: the tricubic spline's 64 taps are
// compiled into the tricubic pipeline only.
override TRICUBIC: bool = false;
// Whether the values and gradients are a paged atlas (a field past the adapter's
// 3D texture side): every voxel read goes through the page table.
override PAGED: bool = false;

// The texel holding voxel c (inside the volume): c itself, or in a paged field its
// page's slot in the atlas plus its offset in the page.
fn texel(c: vec3<i32>) -> vec3<i32> {
    if !PAGED {
        return c;
    }
    let b = i32(pages[0]);
    let pc = c / b;
    let p = u32(pc.x) + pages[1] * (u32(pc.y) + pages[2] * u32(pc.z));
    let s = pages[8u + p];
    let sx = pages[3];
    let sy = pages[4];
    let slot = vec3<i32>(vec3<u32>(s % sx, (s / sx) % sy, s / (sx * sy)));
    return slot * b + (c - pc * b);
}

struct Loc {
    ijk: vec3<i32>,
    t: vec3<f32>,
}

// Field::locate: the trilinear cell holding p, clamped to the border cells.
fn locate(p: vec3<f32>) -> Loc {
    let hi = vec3<f32>(P.dims.xyz - vec3<u32>(2u));
    let f = min(max(p, vec3<f32>(0.0)), hi);
    let ijk = vec3<i32>(f);
    let t = clamp(p - vec3<f32>(ijk), vec3<f32>(0.0), vec3<f32>(1.0));
    return Loc(ijk, t);
}

fn v_at(c: vec3<i32>) -> f32 {
    return textureLoad(values, texel(c), 0).x;
}

// trilinear (field.rs): x, then y, then z, each a + t (b - a).
fn value_at(l: Loc) -> f32 {
    let c = l.ijk;
    let c000 = v_at(c);
    let c100 = v_at(c + vec3<i32>(1, 0, 0));
    let c010 = v_at(c + vec3<i32>(0, 1, 0));
    let c110 = v_at(c + vec3<i32>(1, 1, 0));
    let c001 = v_at(c + vec3<i32>(0, 0, 1));
    let c101 = v_at(c + vec3<i32>(1, 0, 1));
    let c011 = v_at(c + vec3<i32>(0, 1, 1));
    let c111 = v_at(c + vec3<i32>(1, 1, 1));
    let x00 = c000 + l.t.x * (c100 - c000);
    let x10 = c010 + l.t.x * (c110 - c010);
    let x01 = c001 + l.t.x * (c101 - c001);
    let x11 = c011 + l.t.x * (c111 - c011);
    let y0 = x00 + l.t.y * (x10 - x00);
    let y1 = x01 + l.t.y * (x11 - x01);
    return y0 + l.t.z * (y1 - y0);
}

fn g_at(c: vec3<i32>) -> vec3<f32> {
    return vec3<f32>(textureLoad(gradients, texel(c), 0).xyz);
}

// trilinear_gradient (field.rs): the stored integers interpolated, then scaled.
fn gradient_at(l: Loc) -> vec3<f32> {
    let c = l.ijk;
    let x00 = mix3(g_at(c), g_at(c + vec3<i32>(1, 0, 0)), l.t.x);
    let x10 = mix3(g_at(c + vec3<i32>(0, 1, 0)), g_at(c + vec3<i32>(1, 1, 0)), l.t.x);
    let x01 = mix3(g_at(c + vec3<i32>(0, 0, 1)), g_at(c + vec3<i32>(1, 0, 1)), l.t.x);
    let x11 = mix3(g_at(c + vec3<i32>(0, 1, 1)), g_at(c + vec3<i32>(1, 1, 1)), l.t.x);
    let y0 = mix3(x00, x10, l.t.y);
    let y1 = mix3(x01, x11, l.t.y);
    return mix3(y0, y1, l.t.z) * P.lut.z;
}

fn mix3(a: vec3<f32>, b: vec3<f32>, t: f32) -> vec3<f32> {
    return a + t * (b - a);
}

// Lut::position and Lut::get: the nearest entry, clamped.
fn lut_get(v: f32) -> vec4<f32> {
    let x = min(max((v - P.lut.x) * P.lut.y + 0.5, 0.0), P.lut.w - 1.0);
    return lut[u32(x)];
}

// Vec3::normalize_or_zero.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let len = length(v);
    if len > 0.0 && len < 3.4e38 {
        return v * (1.0 / len);
    }
    return vec3<f32>(0.0);
}

// glint-lobe Lobe::eval for the closed forms.
fn lobe_eval(c_in: f32) -> f32 {
    let c = clamp(c_in, -1.0, 1.0);
    let form = u32(P.lobe.x);
    let n = P.lobe.y;
    var y = 0.0;
    if form == 0u {
        // max(c, 0)^n: exp2(n log2 c), 0^0 = 1 as Rust's powf.
        let x = max(c, 0.0);
        if x > 0.0 {
            y = pow(x, n);
        } else if n == 0.0 {
            y = 1.0;
        }
    } else if form == 1u {
        // K_v, G_v, minimax: max(0, 1 - a (1 - c))^(2^v): one FMA, v squarings.
        var b = 1.0 - P.lobe.z * (1.0 - c);
        if b <= 0.0 {
            return 0.0;
        }
        let v = u32(P.lobe.w);
        for (var i = 0u; i < v; i++) {
            b = b * b;
        }
        y = b;
    } else if form == 4u {
        // CosTable::code and value: the nearest code, rounded half away from zero.
        let x = c * P.table.x;
        let t = trunc(x);
        let r = x - t;
        let code = i32(t) + select(0, 1, r >= 0.5) - select(0, 1, r <= -0.5);
        let i = clamp(code - i32(P.table.y), 0, i32(P.table.z) - 1);
        return spec[i];
    } else if form == 2u {
        if c > 0.0 {
            y = c / (n * (1.0 - c) + c);
        }
    } else {
        y = exp(n * (c - 1.0));
    }
    return clamp(y, 0.0, 1.0);
}

// Shader::surface_at for world gradient `grad` seen along `view`: `lit` false where
// the gate leaves no surface; else the unit normal turned to face the eye, N·V, and
// the surface weight (the gate's ramp times the scene's surface weight).
struct Surface {
    lit: bool,
    n: vec3<f32>,
    n_dot_v: f32,
    w: f32,
}

fn surface_at(grad: vec3<f32>, view: vec3<f32>) -> Surface {
    var sf: Surface;
    let gm2 = dot(grad, grad);
    let g0 = P.gate.x;
    if P.gate.y == 0.0 || !(gm2 > g0 * g0 && gm2 < 3.4e38) {
        sf.lit = false;
        return sf;
    }
    let gm = sqrt(gm2);
    var n = grad * (-1.0 / gm);
    var w = 1.0;
    if g0 > 0.0 {
        w = min((gm - g0) / g0, 1.0);
    }
    var n_dot_v = dot(n, view);
    if n_dot_v < 0.0 {
        n = -n;
        n_dot_v = -n_dot_v;
    }
    sf.lit = true;
    sf.n = n;
    sf.n_dot_v = n_dot_v;
    sf.w = w * P.gate.y;
    return sf;
}

// Shader::light_sums at the surface `sf` seen along `view`: the diffuse and specular
// sums over the lights with N·L > 0, each light's intensity scaled by `t[i]` (its
// transmittance in `shadows`, 1 in `local`).
fn light_sums(sf: Surface, view: vec3<f32>, t: array<f32, 8>) -> vec2<f32> {
    var diffuse = 0.0;
    var specular = 0.0;
    let count = u32(P.gate.w);
    for (var i = 0u; i < count; i++) {
        let l = P.lights[i].xyz;
        let intensity = P.lights[i].w * t[i];
        let n_dot_l = dot(sf.n, l);
        if n_dot_l > 0.0 {
            var c: f32;
            if P.gate.z == 0.0 {
                c = 2.0 * n_dot_l * sf.n_dot_v - dot(l, view);
            } else {
                c = dot(sf.n, normalize_or_zero(l + view));
            }
            diffuse += intensity * n_dot_l;
            specular += intensity * lobe_eval(c);
        }
    }
    return vec2<f32>(diffuse, specular);
}

// Shader::shade = Scattering::local for a volume sample of colour `base` and world
// gradient `grad`, viewed along unit `view` (towards the eye).
fn shade(base: vec3<f32>, grad: vec3<f32>, view: vec3<f32>) -> vec3<f32> {
    let amb = P.material.x;
    let dif = P.material.y;
    let spc = P.material.z;
    if P.material.w == 0.0 {
        return base;
    }
    let flat = amb + dif;
    let sf = surface_at(grad, view);
    if !sf.lit {
        return base * flat;
    }
    let w = sf.w;
    var unshadowed: array<f32, 8>;
    for (var i = 0u; i < 8u; i++) {
        unshadowed[i] = 1.0;
    }
    let sums = light_sums(sf, view, unshadowed);
    // gated.
    let lit = amb + dif * sums.x;
    let spec = spc * sums.y;
    let shaded = base * lit + vec3<f32>(spec);
    let unshaded = base * flat;
    return unshaded + w * (shaded - unshaded);
}

// light.rs trilinear: the grid of `len` from `light[first]` (storage
// [q0][q2][q1]) at `q`, clamped to the grid.
fn grid_trilinear(first: u32, len: vec3<u32>, q: vec3<f32>) -> f32 {
    var i = vec3<u32>(0u);
    var f = vec3<f32>(0.0);
    for (var a = 0; a < 3; a++) {
        let top = f32(len[a] - 1u);
        let x = min(max(q[a], 0.0), top);
        let lo = min(u32(x), max(len[a], 2u) - 2u);
        i[a] = lo;
        if len[a] > 1u {
            f[a] = x - f32(lo);
        }
    }
    let s1 = len.y;
    let s0 = len.y * len.z;
    let o1 = select(0u, 1u, len.y > 1u);
    let o2 = select(0u, s1, len.z > 1u);
    let o0 = select(0u, s0, len.x > 1u);
    let b = first + i.x * s0 + i.z * s1 + i.y;
    let c00 = lerp1(light[b], light[b + o1], f.y);
    let c01 = lerp1(light[b + o2], light[b + o2 + o1], f.y);
    let c10 = lerp1(light[b + o0], light[b + o0 + o1], f.y);
    let c11 = lerp1(light[b + o0 + o2], light[b + o0 + o2 + o1], f.y);
    return lerp1(lerp1(c00, c01, f.z), lerp1(c10, c11, f.z), f.x);
}

fn lerp1(a: f32, b: f32, t: f32) -> f32 {
    return a + t * (b - a);
}

// The transmittance of each light to index-space point `p` and the ambient
// occlusion there (ShadowField::at).
struct Shadowing {
    t: array<f32, 8>,
    occlusion: f32,
}

fn shadowing(p: vec3<f32>) -> Shadowing {
    var s: Shadowing;
    let g = p * shadow[0].w;
    let count = u32(P.gate.w);
    for (var i = 0u; i < count; i++) {
        let h = 2u + 3u * i;
        let axes = vec3<u32>(shadow[h].xyz);
        let len = vec3<u32>(shadow[h + 1u].xyz);
        let gb = g + shadow[h + 2u].xyz;
        let q = vec3<f32>(gb[axes.x], gb[axes.y], gb[axes.z]);
        s.t[i] = grid_trilinear(u32(shadow[h].w), len, q);
    }
    s.occlusion = 1.0;
    if shadow[0].y != 0.0 {
        let d = vec3<u32>(shadow[1].xyz);
        s.occlusion = grid_trilinear(u32(shadow[1].w), d.zxy, g.zxy);
    }
    return s;
}

// transport.rs phase_hg.
fn phase_hg(g: f32, l_dot_v: f32) -> f32 {
    let g2 = g * g;
    let denom = 1.0 + g2 + 2.0 * g * l_dot_v;
    return (1.0 - g2) / (denom * sqrt(denom));
}

// Shader::shade_shadowed = Scattering::shadowed for a sample at index-space point
// `p`: each light scaled by its transmittance, the medium lit through the phase
// function (MEDIUM_IRRADIANCE 0.25), the ambient term by the occlusion.
fn shade_shadowed(base: vec3<f32>, grad: vec3<f32>, view: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    let amb = P.material.x;
    let dif = P.material.y;
    let spc = P.material.z;
    if P.material.w == 0.0 {
        return base;
    }
    let s = shadowing(p);
    let count = u32(P.gate.w);
    // Shader::phase_sum.
    var phase = 0.0;
    for (var i = 0u; i < count; i++) {
        let l = P.lights[i].xyz;
        phase += (P.lights[i].w * s.t[i]) * phase_hg(shadow[0].z, dot3(l, view));
    }
    let sf = surface_at(grad, view);
    if !sf.lit {
        return base * (amb * s.occlusion + dif * (0.25 * phase));
    }
    let w = sf.w;
    let sums = light_sums(sf, view, s.t);
    // transport.rs hybrid_terms.
    let lit = amb * s.occlusion + dif * (w * sums.x + (1.0 - w) * (0.25 * phase));
    let spec = w * (spc * sums.y);
    return base * lit + vec3<f32>(spec);
}

// The sample's lighting under the frame's model: local, or `shadows` when the
// frame has light volumes.
fn shade_at(base: vec3<f32>, grad: vec3<f32>, view: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    if shadow[0].x != 0.0 {
        return shade_shadowed(base, grad, view, p);
    }
    return shade(base, grad, view);
}

// Vec3::dot, in its order.
fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// cubic.rs weights: the B-spline's weights of the taps at -1, 0, 1, 2.
fn cubic_weights(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t * t * t;
    return vec4<f32>(
        s * s * s / 6.0,
        (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
        (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
        t3 / 6.0,
    );
}

// cubic.rs derivatives.
fn cubic_derivatives(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    return vec4<f32>(-0.5 * s * s, 1.5 * t * t - 2.0 * t, -1.5 * t * t + t + 0.5, 0.5 * t * t);
}

// cubic.rs dot: w0 x0 + w1 x1 + w2 x2 + w3 x3.
fn dot4(w: vec4<f32>, x: vec4<f32>) -> f32 {
    return w.x * x.x + w.y * x.y + w.z * x.z + w.w * x.w;
}

// A tap of the spline, clamped to the volume (Field::gathered).
fn tap(c: vec3<i32>) -> f32 {
    let hi = vec3<i32>(P.dims.xyz) - vec3<i32>(1);
    return v_at(clamp(c, vec3<i32>(0), hi));
}

// cubic.rs block: the spline's value (x) and, with `grad`, its index-space
// derivatives (yzw) from the 64 taps, separably: x, then y, then z.
fn cubic(l: Loc, grad: bool) -> vec4<f32> {
    let wx = cubic_weights(l.t.x);
    let wy = cubic_weights(l.t.y);
    let wz = cubic_weights(l.t.z);
    let dx = cubic_derivatives(l.t.x);
    let dy = cubic_derivatives(l.t.y);
    let dz = cubic_derivatives(l.t.z);
    let c0 = l.ijk - vec3<i32>(1);
    var slices = vec4<f32>(0.0);
    var gx_s = vec4<f32>(0.0);
    var gy_s = vec4<f32>(0.0);
    for (var c = 0; c < 4; c++) {
        var rows = vec4<f32>(0.0);
        var rows_dx = vec4<f32>(0.0);
        for (var b = 0; b < 4; b++) {
            let o = c0 + vec3<i32>(0, b, c);
            let x = vec4<f32>(
                tap(o),
                tap(o + vec3<i32>(1, 0, 0)),
                tap(o + vec3<i32>(2, 0, 0)),
                tap(o + vec3<i32>(3, 0, 0)),
            );
            rows[b] = dot4(wx, x);
            if grad {
                rows_dx[b] = dot4(dx, x);
            }
        }
        slices[c] = dot4(wy, rows);
        if grad {
            gx_s[c] = dot4(wy, rows_dx);
            gy_s[c] = dot4(dy, rows);
        }
    }
    let value = dot4(wz, slices);
    if !grad {
        return vec4<f32>(value, 0.0, 0.0, 0.0);
    }
    return vec4<f32>(value, dot4(wz, gx_s), dot4(wz, gy_s), dot4(dz, slices));
}

// Field::value_at: the field's filter.
fn sample_value(l: Loc) -> f32 {
    if TRICUBIC {
        return cubic(l, false).x;
    }
    return value_at(l);
}

// Field::gradient_at: the field's filter (cubic_gradient_at maps the spline's
// derivatives by the inverse transpose of the affine).
fn sample_gradient(l: Loc) -> vec3<f32> {
    if TRICUBIC {
        let g = cubic(l, true).yzw;
        return vec3<f32>(
            P.gm0.x * g.x + P.gm0.y * g.y + P.gm0.z * g.z,
            P.gm1.x * g.x + P.gm1.y * g.y + P.gm1.z * g.z,
            P.gm2.x * g.x + P.gm2.y * g.y + P.gm2.z * g.z,
        );
    }
    return gradient_at(l);
}

// Lut::position: the table coordinate of v.
fn lut_position(v: f32) -> f32 {
    return min(max((v - P.lut.x) * P.lut.y + 0.5, 0.0), P.lut.w - 1.0);
}

// PreIntegrated::opacity_of: 1 - exp(-step m), interpolated from the table.
fn opacity_of(m: f32) -> f32 {
    let x = clamp(m, 0.0, P.cut.z) * P.cut.w;
    let i = min(u32(x), OPACITY_TABLE - 2u);
    let t = x - f32(i);
    let a = pre[PRE_AUX + i].y;
    let b = pre[PRE_AUX + i + 1u].y;
    return a + t * (b - a);
}

// PreIntegrated::segment between table coordinates f and b: colour and opacity,
// or w = -1 when no value between them has opacity. The integrals' difference is
// taken in pairs of f32 (high, low), which keep what the CPU's f64 keeps of it.
fn segment(f: f32, b: f32) -> vec4<f32> {
    let bf = u32(f);
    let bb = u32(b);
    let lo = min(bf, bb);
    let hi = max(bf, bb);
    if pre[PRE_AUX + hi + 1u].x == pre[PRE_AUX + lo].x {
        return vec4<f32>(-1.0);
    }
    if bf == bb {
        return pre[PRE_POINT + bb];
    }
    let ff = f - f32(bf);
    let fb = b - f32(bb);
    let d = (pre[PRE_HI + bb] - pre[PRE_HI + bf])
        + ((pre[PRE_LO + bb] - pre[PRE_LO + bf])
        + (fb * pre[PRE_SLOPE + bb] - ff * pre[PRE_SLOPE + bf]));
    if d.w == 0.0 {
        return vec4<f32>(-1.0);
    }
    let inv = 1.0 / d.w;
    return vec4<f32>(d.xyz * inv, opacity_of(d.w / (b - f)));
}

// IndexClip::interval: the part of (t0, t1) where the ray is kept (x > y: none).
fn clip_interval(o: vec3<f32>, d: vec3<f32>, t0: f32, t1: f32) -> vec2<f32> {
    var lo = t0;
    var hi = t1;
    let count = u32(P.extra.w);
    for (var i = 0u; i < count; i++) {
        let q = planes[2u * i];
        let f0 = dot3(q.xyz, o) + q.w;
        let slope = dot3(q.xyz, d);
        if slope > 0.0 {
            lo = max(lo, -f0 / slope);
        } else if slope < 0.0 {
            hi = min(hi, -f0 / slope);
        } else if f0 < 0.0 {
            return vec2<f32>(3.4e38, -3.4e38);
        }
    }
    return vec2<f32>(lo, hi);
}

// IndexClip::cut_gradient: on a cut face, a weak gradient blended towards the
// nearest plane's normal.
fn cut_gradient(p: vec3<f32>, g: vec3<f32>) -> vec3<f32> {
    let count = u32(P.extra.w);
    var found = false;
    var best = 0.0;
    var n = vec3<f32>(0.0);
    for (var i = 0u; i < count; i++) {
        let q = planes[2u * i];
        let s = dot3(q.xyz, p) + q.w;
        if s < P.cut.x && (!found || s < best) {
            found = true;
            best = s;
            n = planes[2u * i + 1u].xyz;
        }
    }
    if !found {
        return g;
    }
    let m = sqrt(dot3(g, g));
    let strong = P.cut.y;
    if m >= strong {
        return g;
    }
    let w = m / strong;
    return n * (strong * (1.0 - w)) + g * w;
}

// ColourVolume::at: the cell's corners' linear colours weighted trilinearly, in
// its order (corner c: x = bit 0, y = bit 1, z = bit 2; weights of 0 skipped).
fn colour_at(l: Loc) -> vec3<f32> {
    var out = vec3<f32>(0.0);
    for (var c = 0u; c < 8u; c++) {
        let o = vec3<u32>(c & 1u, (c >> 1u) & 1u, (c >> 2u) & 1u);
        let w = select(1.0 - l.t.x, l.t.x, o.x == 1u)
            * select(1.0 - l.t.y, l.t.y, o.y == 1u)
            * select(1.0 - l.t.z, l.t.z, o.z == 1u);
        if w == 0.0 {
            continue;
        }
        let v = textureLoad(colours, l.ijk + vec3<i32>(o), 0);
        out += w * vec3<f32>(srgb[v.x], srgb[v.y], srgb[v.z]);
    }
    return out;
}

// Caster::add's and Caster::iso's base colour: the colour volume's, or the table's.
fn base_colour(e: vec4<f32>, l: Loc) -> vec3<f32> {
    if P.table.w != 0.0 {
        return colour_at(l);
    }
    return e.xyz;
}

// Caster::add's gradient: the field's, cut by the clip where it has planes.
fn shading_gradient(l: Loc) -> vec3<f32> {
    let g = sample_gradient(l);
    if P.extra.w == 0.0 {
        return g;
    }
    return cut_gradient(vec3<f32>(l.ijk) + l.t, g);
}

// Caster::cast's interval; the jitter of caster.rs.
fn jitter(x: f32, y: f32) -> f32 {
    return fract(52.982918 * fract(0.06711056 * x + 0.00583715 * y));
}

// A ray in index space and its samples (caster.rs Ray).
struct Ray {
    o: vec3<f32>,
    d: vec3<f32>,
    // The unit world direction.
    dir: vec3<f32>,
    k0: i32,
    k1: i32,
    j: f32,
    // Where the ray enters the kept part of the clip box (mm), its first sample.
    t_entry: f32,
    k_entry: i32,
    // Whether it takes a sample.
    hit: bool,
}

fn at(r: Ray, k: i32) -> vec3<f32> {
    return r.o + r.d * ((f32(k) + r.j) * P.clip_lo.w);
}

// IndexRays::ray, the clip's interval (cut_bounds) and Caster::ray.
fn make_ray(x: f32, y: f32) -> Ray {
    var r: Ray;
    r.hit = false;
    let u = P.plane.x + x * P.plane.y;
    let v = P.plane.z + y * P.plane.w;
    if P.origin.w != 0.0 {
        let wv = P.f_world.xyz + P.r_world.xyz * u + P.u_world.xyz * v;
        let inv = 1.0 / length(wv);
        r.o = P.origin.xyz;
        r.d = (P.f_index.xyz + P.r_index.xyz * u + P.u_index.xyz * v) * inv;
        r.dir = wv * inv;
    } else {
        r.o = P.origin.xyz + P.r_index.xyz * u + P.u_index.xyz * v;
        r.d = P.f_index.xyz;
        r.dir = P.f_world.xyz;
    }
    var start = 0.0;
    var end = 3.4e38;
    if P.extra.w != 0.0 {
        let kept = clip_interval(r.o, r.d, start, end);
        if kept.x > kept.y {
            return r;
        }
        start = kept.x;
        end = kept.y;
    }
    // clip_ray against the clip box from (0, inf).
    var t0 = 0.0;
    var t1 = 3.4e38;
    for (var a = 0; a < 3; a++) {
        let oa = r.o[a];
        let da = r.d[a];
        if abs(da) < 1e-12 {
            if oa < P.clip_lo[a] || oa > P.clip_hi[a] {
                return r;
            }
            continue;
        }
        let inv = 1.0 / da;
        let ta = (P.clip_lo[a] - oa) * inv;
        let tb = (P.clip_hi[a] - oa) * inv;
        t0 = max(t0, min(ta, tb));
        t1 = min(t1, max(ta, tb));
    }
    if t0 > t1 {
        return r;
    }
    t0 = max(t0, start);
    t1 = min(t1, end);
    if t0 > t1 {
        return r;
    }
    let dt = P.clip_lo.w;
    r.j = jitter(x, y);
    r.k0 = i32(ceil(t0 / dt - r.j));
    r.k1 = i32(floor(t1 / dt - r.j));
    r.t_entry = t0;
    r.k_entry = r.k0;
    r.hit = r.k1 >= r.k0;
    return r;
}

fn cell_dims() -> vec3<u32> {
    return vec3<u32>(P.size.z, P.size.w, P.dims.w);
}

// The distance map's entry of macro cell c.
fn distance_at(c: vec3<u32>) -> u32 {
    let cd = cell_dims();
    let i = c.x + cd.x * (c.y + cd.y * c.z);
    return (distance[i >> 2u] >> (8u * (i & 3u))) & 0xffu;
}

// Caster::cell_of: the macro cell holding index-space point p.
fn cell_of(p: vec3<f32>) -> vec3<u32> {
    return min(vec3<u32>(max(p, vec3<f32>(0.0))) / MACRO_CELL, cell_dims() - vec3<u32>(1u));
}

// caster.rs ceil_i64.
fn ceil_i(x: f32) -> i32 {
    let k = i32(x);
    return k + select(0, 1, f32(k) < x);
}

// Caster::leap: past the cube of empty cells around cell c (distance dist), to the
// first sample beyond it (a sixty-fourth of a step short), or k + 1.
fn leap(r: Ray, c: vec3<u32>, dist: u32, k: i32) -> i32 {
    let reach = dist - 1u;
    var q = 3.4e38;
    for (var a = 0; a < 3; a++) {
        let da = r.d[a];
        if abs(da) < 1e-12 {
            continue;
        }
        var face: u32;
        if da > 0.0 {
            face = (c[a] + reach + 1u) * MACRO_CELL;
        } else {
            face = (c[a] - min(c[a], reach)) * MACRO_CELL;
        }
        let inv_dk = (1.0 / da) / P.clip_lo.w;
        q = min(q, (f32(face) - r.o[a]) * inv_dk);
    }
    return max(ceil_i(q - r.j - 1.0 / 64.0), k + 1);
}

// Caster::composite with point sampling or pre-integrated segments, and
// Caster::add: premultiplied colour and opacity. Samples in empty macro cells are
// leapt over as the CPU leaps (they show nothing; a pre-integrated segment that
// ends in one is still taken when its front sample was read).
fn composite(r: Ray) -> vec4<f32> {
    let view = -r.dir;
    var color = vec3<f32>(0.0);
    var alpha = 0.0;
    let preintegrated = P.extra.y != 0.0;
    // The last sample read and its table coordinate (pre-integrated).
    var prev_k = r.k0 - 2;
    var prev_u = 0.0;
    var k = r.k0;
    loop {
        if k > r.k1 {
            break;
        }
        let l = locate(at(r, k));
        let c = vec3<u32>(l.ijk) / MACRO_CELL;
        let dist = distance_at(c);
        let empty = dist != 0u;
        var e = vec4<f32>(0.0);
        var take = false;
        if preintegrated {
            if !empty || prev_k == k - 1 {
                // Caster::before when the sample before was not read.
                var front = prev_u;
                if prev_k != k - 1 {
                    front = lut_position(sample_value(locate(at(r, k - 1))));
                }
                let back = lut_position(sample_value(l));
                prev_k = k;
                prev_u = back;
                e = segment(front, back);
                take = e.w >= 0.0;
            }
        } else if !empty {
            e = lut_get(sample_value(l));
            take = e.w > 0.0;
        }
        if take {
            let p = vec3<f32>(l.ijk) + l.t;
            let rgb = shade_at(base_colour(e, l), shading_gradient(l), view, p);
            let w = (1.0 - alpha) * e.w;
            color += w * rgb;
            alpha += w;
            if alpha >= P.clip_hi.w {
                break;
            }
        }
        if empty {
            k = leap(r, c, dist, k);
        } else {
            k += 1;
        }
    }
    return vec4<f32>(color, alpha);
}

// Caster::mip.
fn mip(r: Ray) -> vec4<f32> {
    var best = -3.4e38;
    var any = false;
    for (var k = r.k0; k <= r.k1; k++) {
        let val = sample_value(locate(at(r, k)));
        if !any || val > best {
            best = val;
            any = true;
        }
    }
    if !any {
        return vec4<f32>(0.0);
    }
    let e = lut_get(best);
    return vec4<f32>(e.xyz * e.w, e.w);
}

fn value_along(r: Ray, t: f32) -> f32 {
    return sample_value(locate(r.o + r.d * t));
}

// Caster::iso and iso_hit: the first sample at or above the threshold, refined by
// bisection and a linear step towards the sample before, shaded there; empty macro
// cells (none reaches the threshold) leapt over.
fn iso(r: Ray) -> vec4<f32> {
    let threshold = P.extra.x;
    let dt = P.clip_lo.w;
    var k = r.k0;
    loop {
        if k > r.k1 {
            break;
        }
        let t = (f32(k) + r.j) * dt;
        let c = cell_of(r.o + r.d * t);
        let dist = distance_at(c);
        if dist != 0u {
            k = leap(r, c, dist, k);
            continue;
        }
        if value_along(r, t) < threshold {
            k += 1;
            continue;
        }
        var lo = max(t - dt, r.t_entry);
        var hi = t;
        if k > r.k_entry && value_along(r, lo) < threshold {
            for (var i = 0u; i < ISO_REFINE_STEPS; i++) {
                let mid = 0.5 * (lo + hi);
                if value_along(r, mid) >= threshold {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let vl = value_along(r, lo);
            let vh = value_along(r, hi);
            if vh > vl {
                hi = lo + (hi - lo) * clamp((threshold - vl) / (vh - vl), 0.0, 1.0);
            }
        }
        let p = r.o + r.d * hi;
        let e = lut_get(threshold);
        let l = locate(p);
        var g = sample_gradient(l);
        if P.extra.w != 0.0 {
            g = cut_gradient(p, g);
        }
        return vec4<f32>(shade_at(base_colour(e, l), g, -r.dir, p), 1.0);
    }
    return vec4<f32>(0.0);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let width = P.size.x;
    let height = P.size.y;
    if gid.x >= width || gid.y >= height {
        return;
    }
    let slot = gid.y * width + gid.x;
    let bg = P.bg.xyz;
    let r = make_ray(f32(gid.x), f32(gid.y));
    var c = vec4<f32>(0.0);
    if r.hit {
        if P.bg.w == 0.0 {
            c = composite(r);
        } else if P.bg.w == 1.0 {
            c = mip(r);
        } else {
            c = iso(r);
        }
    }
    out[slot] = vec4<f32>(c.xyz + (1.0 - c.w) * bg, c.w);
}

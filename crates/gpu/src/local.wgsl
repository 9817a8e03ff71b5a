// The `local` model's ray caster on the GPU: one invocation per pixel, mirroring the
// CPU's reference loop (glint-volume raycast/caster.rs: Caster::ray, composite, add,
// mip) and the core's lighting (glint-core lighting: Shader::for_ray, surface_at,
// light_sums, gated; glint-lobe Lobe::eval) term by term. Values and gradients are
// the field's bricks' own (R32Float and Rgba16Sint texels, read with textureLoad):
// the 8 neighbours are interpolated here in f32, since texture units (and lavapipe)
// quantise trilinear weights to 8 bits.

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
    // form (0 exact, 1 power, 2 Schlick, 3 Gauss), n, a, v.
    lobe: vec4<f32>,
    // width, height, then the field's dims (x, y: nx, ny; nz in dims).
    size: vec4<u32>,
    dims: vec4<u32>,
    // Per light: unit world direction towards it, intensity.
    lights: array<vec4<f32>, 8>,
}

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var values: texture_3d<f32>;
@group(0) @binding(2) var gradients: texture_3d<i32>;
@group(0) @binding(3) var<storage, read> lut: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> out: array<vec4<f32>>;

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
    return textureLoad(values, c, 0).x;
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
    return vec3<f32>(textureLoad(gradients, c, 0).xyz);
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
    } else if form == 2u {
        if c > 0.0 {
            y = c / (n * (1.0 - c) + c);
        }
    } else {
        y = exp(n * (c - 1.0));
    }
    return clamp(y, 0.0, 1.0);
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
    // Shader::surface_at.
    let gm2 = dot(grad, grad);
    let g0 = P.gate.x;
    if P.gate.y == 0.0 || !(gm2 > g0 * g0 && gm2 < 3.4e38) {
        return base * flat;
    }
    let gm = sqrt(gm2);
    var n = grad * (-1.0 / gm);
    var w = 1.0;
    if g0 > 0.0 {
        w = min((gm - g0) / g0, 1.0);
    }
    w = w * P.gate.y;
    // light_sums: facing, then each light with N·L > 0.
    var n_dot_v = dot(n, view);
    if n_dot_v < 0.0 {
        n = -n;
        n_dot_v = -n_dot_v;
    }
    var diffuse = 0.0;
    var specular = 0.0;
    let count = u32(P.gate.w);
    for (var i = 0u; i < count; i++) {
        let l = P.lights[i].xyz;
        let intensity = P.lights[i].w;
        let n_dot_l = dot(n, l);
        if n_dot_l > 0.0 {
            var c: f32;
            if P.gate.z == 0.0 {
                c = 2.0 * n_dot_l * n_dot_v - dot(l, view);
            } else {
                c = dot(n, normalize_or_zero(l + view));
            }
            diffuse += intensity * n_dot_l;
            specular += intensity * lobe_eval(c);
        }
    }
    // gated.
    let lit = amb + dif * diffuse;
    let spec = spc * specular;
    let shaded = base * lit + vec3<f32>(spec);
    let unshaded = base * flat;
    return unshaded + w * (shaded - unshaded);
}

// Caster::cast's interval; the jitter of caster.rs.
fn jitter(x: f32, y: f32) -> f32 {
    return fract(52.982918 * fract(0.06711056 * x + 0.00583715 * y));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let width = P.size.x;
    let height = P.size.y;
    if gid.x >= width || gid.y >= height {
        return;
    }
    let x = f32(gid.x);
    let y = f32(gid.y);
    let slot = gid.y * width + gid.x;
    let bg = P.bg.xyz;
    out[slot] = vec4<f32>(bg, 0.0);
    // IndexRays::ray.
    let u = P.plane.x + x * P.plane.y;
    let v = P.plane.z + y * P.plane.w;
    var o: vec3<f32>;
    var d: vec3<f32>;
    var dir: vec3<f32>;
    if P.origin.w != 0.0 {
        let wv = P.f_world.xyz + P.r_world.xyz * u + P.u_world.xyz * v;
        let inv = 1.0 / length(wv);
        o = P.origin.xyz;
        d = (P.f_index.xyz + P.r_index.xyz * u + P.u_index.xyz * v) * inv;
        dir = wv * inv;
    } else {
        o = P.origin.xyz + P.r_index.xyz * u + P.u_index.xyz * v;
        d = P.f_index.xyz;
        dir = P.f_world.xyz;
    }
    // clip_ray against the clip box from (0, inf).
    var t0 = 0.0;
    var t1 = 3.4e38;
    for (var a = 0; a < 3; a++) {
        let oa = o[a];
        let da = d[a];
        if abs(da) < 1e-12 {
            if oa < P.clip_lo[a] || oa > P.clip_hi[a] {
                return;
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
        return;
    }
    let dt = P.clip_lo.w;
    let j = jitter(x, y);
    let k0 = i32(ceil(t0 / dt - j));
    let k1 = i32(floor(t1 / dt - j));
    if k1 < k0 {
        return;
    }
    let view = -dir;
    var color = vec3<f32>(0.0);
    var alpha = 0.0;
    if P.bg.w == 0.0 {
        // Caster::composite with point sampling, and Caster::add.
        for (var k = k0; k <= k1; k++) {
            let p = o + d * ((f32(k) + j) * dt);
            let l = locate(p);
            let e = lut_get(value_at(l));
            if e.w > 0.0 {
                let rgb = shade(e.xyz, gradient_at(l), view);
                let w = (1.0 - alpha) * e.w;
                color += w * rgb;
                alpha += w;
                if alpha >= P.clip_hi.w {
                    break;
                }
            }
        }
    } else {
        // Caster::mip.
        var best = -3.4e38;
        var any = false;
        for (var k = k0; k <= k1; k++) {
            let p = o + d * ((f32(k) + j) * dt);
            let val = value_at(locate(p));
            if !any || val > best {
                best = val;
                any = true;
            }
        }
        if any {
            let e = lut_get(best);
            color = e.xyz * e.w;
            alpha = e.w;
        }
    }
    out[slot] = vec4<f32>(color + (1.0 - alpha) * bg, alpha);
}

// The `shadows` model's light volumes swept on the GPU: one dispatch per grid plane
// of one light, each invocation one grid point of the plane, mirroring
// glint-volume transport/shadows.rs (LightGrid::new and bilinear) term by term:
// a point's transmittance is the one of the point a plane nearer the light
// (bilinear on that plane; outside it transmittance 1, extinction 0) times the
// extinction of the segment between them (trapezoid of the two extinctions).

struct Sweep {
    // The sweep axis, the two others, the light's first index in `t`.
    axes: vec4<u32>,
    // The grid's extents along `axes`; w: this plane.
    len: vec4<u32>,
    // s (mm between planes), the upstream shift along axes[1] and axes[2]; w: 1
    // when this plane has an upstream plane (0: the plane nearest the light).
    geo: vec4<f32>,
    // The density grid's dims (i fastest); w: the upstream plane.
    dims: vec4<u32>,
}

@group(0) @binding(0) var<uniform> S: Sweep;
@group(0) @binding(1) var<storage, read> sigma: array<f32>;
@group(0) @binding(2) var<storage, read_write> t: array<f32>;

// DensityGrid::at of the grid point at (m, u, v) along the sweep's axes.
fn sigma_at(m: u32, u: u32, v: u32) -> f32 {
    var p = vec3<u32>(0u);
    p[S.axes.x] = m;
    p[S.axes.y] = u;
    p[S.axes.z] = v;
    return sigma[p.x + S.dims.x * (p.y + S.dims.y * p.z)];
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nu = S.len.y;
    let nv = S.len.z;
    let i = gid.x;
    if i >= nu * nv {
        return;
    }
    let u = i % nu;
    let v = i / nu;
    let m = S.len.w;
    let plane = nu * nv;
    let out = S.axes.w + m * plane + v * nu + u;
    if S.geo.w == 0.0 {
        t[out] = 1.0;
        return;
    }
    let up = S.dims.w;
    let upstream = S.axes.w + up * plane;
    // bilinear.
    let x = f32(u) + S.geo.y;
    let y = f32(v) + S.geo.z;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let xi = i32(x0);
    let yi = i32(y0);
    var tr = 0.0;
    var sg = 0.0;
    for (var dy = 0; dy < 2; dy++) {
        let wy = select(fy, 1.0 - fy, dy == 0);
        for (var dx = 0; dx < 2; dx++) {
            let wx = select(fx, 1.0 - fx, dx == 0);
            let uu = xi + dx;
            let vv = yi + dy;
            let w = wx * wy;
            if uu < 0 || vv < 0 || uu >= i32(nu) || vv >= i32(nv) {
                tr += w;
            } else {
                tr += w * t[upstream + u32(uu) + nu * u32(vv)];
                sg += w * sigma_at(up, u32(uu), u32(vv));
            }
        }
    }
    let tau = S.geo.x * 0.5 * (sigma_at(m, u, v) + sg);
    t[out] = tr * exp(-tau);
}

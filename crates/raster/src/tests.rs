//! The tiled, binned, SIMD rasterizer against a per-sample reference: every
//! triangle tested at every sample, the nearest kept, each sample lit alone by
//! [`Shader::shade_normal`].

use glint_lobe::{Geometry, KernelPath, LobeKind};
use std::sync::atomic::{AtomicU64, Ordering};

use super::frame::{Edges, Frame};
use super::*;
use glint_core::camera::{Projection, View};
use glint_core::Light;
use glint_core::Material;

/// A latitude-longitude sphere (degenerate triangles at the poles), normals from
/// the triangles.
fn sphere(center: [f32; 3], r: f32, nlat: u32, nlon: u32) -> Mesh {
    let mut mesh = Mesh::default();
    for i in 0..=nlat {
        let theta = std::f32::consts::PI * i as f32 / nlat as f32;
        for j in 0..nlon {
            let phi = 2.0 * std::f32::consts::PI * j as f32 / nlon as f32;
            let n = [
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ];
            mesh.positions.push([0, 1, 2].map(|a| center[a] + r * n[a]));
        }
    }
    for i in 0..nlat {
        for j in 0..nlon {
            let (a, b) = (i * nlon + j, i * nlon + (j + 1) % nlon);
            mesh.triangles.push([a, a + nlon, b]);
            mesh.triangles.push([b, a + nlon, b + nlon]);
        }
    }
    mesh
}

/// A square in the plane z = `z`, crossing the sphere.
fn square(half: f32, z: f32) -> Mesh {
    Mesh {
        positions: vec![
            [-half, -half, z],
            [half, -half, z],
            [half, half, z],
            [-half, half, z],
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        normals: None,
        scalars: None,
    }
}

/// Per sample of `frame`'s grid (row by row): the key and index of the nearest
/// triangle (the first on a tie) among all that cover it, or among the triangles the
/// frame does not cull when `cull`.
fn winners(s: &Surfaces, frame: &Frame, cull: bool) -> Vec<Option<(f32, usize)>> {
    let mut best = vec![None; frame.sw * frame.sh];
    for (id, tri) in s.triangles.iter().enumerate() {
        let sign = if cull {
            frame.cull_of(s, id as u32)
        } else {
            0.0
        };
        let Some([x0, y0, x1, y1]) = frame.front_bbox(*tri, sign) else {
            continue;
        };
        let [a, b, c] = tri.map(|i| frame.verts[i as usize]);
        let e = Edges::new(a, b, c);
        for sy in usize::from(y0)..=usize::from(y1) {
            for sx in usize::from(x0)..=usize::from(x1) {
                let (w0, w1, w2) = e.at(sx as f32, sy as f32);
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let key = (w0 * a.key + w1 * b.key + w2 * c.key) * e.inv_area();
                let best = &mut best[sy * frame.sw + sx];
                if best.is_none_or(|(k, _)| key > k) {
                    *best = Some((key, id));
                }
            }
        }
    }
    best
}

/// The reference render: per sample, the nearest triangle ([`winners`]), its normal
/// and colour, lit by `shade_normal`; the box filter as [`Surfaces::render`]
/// documents it.
fn reference(
    s: &Surfaces,
    camera: &Camera,
    shader: &Shader,
    settings: &SurfaceSettings,
    cull: bool,
) -> Image {
    let shader = shader.placed(camera);
    let frame = Frame::new(s, camera, settings);
    let n = settings.ssaa as usize;
    let (w, h) = (settings.width as usize, settings.height as usize);
    let mut sum = vec![[0.0f32; 3]; w * h];
    let mut covered = vec![0u32; w * h];
    let winners = winners(s, &frame, cull);
    for sy in 0..h * n {
        for sx in 0..w * n {
            let (x, y) = (sx as f32, sy as f32);
            let best = winners[sy * frame.sw + sx];
            let Some((_, id)) = best else { continue };
            let idx = s.triangles[id].map(|i| i as usize);
            let [a, b, c] = idx.map(|i| frame.verts[i]);
            let (w0, w1, w2) = Edges::new(a, b, c).at(x, y);
            // Perspective-correct weights; their common factor 1 / (p0 + p1 + p2)
            // drops out when the normal is normalised.
            let (p0, p1, p2) = (w0 * a.w, w1 * b.w, w2 * c.w);
            let [n0, n1, n2] = idx.map(|i| s.normals[i]);
            let mut normal = (n0 * p0 + n1 * p1 + n2 * p2).normalize_or_zero();
            if normal == Vec3::ZERO {
                let [pa, pb, pc] = idx.map(|i| s.positions[i]);
                normal = (pb - pa).cross(pc - pa).normalize_or_zero();
            }
            let mesh = s.mesh_of(id as u32);
            let base = *settings.mesh_colors.get(mesh).unwrap_or(&settings.color);
            let lit = shader.shade_normal(base, normal, frame.view(x, y));
            let p = (sy / n) * w + sx / n;
            for i in 0..3 {
                sum[p][i] += lit[i];
            }
            covered[p] += 1;
        }
    }
    let per_pixel = (n * n) as f32;
    let bg = settings.background;
    Image {
        width: settings.width,
        height: settings.height,
        rgb: sum
            .iter()
            .zip(&covered)
            .map(|(c, &k)| [0, 1, 2].map(|i| (c[i] + (per_pixel - k as f32) * bg[i]) / per_pixel))
            .collect(),
        alpha: covered.iter().map(|&k| k as f32 / per_pixel).collect(),
        stats: RenderStats {
            shaded: covered.iter().map(|&k| u64::from(k)).sum(),
            ..RenderStats::default()
        },
    }
}

/// Tiles rasterised by the AVX2 loop and by the scalar one, in this test process
/// (counted in `Ctx::raster`): evidence that a path ran, not a flag saying it should.
pub(super) static AVX2_TILES: AtomicU64 = AtomicU64::new(0);
/// See [`AVX2_TILES`].
pub(super) static SCALAR_TILES: AtomicU64 = AtomicU64::new(0);

/// The loops to test: scalar, and AVX2 where the CPU has it (recorded for the run's
/// summary of optional paths, glint_testkit).
fn paths() -> Vec<bool> {
    #[cfg(target_arch = "x86_64")]
    if avx2::supported() {
        glint_testkit::ran("raster avx2");
        return vec![false, true];
    }
    glint_testkit::skipped("raster avx2", "this CPU lacks it");
    vec![false]
}

/// AVX2 support by /proc/cpuinfo agrees with the detection, so a detection bug cannot
/// make `paths()` leave out a loop the CPU has.
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
#[test]
fn avx2_detection_agrees_with_proc_cpuinfo() {
    let Ok(text) = std::fs::read_to_string("/proc/cpuinfo") else {
        glint_testkit::missing("/proc/cpuinfo");
        return;
    };
    let flags = text.lines().find(|l| l.starts_with("flags")).unwrap();
    let has = flags.split_whitespace().any(|f| f == "avx2");
    assert_eq!(avx2::supported(), has, "{flags}");
}

/// Each loop the CPU has really runs when asked: the tile counters move. And the
/// `GLINT_SIMD` cap (glint_lobe::KernelPath::cap) turns the AVX2 loops off on any
/// machine.
#[test]
fn each_loop_runs_when_asked_and_the_cap_forces_scalar() {
    let ball = sphere([0.0; 3], 10.0, 16, 32);
    let s = Surfaces::new([&ball]).unwrap();
    let settings = SurfaceSettings {
        width: 40,
        height: 40,
        ssaa: 1,
        ..Default::default()
    };
    let shader = Shader::new(
        LobeKind::EnergyFit,
        40.0,
        4,
        Geometry::Phong,
        Material::default(),
        vec![Light::HEADLIGHT],
        0.0,
    )
    .unwrap();
    let camera = s.camera(&settings).unwrap();
    for avx2 in paths() {
        let counter = if avx2 { &AVX2_TILES } else { &SCALAR_TILES };
        let before = counter.load(Ordering::Relaxed);
        s.render_with(&camera, &shader, &settings, None, avx2, false)
            .unwrap();
        assert!(
            counter.load(Ordering::Relaxed) > before,
            "avx2 {avx2} did not run"
        );
    }
    assert!(
        !simd_within(KernelPath::Scalar),
        "the scalar cap leaves AVX2 on"
    );
    #[cfg(target_arch = "x86_64")]
    {
        assert_eq!(simd_within(KernelPath::Avx2), avx2::supported());
        assert_eq!(simd_within(KernelPath::Avx512), avx2::supported());
    }
    assert_eq!(simd(), simd_within(KernelPath::cap()));
}

#[test]
fn tiled_render_is_the_per_sample_reference_bit_for_bit() {
    // Two meshes crossing each other (the square cuts the sphere), sizes that are not
    // multiples of the tile, both projections, both geometries, 1 and 2 samples a side.
    let (ball, plane) = (sphere([0.0; 3], 10.0, 24, 48), square(12.0, 2.0));
    let s = Surfaces::new([&ball, &plane]).unwrap();
    let lights = vec![
        Light::HEADLIGHT,
        Light {
            azimuth: 50.0,
            elevation: -20.0,
            intensity: 0.6,
        },
    ];
    let cases = [
        (Projection::Perspective, Geometry::Phong, 1, 75, 41),
        (Projection::Orthographic, Geometry::Blinn, 2, 37, 66),
        (Projection::Perspective, Geometry::Blinn, 2, 70, 33),
    ];
    for (projection, geometry, ssaa, width, height) in cases {
        let settings = SurfaceSettings {
            width,
            height,
            ssaa,
            camera: CameraSpec {
                view: View::Left,
                azimuth: 25.0,
                elevation: 30.0,
                zoom: 1.8,
                projection,
                ..Default::default()
            },
            background: [0.2, 0.1, 0.05],
            mesh_colors: vec![[0.9, 0.5, 0.3]],
            ..Default::default()
        };
        let shader = Shader::new(
            LobeKind::EnergyFit,
            30.0,
            4,
            geometry,
            Material::default(),
            lights.clone(),
            0.0,
        )
        .unwrap();
        let camera = s.camera(&settings).unwrap();
        let want = reference(&s, &camera, &shader, &settings, true);
        assert!(
            want.stats.shaded > 500,
            "the scene covers the image: {}",
            want.stats.shaded
        );
        for avx2 in paths() {
            // The distances asked for or not, the image is the same.
            let (got, far) = s
                .render_with(&camera, &shader, &settings, None, avx2, !avx2)
                .unwrap();
            assert_eq!(far.is_some(), !avx2);
            let case = format!("{projection:?} {geometry} ssaa {ssaa} avx2 {avx2}");
            assert_eq!(got.stats.shaded, want.stats.shaded, "{case}");
            assert_eq!(got.alpha, want.alpha, "{case}");
            assert_eq!(got.rgb, want.rgb, "{case}");
        }
    }
}

#[test]
fn exact_lobe_differs_from_the_reference_only_by_the_vectorised_pow() {
    // The batch evaluates the lobe with glint-lobe's eval_slice: cos^n within 2 ulp of
    // libm's powf, which the reference calls per sample.
    let ball = sphere([1.0, 2.0, 3.0], 10.0, 32, 64);
    let s = Surfaces::new([&ball]).unwrap();
    let settings = SurfaceSettings {
        width: 64,
        height: 48,
        ssaa: 1,
        ..Default::default()
    };
    let shader = Shader::new(
        LobeKind::Exact,
        40.0,
        4,
        Geometry::Phong,
        Material::default(),
        vec![Light::HEADLIGHT],
        0.0,
    )
    .unwrap();
    let camera = s.camera(&settings).unwrap();
    let want = reference(&s, &camera, &shader, &settings, true);
    for avx2 in paths() {
        let (got, _) = s
            .render_with(&camera, &shader, &settings, None, avx2, false)
            .unwrap();
        assert_eq!(got.alpha, want.alpha);
        let worst = got
            .rgb
            .iter()
            .flatten()
            .zip(want.rgb.iter().flatten())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-5, "avx2 {avx2}: {worst}");
    }
}

/// A closed latitude-longitude sphere (one vertex at each pole, so every edge is in
/// exactly two triangles), wound counter-clockwise seen from outside, or from inside
/// when `inward`.
fn closed_sphere(center: [f32; 3], r: f32, nlat: u32, nlon: u32, inward: bool) -> Mesh {
    let mut mesh = Mesh::default();
    let point = |theta: f32, phi: f32| {
        let n = [
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        ];
        [0, 1, 2].map(|a| center[a] + r * n[a])
    };
    let pi = std::f32::consts::PI;
    mesh.positions.push(point(0.0, 0.0));
    for i in 1..nlat {
        for j in 0..nlon {
            let (theta, phi) = (
                pi * i as f32 / nlat as f32,
                2.0 * pi * j as f32 / nlon as f32,
            );
            mesh.positions.push(point(theta, phi));
        }
    }
    mesh.positions.push(point(pi, 0.0));
    let south = mesh.positions.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * nlon + j % nlon;
    for j in 0..nlon {
        mesh.triangles.push([0, ring(1, j), ring(1, j + 1)]);
        mesh.triangles
            .push([south, ring(nlat - 1, j + 1), ring(nlat - 1, j)]);
    }
    for i in 1..nlat - 1 {
        for j in 0..nlon {
            let (a, b) = (ring(i, j), ring(i, j + 1));
            let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
            mesh.triangles.push([a, c, d]);
            mesh.triangles.push([a, d, b]);
        }
    }
    if inward {
        mesh.triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    mesh
}

fn v3(p: [f32; 3]) -> Vec3 {
    Vec3::new(p[0], p[1], p[2])
}

/// Whether triangle `t`'s winding normal points away from `center`.
fn points_out(mesh: &Mesh, t: [u32; 3], center: [f32; 3]) -> bool {
    let [a, b, c] = t.map(|i| v3(mesh.positions[i as usize]));
    let n = (b - a).cross(c - a);
    n.dot((a + b + c) * (1.0 / 3.0) - v3(center)) > 0.0
}

#[test]
fn closed_components_get_the_orientation_of_their_winding() {
    let out = closed_sphere([0.0; 3], 5.0, 12, 20, false);
    assert!(out.triangles.iter().all(|&t| points_out(&out, t, [0.0; 3])));
    let orient = |m: &Mesh| {
        let p: Vec<Vec3> = m.positions.iter().map(|&p| v3(p)).collect();
        super::cull::Closure::of(&p, &m.triangles).0
    };
    assert!(orient(&out).iter().all(|&o| o == 1));
    let inward = closed_sphere([0.0; 3], 5.0, 12, 20, true);
    assert!(orient(&inward).iter().all(|&o| o == -1));
    // Open: the sphere with the poles split (`sphere`), or cut along a zigzag.
    assert!(orient(&sphere([0.0; 3], 5.0, 12, 20))
        .iter()
        .all(|&o| o == 0));
    let mut zigzag = out.clone();
    zigzag
        .triangles
        .retain(|&t| t.iter().all(|&i| out.positions[i as usize][0] > -1.0));
    assert!(orient(&zigzag).iter().all(|&o| o == 0));
    // Capped: cut along a ring of latitude, a planar rim with the rest of the mesh
    // above it; the cap faces down, out of the dome.
    let mut half = out.clone();
    half.triangles
        .retain(|&t| t.iter().all(|&i| out.positions[i as usize][2] > -1.0));
    let p: Vec<Vec3> = half.positions.iter().map(|&p| v3(p)).collect();
    let (facing, closure) = super::cull::Closure::of(&p, &half.triangles);
    assert!(facing.iter().all(|&o| o == 1));
    assert_eq!(closure.caps.len(), 1);
    let cap = closure.caps[0];
    assert!((cap.normal - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5);
    // In the plane of the lowest ring kept.
    let rim = half
        .triangles
        .iter()
        .flatten()
        .map(|&i| half.positions[i as usize][2])
        .fold(f32::MAX, f32::min);
    assert!(
        (cap.point.z - rim).abs() < 1e-4,
        "{cap:?}, rim at z = {rim}"
    );
    // Wound inwards, the same cap, its normal still out of the dome.
    let mut inward_half = half.clone();
    inward_half.triangles.iter_mut().for_each(|t| t.swap(1, 2));
    let (facing, closure) = super::cull::Closure::of(&p, &inward_half.triangles);
    assert!(facing.iter().all(|&o| o == -1));
    assert!((closure.caps[0].normal - cap.normal).length() < 1e-5);
    // A band cut out: two planar rims, but each with mesh on both sides.
    let mut band = out.clone();
    band.triangles
        .retain(|&t| !t.iter().all(|&i| out.positions[i as usize][2].abs() < 2.0));
    assert!(orient(&band).iter().all(|&o| o == 0));
    // Inconsistent: one triangle turned over spoils its component.
    let mut flipped = out.clone();
    flipped.triangles[7].swap(0, 1);
    assert!(orient(&flipped).iter().all(|&o| o == 0));
    // Per component: a sphere, an inward-wound sphere beside it, an open half, and a
    // cavity (an inward-wound sphere inside the first).
    let (beside, cavity) = (
        closed_sphere([20.0, 0.0, 0.0], 3.0, 8, 10, true),
        closed_sphere([0.0, 0.0, 1.0], 2.0, 6, 8, true),
    );
    let mut all = Mesh::default();
    for m in [&out, &beside, &zigzag, &cavity] {
        let base = all.positions.len() as u32;
        all.positions.extend(&m.positions);
        all.triangles
            .extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    let o = orient(&all);
    let n = [&out, &beside, &zigzag].map(|m| m.triangles.len());
    assert!(o[..n[0]].iter().all(|&o| o == 1));
    assert!(o[n[0]..n[0] + n[1]].iter().all(|&o| o == -1));
    assert!(o[n[0] + n[1]..n[0] + n[1] + n[2]].iter().all(|&o| o == 0));
    assert!(o[n[0] + n[1] + n[2]..].iter().all(|&o| o == -1));
}

/// Two closed spheres crossing each other (the second wound inwards) and an open
/// hemisphere crossing the first, as three meshes.
fn culling_scene() -> Surfaces {
    let ball = closed_sphere([0.0; 3], 10.0, 24, 40, false);
    let inward = closed_sphere([7.0, 2.0, 0.0], 5.0, 16, 24, true);
    let full = closed_sphere([-6.0, 0.0, 4.0], 6.0, 16, 24, false);
    let mut zigzag = full.clone();
    zigzag
        .triangles
        .retain(|&t| t.iter().all(|&i| full.positions[i as usize][0] > -7.0));
    // A dome over a planar rim, open downwards (-z).
    let dome = closed_sphere([3.0, -8.0, -6.0], 5.0, 16, 24, false);
    let mut capped = dome.clone();
    capped
        .triangles
        .retain(|&t| t.iter().all(|&i| dome.positions[i as usize][2] > -7.0));
    Surfaces::new([&ball, &inward, &zigzag, &capped]).unwrap()
}

fn culling_cases() -> Vec<SurfaceSettings> {
    use Projection::{Orthographic as O, Perspective as P};
    let cases = [
        (View::Left, 25.0, 30.0, P, 1, 160, 121),
        (View::Anterior, -40.0, 10.0, O, 2, 95, 102),
        (View::Superior, 10.0, -65.0, P, 2, 100, 80),
        (View::Right, 130.0, 5.0, O, 1, 140, 140),
        (View::Inferior, 20.0, 10.0, P, 1, 120, 100),
        (View::Inferior, -30.0, 5.0, O, 1, 120, 100),
    ];
    cases
        .into_iter()
        .map(
            |(view, azimuth, elevation, projection, ssaa, width, height)| SurfaceSettings {
                width,
                height,
                ssaa,
                camera: CameraSpec {
                    view,
                    azimuth,
                    elevation,
                    zoom: 1.3,
                    projection,
                    ..Default::default()
                },
                // Black (the default) too, which the bands zero rather than fill.
                background: if view == View::Inferior {
                    [0.0; 3]
                } else {
                    [0.2, 0.1, 0.05]
                },
                ..Default::default()
            },
        )
        .collect()
}

#[test]
fn culled_triangles_face_away_from_the_eye_in_world_space() {
    let s = culling_scene();
    let mut seen = [0usize; 2];
    for settings in culling_cases() {
        let camera = s.camera(&settings).unwrap();
        let frame = Frame::new(&s, &camera, &settings);
        for (id, tri) in s.triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| s.positions[i as usize]);
            let n = (b - a).cross(c - a).normalize_or_zero();
            let to = match camera.projection {
                Projection::Perspective => (a - camera.eye).normalize_or_zero(),
                Projection::Orthographic => camera.forward,
            };
            // The winding normal against the line of sight, made outward.
            let away = n.dot(to) * f32::from(s.facing[id]);
            let cull = frame.cull_of(&s, id as u32);
            if s.facing[id] == 0 {
                assert_eq!(cull, 0.0, "open meshes are kept");
            }
            if cull == 0.0 {
                continue;
            }
            let [p, q, r] = tri.map(|i| frame.verts[i as usize]);
            let area = (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x);
            // Nearly edge-on triangles may round either way.
            if away.abs() > 1e-3 {
                assert_eq!(area * cull > 0.0, away > 0.0, "triangle {id}: {away}");
                seen[usize::from(away > 0.0)] += 1;
            }
        }
    }
    assert!(
        seen.iter().all(|&k| k > 1000),
        "front and back faces: {seen:?}"
    );
}

#[test]
fn capped_meshes_are_culled_only_from_behind_their_caps() {
    let s = culling_scene();
    let capped = s.mesh_starts[3].1;
    for settings in culling_cases() {
        let camera = s.camera(&settings).unwrap();
        let frame = Frame::new(&s, &camera, &settings);
        // The dome's opening faces down: seen from below, its inside shows.
        let below = settings.camera.view == View::Inferior;
        assert_eq!(s.facing[capped as usize], 1);
        assert_eq!(frame.cull_of(&s, capped) == 0.0, below, "{settings:?}");
        assert_ne!(frame.cull_of(&s, 0), 0.0, "the closed ball is culled");
        assert_eq!(frame.cull_of(&s, s.mesh_starts[2].1), 0.0, "open: never");
    }
}

/// K_4 with n = 30, Phong geometry, the headlight: the culling tests' shader.
fn headlight_shader() -> Shader {
    Shader::new(
        LobeKind::EnergyFit,
        30.0,
        4,
        Geometry::Phong,
        Material::default(),
        vec![Light::HEADLIGHT],
        0.0,
    )
    .unwrap()
}

#[test]
fn culling_changes_only_depth_ties_with_back_faces() {
    let s = culling_scene();
    let shader = headlight_shader();
    for settings in culling_cases() {
        let camera = s.camera(&settings).unwrap();
        let case = format!("{:?}", settings.camera);
        // The tiled render culls as the reference does, bit for bit.
        let want = reference(&s, &camera, &shader, &settings, true);
        for avx2 in paths() {
            let (got, _) = s
                .render_with(&camera, &shader, &settings, None, avx2, false)
                .unwrap();
            assert_eq!(got.alpha, want.alpha, "{case} avx2 {avx2}");
            assert_eq!(got.rgb, want.rgb, "{case} avx2 {avx2}");
        }
        // Against keeping every triangle: a sample changes only where a back face
        // won, by a tie or a rounding's worth of depth with the front face the culled
        // frame keeps there, which is on the silhouette.
        let frame = Frame::new(&s, &camera, &settings);
        let (culled, all) = (winners(&s, &frame, true), winners(&s, &frame, false));
        let (mut changed, mut covered, mut back) = (0, 0, 0);
        for (k, (c, a)) in culled.iter().zip(&all).enumerate() {
            covered += usize::from(a.is_some());
            let Some((key, id)) = *a else { continue };
            let faces_away = frame
                .front_bbox(s.triangles[id], frame.cull_of(&s, id as u32))
                .is_none();
            back += usize::from(faces_away);
            if *c == *a {
                continue;
            }
            changed += 1;
            assert!(faces_away, "{case}: sample {k} lost a front face");
            let (front, _) = c.unwrap_or_else(|| panic!("{case}: sample {k} lost its cover"));
            assert!(
                (key - front).abs() <= 1e-5 * key.abs(),
                "{case}: sample {k}: back face at {key}, front face at {front}"
            );
        }
        assert!(covered > 1000, "{case}: {covered}");
        assert!(
            changed * 100 <= covered,
            "{case}: {changed} of {covered} changed"
        );
        eprintln!(
            "{case}: {changed} of {covered} covered samples changed, {back} back-face winners"
        );
    }
}

#[test]
fn no_culling_with_the_eye_inside_a_closed_mesh() {
    let s = culling_scene();
    let settings = SurfaceSettings {
        width: 40,
        height: 30,
        ssaa: 1,
        ..Default::default()
    };
    let mut camera = s.camera(&settings).unwrap();
    // Inside the first sphere, looking at its far wall.
    camera.eye = Vec3::new(0.0, 0.0, -8.0);
    let frame = Frame::new(&s, &camera, &settings);
    assert_eq!(frame.cull_of(&s, 0), 0.0);
    let shader = headlight_shader();
    let want = reference(&s, &camera, &shader, &settings, false);
    assert!(want.stats.shaded > 100);
    for avx2 in paths() {
        let (got, _) = s
            .render_with(&camera, &shader, &settings, None, avx2, false)
            .unwrap();
        assert_eq!(got.rgb, want.rgb);
        assert_eq!(got.alpha, want.alpha);
    }
}

/// A clip of one plane through `point` keeping the side `normal` points to.
fn plane_clip(point: Vec3, normal: Vec3) -> glint_core::Clip {
    glint_core::Clip {
        planes: vec![glint_core::ClipPlane {
            point: [point.x, point.y, point.z].map(f64::from),
            normal: [normal.x, normal.y, normal.z].map(f64::from),
        }],
        crop: None,
    }
}

/// 48x48, one sample a pixel, orthographic from an oblique direction.
fn clip_settings() -> SurfaceSettings {
    SurfaceSettings {
        width: 48,
        height: 48,
        ssaa: 1,
        camera: CameraSpec {
            azimuth: 30.0,
            elevation: 20.0,
            projection: Projection::Orthographic,
            ..Default::default()
        },
        background: [0.1, 0.2, 0.3],
        ..Default::default()
    }
}

#[test]
fn a_clipped_sphere_loses_what_lies_beyond_the_plane_and_keeps_the_rest() {
    let ball = sphere([0.0; 3], 10.0, 24, 48);
    let s = Surfaces::new([&ball]).unwrap();
    let settings = clip_settings();
    let camera = s.camera(&settings).unwrap();
    let shader = headlight_shader();
    let whole = s.render(&camera, &shader, &settings, None).unwrap();
    // Keep the image's right of a vertical plane 2 mm right of the centre; the
    // orthographic rays run along the plane, so a pixel's side is its ray's.
    let point = camera.right * 2.0;
    let cut = s.clipped(&plane_clip(point, camera.right), false).unwrap();
    assert!(cut.triangle_count() < s.triangle_count());
    assert_eq!(
        cut.camera(&settings).unwrap(),
        camera,
        "the framing is kept"
    );
    let (w, h) = (settings.width, settings.height);
    let (mut gone, mut same) = (0, 0);
    for avx2 in paths() {
        let (got, _) = cut
            .render_with(&camera, &shader, &settings, None, avx2, false)
            .unwrap();
        for y in 0..h {
            for x in 0..w {
                let (o, _) = camera.ray(x as f32, y as f32, w, h);
                let side = (o - point).dot(camera.right);
                let k = (y * w + x) as usize;
                if side < -1e-3 {
                    assert_eq!(got.alpha[k], 0.0, "({x}, {y}) beyond the plane");
                    assert_eq!(got.rgb[k], settings.background);
                    gone += usize::from(whole.alpha[k] > 0.0);
                } else if side > 2.0 {
                    // Further than a triangle from the cut: the same triangles.
                    assert_eq!(got.alpha[k], whole.alpha[k], "({x}, {y})");
                    assert_eq!(got.rgb[k], whole.rgb[k], "({x}, {y})");
                    same += usize::from(whole.alpha[k] > 0.0);
                }
            }
        }
    }
    assert!(gone > 100 && same > 100, "{gone} cut, {same} kept");
}

#[test]
fn a_capped_sphere_cut_through_its_centre_shows_a_disc_lit_with_the_plane_normal() {
    let r = 10.0;
    let ball = closed_sphere([0.0; 3], r, 24, 48, false);
    let s = Surfaces::new([&ball]).unwrap();
    let settings = clip_settings();
    let camera = s.camera(&settings).unwrap();
    let shader = headlight_shader();
    // Keep the far half: the cut faces the eye.
    let clip = plane_clip(Vec3::ZERO, camera.forward);
    let open = s.clipped(&clip, false).unwrap();
    let capped = s.clipped(&clip, true).unwrap();
    let (w, h) = (settings.width, settings.height);
    let base = settings.color;
    let want = shader
        .placed(&camera)
        .shade_normal(base, -camera.forward, -camera.forward);
    // The plane is this far from the eye's image plane along every ray.
    let depth = (Vec3::ZERO - camera.eye).dot(camera.forward);
    let (plain, _) = open
        .render_with(&camera, &shader, &settings, None, false, false)
        .unwrap();
    let mut disc = 0;
    for avx2 in paths() {
        let (got, far) = capped
            .render_with(&camera, &shader, &settings, None, avx2, true)
            .unwrap();
        let far = far.unwrap();
        for y in 0..h {
            for x in 0..w {
                let (o, _) = camera.ray(x as f32, y as f32, w, h);
                let off = o - camera.eye;
                let k = (y * w + x) as usize;
                if off.length() < 0.9 * r {
                    let c = got.rgb[k];
                    assert!(
                        (0..3).all(|i| (c[i] - want[i]).abs() < 1e-5),
                        "({x}, {y}): {c:?} against the plane's {want:?}"
                    );
                    assert!((far[k] - depth).abs() < 1e-3, "{} against {depth}", far[k]);
                    // Without caps the inside of the far half shows.
                    assert!((0..3).any(|i| (plain.rgb[k][i] - want[i]).abs() > 1e-3));
                    disc += 1;
                }
            }
        }
    }
    assert!(disc > 200, "{disc}");
}

#[test]
fn scalar_and_avx2_agree_on_clipped_and_capped_meshes() {
    let (ball, plane) = (
        closed_sphere([0.0; 3], 10.0, 24, 48, false),
        square(12.0, 2.0),
    );
    let s = Surfaces::new([&ball, &plane]).unwrap();
    let clip = glint_core::Clip {
        planes: vec![glint_core::ClipPlane {
            point: [1.0, 0.0, 0.0],
            normal: [1.0, 0.3, -0.2],
        }],
        crop: Some(glint_core::CropBox {
            min: [-20.0, -20.0, -6.0],
            max: [20.0, 7.0, 20.0],
        }),
    };
    let shader = headlight_shader();
    let mut shown = false;
    for projection in [Projection::Perspective, Projection::Orthographic] {
        let settings = SurfaceSettings {
            width: 45,
            height: 38,
            ssaa: 2,
            camera: CameraSpec {
                azimuth: 200.0,
                elevation: 25.0,
                projection,
                ..Default::default()
            },
            ..Default::default()
        };
        let camera = s.camera(&settings).unwrap();
        let open = s.clipped(&clip, false).unwrap();
        // Uncapped, the clipped triangles are plain triangles: the reference holds.
        let want = reference(&open, &camera, &shader, &settings, false);
        let capped = s.clipped(&clip, true).unwrap();
        let (first, first_far) = capped
            .render_with(&camera, &shader, &settings, None, false, true)
            .unwrap();
        shown |= first.rgb != want.rgb;
        for avx2 in paths() {
            let (got, _) = open
                .render_with(&camera, &shader, &settings, None, avx2, false)
                .unwrap();
            assert_eq!(got.rgb, want.rgb, "{projection:?} avx2 {avx2}");
            assert_eq!(got.alpha, want.alpha);
            let (got, far) = capped
                .render_with(&camera, &shader, &settings, None, avx2, true)
                .unwrap();
            assert_eq!(got.rgb, first.rgb, "{projection:?} avx2 {avx2} capped");
            assert_eq!(got.alpha, first.alpha);
            assert_eq!(far, first_far);
        }
    }
    assert!(shown, "the caps show");
}

#[test]
fn a_pick_goes_through_the_clipped_part_and_stops_at_a_cap() {
    let s = Surfaces::new([&square(1.0, 0.0), &square(1.0, -2.0)]).unwrap();
    let down = Vec3::new(0.0, 0.0, -1.0);
    let from = Vec3::new(0.3, -0.2, 5.0);
    assert_eq!(s.pick(from, down).unwrap().mesh, 0);
    // Keep below z = -1: the upper square is cut away, the ray meets the lower one.
    let cut = s
        .clipped(&plane_clip(Vec3::new(0.0, 0.0, -1.0), down), true)
        .unwrap();
    let hit = cut.pick(from, down).unwrap();
    assert_eq!(hit.mesh, 1);
    assert!((hit.t - 7.0).abs() < 1e-5, "{hit:?}");
    // A closed sphere cut through its centre and capped: the pick stops on the cut.
    let ball = closed_sphere([0.0; 3], 10.0, 24, 48, false);
    let ball = Surfaces::new([&ball]).unwrap();
    let clip = plane_clip(Vec3::ZERO, down);
    let hit = ball.clipped(&clip, true).unwrap().pick(from, down).unwrap();
    assert!(hit.point.z.abs() < 1e-4, "{hit:?}");
    // Uncapped, it goes on to the inside of the far half.
    let hit = ball
        .clipped(&clip, false)
        .unwrap()
        .pick(from, down)
        .unwrap();
    assert!(hit.point.z < -9.0, "{hit:?}");
    let bad = plane_clip(Vec3::ZERO, Vec3::ZERO);
    assert!(ball
        .clipped(&bad, true)
        .unwrap_err()
        .to_string()
        .contains("zero"));
}

#[test]
fn a_capped_hollow_shell_shows_a_ring_and_its_cavity_stays_open() {
    // A shell: a sphere of radius 10 wound outwards around a cavity of radius 5 wound
    // inwards (as an isosurface bounds a hollow object), one mesh.
    let (outer, inner) = (
        closed_sphere([0.0; 3], 10.0, 24, 48, false),
        closed_sphere([0.0; 3], 5.0, 16, 32, true),
    );
    let base = outer.positions.len() as u32;
    let mut shell = outer;
    shell.positions.extend(inner.positions);
    shell
        .triangles
        .extend(inner.triangles.iter().map(|t| t.map(|i| i + base)));
    let s = Surfaces::new([&shell]).unwrap();
    let settings = clip_settings();
    let camera = s.camera(&settings).unwrap();
    let shader = headlight_shader();
    let capped = s
        .clipped(&plane_clip(Vec3::ZERO, camera.forward), true)
        .unwrap();
    let cap = shader
        .placed(&camera)
        .shade_normal(settings.color, -camera.forward, -camera.forward);
    let (w, h) = (settings.width, settings.height);
    let (got, _) = capped
        .render_with(&camera, &shader, &settings, None, simd(), false)
        .unwrap();
    let (mut ring, mut hole) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let (o, _) = camera.ray(x as f32, y as f32, w, h);
            let r = (o - camera.eye).length();
            let c = got.rgb[(y * w + x) as usize];
            let is_cap = (0..3).all(|i| (c[i] - cap[i]).abs() < 1e-5);
            if (5.5..9.5).contains(&r) {
                assert!(is_cap, "({x}, {y}) in the ring: {c:?}");
                ring += 1;
            } else if r < 4.5 {
                // The cavity's far wall, lit with its own normals, not a cap.
                assert!(
                    !is_cap && got.alpha[(y * w + x) as usize] == 1.0,
                    "({x}, {y})"
                );
                hole += 1;
            }
        }
    }
    assert!(ring > 100 && hole > 30, "{ring} ring, {hole} cavity pixels");
}

//! The tiled, binned, SIMD rasterizer against a per-sample reference: every
//! triangle tested at every sample, the nearest kept, each sample lit alone by
//! [`Shader::shade_surface`].

use glint_lobe::{Geometry, LobeKind};

use super::frame::{Edges, Frame};
use super::*;
use crate::camera::{Projection, View};
use crate::shading::Light;
use crate::tf::Material;

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

/// The reference render: per sample, the nearest triangle (the first on a tie)
/// among all that cover it, its normal and colour, lit by `shade_surface`; the box
/// filter as [`Surfaces::render`] documents it.
fn reference(s: &Surfaces, camera: &Camera, shader: &Shader, settings: &SurfaceSettings) -> Image {
    let shader = shader.placed(camera);
    let frame = Frame::new(s, camera, settings);
    let n = settings.ssaa as usize;
    let (w, h) = (settings.width as usize, settings.height as usize);
    let mut sum = vec![[0.0f32; 3]; w * h];
    let mut covered = vec![0u32; w * h];
    for sy in 0..h * n {
        for sx in 0..w * n {
            let (x, y) = (sx as f32, sy as f32);
            let mut best: Option<(f32, usize)> = None;
            for (id, tri) in s.triangles.iter().enumerate() {
                let Some([x0, y0, x1, y1]) = frame.bbox(*tri) else {
                    continue;
                };
                let inside_box = (usize::from(x0)..=usize::from(x1)).contains(&sx)
                    && (usize::from(y0)..=usize::from(y1)).contains(&sy);
                let [a, b, c] = tri.map(|i| frame.verts[i as usize]);
                let e = Edges::new(a, b, c);
                let (w0, w1, w2) = e.at(x, y);
                if !inside_box || w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let key = (w0 * a.key + w1 * b.key + w2 * c.key) * e.inv_area();
                if best.is_none_or(|(k, _)| key > k) {
                    best = Some((key, id));
                }
            }
            let Some((_, id)) = best else { continue };
            let idx = s.triangles[id].map(|i| i as usize);
            let [a, b, c] = idx.map(|i| frame.verts[i]);
            let (w0, w1, w2) = Edges::new(a, b, c).at(x, y);
            let (p0, p1, p2) = (w0 * a.w, w1 * b.w, w2 * c.w);
            let inv = 1.0 / (p0 + p1 + p2);
            let [n0, n1, n2] = idx.map(|i| s.normals[i]);
            let mut normal =
                (n0 * (p0 * inv) + n1 * (p1 * inv) + n2 * (p2 * inv)).normalize_or_zero();
            if normal == Vec3::ZERO {
                let [pa, pb, pc] = idx.map(|i| s.positions[i]);
                normal = (pb - pa).cross(pc - pa).normalize_or_zero();
            }
            let mesh = s.mesh_of(id as u32);
            let base = *settings.mesh_colors.get(mesh).unwrap_or(&settings.color);
            let lit = shader.shade_surface(base, normal, frame.view(x, y));
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

/// The loops to test: scalar, and AVX2 where the CPU has it.
fn paths() -> Vec<bool> {
    #[cfg(target_arch = "x86_64")]
    if avx2::supported() {
        return vec![false, true];
    }
    vec![false]
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
        let want = reference(&s, &camera, &shader, &settings);
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
    let want = reference(&s, &camera, &shader, &settings);
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

//! Surface rendering and isosurface extraction against independent references:
//! analytic ray-sphere shading, analytic plane intersections, the sphere's area.

use std::collections::HashMap;
use std::f64::consts::PI;

use glint_io::{Mesh, Samples, Volume};
use glint_lobe::{Geometry, LobeKind};
use glint_render::math::Vec3;
use glint_render::mesh::{extract, taubin_smooth, Taubin};
use glint_render::{
    CameraSpec, ColorMap, Light, Material, Projection, RenderError, ScalarColors, Shader,
    SurfaceSettings, Surfaces, View,
};

/// A latitude-longitude sphere with exact normals; the poles' rings collapse, so the
/// polar triangles are degenerate.
fn uv_sphere(center: [f32; 3], r: f32, nlat: u32, nlon: u32) -> Mesh {
    let mut mesh = Mesh::default();
    let mut normals = Vec::new();
    for i in 0..=nlat {
        let theta = PI * f64::from(i) / f64::from(nlat);
        for j in 0..nlon {
            let phi = 2.0 * PI * f64::from(j) / f64::from(nlon);
            let n = [
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ]
            .map(|x| x as f32);
            mesh.positions.push([0, 1, 2].map(|a| center[a] + r * n[a]));
            normals.push(n);
        }
    }
    for i in 0..nlat {
        for j in 0..nlon {
            let (a, b) = (i * nlon + j, i * nlon + (j + 1) % nlon);
            let (c, d) = (a + nlon, b + nlon);
            mesh.triangles.push([a, c, b]);
            mesh.triangles.push([b, c, d]);
        }
    }
    mesh.normals = Some(normals);
    mesh
}

fn shader(material: Material, lights: Vec<Light>, n: f64) -> Shader {
    Shader::new(
        LobeKind::Exact,
        n,
        4,
        Geometry::Phong,
        material,
        lights,
        0.0,
    )
    .unwrap()
}

/// `Surfaces::render_layer`'s per-pixel distance is where the pixel's ray meets the
/// sphere (analytic, within the tessellation's chord error), infinite exactly where
/// no surface is drawn, for both projections.
#[test]
fn layer_distances_are_the_rays_hits_on_a_sphere() {
    let (c, r) = (Vec3::new(-4.0, 7.0, 1.0), 12.0f32);
    let mesh = uv_sphere([c.x, c.y, c.z], r, 128, 256);
    let surfaces = Surfaces::new([&mesh]).unwrap();
    for projection in [Projection::Perspective, Projection::Orthographic] {
        let settings = SurfaceSettings {
            width: 64,
            height: 48,
            ssaa: 1,
            camera: CameraSpec {
                view: View::Superior,
                azimuth: 30.0,
                projection,
                ..Default::default()
            },
            ..Default::default()
        };
        let camera = surfaces.camera(&settings).unwrap();
        let shader = shader(Material::default(), vec![Light::HEADLIGHT], 10.0);
        let (image, far) = surfaces
            .render_layer(&camera, &shader, &settings, None)
            .unwrap();
        let mut hits = 0;
        for y in 0..48 {
            for x in 0..64 {
                let k = y * 64 + x;
                assert_eq!(far[k].is_finite(), image.alpha[k] > 0.0, "pixel {x},{y}");
                let (o, d) = camera.ray(x as f32, y as f32, 64, 48);
                let oc = o - c;
                let b = oc.dot(d);
                let disc = b * b - (oc.dot(oc) - r * r);
                // Away from the silhouette, where the polygon and the sphere differ.
                if disc > 0.05 * r * r {
                    let t = -b - disc.sqrt();
                    assert!(
                        (far[k] - t).abs() < 0.01 * r,
                        "{projection:?} pixel {x},{y}: {} vs {t}",
                        far[k]
                    );
                    hits += 1;
                }
            }
        }
        assert!(hits > 500, "{hits}");
    }
}

#[test]
fn rasterised_sphere_matches_analytic_shading() {
    let (c, r) = (Vec3::new(1.0, 2.0, 3.0), 10.0f32);
    let mesh = uv_sphere([c.x, c.y, c.z], r, 128, 256);
    let surfaces = Surfaces::new([&mesh]).unwrap();
    let settings = SurfaceSettings {
        width: 96,
        height: 80,
        ssaa: 1,
        camera: CameraSpec {
            view: View::Left,
            azimuth: 20.0,
            ..Default::default()
        },
        background: [0.1, 0.2, 0.3],
        color: [0.8, 0.6, 0.4],
        mesh_colors: Vec::new(),
    };
    let camera = surfaces.camera(&settings).unwrap();
    let relative = vec![
        Light::HEADLIGHT,
        Light {
            azimuth: 40.0,
            elevation: 30.0,
            intensity: 0.7,
        },
    ];
    let lights: Vec<(Vec3, f32)> = relative
        .iter()
        .map(|l| (l.direction(&camera), l.intensity))
        .collect();
    let m = Material {
        specular: 0.6,
        ..Material::default()
    };
    let n = 20.0;
    let image = surfaces
        .render(&camera, &shader(m, relative, n), &settings, None)
        .unwrap();
    let (mut hits, mut misses, mut worst) = (0, 0, 0.0f32);
    for y in (2..80).step_by(3) {
        for x in (2..96).step_by(3) {
            let (o, d) = camera.ray(x as f32, y as f32, 96, 80);
            // |o + t d - c| = r.
            let oc = o - c;
            let b = oc.dot(d);
            let disc = b * b - (oc.dot(oc) - r * r);
            let k = (y * 96 + x) as usize;
            if disc < 0.0 {
                if -disc > 0.05 * r * r {
                    assert_eq!(image.rgb[k], settings.background, "pixel {x},{y}");
                    assert_eq!(image.alpha[k], 0.0);
                    misses += 1;
                }
                continue;
            }
            let p = o + d * (-b - disc.sqrt());
            let normal = (p - c) * (1.0 / r);
            let view = -d;
            if normal.dot(view) < 0.3 {
                continue; // too near the silhouette for a faceted sphere
            }
            let (mut diffuse, mut spec) = (0.0f32, 0.0f32);
            for &(l, i) in &lights {
                let ndl = normal.dot(l);
                if ndl > 0.0 {
                    diffuse += i * ndl;
                    let refl = normal * (2.0 * ndl) - l;
                    spec += i * refl.dot(view).max(0.0).powf(n as f32);
                }
            }
            let want = settings
                .color
                .map(|b| b * (m.ambient + m.diffuse * diffuse) + m.specular * spec);
            for (got, want) in image.rgb[k].iter().zip(want) {
                worst = worst.max((got - want).abs());
            }
            assert_eq!(image.alpha[k], 1.0);
            hits += 1;
        }
    }
    assert!(hits > 60 && misses > 20, "{hits} hits, {misses} misses");
    assert!(
        worst < 0.01,
        "largest difference from the analytic shading: {worst}"
    );
}

#[test]
fn supersampling_blends_the_silhouette() {
    let mesh = uv_sphere([0.0; 3], 5.0, 32, 64);
    let surfaces = Surfaces::new([&mesh]).unwrap();
    for (ssaa, partial_expected) in [(1, false), (4, true)] {
        let settings = SurfaceSettings {
            width: 64,
            height: 64,
            ssaa,
            ..Default::default()
        };
        let camera = surfaces.camera(&settings).unwrap();
        let s = shader(Material::default(), vec![Light::HEADLIGHT], 10.0);
        let image = surfaces.render(&camera, &s, &settings, None).unwrap();
        let partial = image.alpha.iter().filter(|&&a| a > 0.0 && a < 1.0).count();
        assert_eq!(
            partial > 0,
            partial_expected,
            "ssaa {ssaa}: {partial} partial pixels"
        );
        assert!(image.alpha.iter().filter(|&&a| a == 1.0).count() > 500);
    }
}

#[test]
fn scalars_are_interpolated_perspective_correctly() {
    // A square in the plane x = 0 seen from an angle; the scalar is the vertex's z.
    // Each pixel's colour must be the map at the z where its ray meets the plane.
    let mut mesh = Mesh::default();
    for (y, z) in [(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)] {
        mesh.positions.push([0.0, y, z]);
    }
    mesh.triangles = vec![[0, 1, 2], [0, 2, 3]];
    mesh.scalars = Some(mesh.positions.iter().map(|p| p[2]).collect());
    let surfaces = Surfaces::new([&mesh]).unwrap();
    let settings = SurfaceSettings {
        width: 64,
        height: 64,
        ssaa: 1,
        camera: CameraSpec {
            view: View::Left,
            elevation: 60.0,
            zoom: 1.5,
            ..Default::default()
        },
        ..Default::default()
    };
    let camera = surfaces.camera(&settings).unwrap();
    // Ambient only: the pixel is the base colour.
    let flat = Material {
        ambient: 1.0,
        diffuse: 0.0,
        specular: 0.0,
        ..Material::default()
    };
    let colors = ScalarColors::new(ColorMap::Viridis, (-10.0, 10.0)).unwrap();
    let image = surfaces
        .render(
            &camera,
            &shader(flat, vec![], 10.0),
            &settings,
            Some(&colors),
        )
        .unwrap();
    let mut checked = 0;
    for y in (0..64).step_by(3) {
        for x in (0..64).step_by(3) {
            let (o, d) = camera.ray(x as f32, y as f32, 64, 64);
            let t = -o.x / d.x;
            let p = o + d * t;
            if p.y.abs() > 9.5 || p.z.abs() > 9.5 {
                continue;
            }
            let want = ColorMap::Viridis.linear((f64::from(p.z) + 10.0) / 20.0);
            let got = image.pixel(x, y);
            for ch in 0..3 {
                assert!(
                    (got[ch] - want[ch]).abs() < 0.01,
                    "pixel {x},{y}: {got:?} vs {want:?} (z {})",
                    p.z
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 50, "{checked}");
}

#[test]
fn bad_meshes_fail_clearly_and_degenerate_triangles_render() {
    let mut nan = uv_sphere([0.0; 3], 1.0, 8, 8);
    nan.positions[5][1] = f32::NAN;
    let err = Surfaces::new([&nan]).unwrap_err();
    assert!(matches!(err, RenderError::Mesh(_)));
    let chain = format!("{err}: {}", std::error::Error::source(&err).unwrap());
    assert!(chain.contains("non-finite"), "{chain}");

    let mut bad_index = uv_sphere([0.0; 3], 1.0, 8, 8);
    bad_index.triangles.push([0, 1, 100_000]);
    assert!(Surfaces::new([&bad_index]).is_err());
    let mut bad_scalars = uv_sphere([0.0; 3], 1.0, 8, 8);
    bad_scalars.scalars = Some(vec![0.0; 3]);
    assert!(Surfaces::new([&bad_scalars]).is_err());
    assert!(Surfaces::new([&Mesh::default()]).is_err());

    // Only degenerate triangles (a point and a segment) plus one real one.
    let mesh = Mesh {
        positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        triangles: vec![[0, 0, 0], [0, 1, 2], [0, 1, 3]],
        normals: None,
        scalars: None,
    };
    let surfaces = Surfaces::new([&mesh]).unwrap();
    for ssaa in [1, 2, 4] {
        let settings = SurfaceSettings {
            width: 40,
            height: 30,
            ssaa,
            camera: CameraSpec {
                view: View::Superior,
                ..Default::default()
            },
            ..Default::default()
        };
        let camera = surfaces.camera(&settings).unwrap();
        let image = surfaces
            .render(
                &camera,
                &shader(Material::default(), vec![Light::HEADLIGHT], 10.0),
                &settings,
                None,
            )
            .unwrap();
        assert!(image.rgb.iter().flatten().all(|c| c.is_finite()));
        assert!(
            image.alpha.iter().any(|&a| a > 0.0),
            "the real triangle shows"
        );
    }
    // All degenerate: nothing covered, no panic.
    let points = Mesh {
        triangles: vec![[0, 0, 0], [0, 1, 2]],
        ..mesh
    };
    let surfaces = Surfaces::new([&points]).unwrap();
    let settings = SurfaceSettings {
        width: 16,
        height: 16,
        ..Default::default()
    };
    let camera = surfaces.camera(&settings).unwrap();
    let image = surfaces
        .render(
            &camera,
            &shader(Material::default(), vec![], 10.0),
            &settings,
            None,
        )
        .unwrap();
    assert!(image.alpha.iter().all(|&a| a == 0.0));
    assert!(SurfaceSettings {
        ssaa: 3,
        ..Default::default()
    }
    .validate()
    .is_err());
}

/// A volume whose value falls linearly with the distance from `center` (world mm):
/// `r - |x - center|`, so the iso value 0 is the sphere of radius `r`. The affine
/// mirrors x and has unequal spacings.
fn sphere_volume(center: [f64; 3], r: f64) -> Volume {
    let dims = [48, 44, 40];
    let spacing = [0.7, 0.8, 0.9];
    let mut affine = [[0.0; 4]; 4];
    affine[0][0] = -spacing[0];
    affine[0][3] = 30.0;
    affine[1][1] = spacing[1];
    affine[1][3] = -5.0;
    affine[2][2] = spacing[2];
    affine[2][3] = 2.0;
    affine[3][3] = 1.0;
    let mut v = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let idx = [i as f64, j as f64, k as f64];
                let w: Vec<f64> = (0..3)
                    .map(|a| (0..3).map(|b| affine[a][b] * idx[b]).sum::<f64>() + affine[a][3])
                    .collect();
                let d = ((w[0] - center[0]).powi(2)
                    + (w[1] - center[1]).powi(2)
                    + (w[2] - center[2]).powi(2))
                .sqrt();
                v.push((r - d) as f32);
            }
        }
    }
    let mut vol = Volume::new(dims, spacing, Samples::F32(v)).unwrap();
    vol.affine = affine;
    vol
}

fn area(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].map(f64::from));
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
        })
        .sum()
}

/// Every undirected edge is used by exactly two triangles, and every directed edge
/// by exactly one (consistent orientation).
fn assert_closed_and_oriented(mesh: &Mesh) {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "edge {a}->{b} used {n} times in one direction");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "edge {a}-{b} is on the boundary"
        );
    }
}

#[test]
fn sphere_isosurface_is_watertight_with_the_right_area_and_outward_normals() {
    let (center, r) = ([12.0, 11.0, 20.0], 12.0);
    let vol = sphere_volume(center, r);
    let mesh = extract(&vol, 0.0).unwrap();
    assert!(mesh.triangles.len() > 1000);
    assert_closed_and_oriented(&mesh);
    let want = 4.0 * PI * r * r;
    let got = area(&mesh);
    assert!(
        (got / want - 1.0).abs() < 0.01,
        "area {got} vs 4 pi r^2 = {want}"
    );
    let normals = mesh.normals.as_ref().unwrap();
    for (p, n) in mesh.positions.iter().zip(normals) {
        let d: Vec<f64> = (0..3).map(|a| f64::from(p[a]) - center[a]).collect();
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        assert!((len - r).abs() < 0.05, "vertex {p:?} at distance {len}");
        let cos = (0..3).map(|a| f64::from(n[a]) * d[a]).sum::<f64>() / len;
        assert!(cos > 0.99, "normal {n:?} at {p:?}: cos {cos}");
    }
    // Triangles wind counter-clockwise seen from outside: their normals point out.
    for t in mesh.triangles.iter().step_by(97) {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].map(f64::from));
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let out: f64 = (0..3).map(|k| n[k] * (a[k] - center[k])).sum();
        assert!(out >= 0.0, "triangle {t:?} faces inwards");
    }
}

#[test]
fn taubin_smoothing_keeps_the_sphere_closed_and_its_size() {
    let (center, r) = ([12.0, 11.0, 20.0], 10.0);
    let mut mesh = extract(&sphere_volume(center, r), 0.0).unwrap();
    let before = area(&mesh);
    taubin_smooth(&mut mesh, &Taubin::default()).unwrap();
    assert_closed_and_oriented(&mesh);
    // Taubin's point: smoothing without shrinkage (the μ step undoes the λ step's
    // shrinking of low frequencies).
    let after = area(&mesh);
    assert!((after / before - 1.0).abs() < 0.01, "{before} -> {after}");
    let bad = Taubin {
        lambda: 0.5,
        mu: 0.2,
        iterations: 3,
    };
    assert!(taubin_smooth(&mut mesh, &bad).is_err());
}

#[test]
fn isosurface_rejects_bad_input_and_tolerates_nan_samples() {
    let flat = Volume::new([4, 4, 1], [1.0; 3], Samples::U8(vec![0; 16])).unwrap();
    assert!(matches!(
        extract(&flat, 0.5),
        Err(glint_render::mesh::MeshError::Volume(_))
    ));
    let mut vol = sphere_volume([12.0, 11.0, 20.0], 8.0);
    assert!(matches!(
        extract(&vol, f32::NAN),
        Err(glint_render::mesh::MeshError::Parameter(_))
    ));
    if let Samples::F32(v) = &mut vol.samples {
        for x in v.iter_mut().step_by(7) {
            *x = f32::NAN;
        }
    }
    let mesh = extract(&vol, 0.0).unwrap();
    assert!(mesh.positions.iter().flatten().all(|x| x.is_finite()));
    assert!(!mesh.triangles.is_empty());
    // Nothing crosses: an empty mesh, not an error.
    let mesh = extract(&sphere_volume([12.0, 11.0, 20.0], 8.0), 100.0).unwrap();
    assert!(mesh.triangles.is_empty());
}
